//! The solve outputs end to end on real scenes: synthetic per-polygon results streamed in
//! global-id order (as the solver hands them over) become a results table, an image, a
//! reference comparison and a stats file, written atomically and read back.

use glam::Vec3;
use hirad::files::load_scene;
use hirad::output::{
    ImageSink, Outputs, ReferenceSink, ResultsFile, ResultsTable, Size, SolveReport, compare,
    default_camera, read_exr, read_results, scene_bounds,
};
use hirad::scene::{ExpandVisitor, ExpandedNode, Scene, expand, sample};
use hirad_core::limits::NONE;
use hirad_core::sink::{PatchResult, PolygonResult, Sink};
use hirad_tests::fixture;
use std::collections::HashSet;
use std::f32::consts::PI;
use std::path::Path;

/// Streams made-up results for every polygon of the expanded scene, one patch per polygon:
/// front radiosity `emit + rho * (1 + id % 7)` per band, back `emit_back + rho_back * (2 +
/// id % 5)` for two-sided materials, all scaled by `gain`.
struct Synth<'a, S> {
    scene: &'a Scene,
    sink: &'a mut S,
    gain: f32,
    /// Front and back radiance (radiosity / pi) of every polygon, as bits.
    radiances: HashSet<Vec<u32>>,
}

impl<S: Sink> ExpandVisitor for Synth<'_, S>
where
    S::Error: std::fmt::Display,
{
    type Error = String;

    fn node(&mut self, node: &ExpandedNode<'_>) -> Result<(), String> {
        let bands = usize::from(self.scene.bands);
        for (k, p) in node.cluster.polygons.iter().enumerate() {
            let id = node.first_id + k as u64;
            let corners: Vec<Vec3> = p
                .corners
                .iter()
                .filter(|&&c| c != NONE)
                .map(|&c| node.to_world.point(node.cluster.vertices[c as usize]))
                .collect();
            let cross = if corners.len() == 3 {
                (corners[1] - corners[0]).cross(corners[2] - corners[0])
            } else {
                (corners[2] - corners[0]).cross(corners[3] - corners[1])
            };
            let m = &self.scene.materials[p.material as usize].data;
            let light = (1 + id % 7) as f32;
            let front: Vec<f32> = (0..bands)
                .map(|b| (m.emit_front[b] + m.rho_front[b] * light) * self.gain)
                .collect();
            let back: Vec<f32> = if m.two_sided {
                let light = (2 + id % 5) as f32;
                (0..bands)
                    .map(|b| (m.emit_back[b] + m.rho_back[b] * light) * self.gain)
                    .collect()
            } else {
                Vec::new()
            };
            let irradiance = vec![light; bands];
            let back_irradiance = if m.two_sided {
                irradiance.clone()
            } else {
                Vec::new()
            };
            for side in [&front, &back] {
                self.radiances
                    .insert(side.iter().map(|v| (v / PI).to_bits()).collect());
            }
            self.sink
                .patch(&PatchResult {
                    id,
                    corners: &corners,
                    normal: cross.normalize(),
                    material: p.material,
                    radiosity: [&front, &back],
                })
                .map_err(|e| e.to_string())?;
            self.sink
                .polygon(&PolygonResult {
                    id,
                    area: cross.length() * 0.5,
                    two_sided: m.two_sided,
                    radiosity: [&front, &back],
                    irradiance: [&irradiance, &back_irradiance],
                })
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    }
}

fn stream<S: Sink>(scene: &Scene, sink: &mut S, gain: f32) -> HashSet<Vec<u32>>
where
    S::Error: std::fmt::Display,
{
    let mut synth = Synth {
        scene,
        sink,
        gain,
        radiances: HashSet::new(),
    };
    expand(scene, &mut synth).unwrap();
    synth.radiances
}

fn two_sided(scene: &Scene) -> bool {
    scene.materials.iter().any(|m| m.data.two_sided)
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    names
}

#[test]
fn cornell_box_table_and_image() {
    let scene = load_scene(&fixture("cornell_box.hir")).unwrap().scene;
    let bands = usize::from(scene.bands);
    let dir = tempfile::tempdir().unwrap();
    let (csv, exr) = (dir.path().join("box.csv"), dir.path().join("box.exr"));
    let size = Size {
        width: 64,
        height: 48,
    };
    let camera = scene.cameras[0].clone();
    let mut out = Outputs {
        results: Some(ResultsFile::create(&csv, bands, two_sided(&scene)).unwrap()),
        // Flat: every element in its own value (smooth shading blends shared corners).
        image: Some(
            ImageSink::new(&exr, &camera, size, 1, bands, &scene.band_names)
                .unwrap()
                .with_shading(hirad::output::Shading::Flat),
        ),
        reference: None,
    };
    let radiances = stream(&scene, &mut out, 1.0);
    assert_eq!(out.finish().unwrap(), None);
    assert_eq!(files_in(dir.path()), ["box.csv", "box.exr"]);

    // The table on disk is the table in memory, bit for bit.
    let table = read_results(&std::fs::read(&csv).unwrap()).unwrap();
    let mut memory = ResultsTable::new(bands, false);
    stream(&scene, &mut memory, 1.0);
    assert_eq!(table, memory);
    assert_eq!(table.ids, (0..17).collect::<Vec<u64>>());
    assert!(table.areas.iter().all(|&a| a > 0.0));

    // Flat shading: every pixel is the background or the radiance of one polygon (one
    // sample per pixel), and the box fills most of the view.
    let image = read_exr(&exr).unwrap();
    assert_eq!((image.width, image.height), (64, 48));
    let order: Vec<usize> = ["R", "G", "B"]
        .iter()
        .map(|c| image.channel(c).unwrap())
        .collect();
    let mut covered = 0;
    for y in 0..48 {
        for x in 0..64 {
            let px = image.pixel(x, y);
            let rgb: Vec<u32> = order.iter().map(|&c| px[c].to_bits()).collect();
            if px.iter().any(|&v| v != 0.0) {
                covered += 1;
                assert!(radiances.contains(&rgb), "pixel {x},{y} = {px:?}");
            }
        }
    }
    assert!(covered > 64 * 48 / 2, "{covered} pixels covered");
}

#[test]
fn reference_error_and_stats() {
    let scene = load_scene(&fixture("cornell_box.hir")).unwrap().scene;
    let bands = usize::from(scene.bands);
    let mut reference = ResultsTable::new(bands, false);
    stream(&scene, &mut reference, 1.0);
    assert_eq!(compare(&reference, &reference).unwrap().error_percent, 0.0);

    // Every radiosity 2 % too high: the error is 2 % of the reference's RMS radiosity over
    // its maximum, with the f32 rounding of the scaled values.
    let mut out = Outputs {
        reference: Some(ReferenceSink::new(reference.clone(), bands, false).unwrap()),
        ..Outputs::default()
    };
    stream(&scene, &mut out, 1.02);
    let got = out.finish().unwrap().unwrap();
    let (mut sum, mut area, mut max) = (0.0f64, 0.0f64, 0.0f64);
    for row in 0..reference.len() {
        let a = f64::from(reference.areas[row]);
        area += a;
        for &r in reference.radiosity(row, 0) {
            sum += a * (0.02 * f64::from(r)).powi(2);
            max = max.max(f64::from(r));
        }
    }
    let want = 100.0 * (sum / (bands as f64 * area)).sqrt() / max;
    assert!(
        (got.error_percent - want).abs() < 1e-5 * want,
        "{} vs {want}",
        got.error_percent
    );
    assert_eq!(got.polygons, 17);
    assert_eq!(got.per_band_percent.len(), 3);

    // The stats file carries the error.
    let mut report = SolveReport {
        method: "hr".into(),
        epsilon: Some(0.01),
        threads: 2,
        polygons: 17,
        elements: 40,
        links: 300,
        iterations: 5,
        refinement_passes: 2,
        seconds: 0.25,
        peak_workspace_bytes: 1 << 16,
        workspace_bytes: 1 << 20,
        budget_limited: false,
        error_percent: None,
        error_per_band_percent: Vec::new(),
        max_abs_difference: None,
        worst_polygons: Vec::new(),
        ..SolveReport::default()
    };
    report.set_comparison(&got);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("stats.json");
    report.write_json(&path).unwrap();
    let back = SolveReport::from_json(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(back, report);
    assert_eq!(back.error_percent, Some(got.error_percent));

    // A reference of another scene is refused with a message.
    let mut other = Outputs {
        reference: Some(ReferenceSink::new(reference, bands, false).unwrap()),
        ..Outputs::default()
    };
    let plant = load_scene(&fixture("chair_room.hir")).unwrap().scene;
    if usize::from(plant.bands) == bands {
        let mut synth = Synth {
            scene: &plant,
            sink: &mut other,
            gain: 1.0,
            radiances: HashSet::new(),
        };
        let e = match expand(&plant, &mut synth) {
            Err(e) => e,
            Ok(_) => other.finish().unwrap_err().to_string(),
        };
        assert!(e.contains("reference"), "{e}");
    }
}

#[test]
fn two_sided_scene_with_default_camera() {
    let scene = sample();
    assert!(scene.cameras.len() <= 1);
    let bands = usize::from(scene.bands);
    let dir = tempfile::tempdir().unwrap();
    let (csv, png) = (dir.path().join("s.csv"), dir.path().join("s.png"));
    let size = Size {
        width: 32,
        height: 24,
    };
    let bounds = scene_bounds(&scene);
    let camera = default_camera(&bounds, size).unwrap();
    let mut out = Outputs {
        results: Some(ResultsFile::create(&csv, bands, true).unwrap()),
        image: Some(ImageSink::new(&png, &camera, size, 2, bands, &scene.band_names).unwrap()),
        reference: None,
    };
    stream(&scene, &mut out, 1.0);
    out.finish().unwrap();

    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with(
        "id,area_m2,rad_0_W_m2,rad_1_W_m2,irr_0_W_m2,irr_1_W_m2,rad_back_0_W_m2,rad_back_1_W_m2,irr_back_0_W_m2,irr_back_1_W_m2\n"
    ));
    let table = read_results(text.as_bytes()).unwrap();
    assert!(table.two_sided);
    // One-sided polygons have empty back fields (read as zeros), two-sided ones their back
    // values.
    let mut memory = ResultsTable::new(bands, true);
    stream(&scene, &mut memory, 1.0);
    assert_eq!(table, memory);

    // The PNG has the right signature and size (IHDR width and height, big-endian).
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(&bytes[12..16], b"IHDR");
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 32);
    assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 24);

    // The box holds every vertex of the expanded scene.
    struct Inside(hirad_core::geometry::Aabb, usize);
    impl ExpandVisitor for Inside {
        type Error = String;
        fn node(&mut self, n: &ExpandedNode<'_>) -> Result<(), String> {
            for p in &n.cluster.polygons {
                for &c in p.corners.iter().filter(|&&c| c != NONE) {
                    let v = n.to_world.point(n.cluster.vertices[c as usize]);
                    let slack = 1e-5 * (self.0.max - self.0.min).length();
                    if (self.0.min - v).max_element() > slack
                        || (v - self.0.max).max_element() > slack
                    {
                        return Err(format!("{v} outside {:?}", self.0));
                    }
                    self.1 += 1;
                }
            }
            Ok(())
        }
    }
    let mut inside = Inside(bounds, 0);
    expand(&scene, &mut inside).unwrap();
    assert!(inside.1 > 0);
}

#[test]
fn an_unfinished_run_leaves_no_file() {
    let scene = load_scene(&fixture("cornell_box.hir")).unwrap().scene;
    let bands = usize::from(scene.bands);
    let dir = tempfile::tempdir().unwrap();
    let size = Size {
        width: 8,
        height: 8,
    };
    let camera = scene.cameras[0].clone();
    let mut out = Outputs {
        results: Some(ResultsFile::create(&dir.path().join("a.csv"), bands, false).unwrap()),
        image: Some(
            ImageSink::new(&dir.path().join("a.exr"), &camera, size, 1, bands, &[]).unwrap(),
        ),
        reference: None,
    };
    stream(&scene, &mut out, 1.0);
    drop(out);
    assert!(files_in(dir.path()).is_empty());
}
