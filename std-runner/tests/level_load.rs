//! A level with closed instances, loaded (issue 18, the level solve under construction):
//! every instance below the root becomes one leaf with its own transform and box, its
//! original's tables are read into the workspace once and come back equal to the image's,
//! the counts match the level's census, and each cluster's instances are consecutive.

mod level_scene;

use glam::Vec3;
use hirad::scene::compile;
use hirad_core::hr::level_probe::load_level;
use hirad_core::hr::{HrError, Instancing, Settings, census, census_scratch_bytes};
use hirad_core::image::{SceneView, SliceSource};
use hirad_core::tables::directional::DirectionalTables;
use level_scene::{corners, scene};

#[test]
fn the_top_level_closes_every_instance_with_its_tables() {
    for n in [0usize, 1, 5, 40] {
        let (s, places) = scene(n);
        let bytes = compile(&s).unwrap();
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let settings = Settings::default();
        let mut ws = vec![0u8; 64 << 20];
        let image_tables: Vec<_> = s
            .tables
            .iter()
            .map(|t| DirectionalTables::from_record(&t.record, &t.values, &t.visible).unwrap())
            .collect();
        let mut seen = Vec::new();
        let counts = load_level(&view, &settings, Instancing::Top, &mut ws, |level| {
            for i in 0..level.instances() {
                let c = level.instance(i);
                // Every leaf's box holds its original's placed box.
                let (lo, hi) = c.placed.tables().bounds();
                for p in corners(lo, hi) {
                    let w = c.place.point(p);
                    let pad = 1e-4 * (1.0 + w.length());
                    assert!(
                        (c.bounds.min - Vec3::splat(pad)).cmple(w).all()
                            && w.cmple(c.bounds.max + Vec3::splat(pad)).all(),
                        "corner {w} outside {:?}",
                        c.bounds
                    );
                }
                assert!(c.received.iter().all(|&v| v.is_finite()));
                let which = image_tables.iter().position(|t| t == c.placed.tables());
                seen.push((c.node, c.place, which));
            }
        })
        .unwrap();
        // The ground's one polygon; the row's instances, the shrubs and the approximate
        // leaf closed; clusters: root, row (and grouping under crowded ones).
        assert_eq!(counts.polygons, 1);
        assert_eq!(counts.instances as usize, n + 3);
        assert_eq!(counts.census.instances as usize, n + 3);
        assert_eq!(counts.clusters as u64, counts.census.clusters);
        assert_eq!(counts.slots, 2);
        assert_eq!(counts.census.closed_originals, 2);
        assert!(counts.order_consistent);
        // By node, the scene's depth-first order: the row's, the shrubs, the leaf (a
        // node's own instances load with it, before its child clusters').
        assert_eq!(seen.len(), places.len());
        seen.sort_by_key(|x| x.0);
        for (k, ((_, got_place, which), want_place)) in seen.iter().zip(&places).enumerate() {
            let d = got_place.point(Vec3::new(0.3, -0.2, 0.7))
                - want_place.point(Vec3::new(0.3, -0.2, 0.7));
            assert!(d.length() < 1e-5, "instance {k}: placed elsewhere");
            let original = if k >= n && k < n + 2 { 1 } else { 0 };
            assert_eq!(*which, Some(original), "instance {k}");
        }
        // Without instancing, nothing is closed and the census is the expanded one.
        let mut scratch = vec![0u8; census_scratch_bytes(&view)];
        let expanded = census(&view, settings.max_children, &mut scratch).unwrap();
        let none = load_level(&view, &settings, Instancing::None, &mut ws, |level| {
            assert_eq!(level.instances(), 0)
        })
        .unwrap();
        assert_eq!(none.instances, 0);
        assert_eq!(none.census, expanded);
        assert_eq!(none.polygons as u64, 1 + n as u64 + 6 + 1);
    }
}

#[test]
fn a_closed_instance_without_tables_is_refused() {
    let (mut s, _) = scene(3);
    s.tables.remove(1);
    let bytes = compile(&s).unwrap();
    let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
    let mut ws = vec![0u8; 16 << 20];
    let err = load_level(
        &view,
        &Settings::default(),
        Instancing::Top,
        &mut ws,
        |_| {},
    )
    .unwrap_err();
    assert!(matches!(err, HrError::NoTables { .. }), "{err:?}");
    assert!(err.to_string().contains("hirad tables"));
    // Expanded, it needs none.
    load_level(
        &view,
        &Settings::default(),
        Instancing::None,
        &mut ws,
        |_| {},
    )
    .unwrap();
}

/// Visible fractions finer than the workspace keeps come back averaged over the fine cells
/// each coarse cell covers (rounded), the rest of the tables equal to the image's.
#[test]
fn fine_visible_fractions_load_averaged_onto_a_coarser_grid() {
    // Sides kept (32 and less), halved twice (128), thrice (256) and from an uneven side
    // (96: 48, then 24).
    for (fine, coarse) in [(2u32, 2u32), (32, 32), (128, 32), (256, 32), (96, 24)] {
        let (mut s, _) = scene(2);
        let scatterers = 3u32;
        let t = &mut s.tables[0];
        let keep = t.values.len() - t.record.lengths()[4] as usize;
        t.record.scatterers = scatterers;
        t.record.single_side = fine;
        let stride = hirad_core::tables::single::shape_stride(2);
        let shapes: Vec<f32> = (0..scatterers)
            .flat_map(|p| {
                let mut v = vec![0.0, 0.6, 0.8, 0.01 * (1 + p) as f32];
                v.extend([0.1, 0.2, 0.3, 0.1, 0.2, 0.3]);
                v
            })
            .collect();
        assert_eq!(shapes.len(), scatterers as usize * stride);
        t.values.truncate(keep);
        t.values.extend(shapes);
        // A fraction that varies within every coarse cell, by cell and polygon.
        let frac = |cell: u32, p: u32| ((cell * 37 + p * 101 + (cell / fine) * 11) % 256) as u8;
        t.visible = (0..fine * fine)
            .flat_map(|c| (0..scatterers).map(move |p| frac(c, p)))
            .collect();
        let bytes = compile(&s).unwrap();
        let view = SceneView::open(SliceSource(&bytes[..])).unwrap();
        let mut ws = vec![0u8; 64 << 20];
        let mut checked = 0;
        load_level(
            &view,
            &Settings::default(),
            Instancing::Top,
            &mut ws,
            |level| {
                for i in 0..level.instances() {
                    let c = level.instance(i);
                    let Some(single) = c.placed.tables().single() else {
                        continue;
                    };
                    assert_eq!(single.grid().side(), coarse, "from {fine}");
                    let f = fine / coarse;
                    for cell in 0..coarse * coarse {
                        let (ci, cj) = (cell % coarse, cell / coarse);
                        for p in 0..scatterers {
                            let mut sum = 0u32;
                            for dj in 0..f {
                                for di in 0..f {
                                    let fc = (cj * f + dj) * fine + ci * f + di;
                                    sum += u32::from(frac(fc, p));
                                }
                            }
                            let want = ((sum + f * f / 2) / (f * f)) as u8;
                            let got = single.visible()[(cell * scatterers + p) as usize];
                            assert_eq!(got, want, "from {fine}: cell {cell} polygon {p}");
                        }
                    }
                    checked += 1;
                }
            },
        )
        .unwrap();
        assert!(checked > 0);
    }
}
