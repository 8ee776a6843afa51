//! The checked binary view on arbitrary bytes: it must refuse or accept without panicking, and
//! whatever it accepts must decompile and compile back, and its directional tables must make
//! sound tables that answer lookups.
#![no_main]

use hirad::scene::{compile, decompile};
use hirad::tables::OriginalTables;
use hirad_core::image::{SceneView, SliceSource};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(view) = SceneView::open(SliceSource(data)) {
        let scene = decompile(&view).expect("a validated image decompiles");
        for t in &scene.tables {
            let tables = OriginalTables::from_record(
                "fuzz", t.original, 0, &t.record, &t.values, &t.visible,
            )
            .expect("a validated image's tables are sound");
            let v = tables.view();
            // The core reads them from the record alone, as a solve with closed instances
            // does: the same tables.
            let core = hirad_core::tables::directional::DirectionalTables::from_record(
                &t.record, &t.values, &t.visible,
            )
            .expect("a validated image's tables are sound in the core too");
            assert_eq!(core, v);
            let grid = v.tau_grid();
            for k in 0..grid.cells().min(4) {
                let (d, o) = (grid.direction(k), -grid.direction(grid.cells() - 1 - k));
                for b in 0..tables.bands {
                    // Any finite values are valid, so only that they answer is checked.
                    std::hint::black_box((v.intensity(d, o, b), v.scattered(d, b)));
                }
            }
        }
        compile(&scene).expect("a decompiled image compiles");
    }
});
