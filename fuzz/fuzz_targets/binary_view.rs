//! The checked binary view on arbitrary bytes: it must refuse or accept without panicking, and
//! whatever it accepts must decompile and compile back.
#![no_main]

use hirad::scene::{compile, decompile};
use hirad_core::image::{SceneView, SliceSource};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(view) = SceneView::open(SliceSource(data)) {
        let scene = decompile(&view).expect("a validated image decompiles");
        compile(&scene).expect("a decompiled image compiles");
    }
});
