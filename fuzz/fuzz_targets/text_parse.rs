//! The `.hir` parser on arbitrary bytes: never panics; what it accepts compiles and prints
//! back to the same scene.
#![no_main]

use hirad::{scene::compile, text};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(scene) = text::parse(data) {
        compile(&scene).expect("a parsed scene compiles");
        let printed = text::print(&scene);
        let again = text::parse(printed.as_bytes()).expect("printed text parses");
        assert_eq!(again, scene, "print/parse round trip");
    }
});
