//! The tables section of the binary image: tables survive compile and decompile (with the
//! originals reordered), and each kind of damage to a record or a value is refused with its
//! own error at the right byte.

use super::tests::one_leaf;
use crate::scene::{Cluster, InstanceOf, Original, Similarity, Tables, compile, decompile};
use hirad_core::image::{
    Header, ImageErrorKind as K, SceneView, Section, SliceSource, TABLE_MET, TableRecord,
};

/// Tables with small grids and values that tell their place, with `scatterers` polygons'
/// first scattering kept apart on a grid of side 2.
fn tables(original: usize, bands: u32, scatterers: u32) -> Tables {
    let record = TableRecord {
        original: 0,
        bands,
        tau_side: 2,
        incoming_side: 2,
        outgoing_side: 3,
        flags: TABLE_MET,
        lo: [-1.0, -1.0, 0.0],
        hi: [1.0, 1.0, 0.5],
        first: 0,
        tau_error: 0.01,
        scattered_error: 0.02,
        intensity_error: 0.03,
        scatterers,
        single_side: if scatterers > 0 { 2 } else { 0 },
        reserved: 0,
        first_visible: 0,
    };
    let [tau, albedo, shares, response, _] = record.lengths();
    let mut values = Vec::new();
    values.extend((0..tau).map(|i| 0.1 * i as f32));
    values.extend((0..albedo).map(|i| 0.5 + 0.01 * i as f32));
    values.extend((0..shares).map(|i| 0.25 + 0.005 * i as f32));
    values.extend((0..response).map(|i| 2.0 + i as f32));
    for p in 0..scatterers {
        // A unit normal, an area, then per band the two reflectances and the transmittance.
        values.extend([0.6, 0.0, 0.8, 0.01 * (1 + p) as f32]);
        for b in 0..bands {
            values.extend([0.1, 0.2 + 0.1 * b as f32, 0.3]);
        }
    }
    let visible = (0..record.visible_bytes())
        .map(|i| (i * 37) as u8)
        .collect();
    Tables {
        original,
        record,
        values,
        visible,
    }
}

/// A scene of two originals stored in the order compile changes (the one that holds the
/// other first), each with tables.
fn scene() -> crate::scene::Scene {
    let mut s = one_leaf(glam::Vec3::Z, 1.0);
    let mut holder = Cluster::named("holder");
    holder.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 1,
            exact: true,
            transform: Similarity::IDENTITY,
        }),
        ..Cluster::default()
    });
    let leaf = s.originals.remove(0);
    s.originals = vec![
        Original {
            name: "holder".into(),
            root: holder,
        },
        leaf,
    ];
    s.root.children[0].instance.as_mut().unwrap().original = 0;
    s.tables = vec![tables(0, 2, 0), tables(1, 2, 2)];
    s.tables[1].values[0] = 0.75;
    s
}

fn header(bytes: &[u8]) -> Header {
    *bytemuck::from_bytes(&bytes[..std::mem::size_of::<Header>()])
}

#[test]
fn tables_survive_compile_and_decompile() {
    let s = scene();
    let bytes = compile(&s).unwrap();
    let view = SceneView::open(SliceSource(&bytes)).unwrap();
    assert_eq!(view.info().tables, 2);
    let back = decompile(&view).unwrap();
    // Originals come back in compile's order (the leaf first); the tables follow them.
    let leaf = back.original_index("leaf").unwrap();
    let holder = back.original_index("holder").unwrap();
    let of = |o: usize| back.tables.iter().find(|t| t.original == o).unwrap();
    assert_eq!(of(leaf).values, s.tables[1].values);
    assert_eq!(of(leaf).visible, s.tables[1].visible);
    assert_eq!(of(holder).values, s.tables[0].values);
    assert!(of(holder).visible.is_empty());
    assert_eq!(of(leaf).record.tau_error, 0.01);
    let table = view
        .table_of(hirad_core::OriginalId(leaf as u32))
        .unwrap()
        .unwrap();
    let mut v = vec![0.0f32; 4];
    view.table_values(table.first, &mut v).unwrap();
    assert_eq!(v[0], 0.75);
    // The same bytes again.
    assert_eq!(compile(&back).unwrap(), bytes);
}

#[test]
fn compile_refuses_tables_that_do_not_fit() {
    let mut s = scene();
    s.tables[0].values.pop();
    assert!(
        compile(&s)
            .unwrap_err()
            .message
            .contains("values where their grids need")
    );
    let mut s = scene();
    s.tables[1].visible.pop();
    assert!(
        compile(&s)
            .unwrap_err()
            .message
            .contains("visible fractions where their grid needs")
    );
    let mut s = scene();
    s.tables[1].original = 0;
    assert!(compile(&s).unwrap_err().message.contains("two tables"));
    let mut s = scene();
    s.tables[1].original = 9;
    assert!(compile(&s).is_err());
}

#[test]
fn damaged_tables_are_refused_where_they_are_damaged() {
    let bytes = compile(&scene()).unwrap();
    let h = header(&bytes);
    let rec = h.section(Section::Tables).offset as usize;
    let pool = h.section(Section::TableValues).offset as usize;
    let size = std::mem::size_of::<TableRecord>();
    // The leaf's table is the first (compile puts the leaf first); its scatterers' shapes
    // follow its response.
    let leaf = SceneView::open(SliceSource(&bytes))
        .unwrap()
        .table(0)
        .unwrap();
    assert_eq!(leaf.scatterers, 2);
    let [tau, albedo, shares, response, _] = leaf.lengths();
    let shape = (tau + albedo + shares + response) as usize;
    type Damage = (&'static str, usize, Box<dyn Fn(&mut [u8])>, fn(&K) -> bool);
    let put_u32 =
        |at: usize, v: u32| move |b: &mut [u8]| b[at..at + 4].copy_from_slice(&v.to_le_bytes());
    let put_f32 =
        |at: usize, v: f32| move |b: &mut [u8]| b[at..at + 4].copy_from_slice(&v.to_le_bytes());
    let damages: Vec<Damage> = vec![
        ("no such original", rec, Box::new(put_u32(rec, 7)), |k| {
            matches!(k, K::TableOriginal { table: 0 })
        }),
        (
            "out of order",
            rec + size,
            Box::new(put_u32(rec + size, 0)),
            |k| matches!(k, K::TableOriginal { table: 1 }),
        ),
        ("bands", rec + 4, Box::new(put_u32(rec + 4, 3)), |k| {
            matches!(k, K::TableGrid { table: 0 })
        }),
        ("no grid", rec + 8, Box::new(put_u32(rec + 8, 0)), |k| {
            matches!(k, K::TableGrid { table: 0 })
        }),
        ("flags", rec + 20, Box::new(put_u32(rec + 20, 6)), |k| {
            matches!(k, K::TableGrid { table: 0 })
        }),
        ("box", rec + 24, Box::new(put_f32(rec + 24, 5.0)), |k| {
            matches!(k, K::TableBox { table: 0 })
        }),
        (
            "error",
            rec + size + 56,
            Box::new(put_f32(rec + size + 56, f32::NAN)),
            |k| matches!(k, K::TableBox { table: 1 }),
        ),
        (
            "first",
            rec + size + 48,
            Box::new(put_u32(rec + size + 48, 3)),
            |k| matches!(k, K::TableRange { table: 1 }),
        ),
        (
            "tau above 1",
            pool + 4,
            Box::new(put_f32(pool + 4, 1.5)),
            |k| matches!(k, K::TableValue { table: 0, index: 1 }),
        ),
        (
            "albedo negative",
            pool + 4 * 5,
            Box::new(put_f32(pool + 4 * 5, -0.1)),
            |k| matches!(k, K::TableValue { table: 0, index: 5 }),
        ),
        (
            "scatterers without their grid",
            rec + 72,
            Box::new(put_u32(rec + 72, 0)),
            |k| matches!(k, K::TableGrid { table: 0 }),
        ),
        (
            "a grid without scatterers",
            rec + size + 72,
            Box::new(put_u32(rec + size + 72, 4)),
            |k| matches!(k, K::TableGrid { table: 1 }),
        ),
        (
            "first visible fraction",
            rec + size + 80,
            Box::new(put_u32(rec + size + 80, 1)),
            |k| matches!(k, K::TableRange { table: 1 }),
        ),
        (
            "normal not unit",
            pool + 4 * (shape + 2),
            Box::new(put_f32(pool + 4 * (shape + 2), 0.5)),
            |k| matches!(k, K::TableValue { table: 0, .. }),
        ),
        (
            "negative area",
            pool + 4 * (shape + 3),
            Box::new(put_f32(pool + 4 * (shape + 3), -1.0)),
            |k| matches!(k, K::TableValue { table: 0, .. }),
        ),
        (
            "transmittance above 1",
            pool + 4 * (shape + 10 + 6),
            Box::new(put_f32(pool + 4 * (shape + 16), 1.01)),
            |k| matches!(k, K::TableValue { table: 0, .. }),
        ),
        (
            "response not finite",
            pool + 4 * 30,
            Box::new(put_f32(pool + 4 * 30, f32::INFINITY)),
            |k| {
                matches!(
                    k,
                    K::TableValue {
                        table: 0,
                        index: 30
                    }
                )
            },
        ),
    ];
    // (The value's index is its byte: checked below.)
    for (what, at, damage, expected) in damages {
        let mut b = bytes.clone();
        damage(&mut b);
        let e = SceneView::open(SliceSource(&b))
            .err()
            .unwrap_or_else(|| panic!("{what}: accepted"));
        assert!(expected(&e.kind), "{what}: {e}");
        // A value's own byte; a record's first byte.
        let want = if at >= pool {
            at
        } else {
            rec + (at - rec) / size * size
        };
        assert_eq!(e.offset as usize, want, "{what}: {e}");
        assert!(!e.to_string().is_empty());
    }
}
