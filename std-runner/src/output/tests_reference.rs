//! The reference measure on hand-computed cases, its refusals, and the streaming sink.

use super::reference::{RELATIVE_FLOOR, ReferenceSink, WorstPolygon, compare};
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

/// Ids and signed percentages of the worst polygons.
fn worst_of(result: &ResultsTable, reference: &ResultsTable) -> Vec<(u64, usize, bool, f64)> {
    compare(result, reference)
        .unwrap()
        .worst
        .iter()
        .map(|w| (w.id, w.band, w.back, w.relative_error_percent))
        .collect()
}

#[test]
fn worst_polygons_by_relative_error() {
    // Reference max 100, so the floor is 0.1 W/m^2.
    let reference = table(
        2,
        &[
            (0, 1.0, &[100.0, 50.0]),
            (1, 1.0, &[10.0, 10.0]),
            (2, 1.0, &[1.0, 0.05]),
            (3, 1.0, &[20.0, 20.0]),
            (4, 1.0, &[4.0, 4.0]),
            (5, 1.0, &[0.0, 0.0]),
            (6, 1.0, &[8.0, 8.0]),
            (7, 1.0, &[10.0, 10.0]),
            (8, 1.0, &[0.2, 2.0]),
        ],
    );
    let result = table(
        2,
        &[
            // -1 %: sixth, not listed.
            (0, 1.0, &[99.0, 50.0]),
            // +20 % in band 1 beats -10 % in band 0.
            (1, 1.0, &[9.0, 12.0]),
            // Band 1 is below the floor (0.05 < 0.1): its +1900 % does not count; band 0 +5 %.
            (2, 1.0, &[1.05, 1.0]),
            // -20 %: ties with polygon 1 (|20 %|), listed after it (higher id).
            (3, 1.0, &[16.0, 20.0]),
            // +50 %: the worst.
            (4, 1.0, &[6.0, 4.0]),
            // A black reference (0/0): never listed, whatever the result.
            (5, 1.0, &[3.0, 3.0]),
            // Exact: 0 %.
            (6, 1.0, &[8.0, 8.0]),
            // -20 % in band 0 and +20 % in band 1: the first column wins the tie.
            (7, 1.0, &[8.0, 12.0]),
            // Band 0 at 0.2 is above the floor: -25 %.
            (8, 1.0, &[0.15, 2.0]),
        ],
    );
    let close = |a: f64, b: f64| (a - b).abs() < 1e-4;
    let got = worst_of(&result, &reference);
    let want = [
        (4, 0, false, 50.0),
        (8, 0, false, -25.0),
        (1, 1, false, 20.0),
        (3, 0, false, -20.0),
        (7, 0, false, -20.0),
    ];
    assert_eq!(got.len(), 5, "{got:?}");
    for (g, w) in got.iter().zip(&want) {
        assert!(
            g.0 == w.0 && g.1 == w.1 && g.2 == w.2 && close(g.3, w.3),
            "{got:?}"
        );
    }
    let c = compare(&result, &reference).unwrap();
    assert_eq!(c.relative_floor, RELATIVE_FLOOR * 100.0);
    assert_eq!(
        c.worst[0],
        WorstPolygon {
            id: 4,
            band: 0,
            back: false,
            reference: 4.0,
            result: 6.0,
            relative_error_percent: 50.0,
        }
    );
    // Fewer polygons than five: all of those above the floor are listed.
    let small = table(1, &[(0, 1.0, &[2.0]), (1, 1.0, &[0.0])]);
    let off = table(1, &[(0, 1.0, &[1.0]), (1, 1.0, &[5.0])]);
    assert_eq!(worst_of(&off, &small), [(0, 0, false, -50.0)]);
}

#[test]
fn worst_polygons_name_the_back_side() {
    // Front equal, back 10 % high; a one-sided result compares fronts only.
    let c = compare(&two_sided(2.0, 4.4), &two_sided(2.0, 4.0)).unwrap();
    assert_eq!(c.worst.len(), 1);
    let w = &c.worst[0];
    assert!((w.id, w.band, w.back) == (0, 0, true), "{w:?}");
    assert!((w.relative_error_percent - 10.0).abs() < 1e-4, "{w:?}");
    let one = table(1, &[(0, 1.0, &[2.0])]);
    let c = compare(&one, &two_sided(2.0, 8.0)).unwrap();
    assert!(!c.worst[0].back);
    assert_eq!(c.worst[0].relative_error_percent, 0.0);
}

#[test]
fn worst_polygons_print_with_the_floor() {
    let mut reference = ResultsTable::new(2, true);
    let mut result = ResultsTable::new(2, true);
    for (id, front, back, got_back) in [
        (3u64, [20.0, 1.0], [0.5, 0.1], [0.5, 0.1]),
        (17, [1.0, 1.0], [0.5, 0.02618], [0.5, 0.02795]),
    ] {
        for (t, b) in [(&mut reference, back), (&mut result, got_back)] {
            t.ids.push(id);
            t.areas.push(1.0);
            t.radiosity[0].extend_from_slice(&front);
            t.radiosity[1].extend_from_slice(&b);
            t.irradiance[0].extend_from_slice(&[0.0, 0.0]);
            t.irradiance[1].extend_from_slice(&[0.0, 0.0]);
        }
    }
    let c = compare(&result, &reference).unwrap();
    let names = ["par".to_string(), "nir".to_string()];
    assert_eq!(
        c.worst_lines(&names),
        "worst polygons (relative error of radiosity, where the reference is at least 0.1% of \
         its largest, 0.02 W/m^2):\n  \
         id 17 back band 1 (nir): reference 0.02618 W/m^2, got 0.02795, +6.76 %\n  \
         id 3 front band 0 (par): reference 20 W/m^2, got 20, +0.00 %\n"
    );
    assert!(
        c.worst_lines(&[])
            .contains("  id 17 back band 1: reference")
    );
}
