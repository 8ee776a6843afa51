//! The reference measure on hand-computed cases, its refusals, and the streaming sink.

use super::reference::{ReferenceSink, compare};
use super::results::ResultsTable;
use hirad_core::sink::{PolygonResult, Sink};

/// A one-sided table from (id, area, radiosity per band) rows; irradiance is 0.
fn table(bands: usize, rows: &[(u64, f32, &[f32])]) -> ResultsTable {
    let mut t = ResultsTable::new(bands, false);
    for &(id, area, rad) in rows {
        t.ids.push(id);
        t.areas.push(area);
        t.radiosity[0].extend_from_slice(rad);
        t.irradiance[0].extend(std::iter::repeat_n(0.0, bands));
    }
    t
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1.0)
}

#[test]
fn identical_tables_have_no_error() {
    let t = table(2, &[(0, 1.0, &[1.0, 2.0]), (4, 2.0, &[3.0, 0.5])]);
    let c = compare(&t, &t).unwrap();
    assert_eq!(c.error_percent, 0.0);
    assert_eq!(c.per_band_percent, vec![0.0, 0.0]);
    assert_eq!(c.max_abs_difference, 0.0);
    assert_eq!(c.reference_max, 3.0);
    assert_eq!(c.polygons, 2);
    assert!(!c.back_compared);
}

#[test]
fn known_difference_one_band() {
    // Areas 1 and 3, reference 2 and 4, result 2 and 5: sum A d^2 = 3, sum A = 4,
    // error = 100 * sqrt(3 / 4) / 4.
    let reference = table(1, &[(0, 1.0, &[2.0]), (1, 3.0, &[4.0])]);
    let result = table(1, &[(0, 1.0, &[2.0]), (1, 3.0, &[5.0])]);
    let c = compare(&result, &reference).unwrap();
    let want = 100.0 * (0.75f64).sqrt() / 4.0;
    assert!(
        close(c.error_percent, want),
        "{} vs {want}",
        c.error_percent
    );
    assert!(close(c.per_band_percent[0], want));
    assert_eq!(c.max_abs_difference, 1.0);
}

#[test]
fn known_difference_two_bands() {
    // One polygon of area 2: differences 1 and 3 in the two bands, reference max 10.
    // error = 100 * sqrt(2 * (1 + 9) / (2 * 2)) / 10 = 10 * sqrt(5);
    // per band: 100 * sqrt(2 * 1 / 2) / 10 = 10 and 100 * sqrt(2 * 9 / 2) / 10 = 30.
    let reference = table(2, &[(3, 2.0, &[10.0, 5.0])]);
    let result = table(2, &[(3, 2.0, &[11.0, 2.0])]);
    let c = compare(&result, &reference).unwrap();
    assert!(close(c.error_percent, 10.0 * 5f64.sqrt()));
    assert!(close(c.per_band_percent[0], 10.0));
    assert!(close(c.per_band_percent[1], 30.0));
    assert_eq!(c.max_abs_difference, 3.0);
    assert_eq!(c.reference_max, 10.0);
}

fn two_sided(front: f32, back: f32) -> ResultsTable {
    let mut t = ResultsTable::new(1, true);
    t.ids.push(0);
    t.areas.push(1.0);
    t.radiosity = [vec![front], vec![back]];
    t.irradiance = [vec![0.0], vec![0.0]];
    t
}

#[test]
fn back_sides_count_when_both_tables_have_them() {
    // Front equal, back differs by 4; reference max over both sides = 8.
    // error = 100 * sqrt(16 / (2 * 1)) / 8.
    let c = compare(&two_sided(2.0, 4.0), &two_sided(2.0, 8.0)).unwrap();
    assert!(c.back_compared);
    assert!(close(c.error_percent, 100.0 * 8f64.sqrt() / 8.0));
    assert_eq!(c.max_abs_difference, 4.0);
    // A one-sided result: only fronts are compared.
    let one = table(1, &[(0, 1.0, &[2.0])]);
    let c = compare(&one, &two_sided(2.0, 8.0)).unwrap();
    assert!(!c.back_compared);
    assert_eq!(c.error_percent, 0.0);
    assert_eq!(c.reference_max, 2.0);
}

#[test]
fn mismatched_tables_are_refused() {
    let reference = table(1, &[(0, 1.0, &[2.0]), (1, 3.0, &[4.0])]);
    let bands = table(2, &[(0, 1.0, &[2.0, 1.0]), (1, 3.0, &[4.0, 1.0])]);
    let e = compare(&bands, &reference).unwrap_err().to_string();
    assert!(e.contains("2 bands") && e.contains("has 1"), "{e}");
    let count = table(1, &[(0, 1.0, &[2.0])]);
    let e = compare(&count, &reference).unwrap_err().to_string();
    assert!(e.contains("1 polygons") && e.contains("has 2"), "{e}");
    let ids = table(1, &[(0, 1.0, &[2.0]), (2, 3.0, &[4.0])]);
    let e = compare(&ids, &reference).unwrap_err().to_string();
    assert!(
        e.contains("row 2: polygon 2") && e.contains("polygon 1 in the reference"),
        "{e}"
    );
    let area = table(1, &[(0, 1.0, &[2.0]), (1, 3.1, &[4.0])]);
    let e = compare(&area, &reference).unwrap_err().to_string();
    assert!(
        e.contains("area") && e.contains("not the same scene"),
        "{e}"
    );
    let dark = table(1, &[(0, 1.0, &[0.0])]);
    let e = compare(&dark, &dark).unwrap_err().to_string();
    assert!(e.contains("largest radiosity is 0"), "{e}");
    let empty = table(1, &[]);
    assert!(compare(&empty, &empty).is_err());
}

#[test]
fn streaming_sink_matches_the_table_comparison() {
    let reference = table(2, &[(0, 1.0, &[2.0, 1.0]), (5, 3.0, &[4.0, 0.5])]);
    let result = table(2, &[(0, 1.0, &[2.5, 1.0]), (5, 3.0, &[3.0, 0.25])]);
    let want = compare(&result, &reference).unwrap();
    let mut sink = ReferenceSink::new(reference.clone(), 2, false).unwrap();
    for row in 0..result.len() {
        sink.polygon(&PolygonResult {
            id: result.ids[row],
            area: result.areas[row],
            two_sided: false,
            radiosity: [result.radiosity(row, 0), &[]],
            irradiance: [result.irradiance(row, 0), &[]],
        })
        .unwrap();
    }
    assert_eq!(sink.finish().unwrap(), want);

    // Too few polygons, too many, a wrong band count and a wrong id are refused at the end,
    // without stopping the stream.
    let short = ReferenceSink::new(reference.clone(), 2, false).unwrap();
    assert_eq!(short.reference_polygons(), 2);
    let e = short.finish().unwrap_err().to_string();
    assert!(e.contains("0 polygons"), "{e}");
    assert!(ReferenceSink::new(reference.clone(), 1, false).is_err());
    let p = |id: u64| PolygonResult {
        id,
        area: 1.0,
        two_sided: false,
        radiosity: [&[2.0, 1.0], &[]],
        irradiance: [&[0.0, 0.0], &[]],
    };
    let mut long = ReferenceSink::new(table(2, &[]), 2, false).unwrap();
    let Ok(()) = long.polygon(&p(0));
    let e = long.finish().unwrap_err().to_string();
    assert!(e.contains("1 polygons but the reference has 0"), "{e}");
    let mut wrong = ReferenceSink::new(reference.clone(), 2, false).unwrap();
    for id in [0, 4] {
        let Ok(()) = wrong.polygon(&p(id));
    }
    let e = wrong.finish().unwrap_err().to_string();
    assert!(e.contains("row 2: polygon 4"), "{e}");
}
