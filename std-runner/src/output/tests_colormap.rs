//! The colour-map display: viridis, the scale and its labels, the bar drawn into the
//! picture, and which display a scene gets.

use super::camera::Size;
use super::colorbar::{MapDisplay, Scale, layout, map_pixels, title};
use super::colormap::{viridis, viridis_u8};
use super::display::{Display, DisplayMode};
use super::frame::Frame;
use super::image::ImageSink;
use super::png_file::DisplayBands;
use crate::scene::Camera;
use glam::Vec3;
use hirad_core::sink::{PatchResult, Sink};
use std::f32::consts::PI;

fn linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * linear(c[0]) + 0.7152 * linear(c[1]) + 0.0722 * linear(c[2])
}

#[test]
fn viridis_is_monotone_in_luminance_with_its_ends_at_0_and_1() {
    assert_eq!(viridis(0.0), [0.267004, 0.004874, 0.329415]);
    assert_eq!(viridis(1.0), [0.993248, 0.906157, 0.143936]);
    assert_eq!(viridis(-3.0), viridis(0.0));
    assert_eq!(viridis(7.0), viridis(1.0));
    assert_eq!(viridis(f32::NAN), viridis(0.0));
    let mut last = luminance(viridis(0.0));
    for k in 1..=1000 {
        let l = luminance(viridis(k as f32 / 1000.0));
        assert!(l > last, "luminance falls at {k}/1000");
        last = l;
    }
    // Matplotlib's viridis(0.5) is entry 128.
    assert!((viridis(128.0 / 255.0)[1] - 0.566949).abs() < 1e-6);
}

#[test]
fn the_scale_is_round_and_covers_the_values() {
    let s = Scale::new(37.2);
    assert_eq!(s.top, 40.0);
    assert_eq!(s.ticks, [0.0, 10.0, 20.0, 30.0, 40.0]);
    assert_eq!(s.label(20.0), "20");
    let s = Scale::new(0.61);
    assert!((s.top - 0.8).abs() < 1e-12);
    assert!(s.ticks.len() >= 3 && s.ticks.len() <= 7);
    assert_eq!(s.ticks[0], 0.0);
    assert!(s.ticks.iter().all(|t| *t <= s.top * (1.0 + 1e-9)));
    assert_eq!(s.label(s.ticks[1]), format!("{:.1}", s.ticks[1]));
    let s = Scale::new(2.3e6);
    assert!(s.top >= 2.3e6 && s.top <= 2.3e6 * 1.3);
    assert!(s.label(s.ticks[1]).contains('e'));
    for high in [0.013, 1.0, 1.01, 99.0, 1234.5, 7e-5] {
        let s = Scale::new(high);
        assert!(s.top >= high && s.top <= high * 1.26, "{high}: {}", s.top);
    }
}

/// A `w` x `h` PAR/NIR frame whose PAR radiance rises from left to right (0 in the
/// leftmost column: nothing there).
fn ramp(w: u32, h: u32) -> Frame {
    let mut data = Vec::new();
    for _ in 0..h {
        for x in 0..w {
            data.push(x as f32 / PI);
            data.push(100.0);
        }
    }
    Frame {
        width: w,
        height: h,
        channels: vec!["par".into(), "nir".into()],
        data,
    }
}

fn par() -> MapDisplay {
    MapDisplay {
        band: 0,
        name: "PAR".into(),
    }
}

#[test]
fn the_bar_follows_the_map_and_is_labelled() {
    let (w, h) = (400, 300);
    let f = ramp(w, h);
    let (rgb, scale) = map_pixels(&f, &par());
    assert!(
        scale.top >= 0.99 * 399.0,
        "the 99th percentile of 0..399 W/m^2"
    );
    let labels: Vec<String> = scale.ticks.iter().map(|v| scale.label(*v)).collect();
    let l = layout(w, h, &labels, &title(&par())).expect("room for a bar");
    let at = |x: u32, y: u32| {
        let i = (y * w + x) as usize * 3;
        [rgb[i], rgb[i + 1], rgb[i + 2]]
    };
    // The bar's left column follows the map from 0 at the bottom to the top.
    let span = (l.bottom - l.top) as f32;
    for y in l.top..=l.bottom {
        assert_eq!(
            at(l.x0, y),
            viridis_u8((l.bottom - y) as f32 / span),
            "row {y}"
        );
    }
    assert_eq!(at(l.x0, l.bottom), viridis_u8(0.0));
    assert_eq!(at(l.x0, l.top), viridis_u8(1.0));
    // White text right of the bar (tick labels) and above it (the title).
    let white = |xs: std::ops::Range<u32>, ys: std::ops::Range<u32>| {
        ys.flat_map(|y| xs.clone().map(move |x| (x, y)))
            .filter(|&(x, y)| at(x, y) == [255, 255, 255])
            .count()
    };
    assert!(white(l.x1..w, l.top..h) > 20, "tick labels");
    assert!(white(l.panel..w, 0..l.top) > 20, "title");
    assert_eq!(white(0..l.panel, 0..h), 0, "no text over the scene");
    // The scene: nothing is black, the rest follows the map and rises with the value.
    assert_eq!(at(0, 10), [0, 0, 0]);
    let v = 100.0 / scale.top;
    assert_eq!(at(100, 10), viridis_u8(v as f32));
    let lum = |c: [u8; 3]| luminance(c.map(|x| f32::from(x) / 255.0));
    // (8-bit rounding may dim a neighbour a little: compare columns 8 apart.)
    for x in 1..l.panel - 8 {
        assert!(lum(at(x + 8, 10)) > lum(at(x, 10)), "column {x}");
    }
}

#[test]
fn small_pictures_have_no_bar() {
    let f = ramp(40, 20);
    let (rgb, _) = map_pixels(&f, &par());
    let lit = (1..40).all(|x| rgb[(10 * 40 + x) * 3..(10 * 40 + x) * 3 + 3] != [0, 0, 0]);
    assert!(lit, "every lit pixel keeps its colour");
}

#[test]
fn which_display_a_scene_gets() {
    let names = |n: &[&str]| n.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let pn = names(&["par", "nir"]);
    assert_eq!(Display::default_for(2, &pn), Display::Map(par()));
    assert_eq!(
        Display::default_for(2, &names(&["NIR", "PAR"])),
        Display::Map(MapDisplay {
            band: 1,
            name: "PAR".into()
        })
    );
    assert_eq!(
        Display::default_for(3, &names(&["red", "green", "blue"])),
        Display::Bands(DisplayBands([0, 1, 2]))
    );
    assert_eq!(
        Display::default_for(2, &names(&["a", "b"])),
        Display::Bands(DisplayBands([1, 0, 0]))
    );
    assert_eq!(
        Display::choose(None, Some("nir"), 2, &pn),
        Ok(Display::Bands(DisplayBands([1, 1, 1])))
    );
    assert_eq!(
        Display::choose(Some(DisplayMode::Bands), None, 2, &pn),
        Ok(Display::Bands(DisplayBands([1, 0, 0])))
    );
    assert!(Display::choose(Some(DisplayMode::Map), Some("par"), 2, &pn).is_err());
    let grey = Display::choose(Some(DisplayMode::Map), None, 1, &names(&["grey"])).unwrap();
    assert_eq!(
        grey,
        Display::Map(MapDisplay {
            band: 0,
            name: "GREY".into()
        })
    );
    assert!(
        Display::default_for(2, &pn)
            .note(2, &pn, false)
            .unwrap()
            .contains("viridis")
    );
    assert_eq!(Display::default_for(3, &[]).note(3, &[], false), None);
}

#[test]
fn a_par_nir_png_shows_the_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.png");
    let camera = Camera {
        name: None,
        position: Vec3::new(0.0, -2.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::Z,
        fovy_deg: 90.0,
    };
    let size = Size {
        width: 320,
        height: 240,
    };
    let names = vec!["par".to_string(), "nir".to_string()];
    let mut sink = ImageSink::new(&path, &camera, size, 1, 2, &names).unwrap();
    let corners = [
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(-1.0, 0.0, 1.0),
    ];
    sink.patch(&PatchResult {
        id: 0,
        corners: &corners,
        normal: -Vec3::Y,
        material: 0,
        radiosity: [&[30.0, 50.0], &[]],
    })
    .unwrap();
    sink.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (320, 240));
    // PAR radiosity 30 W/m^2 on a scale to 30: the top colour.
    let c = (120 * 320 + 120) * 3;
    assert_eq!(&buf[c..c + 3], &viridis_u8(1.0));
}
