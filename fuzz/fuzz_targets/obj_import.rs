//! The OBJ importer on arbitrary bytes, with the input's tail doubling as an MTL file: never
//! panics; what it accepts compiles.
#![no_main]

use hirad::{obj, scene::compile};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // Split at the first 0xFF byte: OBJ before it, MTL after it.
    let (obj_bytes, mtl_bytes) = match data.iter().position(|&b| b == 0xFF) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let mut load = |_: &str| -> Result<Vec<u8>, String> { Ok(mtl_bytes.to_vec()) };
    if let Ok(imported) = obj::import(obj_bytes, &mut load) {
        compile(&imported.scene).expect("an imported scene compiles");
    }
});
