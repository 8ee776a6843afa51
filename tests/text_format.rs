//! The `.hir` text format across crates: every fixture parses, compiles and has its stated
//! counts; arbitrary valid scenes survive print -> parse bit for bit and compile to the same
//! bytes; arbitrary bytes, token soup and mutated documents never make the parser panic.

use glam::{Quat, Vec3};
use hirad::scene::*;
use hirad::text::{parse, print};
use hirad_core::geometry::{camera_ok, polygon_shape};
use hirad_core::limits::{MAX_BANDS, NONE};
use hirad_tests::fixture;
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------
// Fixtures

/// Every fixture with its stated expanded polygon count and instancing depth (the numbers
/// in its header comment and in fixtures/README.md).
const FIXTURES: [(&str, u64, u32); 9] = [
    ("cornell_box.hir", 17, 0),
    ("parallel_squares.hir", 2, 0),
    ("perpendicular_squares.hir", 2, 0),
    ("furnace.hir", 24, 0),
    ("furnace_099.hir", 24, 0),
    ("chair_room.hir", 902, 1),
    ("small_plant.hir", 105, 2),
    ("leaves_cluster.hir", 156, 0),
    ("maize_2x2.hir", 1926, 1),
];

#[test]
fn fixtures_parse_compile_and_have_their_stated_counts() {
    for (name, expanded, depth) in FIXTURES {
        let src = std::fs::read(fixture(name)).unwrap();
        assert!(src.starts_with(b"# "), "{name} must start with a comment");
        let scene = parse(&src).unwrap_or_else(|e| panic!("{name}:{e}"));
        let bytes = compile(&scene).unwrap_or_else(|e| panic!("{name}: {e}"));
        let info = *read_image(&bytes).unwrap().info();
        assert_eq!(
            info.expanded_polygons, expanded,
            "{name}: expanded polygons"
        );
        assert_eq!(info.instancing_depth, depth, "{name}: instancing depth");
        let text = print(&scene);
        let back = parse(text.as_bytes()).unwrap();
        assert_eq!(back, scene, "{name}: print -> parse");
        assert_eq!(compile(&back).unwrap(), bytes, "{name}: recompiled");
        // The README lists every fixture with the same count.
        let readme = std::fs::read_to_string(fixture("README.md")).unwrap();
        let row = readme
            .lines()
            .find(|l| l.contains(&format!("`{name}`")))
            .unwrap_or_else(|| panic!("README.md does not list {name}"));
        assert!(
            row.contains(&format!("| {expanded} |")),
            "README.md row of {name} lacks {expanded}: {row}"
        );
    }
    // Nothing in fixtures/ is left out of the table.
    let mut listed: Vec<&str> = FIXTURES.iter().map(|f| f.0).collect();
    listed.sort();
    let mut found: Vec<String> = std::fs::read_dir(fixture(""))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".hir"))
        .collect();
    found.sort();
    assert_eq!(found, listed);
}

#[test]
fn fixture_answers_hold_where_they_are_structural() {
    // Furnaces: one material, every polygon emitting 1 with the stated reflectance, and the
    // cube closed: the 24 inward normals sum to zero area-weighted.
    for (name, rho) in [("furnace.hir", 0.5f32), ("furnace_099.hir", 0.99)] {
        let s = parse(&std::fs::read(fixture(name)).unwrap()).unwrap();
        assert_eq!(s.materials.len(), 1);
        assert_eq!(s.materials[0].data.rho_front[0], rho);
        assert_eq!(s.materials[0].data.emit_front[0], 1.0);
        let cube = &s.root.children[0];
        let mut sum = Vec3::ZERO;
        let mut area = 0.0;
        for p in &cube.polygons {
            let c: Vec<Vec3> = p.corners[..p.corner_count()]
                .iter()
                .map(|&i| cube.vertices[i as usize])
                .collect();
            let shape = polygon_shape(&c).unwrap();
            sum += shape.normal * shape.area;
            area += shape.area;
            // Inward: the normal points towards the centre of the cube.
            let centre: Vec3 = c.iter().copied().sum::<Vec3>() / c.len() as f32;
            assert!(shape.normal.dot(Vec3::splat(0.5) - centre) > 0.0, "{name}");
        }
        assert!(sum.length() < 1e-5, "{name}: not closed");
        assert!((area - 6.0).abs() < 1e-5);
    }
    // Parallel squares: emitter faces +z, receiver faces -z, 1 m apart.
    let s = parse(&std::fs::read(fixture("parallel_squares.hir")).unwrap()).unwrap();
    let normal = |c: &Cluster| {
        let p = &c.polygons[0];
        let pts: Vec<Vec3> = p.corners.iter().map(|&i| c.vertices[i as usize]).collect();
        polygon_shape(&pts).unwrap().normal
    };
    assert_eq!(normal(&s.root.children[0]), Vec3::Z);
    assert_eq!(normal(&s.root.children[1]), -Vec3::Z);
    let s = parse(&std::fs::read(fixture("perpendicular_squares.hir")).unwrap()).unwrap();
    assert_eq!(normal(&s.root.children[0]), Vec3::Z);
    assert_eq!(normal(&s.root.children[1]), Vec3::X);
}

// ---------------------------------------------------------------------------------------
// A generator of valid scenes driven by a tape of random numbers, so that proptest
// shrinks a failing scene by shortening the tape (an exhausted tape reads zeros: the
// simplest choice everywhere).

struct Tape<'a> {
    data: &'a [u32],
    at: usize,
}

impl Tape<'_> {
    fn next(&mut self) -> u32 {
        let v = self.data.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        v
    }
    /// 0..n
    fn below(&mut self, n: u32) -> u32 {
        if n == 0 { 0 } else { self.next() % n }
    }
    fn chance(&mut self, percent: u32) -> bool {
        self.below(100) < percent
    }
    /// Uniform in [0, 1], with arbitrary mantissa bits.
    fn unit(&mut self) -> f32 {
        (self.next() as f64 / u32::MAX as f64) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
    /// A value spanning magnitudes 10^-3 .. 10^3, either sign.
    fn coordinate(&mut self) -> f32 {
        let m = self.range(-1.0, 1.0);
        let e = self.below(7) as i32 - 3;
        m * 10f32.powi(e)
    }
    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.coordinate(), self.coordinate(), self.coordinate())
    }
    fn direction(&mut self) -> Vec3 {
        let v = Vec3::new(
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
        );
        v.try_normalize().unwrap_or(Vec3::Z)
    }
    fn rotation(&mut self) -> Quat {
        if self.chance(20) {
            return Quat::IDENTITY;
        }
        let q = Quat::from_xyzw(
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
        );
        if q.length_squared() < 1e-3 {
            Quat::IDENTITY
        } else {
            q.normalize()
        }
    }
    fn name(&mut self) -> String {
        const POOL: [&str; 14] = [
            "a",
            "chair",
            "leaf_2.b-c",
            "rho",
            "scene",
            "v",
            "with space",
            "quote\"d",
            "back\\slash",
            "line\nbreak\ttab",
            "été 🌿",
            "",
            "123",
            "inf",
        ];
        POOL[self.below(POOL.len() as u32) as usize].to_string()
    }
    fn unique_name(&mut self, taken: &[String]) -> String {
        let base = self.name();
        let mut name = base.clone();
        let mut k = 0;
        while taken.contains(&name) {
            name = format!("{base}_{k}");
            k += 1;
        }
        name
    }
}

fn material(t: &mut Tape, bands: u8) -> MaterialData {
    let n = bands as usize;
    let mut m = MaterialData::black(bands);
    m.two_sided = t.chance(40);
    for b in 0..n {
        m.rho_front[b] = t.unit();
        if t.chance(40) {
            m.emit_front[b] = if t.chance(10) {
                -0.0
            } else {
                t.range(0.0, 1000.0)
            };
        }
        if m.two_sided {
            m.rho_back[b] = t.unit();
            if t.chance(70) {
                let room = 1.0 - m.rho_front[b].max(m.rho_back[b]);
                m.tau[b] = (room * t.unit()).max(0.0);
            }
            if t.chance(20) {
                m.emit_back[b] = t.range(0.0, 10.0);
            }
        }
    }
    m
}

/// Vertices and polygons of a random triangle or rectangle in a random orientation.
fn add_polygon(t: &mut Tape, c: &mut Cluster, materials: u32) {
    let frame = t.rotation();
    let centre = t.vec3();
    let size = 10f32.powi(t.below(5) as i32 - 2) * t.range(0.5, 2.0);
    let (u, v) = (frame * Vec3::X, frame * Vec3::Y);
    let local: Vec<(f32, f32)> = if t.chance(50) {
        let (w, h) = (t.range(0.2, 1.0), t.range(0.2, 1.0));
        vec![(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
    } else {
        vec![
            (0.0, 0.0),
            (t.range(0.3, 1.0), t.range(-0.2, 0.2)),
            (t.range(-0.5, 0.5), t.range(0.3, 1.0)),
        ]
    };
    let pts: Vec<Vec3> = local
        .iter()
        .map(|&(x, y)| centre + (u * x + v * y) * size)
        .collect();
    if polygon_shape(&pts).is_err() {
        return;
    }
    // Reuse an existing vertex now and then (shared corners), else append.
    let mut corners = [NONE; 4];
    for (k, p) in pts.iter().enumerate() {
        corners[k] = c.vertex(*p);
    }
    let material = t.below(materials);
    c.polygons.push(Polygon { corners, material });
    if t.chance(20) {
        // A stray vertex no polygon uses.
        c.vertex(t.vec3());
    }
}

fn attributes(t: &mut Tape, c: &mut Cluster) {
    if t.chance(50) {
        c.name = Some(t.name());
    }
    if t.chance(30) {
        c.axis = Some(if t.chance(20) { NONE - 1 } else { t.below(5) });
    }
    if t.chance(30) {
        c.age = Some(if t.chance(10) {
            -0.0
        } else {
            t.range(0.0, 100.0)
        });
    }
}

/// A random tree; `originals` is how many originals an instance here may refer to.
fn tree(t: &mut Tape, depth: u32, materials: u32, originals: usize) -> Cluster {
    let mut c = Cluster::default();
    attributes(t, &mut c);
    fill(t, &mut c, depth, materials, originals);
    c
}

fn fill(t: &mut Tape, c: &mut Cluster, depth: u32, materials: u32, originals: usize) {
    if materials > 0 {
        for _ in 0..t.below(4) {
            add_polygon(t, c, materials);
        }
    }
    if depth == 0 {
        return;
    }
    for _ in 0..t.below(4) {
        let kind = t.below(3);
        if kind == 0 || originals == 0 {
            c.children.push(tree(t, depth - 1, materials, originals));
        } else {
            let exact = kind == 1;
            let mut child = Cluster::default();
            attributes(t, &mut child);
            if !exact {
                fill(t, &mut child, depth - 1, materials, originals);
            }
            let translation = if t.chance(20) { Vec3::ZERO } else { t.vec3() };
            let scale = if t.chance(30) {
                1.0
            } else {
                t.range(0.1, 10.0)
            };
            child.instance = Some(InstanceOf {
                original: t.below(originals as u32) as usize,
                exact,
                transform: Similarity {
                    rotation: t.rotation(),
                    translation,
                    scale,
                },
            });
            c.children.push(child);
        }
    }
}

fn scene(tape: &[u32]) -> Scene {
    let t = &mut Tape { data: tape, at: 0 };
    let bands = 1 + t.below(MAX_BANDS as u32) as u8;
    let mut s = Scene::new(bands);
    if t.chance(50) {
        s.band_names = (0..bands).map(|_| t.name()).collect();
    }
    for _ in 0..t.below(5) {
        let taken: Vec<String> = s.materials.iter().map(|m| m.name.clone()).collect();
        let name = t.unique_name(&taken);
        s.materials.push(Material {
            name,
            data: material(t, bands),
        });
    }
    let materials = s.materials.len() as u32;
    // Originals are generated so that each may only instance earlier ones (no cycles), then
    // shuffled so that the text uses forward references.
    let count = t.below(4) as usize;
    let mut originals: Vec<Original> = Vec::new();
    for k in 0..count {
        let taken: Vec<String> = originals.iter().map(|o| o.name.clone()).collect();
        let name = t.unique_name(&taken);
        let mut root = tree(t, 2, materials, k);
        root.instance = None;
        originals.push(Original { name, root });
    }
    let mut order: Vec<usize> = (0..count).collect();
    for i in (1..count).rev() {
        order.swap(i, t.below(i as u32 + 1) as usize);
    }
    let mut new_of = vec![0; count];
    for (new, &old) in order.iter().enumerate() {
        new_of[old] = new;
    }
    let mut shuffled: Vec<Original> = order.iter().map(|&k| originals[k].clone()).collect();
    let mut root = tree(t, 3, materials, count);
    root.instance = None;
    for r in shuffled
        .iter_mut()
        .map(|o| &mut o.root)
        .chain(std::iter::once(&mut root))
    {
        let mut stack = vec![r];
        while let Some(n) = stack.pop() {
            if let Some(i) = &mut n.instance {
                i.original = new_of[i.original];
            }
            stack.extend(n.children.iter_mut());
        }
    }
    s.originals = shuffled;
    s.root = root;
    let irradiance = |t: &mut Tape| -> Vec<f32> {
        (0..bands)
            .map(|_| {
                if t.chance(10) {
                    0.0
                } else {
                    t.range(0.0, 1000.0)
                }
            })
            .collect()
    };
    for _ in 0..t.below(3) {
        let d = t.direction();
        let irr = irradiance(t);
        s.suns.push(light(d, &irr));
    }
    for _ in 0..t.below(4) {
        let d = t.direction();
        let irr = irradiance(t);
        s.sky.push(light(d, &irr));
    }
    for _ in 0..t.below(3) {
        let position = t.vec3();
        let target = position + t.direction() * t.range(0.5, 20.0);
        let up = t.direction();
        let fovy_deg = t.range(1.0, 170.0);
        if camera_ok(position, target, up, fovy_deg) {
            let name = if t.chance(50) { Some(t.name()) } else { None };
            s.cameras.push(Camera {
                name,
                position,
                target,
                up,
                fovy_deg,
            });
        }
    }
    s
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn valid_scenes_round_trip(tape in proptest::collection::vec(any::<u32>(), 0..3000)) {
        let s = scene(&tape);
        s.check().unwrap();
        let bytes = compile(&s).unwrap();
        let text = print(&s);
        let back = parse(text.as_bytes()).unwrap_or_else(|e| panic!("{e}\n{text}"));
        prop_assert_eq!(&back, &s, "{}", text);
        prop_assert_eq!(print(&back), text);
        prop_assert_eq!(compile(&back).unwrap(), bytes);
    }

    /// text -> binary -> text: the binary image reads back as a scene whose text compiles to
    /// the same bytes; that text is a fixed point; and it is the original text whenever the
    /// originals were already in dependency order (compiling sorts them).
    #[test]
    fn text_binary_text_round_trip(tape in proptest::collection::vec(any::<u32>(), 0..3000)) {
        let s = scene(&tape);
        let text = print(&s);
        let bytes = compile(&parse(text.as_bytes()).unwrap()).unwrap();
        let from_binary = decompile(&read_image(&bytes).unwrap()).unwrap();
        let text2 = print(&from_binary);
        let bytes2 = compile(&parse(text2.as_bytes()).unwrap()).unwrap();
        prop_assert_eq!(&bytes2, &bytes);
        let text3 = print(&decompile(&read_image(&bytes2).unwrap()).unwrap());
        prop_assert_eq!(&text3, &text2);
        let ordered = s.originals.iter().enumerate().all(|(k, o)| {
            let mut refs = Vec::new();
            let mut stack = vec![&o.root];
            while let Some(c) = stack.pop() {
                refs.extend(c.instance.map(|i| i.original));
                stack.extend(&c.children);
            }
            refs.iter().all(|&r| r < k)
        });
        if ordered {
            prop_assert_eq!(&text2, &text);
        }
    }

    #[test]
    fn mutated_documents_never_panic(
        tape in proptest::collection::vec(any::<u32>(), 0..300),
        edits in proptest::collection::vec((any::<u32>(), 0u8..3, any::<u8>()), 1..8),
    ) {
        let mut text = print(&scene(&tape)).into_bytes();
        for (at, kind, byte) in edits {
            let at = at as usize % (text.len() + 1);
            match kind {
                0 => text.insert(at, byte),
                1 if at < text.len() => { text.remove(at); }
                _ if at < text.len() => text[at] = byte,
                _ => {}
            }
        }
        if let Err(e) = parse(&text) {
            prop_assert!(e.line >= 1 && e.column >= 1);
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
        let _ = parse(&bytes);
    }

    #[test]
    fn token_soup_never_panics(
        prefix in any::<bool>(),
        tokens in proptest::collection::vec(0usize..soup().len(), 0..300),
        separators in proptest::collection::vec(0usize..4, 0..300),
    ) {
        let mut text = String::new();
        if prefix {
            text.push_str("hirad 1 bands 2 material m rho 0.5 0.5 original o { } ");
        }
        for (k, &tok) in tokens.iter().enumerate() {
            text.push_str(soup()[tok]);
            text.push_str([" ", "\n", "", "\t"][separators.get(k).copied().unwrap_or(0)]);
        }
        if let Err(e) = parse(text.as_bytes()) {
            prop_assert!(e.line >= 1 && e.column >= 1 && !e.message.is_empty());
        }
    }
}

/// Tokens for the soup besides the keywords: braces, numbers good and bad, names and strings.
const EXTRA: [&str; 25] = [
    "{",
    "}",
    "{",
    "}",
    "0",
    "1",
    "2",
    "3",
    "0.5",
    "-1",
    "1e39",
    "nan",
    "inf",
    "4294967295",
    "99999999999",
    "1.5.2",
    "m",
    "o",
    "x",
    "\"a b\"",
    "\"unterminated",
    "\"\\q\"",
    "# comment\n",
    "@",
    "é",
];

/// Every keyword, then the extras.
fn soup() -> Vec<&'static str> {
    hirad::text::KEYWORDS.iter().copied().chain(EXTRA).collect()
}

#[test]
fn the_example_in_the_specification_is_valid() {
    let spec = std::fs::read_to_string(fixture("../docs/format.md")).unwrap();
    // ```hir blocks, with or without an info string after the language (`title=first.hir`).
    let examples: Vec<&str> = spec
        .split("```hir")
        .skip(1)
        .filter_map(|s| s.split_once('\n'))
        .filter(|(info, _)| info.is_empty() || info.starts_with(' '))
        .filter_map(|(_, s)| s.split("\n```").next())
        .collect();
    assert_eq!(examples.len(), 2, "the first look and the complete example");
    for text in &examples {
        let s = parse(text.as_bytes()).unwrap_or_else(|e| panic!("{e}\n{text}"));
        compile(&s).unwrap();
    }
    // The complete example's stated numbers.
    let info = *read_image(&compile(&parse(examples[1].as_bytes()).unwrap()).unwrap())
        .unwrap()
        .info();
    assert_eq!(info.expanded_polygons, 8);
    assert_eq!(info.instancing_depth, 1);
    assert_eq!(info.exact_instances, 2);
    assert_eq!(info.approximate_instances, 1);
}
