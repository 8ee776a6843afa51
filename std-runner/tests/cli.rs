//! The `hirad` binary end to end: every command on every fixture, round trips between the
//! formats, located errors with a non-zero status, and no output left behind on failure.

mod common;

use common::{fails, fixture, ok, s};
use std::path::{Path, PathBuf};

fn fixtures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "hir"))
        .collect();
    v.sort();
    assert!(v.len() >= 7, "expected the fixtures in {}", dir.display());
    v
}

/// The `polygons N` line of `hirad info`.
fn polygons(info: &str) -> u64 {
    let line = info
        .lines()
        .find(|l| l.starts_with("polygons"))
        .expect("a polygons line");
    line.split_whitespace().nth(1).unwrap().parse().unwrap()
}

fn faces(obj: &Path) -> u64 {
    std::fs::read_to_string(obj)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("f "))
        .count() as u64
}

/// Entries of a directory (to check that nothing, temporary files included, was left).
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    v.sort();
    v
}

#[test]
fn help_on_every_command() {
    for cmd in [
        &["--help"][..],
        &["info", "--help"],
        &["convert", "--help"],
        &["flatten", "--help"],
    ] {
        let out = ok(cmd);
        assert!(out.contains("Usage"), "{out}");
    }
}

#[test]
fn info_and_flatten_on_every_fixture() {
    let dir = tempfile::tempdir().unwrap();
    for f in fixtures() {
        let info = ok(&["info", s(&f)]);
        let n = polygons(&info);
        assert!(n > 0, "{}: {info}", f.display());
        let out = dir
            .path()
            .join(f.file_stem().unwrap())
            .with_extension("obj");
        ok(&["flatten", "-q", s(&f), "-o", s(&out)]);
        assert_eq!(
            faces(&out),
            n,
            "{}: faces in the flattened OBJ",
            f.display()
        );
        assert!(out.with_extension("mtl").exists());
        // The flattened OBJ reads back with the same polygon count.
        assert_eq!(
            polygons(&ok(&["info", "-q", s(&out)])),
            n,
            "{}",
            f.display()
        );
    }
}

/// OBJ files in the styles of common modelling tools, and two written by Blender itself.
#[test]
fn info_and_flatten_on_exported_obj_files() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/obj");
    let mut files = Vec::new();
    for d in [root.clone(), root.join("blender")] {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|e| e == "obj") {
                files.push(p);
            }
        }
    }
    files.sort();
    assert!(files.len() >= 10);
    for f in files {
        let n = polygons(&ok(&["info", "-q", s(&f)]));
        let out = dir.path().join(f.file_name().unwrap());
        ok(&["flatten", "-q", s(&f), "-o", s(&out)]);
        assert_eq!(faces(&out), n, "{}", f.display());
        assert_eq!(
            polygons(&ok(&["info", "-q", s(&out)])),
            n,
            "{}",
            f.display()
        );
    }
}

#[test]
fn chair_room_flattens_to_24_chairs_plus_the_room() {
    let path = fixture("chair_room.hir");
    let scene = hirad::text::parse(&std::fs::read(&path).unwrap()).unwrap();
    fn own(c: &hirad::scene::Cluster) -> u64 {
        if c.instance.is_some() {
            return 0;
        }
        c.polygons.len() as u64 + c.children.iter().map(own).sum::<u64>()
    }
    fn instances(c: &hirad::scene::Cluster) -> u64 {
        c.instance.is_some() as u64 + c.children.iter().map(instances).sum::<u64>()
    }
    let chair = scene
        .original_index("chair")
        .expect("an original named chair");
    let chair_polys = own(&scene.originals[chair].root);
    assert_eq!(instances(&scene.root), 24);
    let expected = own(&scene.root) + 24 * chair_polys;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("room.obj");
    ok(&["flatten", "-q", s(&path), "-o", s(&out)]);
    assert_eq!(faces(&out), expected);
    assert_eq!(polygons(&ok(&["info", s(&path)])), expected);
}

/// Outputs are ordinary files (mode from the umask), not owner-only temporary files.
#[cfg(unix)]
#[test]
fn outputs_have_ordinary_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("box.hirb");
    ok(&[
        "convert",
        "-q",
        s(&fixture("cornell_box.hir")),
        "-o",
        s(&out),
    ]);
    let mode = std::fs::metadata(&out).unwrap().permissions().mode();
    assert_eq!(mode & 0o644, 0o644, "mode {mode:o}");
}

#[test]
fn convert_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    for f in fixtures() {
        let stem = f.file_stem().unwrap().to_str().unwrap();
        let b1 = dir.path().join(format!("{stem}.hirb"));
        let t2 = dir.path().join(format!("{stem}.2.hir"));
        let b2 = dir.path().join(format!("{stem}.2.hirb"));
        ok(&["convert", "-q", s(&f), "-o", s(&b1)]);
        ok(&["convert", "-q", s(&b1), "-o", s(&t2)]);
        ok(&["convert", "-q", s(&t2), "-o", s(&b2)]);
        assert_eq!(
            std::fs::read(&b1).unwrap(),
            std::fs::read(&b2).unwrap(),
            "{stem}: hir -> hirb -> hir -> hirb"
        );
        // info agrees whatever the format.
        let a = ok(&["info", "--json", s(&f)]);
        let b = ok(&["info", "--json", s(&b1)]);
        let strip = |j: &str| {
            j.split(",\"format\"")
                .nth(1)
                .unwrap()
                .split(",\"bands\"")
                .nth(1)
                .unwrap()
                .to_string()
        };
        assert_eq!(strip(&a), strip(&b), "{stem}");
    }
}

#[test]
fn located_errors_and_nothing_left_behind() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Text: an unknown material on line 4.
    let bad = d.join("bad.hir");
    std::fs::write(
        &bad,
        "hirad 1\nbands 1\nscene {\n  tri nope 0 0 0 1 0 0 0 1 0\n}\n",
    )
    .unwrap();
    let err = fails(&["info", s(&bad)]);
    assert!(err.contains(&format!("{}:4:", bad.display())), "{err}");
    let out = d.join("out.obj");
    fails(&["flatten", s(&bad), "-o", s(&out)]);
    fails(&["convert", s(&bad), "-o", s(&d.join("out.hirb"))]);
    // Binary: a valid image with one corrupted vertex coordinate.
    let good = d.join("good.hirb");
    ok(&[
        "convert",
        "-q",
        s(&fixture("parallel_squares.hir")),
        "-o",
        s(&good),
    ]);
    let mut bytes = std::fs::read(&good).unwrap();
    let header = *hirad::scene::read_image(&bytes).unwrap().header();
    let at = header.section(hirad_core::image::Section::Vertices).offset as usize;
    bytes[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let corrupt = d.join("corrupt.hirb");
    std::fs::write(&corrupt, &bytes).unwrap();
    let err = fails(&["info", s(&corrupt)]);
    assert!(
        err.contains(&format!("{}: byte {at}: vertex 0", corrupt.display())),
        "{err}"
    );
    // Truncated binary.
    std::fs::write(&corrupt, &bytes[..bytes.len() / 2]).unwrap();
    let err = fails(&["flatten", s(&corrupt), "-o", s(&out)]);
    assert!(err.contains("byte"), "{err}");
    // OBJ: a face index out of range on line 3, column 7.
    let obj = d.join("bad.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let err = fails(&["info", s(&obj)]);
    assert!(err.contains(&format!("{}:3:7:", obj.display())), "{err}");
    // Missing files and unknown formats.
    let err = fails(&["info", s(&d.join("missing.hir"))]);
    assert!(err.contains("missing.hir"), "{err}");
    let err = fails(&["info", s(&d.join("scene.txt"))]);
    assert!(err.contains("unknown scene format"), "{err}");
    let err = fails(&[
        "flatten",
        s(&fixture("furnace.hir")),
        "-o",
        s(&d.join("x.hir")),
    ]);
    assert!(err.contains(".obj"), "{err}");
    // Nothing half-written: only the inputs remain.
    assert_eq!(
        entries(d),
        ["bad.hir", "bad.obj", "corrupt.hirb", "good.hirb"]
    );
}

/// Every class of malformed input, in every format, through the command line: a non-zero
/// status and a message that starts with the file and the location of the fault.
#[test]
fn malformed_inputs_are_located() {
    let dir = tempfile::tempdir().unwrap();
    let head = "hirad 1\nbands 3\nmaterial m rho 0.5 0.5 0.5\n";
    let deep = format!("{head}scene {{\n{}", "cluster {\n".repeat(10_000));
    let text_cases: Vec<(&str, String, &str)> = vec![
        (
            "truncated",
            format!("{head}scene {{\n  v 0 0 0\n  tri m 0"),
            ":6:3:",
        ),
        (
            "wrong count",
            "hirad 1\nbands 3\nmaterial m rho 0.5 0.5\nscene {}\n".into(),
            ":3:12:",
        ),
        ("nan", format!("{head}scene {{\n  v nan 0 0\n}}\n"), ":5:5:"),
        (
            "infinite",
            format!("{head}scene {{\n  v 1e39 0 0\n}}\n"),
            ":5:5:",
        ),
        (
            "index out of range",
            format!("{head}scene {{\n  v 0 0 0\n  tri m 0 1 7\n}}\n"),
            ":6:11:",
        ),
        (
            "cycle",
            format!(
                "{head}original a {{ instance b exact }}\noriginal b {{ instance a exact }}\nscene {{}}\n"
            ),
            ":5:14:",
        ),
        ("10,000-deep nesting", deep, ":68:1:"),
        (
            "absurd count",
            "hirad 1\nbands 4294967295\n".into(),
            ":2:7:",
        ),
        (
            "absurd index",
            format!("{head}scene {{\n  tri m 0 1 99999999999\n}}\n"),
            ":5:13:",
        ),
    ];
    for (what, text, location) in text_cases {
        let p = dir.path().join("bad.hir");
        std::fs::write(&p, text).unwrap();
        let err = fails(&["info", s(&p)]);
        let prefix = format!("error: {}{location}", p.display());
        assert!(
            err.starts_with(&prefix),
            "{what}: expected '{prefix}...', got {err}"
        );
        assert!(
            err.split(':').count() >= 4,
            "{what}: line and column in {err}"
        );
    }

    let obj_cases: Vec<(&str, &str, &str)> = vec![
        ("truncated", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2", ":4:1:"),
        ("nan", "v 0 nan 0\n", ":1:5:"),
        ("infinite", "v 0 0 -1e39\n", ":1:7:"),
        (
            "index out of range",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n",
            ":4:7:",
        ),
        (
            "index zero",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            ":4:3:",
        ),
        (
            "absurd index",
            "v 0 0 0\nf 1 1 99999999999999999999999\n",
            ":2:7:",
        ),
        ("missing mtl", "mtllib nowhere.mtl\n", ":1:8:"),
        ("unknown material", "usemtl nowhere\n", ":1:8:"),
    ];
    for (what, text, location) in obj_cases {
        let p = dir.path().join("bad.obj");
        std::fs::write(&p, text).unwrap();
        let err = fails(&["info", s(&p)]);
        let prefix = format!("error: {}{location}", p.display());
        assert!(
            err.starts_with(&prefix),
            "{what}: expected '{prefix}...', got {err}"
        );
    }

    // Binary: faults at known offsets of a valid image.
    let good = dir.path().join("good.hirb");
    ok(&[
        "convert",
        "-q",
        s(&fixture("small_plant.hir")),
        "-o",
        s(&good),
    ]);
    let bytes = std::fs::read(&good).unwrap();
    let header = *hirad::scene::read_image(&bytes).unwrap().header();
    use hirad_core::image::Section;
    let at = |sec: Section, i: u64| {
        let e = header.section(sec);
        (e.offset + i * e.record_size as u64) as usize
    };
    type Patch = Box<dyn Fn(&mut Vec<u8>)>;
    let put = |off: usize, v: [u8; 4]| -> Patch {
        Box::new(move |b: &mut Vec<u8>| b[off..off + 4].copy_from_slice(&v))
    };
    let count_at = 40 + 24 * Section::Polygons as usize + 8;
    let bin_cases: Vec<(&str, Patch, String)> = vec![
        (
            "truncated",
            Box::new(|b: &mut Vec<u8>| b.truncate(b.len() - 9)),
            "byte 32:".into(),
        ),
        (
            "wrong count",
            put(
                count_at,
                (header.section(Section::Polygons).count as u32 + 1).to_le_bytes(),
            ),
            format!(
                "byte {}: section 'nodes' starts at byte",
                40 + 24 * Section::Nodes as usize
            ),
        ),
        (
            "nan",
            put(at(Section::Vertices, 3) + 8, f32::NAN.to_le_bytes()),
            format!("byte {}:", at(Section::Vertices, 3)),
        ),
        (
            "infinite",
            put(at(Section::Values, 2), f32::INFINITY.to_le_bytes()),
            format!("byte {}:", at(Section::Values, 2)),
        ),
        (
            "index out of range",
            put(at(Section::Polygons, 5) + 4, 5000u32.to_le_bytes()),
            format!("byte {}:", at(Section::Polygons, 5)),
        ),
        (
            "cycle",
            put(at(Section::Instances, 0), 1u32.to_le_bytes()),
            format!(
                "byte {}: instance 0: original 1 is the original being defined",
                at(Section::Instances, 0)
            ),
        ),
        (
            "absurd size",
            Box::new(move |b: &mut Vec<u8>| {
                b[count_at..count_at + 8].copy_from_slice(&(1u64 << 50).to_le_bytes())
            }),
            format!("byte {count_at}: section 'polygons' claims an absurd record count"),
        ),
    ];
    for (what, patch, location) in bin_cases {
        let mut b = bytes.clone();
        patch(&mut b);
        let p = dir.path().join("bad.hirb");
        std::fs::write(&p, &b).unwrap();
        let err = fails(&["info", s(&p)]);
        let prefix = format!("error: {}: {location}", p.display());
        assert!(
            err.starts_with(&prefix),
            "{what}: expected '{prefix}...', got {err}"
        );
    }
}
