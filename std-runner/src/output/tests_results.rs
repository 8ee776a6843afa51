//! The results table: exact text, writer checks, bit-exact round trips, located reader
//! errors, and no panic on any input.

use super::results::{ResultsTable, ResultsWriter, TableLayout, header};
use super::results_read::{read_results, read_results_file};
use super::row_labels::RowLabels;
use hirad_core::sink::{PolygonResult, Sink};
use proptest::prelude::*;

fn poly<'a>(id: u64, area: f32, rad: [&'a [f32]; 2], irr: [&'a [f32]; 2]) -> PolygonResult<'a> {
    PolygonResult {
        id,
        area,
        two_sided: !rad[1].is_empty(),
        radiosity: rad,
        irradiance: irr,
    }
}

fn write(bands: usize, two_sided: bool, polys: &[PolygonResult<'_>]) -> String {
    let mut w = ResultsWriter::new(Vec::new(), bands, two_sided).unwrap();
    for p in polys {
        w.polygon(p).unwrap();
    }
    String::from_utf8(w.finish().unwrap()).unwrap()
}

#[test]
fn one_sided_text() {
    let text = write(
        3,
        false,
        &[
            poly(0, 0.5, [&[1.0, 2.0, 3.0], &[]], [&[0.1, 0.25, 3e-8], &[]]),
            poly(7, 2.0, [&[0.0, -0.0, 1e20], &[]], [&[4.5, 0.0, 1.0], &[]]),
        ],
    );
    assert_eq!(
        text,
        "id,area_m2,rad_0_W_m2,rad_1_W_m2,rad_2_W_m2,irr_0_W_m2,irr_1_W_m2,irr_2_W_m2\n\
         0,0.5,1,2,3,0.1,0.25,0.00000003\n\
         7,2,0,-0,100000000000000000000,4.5,0,1\n"
    );
}

#[test]
fn two_sided_text() {
    let text = write(
        2,
        true,
        &[
            poly(
                0,
                1.0,
                [&[1.0, 2.0], &[3.0, 4.0]],
                [&[5.0, 6.0], &[7.0, 8.0]],
            ),
            // A one-sided polygon in a two-sided scene: no back, empty fields.
            poly(1, 0.25, [&[9.0, 10.0], &[]], [&[11.0, 12.0], &[]]),
        ],
    );
    assert_eq!(
        text,
        "id,area_m2,rad_0_W_m2,rad_1_W_m2,irr_0_W_m2,irr_1_W_m2,rad_back_0_W_m2,rad_back_1_W_m2,irr_back_0_W_m2,irr_back_1_W_m2\n\
         0,1,1,2,5,6,3,4,7,8\n\
         1,0.25,9,10,11,12,,,,\n"
    );
}

#[test]
fn empty_table_is_a_header() {
    assert_eq!(write(1, false, &[]), "id,area_m2,rad_0_W_m2,irr_0_W_m2\n");
    assert_eq!(
        header(1, true),
        "id,area_m2,rad_0_W_m2,irr_0_W_m2,rad_back_0_W_m2,irr_back_0_W_m2"
    );
    let t = read_results(b"id,area,rad_0,irr_0\n").unwrap();
    assert!(t.is_empty() && t.bands == 1 && !t.two_sided);
}

#[test]
fn writer_refuses_what_it_could_not_read_back() {
    let mut w = ResultsWriter::new(Vec::new(), 1, false).unwrap();
    let nan = poly(0, 1.0, [&[f32::NAN], &[]], [&[0.0], &[]]);
    assert!(w.polygon(&nan).unwrap_err().to_string().contains("NaN"));
    w.polygon(&poly(3, 1.0, [&[1.0], &[]], [&[0.0], &[]]))
        .unwrap();
    let again = poly(3, 1.0, [&[1.0], &[]], [&[0.0], &[]]);
    assert!(
        w.polygon(&again)
            .unwrap_err()
            .to_string()
            .contains("increase")
    );
    let bands = poly(4, 1.0, [&[1.0, 2.0], &[]], [&[0.0], &[]]);
    assert!(w.polygon(&bands).is_err());
    let back = poly(5, 1.0, [&[1.0], &[1.0]], [&[0.0], &[0.0]]);
    assert!(w.polygon(&back).unwrap_err().to_string().contains("back"));
    let area = poly(6, f32::INFINITY, [&[1.0], &[]], [&[0.0], &[]]);
    assert!(w.polygon(&area).is_err());
    assert!(ResultsWriter::new(Vec::new(), 0, false).is_err());
    assert!(ResultsWriter::new(Vec::new(), 9, false).is_err());
}

#[test]
fn table_push_and_write_match_the_streaming_writer() {
    let polys = [
        poly(2, 1.5, [&[1.0], &[2.0]], [&[3.0], &[4.0]]),
        poly(5, 0.5, [&[5.0], &[]], [&[6.0], &[]]),
    ];
    let mut t = ResultsTable::new(1, true);
    for p in &polys {
        t.polygon(p).unwrap();
    }
    // The streamed table reads back as the table in memory (a one-sided row's empty back
    // fields as zeros), and the table writes what it holds.
    assert_eq!(read_results(write(1, true, &polys).as_bytes()).unwrap(), t);
    let mut buf = Vec::new();
    t.write_csv(&mut buf).unwrap();
    assert_eq!(read_results(&buf).unwrap(), t);
    assert_eq!(t.radiosity(1, 1), &[0.0]);
    assert!(t.polygon(&polys[0]).is_err(), "ids must increase");
}

fn err(text: &str) -> (u64, u64, String) {
    let e = read_results(text.as_bytes()).unwrap_err();
    (e.line, e.column, e.message)
}

#[test]
fn reader_errors_are_located() {
    let h = "id,area,rad_0,irr_0\n";
    let (l, c, m) = err(&format!("{h}0,1,2,3\n1,1,abc,3\n"));
    assert_eq!((l, c), (3, 5));
    assert!(m.contains("`abc`"), "{m}");
    let (l, c, m) = err(&format!("{h}0,1,NaN,3\n"));
    assert_eq!((l, c), (2, 5));
    assert!(m.contains("finite"), "{m}");
    let (l, c, _) = err(&format!("{h}0,1,2,inf\n"));
    assert_eq!((l, c), (2, 7));
    let (l, c, m) = err(&format!("{h}0,1,2,1e39\n"));
    assert_eq!((l, c), (2, 7));
    assert!(m.contains("range"), "{m}");
    let (l, c, m) = err(&format!("{h}0,1,2,3,4\n"));
    assert_eq!((l, c), (2, 9));
    assert!(m.contains("expected 4 fields, found 5"), "{m}");
    let (l, c, m) = err(&format!("{h}0,1,2\n"));
    assert_eq!((l, c), (2, 6));
    assert!(m.contains("found 3"), "{m}");
    let (l, c, m) = err(&format!("{h}0,1,2,3\n0,1,2,3\n"));
    assert_eq!((l, c), (3, 1));
    assert!(m.contains("duplicate id 0"), "{m}");
    let (l, _, m) = err(&format!("{h}5,1,2,3\n4,1,2,3\n"));
    assert_eq!(l, 3);
    assert!(m.contains("increasing"), "{m}");
    let (l, c, m) = err(&format!("{h}-1,1,2,3\n"));
    assert_eq!((l, c), (2, 1));
    assert!(m.contains("polygon id"), "{m}");
    let (l, c, m) = err(&format!("{h}0,-1,2,3\n"));
    assert_eq!((l, c), (2, 3));
    assert!(m.contains("negative area"), "{m}");
    let (l, _, m) = err(&format!("{h}0,1,2,3\n\n1,1,2,3\n"));
    assert_eq!(l, 3);
    assert!(m.contains("empty line"), "{m}");
    let (l, c, m) = err("id,area,rad_0,irr_x\n");
    assert_eq!((l, c), (1, 15));
    assert!(m.contains("band `x`"), "{m}");
    let (l, _, m) = err("id,area,rad_0\n");
    assert_eq!(l, 1);
    assert!(m.contains("no column `irr_0_W_m2`"), "{m}");
    let (l, c, m) = err("id,area,rad_0,irr_0,colour\n");
    assert_eq!((l, c), (1, 21));
    assert!(m.contains("unknown column `colour`"), "{m}");
    let (l, c, m) = err("id,area,rad_0,irr_0,rad_0\n");
    assert_eq!((l, c), (1, 21));
    assert!(m.contains("twice"), "{m}");
    let (_, _, m) = err("id,rad_0,irr_0\n");
    assert!(m.contains("no `area_m2`"), "{m}");
    let (l, c, m) = err("id,area,rad_0,irr_0,material\n0,1,2,3,\"wood\n");
    assert_eq!((l, c), (2, 9));
    assert!(m.contains("quoted"), "{m}");
    let (l, c, m) = err("");
    assert_eq!((l, c), (1, 1));
    assert!(m.contains("empty file"), "{m}");
    let (l, c, _) = err(&format!("{h}0,1,2,3\r\r\n"));
    assert_eq!((l, c), (2, 7), "a bare carriage return is not a number");
    let e = read_results(format!("{h}1,1,x,3\n").as_bytes()).unwrap_err();
    assert_eq!(e.to_string(), "2:5: `x` is not a finite decimal number");
}

#[test]
fn reader_accepts_crlf_bom_and_no_final_newline() {
    let t = read_results(b"\xEF\xBB\xBFid,area,rad_0,irr_0\r\n3,1.5,2,0.5\r\n4,1,1e-3,2").unwrap();
    assert_eq!(t.ids, vec![3, 4]);
    assert_eq!(t.areas, vec![1.5, 1.0]);
    assert_eq!(t.radiosity[0], vec![2.0, 1e-3]);
    assert_eq!(t.irradiance[0], vec![0.5, 2.0]);
}

fn finite_f32() -> impl Strategy<Value = f32> {
    any::<u32>().prop_map(|bits| {
        let v = f32::from_bits(bits);
        if v.is_finite() {
            v
        } else {
            f32::from_bits(bits & 0x807f_ffff)
        }
    })
}

fn table() -> impl Strategy<Value = ResultsTable> {
    (1usize..=8, any::<bool>(), 0usize..20).prop_flat_map(|(bands, two_sided, rows)| {
        let sides = if two_sided { 2 } else { 1 };
        (
            proptest::collection::btree_set(any::<u64>(), rows),
            proptest::collection::vec(finite_f32().prop_map(f32::abs), rows),
            proptest::collection::vec(finite_f32(), rows * bands * 2 * sides),
        )
            .prop_map(move |(ids, areas, values)| {
                let mut t = ResultsTable::new(bands, two_sided);
                let n = ids.len();
                t.ids = ids.into_iter().collect();
                t.areas = areas[..n].to_vec();
                let mut it = values.into_iter();
                for side in 0..sides {
                    t.radiosity[side] = it.by_ref().take(n * bands).collect();
                    t.irradiance[side] = it.by_ref().take(n * bands).collect();
                }
                t
            })
    })
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

proptest! {
    #[test]
    fn round_trip_is_bit_exact(t in table()) {
        let mut buf = Vec::new();
        t.write_csv(&mut buf).unwrap();
        let back = read_results(&buf).unwrap();
        prop_assert_eq!(back.bands, t.bands);
        prop_assert_eq!(back.two_sided, t.two_sided);
        prop_assert_eq!(&back.ids, &t.ids);
        prop_assert_eq!(bits(&back.areas), bits(&t.areas));
        for side in 0..2 {
            prop_assert_eq!(bits(&back.radiosity[side]), bits(&t.radiosity[side]));
            prop_assert_eq!(bits(&back.irradiance[side]), bits(&t.irradiance[side]));
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = read_results(&bytes);
    }

    #[test]
    fn mutated_tables_never_panic(
        t in table(),
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
    ) {
        let mut buf = Vec::new();
        t.write_csv(&mut buf).unwrap();
        for (at, byte) in edits {
            let i = at.index(buf.len());
            buf[i] = byte;
        }
        if let Err(e) = read_results(&buf) {
            prop_assert!(e.line >= 1 && e.column >= 1);
        }
    }
}

#[test]
fn file_errors_name_the_file_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ref.csv");
    std::fs::write(&path, "id,area,rad_0,irr_0\n0,1,2,3\n1,1,2,x\n").unwrap();
    let e = read_results_file(&path).unwrap_err().to_string();
    assert_eq!(
        e,
        format!("{}:3:7: `x` is not a finite decimal number", path.display())
    );
    let e = read_results_file(&dir.path().join("missing.csv"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing.csv: cannot read"), "{e}");
}

fn faces_layout(faces: Vec<u64>) -> TableLayout {
    TableLayout {
        faces: Some(faces),
        ..TableLayout::plain(1, false)
    }
}

#[test]
fn the_face_column_is_written_after_the_numbers_and_read_back() {
    let mut w = ResultsWriter::with_layout(Vec::new(), faces_layout(vec![7, 7, 9])).unwrap();
    for id in 0..3 {
        w.polygon(&poly(id, 1.0, [&[0.5], &[]], [&[1.0], &[]]))
            .unwrap();
    }
    let text = String::from_utf8(w.finish().unwrap()).unwrap();
    assert_eq!(
        text,
        "id,area_m2,rad_0_W_m2,irr_0_W_m2,face\n0,1,0.5,1,7\n1,1,0.5,1,7\n2,1,0.5,1,9\n"
    );
    let t = read_results(text.as_bytes()).unwrap();
    assert_eq!(t.len(), 3);
    assert_eq!(t.radiosity(2, 0), &[0.5]);
    // A row beyond the face numbers is refused, not written with a wrong one.
    let mut w = ResultsWriter::with_layout(Vec::new(), faces_layout(vec![1])).unwrap();
    assert!(
        w.polygon(&poly(1, 1.0, [&[0.5], &[]], [&[1.0], &[]]))
            .is_err()
    );
    // A face that is not a whole number is located.
    let (l, c, m) = err("id,area,rad_0,irr_0,face\n0,1,2,3,x\n");
    assert_eq!((l, c), (2, 9));
    assert!(m.contains("`x`"), "{m}");
}

#[test]
fn tables_of_every_earlier_layout_read_alike() {
    // Index labels without units (before band names and units), named bands with units, and
    // the columns in another order (the bands' order is that of the front radiosity's).
    let old = read_results(b"id,area,rad_0,rad_1,irr_0,irr_1\n0,2,1,2,3,4\n").unwrap();
    let new = read_results(
        b"id,area_m2,rad_par_W_m2,rad_nir_W_m2,irr_par_W_m2,irr_nir_W_m2,material,group\n\
          0,2,1,2,3,4,leaf,\"scene/a,b\"\n",
    )
    .unwrap();
    let shuffled = read_results(
        b"group,irr_nir_W_m2,id,rad_par_W_m2,area_m2,irr_par_W_m2,rad_nir_W_m2\nx,4,0,1,2,3,2\n",
    )
    .unwrap();
    assert_eq!(old, new);
    assert_eq!(old, shuffled);
    assert_eq!(old.radiosity(0, 0), &[1.0, 2.0]);
    assert_eq!(old.irradiance(0, 0), &[3.0, 4.0]);
}

#[test]
fn named_bands_units_material_and_group_columns() {
    use super::columns::band_labels;
    let names = vec!["par".to_string(), "nir".to_string()];
    // Built through a scene: two materials, a named cluster and an unnamed one.
    let rows = {
        use crate::scene::{Cluster, Material, Scene, quad};
        use glam::Vec3;
        let mut s = Scene::new(2);
        s.band_names = names.clone();
        for name in ["soil", "leaf, green \"young\""] {
            s.materials.push(Material {
                name: name.into(),
                data: hirad_core::material::MaterialData::black(2),
            });
        }
        let mut plant = Cluster::named("plant");
        let mut organ = Cluster::default();
        for x in 0..2 {
            let c = &mut organ;
            let base = c.vertices.len() as u32;
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                c.vertex(Vec3::new(x as f32 + dx, dy, 1.0));
            }
            c.polygons.push(quad(base, base + 1, base + 2, base + 3, 1));
        }
        plant.children.push(organ);
        let g = &mut s.root;
        for (dx, dy) in [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0)] {
            g.vertex(Vec3::new(dx, dy, 0.0));
        }
        g.polygons.push(quad(0, 1, 2, 3, 0));
        s.root.children.push(plant);
        RowLabels::of(&s)
    };
    let mut rows = rows;
    assert_eq!(rows.len(), 3);
    assert_eq!(rows.group(0), Some("scene"));
    assert_eq!(rows.group(1), Some("scene/plant/#0"));
    assert_eq!(rows.group(2), Some("scene/plant/#0"));
    assert_eq!(rows.group(3), None);
    assert_eq!(rows.material(2), Some("leaf, green \"young\""));
    assert!(rows.uses_material(|m| m == 1) && !rows.uses_material(|m| m > 1));
    let layout = TableLayout {
        labels: band_labels(2, &names),
        two_sided: false,
        faces: None,
        rows: Some(rows),
    };
    let mut w = ResultsWriter::with_layout(Vec::new(), layout).unwrap();
    for id in 0..3 {
        w.polygon(&poly(id, 1.0, [&[0.5, 1.5], &[]], [&[1.0, 2.0], &[]]))
            .unwrap();
    }
    let text = String::from_utf8(w.finish().unwrap()).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "id,area_m2,rad_par_W_m2,rad_nir_W_m2,irr_par_W_m2,irr_nir_W_m2,material,group"
    );
    assert_eq!(lines[1], "0,1,0.5,1.5,1,2,soil,scene");
    assert_eq!(
        lines[2],
        "1,1,0.5,1.5,1,2,\"leaf, green \"\"young\"\"\",scene/plant/#0"
    );
    // Quoted fields read back whole.
    let fields = super::columns::split_fields(lines[2].as_bytes()).unwrap();
    assert_eq!(&*fields[6].text, b"leaf, green \"young\"");
    assert_eq!(&*fields[7].text, b"scene/plant/#0");
    assert_eq!(read_results(text.as_bytes()).unwrap().len(), 3);
    // Names that are not plain (or repeat) fall back to indices.
    assert_eq!(band_labels(2, &["a b".into(), "c".into()]), ["0", "1"]);
    assert_eq!(band_labels(2, &["c".into(), "c".into()]), ["0", "1"]);
    assert_eq!(band_labels(2, &[]), ["0", "1"]);
}
