//! The checked binary view refuses every kind of malformed image with the byte offset of the
//! fault, and never panics: truncation at every length, every byte corrupted, wrong counts,
//! non-finite numbers, out-of-range indices, cycles, absurd sizes, deep nesting.

use hirad::scene::{compile, decompile, read_image};
use hirad_core::image::*;
use hirad_core::limits::NONE;
use hirad_core::material::MaterialData;
use hirad_tests::sample::sample;

fn header(bytes: &[u8]) -> Header {
    bytemuck::pod_read_unaligned(&bytes[..std::mem::size_of::<Header>()])
}

fn record_offset(bytes: &[u8], s: Section, index: u64) -> usize {
    let e = header(bytes).section(s);
    (e.offset + index * e.record_size as u64) as usize
}

fn patch_u32(bytes: &mut [u8], at: usize, v: u32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

fn patch_f32(bytes: &mut [u8], at: usize, v: f32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

fn open_err(bytes: &[u8]) -> ImageError {
    read_image(bytes).expect_err("image should be refused")
}

#[test]
fn valid_image_opens_and_decompiles() {
    let bytes = compile(&sample()).unwrap();
    let v = read_image(&bytes).unwrap();
    assert_eq!(v.info().expanded_polygons, 12);
    assert_eq!(v.info().image_bytes, bytes.len() as u64);
    let back = decompile(&v).unwrap();
    assert_eq!(compile(&back).unwrap(), bytes);
}

#[test]
fn every_truncation_is_refused() {
    let bytes = compile(&sample()).unwrap();
    for len in 0..bytes.len() {
        let e = open_err(&bytes[..len]);
        assert!(e.offset <= bytes.len() as u64, "len {len}: {e}");
    }
    let mut longer = bytes.clone();
    longer.extend_from_slice(&[0; 8]);
    assert!(matches!(
        open_err(&longer).kind,
        ImageErrorKind::FileSize { .. }
    ));
}

/// Any single corrupted byte either is refused or gives an image whose model compiles back.
#[test]
fn every_corrupted_byte_is_handled() {
    let bytes = compile(&sample()).unwrap();
    for i in 0..bytes.len() {
        for value in [0xFFu8, bytes[i] ^ 0x01, bytes[i] ^ 0x80, 0x00, 0x7F] {
            let mut b = bytes.clone();
            b[i] = value;
            if let Ok(v) = read_image(&b) {
                let scene = decompile(&v).unwrap_or_else(|e| panic!("byte {i} = {value}: {e}"));
                compile(&scene).unwrap_or_else(|e| panic!("byte {i} = {value}: {e}"));
            }
        }
    }
}

#[test]
fn header_faults() {
    let bytes = compile(&sample()).unwrap();
    let mut b = bytes.clone();
    b[0] = b'X';
    assert_eq!(open_err(&b).kind, ImageErrorKind::BadMagic);
    assert_eq!(open_err(b"not a scene").kind, ImageErrorKind::BadMagic);
    let mut b = bytes.clone();
    patch_u32(&mut b, 8, 7);
    assert_eq!(
        open_err(&b),
        ImageError {
            offset: 8,
            kind: ImageErrorKind::UnsupportedVersion { found: 7 }
        }
    );
    let mut b = bytes.clone();
    patch_u32(&mut b, 16, 9);
    assert_eq!(open_err(&b).kind, ImageErrorKind::Bands { found: 9 });
    // Absurd claimed sizes: a section claiming 2^40 records, a file claiming 1 TB.
    let mut b = bytes.clone();
    let at = 40 + 24 * Section::Vertices as usize + 8;
    b[at..at + 8].copy_from_slice(&(1u64 << 40).to_le_bytes());
    assert_eq!(
        open_err(&b).kind,
        ImageErrorKind::SectionTooLarge {
            section: Section::Vertices
        }
    );
    let mut b = bytes.clone();
    b[32..40].copy_from_slice(&(1u64 << 40).to_le_bytes());
    assert!(matches!(open_err(&b).kind, ImageErrorKind::FileSize { .. }));
    // A wrong count shifts every later section.
    let mut b = bytes.clone();
    let at = 40 + 24 * Section::Polygons as usize + 8;
    let n = u64::from_le_bytes(b[at..at + 8].try_into().unwrap());
    b[at..at + 8].copy_from_slice(&(n + 1).to_le_bytes());
    assert!(matches!(
        open_err(&b).kind,
        ImageErrorKind::SectionOffset {
            section: Section::Nodes,
            ..
        }
    ));
}

#[test]
fn record_faults_are_located() {
    let bytes = compile(&sample()).unwrap();
    // A NaN vertex coordinate.
    let mut b = bytes.clone();
    let at = record_offset(&b, Section::Vertices, 2);
    patch_f32(&mut b, at + 4, f32::NAN);
    assert_eq!(
        open_err(&b),
        ImageError {
            offset: at as u64,
            kind: ImageErrorKind::Vertex { vertex: 2 }
        }
    );
    // An infinite material value.
    let mut b = bytes.clone();
    let at = record_offset(&b, Section::Values, 1);
    patch_f32(&mut b, at, f32::INFINITY);
    assert_eq!(open_err(&b).kind, ImageErrorKind::Value { index: 1 });
    // A corner past its node's vertices.
    let mut b = bytes.clone();
    let at = record_offset(&b, Section::Polygons, 0);
    patch_u32(&mut b, at, 1000);
    assert_eq!(
        open_err(&b),
        ImageError {
            offset: at as u64,
            kind: ImageErrorKind::Corner {
                polygon: 0,
                corner: 0
            }
        }
    );
    // A material that does not exist.
    let mut b = bytes.clone();
    patch_u32(&mut b, at + 16, 77);
    assert_eq!(
        open_err(&b).kind,
        ImageErrorKind::PolygonMaterial {
            polygon: 0,
            material: 77
        }
    );
    // A reflectance above 1.
    let mut b = bytes.clone();
    let at = record_offset(&b, Section::Values, 0);
    patch_f32(&mut b, at, 1.5);
    assert!(matches!(
        open_err(&b).kind,
        ImageErrorKind::Material { material: 0, .. }
    ));
}

#[test]
fn instance_faults() {
    let bytes = compile(&sample()).unwrap();
    let v = read_image(&bytes).unwrap();
    // Originals were ordered twig (0), branch (1); branch's three twig instances are
    // instances 0..3. Pointing one back at branch closes a cycle.
    assert_eq!(
        v.original(hirad_core::OriginalId(1))
            .unwrap()
            .instancing_depth,
        1
    );
    let mut b = bytes.clone();
    let at = record_offset(&b, Section::Instances, 0);
    patch_u32(&mut b, at, 1);
    assert_eq!(
        open_err(&b),
        ImageError {
            offset: at as u64,
            kind: ImageErrorKind::OriginalCycle {
                instance: 0,
                original: 1
            }
        }
    );
    patch_u32(&mut b, at, 9);
    assert_eq!(
        open_err(&b).kind,
        ImageErrorKind::OriginalIndex {
            instance: 0,
            original: 9
        }
    );
    // A scale of zero and a rotation that is not unit.
    let mut b = bytes.clone();
    patch_f32(&mut b, at + 36, 0.0);
    assert!(matches!(
        open_err(&b).kind,
        ImageErrorKind::Transform { instance: 0, .. }
    ));
    let mut b = bytes.clone();
    patch_f32(&mut b, at + 20, 3.0);
    assert!(matches!(
        open_err(&b).kind,
        ImageErrorKind::Transform { instance: 0, .. }
    ));
}

/// A hand-laid image, for faults a model can never produce.
#[derive(Default)]
struct Raw {
    values: Vec<f32>,
    materials: Vec<MaterialRecord>,
    verts: Vec<[f32; 3]>,
    polys: Vec<PolygonRecord>,
    nodes: Vec<NodeRecord>,
    instances: Vec<InstanceRecord>,
    originals: Vec<OriginalRecord>,
    scene_root: u32,
}

const BOX: ([f32; 3], [f32; 3]) = ([-10.0; 3], [10.0; 3]);

impl Raw {
    fn new() -> Self {
        let mut r = Raw::default();
        let mut m = MaterialData::black(1);
        m.rho_front[0] = 0.5;
        let mut vals = [0.0; 40];
        let n = m.to_values(&mut vals).unwrap();
        r.values.extend_from_slice(&vals[..n]);
        r.materials.push(MaterialRecord {
            name: NONE,
            flags: 0,
            values: 0,
            reserved: 0,
        });
        r
    }

    fn node(&mut self, subtree_end: u32, instance: u32, expanded: u64) -> u32 {
        self.nodes.push(NodeRecord {
            bbox_min: BOX.0,
            bbox_max: BOX.1,
            expanded_polygons: expanded,
            subtree_end,
            poly_first: self.polys.len() as u32,
            poly_count: 0,
            vert_first: self.verts.len() as u32,
            vert_count: 0,
            instance,
            name: NONE,
            axis: NONE,
            age: 0.0,
            flags: 0,
        });
        (self.nodes.len() - 1) as u32
    }

    fn triangle_node(&mut self, subtree_end: u32) -> u32 {
        let n = self.node(subtree_end, NONE, 1);
        self.verts
            .extend_from_slice(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]);
        self.polys.push(PolygonRecord {
            corners: [0, 1, 2, NONE],
            material: 0,
        });
        let node = &mut self.nodes[n as usize];
        node.poly_count = 1;
        node.vert_count = 3;
        n
    }

    fn exact(&mut self, original: u32, expanded: u64) -> u32 {
        self.instances.push(InstanceRecord {
            original,
            flags: EXACT,
            rotation: [0., 0., 0., 1.],
            translation: [0.; 3],
            scale: 1.0,
        });
        let end = self.nodes.len() as u32 + 1;
        self.node(end, (self.instances.len() - 1) as u32, expanded)
    }

    fn bytes(&self) -> Vec<u8> {
        let sections: [&[u8]; SECTION_COUNT] = [
            &[],
            &[],
            &[],
            bytemuck::cast_slice(&self.values),
            bytemuck::cast_slice(&self.materials),
            bytemuck::cast_slice(&self.verts),
            bytemuck::cast_slice(&self.polys),
            bytemuck::cast_slice(&self.nodes),
            bytemuck::cast_slice(&self.instances),
            bytemuck::cast_slice(&self.originals),
            &[],
            &[],
            &[],
            &[],
            &[],
            &[],
        ];
        let mut counts = [0u64; SECTION_COUNT];
        for s in Section::ALL {
            counts[s as usize] = sections[s as usize].len() as u64 / s.record_size() as u64;
        }
        let layout = ImageLayout::new(&counts).unwrap();
        let mut out = bytemuck::bytes_of(&layout.header(1, self.scene_root)).to_vec();
        for s in Section::ALL {
            out.resize(layout.sections[s as usize].offset as usize, 0);
            out.extend_from_slice(sections[s as usize]);
        }
        out.resize(layout.file_size as usize, 0);
        out
    }
}

#[test]
fn ten_thousand_deep_nesting_is_refused() {
    let mut r = Raw::new();
    const N: u32 = 10_000;
    for _ in 0..N - 1 {
        r.node(N, NONE, 0);
    }
    r.triangle_node(N);
    for n in r.nodes.iter_mut() {
        n.expanded_polygons = 1;
    }
    let e = open_err(&r.bytes());
    let limit = hirad_core::limits::MAX_NODE_DEPTH as u32;
    assert_eq!(e.kind, ImageErrorKind::TooDeep { node: limit });
    // The same chain cut to the limit is accepted.
    let mut r = Raw::new();
    for _ in 0..limit - 1 {
        r.node(limit, NONE, 1);
    }
    r.triangle_node(limit);
    read_image(&r.bytes()).unwrap();
}

/// Originals each holding `fan` instances of the previous one.
fn chain(levels: u32, fan: u32) -> Raw {
    let mut r = Raw::new();
    r.originals.push(OriginalRecord {
        root: 0,
        name: NONE,
        instancing_depth: 0,
        reserved: 0,
        expanded_polygons: 1,
    });
    r.triangle_node(1);
    let mut expanded = 1u64;
    for level in 1..=levels {
        let root = r.nodes.len() as u32;
        r.node(root + 1 + fan, NONE, expanded.wrapping_mul(fan as u64));
        for _ in 0..fan {
            r.exact(level - 1, expanded);
        }
        expanded = expanded.wrapping_mul(fan as u64);
        r.originals.push(OriginalRecord {
            root,
            name: NONE,
            instancing_depth: level,
            reserved: 0,
            expanded_polygons: expanded,
        });
    }
    r
}

#[test]
fn expansion_overflow_is_refused() {
    // 256^7 = 2^56 polygons: accepted; a scene of 256 of those overflows 2^64.
    let mut r = chain(7, 256);
    r.scene_root = r.nodes.len() as u32;
    r.node(r.scene_root + 1 + 255, NONE, 0);
    for _ in 0..255 {
        r.exact(7, 1 << 56);
    }
    r.nodes[r.scene_root as usize].expanded_polygons = 255 << 56;
    let bytes = r.bytes();
    let info = *read_image(&bytes).unwrap().info();
    assert_eq!(info.expanded_polygons, 255 << 56);
    assert_eq!(info.instancing_depth, 8);
    r.nodes[r.scene_root as usize].subtree_end += 1;
    r.exact(7, 1 << 56);
    let e = open_err(&r.bytes());
    assert!(
        matches!(e.kind, ImageErrorKind::ExpansionOverflow { .. }),
        "{e}"
    );
}

#[test]
fn instancing_too_deep_is_refused() {
    let limit = hirad_core::limits::MAX_INSTANCING_DEPTH;
    let mut r = chain(limit, 1);
    r.scene_root = r.nodes.len() as u32;
    r.node(r.scene_root + 2, NONE, 1);
    r.exact(limit, 1);
    let e = open_err(&r.bytes());
    assert!(
        matches!(e.kind, ImageErrorKind::InstancingTooDeep { .. }),
        "{e}"
    );
    let mut r = chain(limit - 1, 1);
    r.scene_root = r.nodes.len() as u32;
    r.node(r.scene_root + 2, NONE, 1);
    r.exact(limit - 1, 1);
    assert_eq!(
        read_image(&r.bytes()).unwrap().info().instancing_depth,
        limit
    );
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// Arbitrary bytes, with and without a valid header, never panic the view.
        #[test]
        fn arbitrary_bytes_never_panic(mut bytes in proptest::collection::vec(any::<u8>(), 0..4096), keep_header in any::<bool>()) {
            if keep_header {
                let valid = compile(&sample()).unwrap();
                let n = valid.len().min(bytes.len()).min(std::mem::size_of::<Header>());
                bytes[..n].copy_from_slice(&valid[..n]);
            }
            if let Ok(v) = read_image(&bytes) {
                let scene = decompile(&v).unwrap();
                compile(&scene).unwrap();
            }
        }

        /// A valid image with several random bytes overwritten is refused or still consistent.
        #[test]
        fn mutated_images_never_panic(edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..12)) {
            let mut bytes = compile(&sample()).unwrap();
            for (i, v) in edits {
                let at = i.index(bytes.len());
                bytes[at] = v;
            }
            if let Ok(v) = read_image(&bytes) {
                let scene = decompile(&v).unwrap();
                compile(&scene).unwrap();
            }
        }
    }
}
