//! The results-table reader (`--reference`) on arbitrary bytes: never panics; what it accepts
//! writes back to a table that reads identically.
#![no_main]

use hirad::output::read_results;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(table) = read_results(data) {
        let mut out = Vec::new();
        table.write_csv(&mut out).expect("write to memory");
        let again = read_results(&out).expect("written table reads back");
        assert_eq!(again.ids, table.ids);
    }
});
