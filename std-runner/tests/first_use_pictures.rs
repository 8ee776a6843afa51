//! A new user's first hour (issue 9), the pictures: a default view that shows the scene
//! upright, a nearly black picture that says why, false colour explained and chosen, a
//! scene's up kept through OBJ. The other items are in `first_use.rs`.

mod common;
use common::{canopy, fixture, hirad, ok, s, write};
use std::path::Path;

/// The pixels of an 8-bit RGB PNG.
fn png_pixels(path: &Path) -> Vec<[u8; 3]> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf[..info.buffer_size()]
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

/// Item 9: a two-band picture (PAR/NIR, plants' default) says what it shows: by default PAR
/// through a colour map with a bar (issue 16); `--display bands` shows the bands in false
/// colour, saying which band each colour shows, and `--display-bands` chooses them.
#[test]
fn false_colour_is_explained_and_chosen() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = canopy(d, 1, 2);
    let run = |extra: &[&str], png: &Path| {
        let mut args = vec![
            "solve",
            s(&scene),
            "--image",
            s(png),
            "--max-imbalance",
            "100",
        ];
        args.extend_from_slice(extra);
        let out = hirad(&args);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{err}");
        err
    };
    let map = d.join("m.png");
    let err = run(&[], &map);
    assert!(
        err.contains("PAR radiosity (W/m^2) through the viridis colour map")
            && err.contains("--display bands"),
        "{err}"
    );
    let px = png_pixels(&map);
    assert!(px.contains(&[255, 255, 255]), "no labels on the colour bar");
    let false_colour = d.join("f.png");
    let err = run(&["--display", "bands"], &false_colour);
    assert!(
        err.contains("red = nir, green = par, blue = par") && err.contains("--display-bands"),
        "{err}"
    );
    let grey = d.join("g.png");
    let err = run(&["--display-bands", "nir"], &grey);
    assert!(err.contains("grey = nir"), "{err}");
    let px = png_pixels(&grey);
    assert!(px.iter().all(|p| p[0] == p[1] && p[1] == p[2]), "not grey");
    assert!(px.iter().any(|p| p[0] > 0), "black");
    // In false colour the leaves (NIR much brighter than PAR) look red.
    let px = png_pixels(&false_colour);
    assert!(
        px.iter().any(|p| p[0] > p[1]),
        "no red in the false colour picture"
    );
    // Bands are checked, by name or index.
    let e = String::from_utf8_lossy(
        &hirad(&[
            "solve",
            s(&scene),
            "--image",
            s(&d.join("x.png")),
            "--display-bands",
            "red",
        ])
        .stderr,
    )
    .to_string();
    assert!(
        e.contains("`red` is not a band of this scene") && e.contains("par"),
        "{e}"
    );
    assert!(!d.join("x.png").exists());
}

/// Item 1: an OBJ room without a camera shows its walls at the default settings (the open
/// side of the Cornell box as exporters write it; a closed room from inside), and a picture
/// that comes out nearly black says why.
#[test]
fn default_pictures_show_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let share = |px: &[[u8; 3]], f: &dyn Fn(&[u8; 3]) -> bool| {
        px.iter().filter(|p| f(p)).count() as f64 / px.len() as f64
    };
    // The Cornell box as 32 triangles: seen through its open side, red and green walls.
    let png = d.join("box.png");
    ok(&[
        "solve",
        s(&fixture("obj/cornell_triangles.obj")),
        "--image",
        s(&png),
        "-q",
    ]);
    let px = png_pixels(&png);
    assert!(
        share(&px, &|p| p.iter().any(|&v| v > 20)) > 0.25,
        "mostly black"
    );
    assert!(
        share(&px, &|p| 10 * u16::from(p[0]) > 13 * u16::from(p[1])
            && p[0] > 60)
            > 0.02,
        "no red wall"
    );
    assert!(
        share(&px, &|p| 10 * u16::from(p[1]) > 13 * u16::from(p[0])
            && p[1] > 60)
            > 0.02,
        "no green wall"
    );
    // The same box closed by a front wall: from inside.
    let src = std::fs::read_to_string(fixture("obj/cornell_triangles.obj")).unwrap();
    let vertices = src.lines().filter(|l| l.starts_with("v ")).count();
    let closed = format!(
        "{}\ng front\nusemtl white\nv 0.5528 0 0\nv 0.556 0.5488 0\nv 0 0.5488 0\nv 0 0 0\nf {} {} {}\nf {} {} {}\n",
        src.replace(
            "mtllib cornell_triangles.mtl",
            &format!("mtllib {}", s(&fixture("obj/cornell_triangles.mtl")))
        ),
        vertices + 1,
        vertices + 2,
        vertices + 3,
        vertices + 1,
        vertices + 3,
        vertices + 4
    );
    let obj = write(d, "closed.obj", &closed);
    let png = d.join("closed.png");
    ok(&[
        "solve",
        s(&obj),
        "--image",
        s(&png),
        "--final-rays",
        "0",
        "--max-imbalance",
        "100",
        "-q",
    ]);
    let px = png_pixels(&png);
    assert!(
        share(&px, &|p| p.iter().any(|&v| v > 20)) > 0.5,
        "a closed room from outside"
    );
    // A camera that looks away: the picture is black, and the run says why.
    let png = d.join("away.png");
    let out = hirad(&[
        "solve",
        s(&fixture("obj/cornell_triangles.obj")),
        "--image",
        s(&png),
        "--camera",
        "0.3,0.3,-2,0.3,0.3,-3,0,1,0,40",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("nearly black") && err.contains("--camera"),
        "{err}"
    );
    // From outside the closed room: the backs of its walls are named.
    let out = hirad(&[
        "solve",
        s(&obj),
        "--image",
        s(&d.join("out.png")),
        "--camera",
        "0.27,0.27,-2,0.27,0.27,0.27,0,1,0,40",
        "--final-rays",
        "0",
        "--max-imbalance",
        "100",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("backs of one-sided polygons"), "{err}");
}

/// Item 1, its sibling: a scene keeps its up through OBJ. hirad's scenes are z up, OBJ files
/// y up: `flatten` turns one into the other (and says so), `convert` turns an OBJ back, and
/// the default view of the OBJ is upright (the lamps on the ceiling at the top of the
/// picture; before, the flattened room was read lying on its side), and the view chosen is
/// said as the `--camera` that gives it back. `--up` names another axis, checked.
#[test]
fn a_scene_keeps_its_up_through_obj() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let room = d.join("room.hirb");
    ok(&[
        "gen",
        "room",
        "--chairs",
        "0",
        "--tables",
        "0",
        "--orchids",
        "0",
        "--plants",
        "1",
        "-q",
        "-o",
        s(&room),
    ]);
    let obj = d.join("room.obj");
    let out = hirad(&["flatten", s(&room), "-o", s(&obj)]);
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("+z axis is written as +y"), "{err}");
    let text = std::fs::read_to_string(&obj).unwrap();
    assert!(text.contains("# The scene's +z axis is written as +y"));
    // Upright: the saturated pixels (the ceiling's lamp panels) in the picture's top half.
    let png = d.join("room.png");
    let out = hirad(&["solve", s(&obj), "--image", s(&png), "--size", "160x120"]);
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    // The view chosen is said as the --camera that gives it back.
    let camera = err
        .lines()
        .find_map(|l| l.strip_prefix("note: the default view, +y up: --camera "))
        .unwrap_or_else(|| panic!("{err}"))
        .split(' ')
        .next()
        .unwrap()
        .to_string();
    let again = d.join("again.png");
    let size = ["--size", "160x120", "-q"];
    ok(&[
        &["solve", s(&obj), "--image", s(&again), "--camera", &camera],
        &size[..],
    ]
    .concat());
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&png).unwrap());
    let px = png_pixels(&png);
    let lamps: Vec<usize> = (0..px.len())
        .filter(|&i| px[i].iter().all(|&v| v >= 250))
        .collect();
    let top = lamps.iter().filter(|&&i| i / 160 < 60).count();
    assert!(lamps.len() > 20, "{} lamp pixels", lamps.len());
    assert!(
        top * 10 >= lamps.len() * 9,
        "{top} of {} lamp pixels in the top half",
        lamps.len()
    );
    // Back to z up: the same coordinates as the scene it came from.
    let back = d.join("back.hir");
    let err =
        String::from_utf8_lossy(&hirad(&["convert", s(&obj), "-o", s(&back)]).stderr).into_owned();
    assert!(err.contains("+y axis becomes +z"), "{err}");
    // `info` says which axis is up, and why.
    assert!(ok(&["info", s(&obj)]).contains("up axis           +y (the OBJ convention"));
    assert!(ok(&["info", s(&back)]).contains("up axis           +z (hirad's default"));
    assert!(ok(&["info", s(&room)]).contains("up axis           +z (its first camera"));
    let again = d.join("again.obj");
    ok(&["flatten", s(&back), "-o", s(&again), "-q"]);
    let vertices = |p: &Path| -> Vec<String> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .filter(|l| l.starts_with("v "))
            .map(String::from)
            .collect()
    };
    assert_eq!(vertices(&again), vertices(&obj));
    // Another axis, named; a wrong one refused with the choices; one with no effect warned.
    let side = d.join("side.obj");
    ok(&["flatten", s(&room), "-o", s(&side), "--up", "-x", "-q"]);
    let first = |p: &Path| vertices(p).into_iter().nth(1).unwrap();
    assert_ne!(first(&side), first(&obj));
    let out = hirad(&["flatten", s(&room), "-o", s(&side), "--up", "w"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("not an axis") && err.contains("-z"), "{err}");
    let out = hirad(&["solve", s(&obj), "--up", "y", "--final-rays", "0"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--up has no effect without --image"), "{err}");
}
