//! Rendering through the image sink: depth order, sides, clipping, supersampling, and the
//! EXR and PNG files read back with their own crates.

use super::camera::Size;
use super::frame::{Frame, channel_names};
use super::image::ImageSink;
use super::png_file::{exposure, srgb_encode, tone_map};
use super::raster::Rasterizer;
use super::read_exr;
use crate::scene::Camera;
use glam::Vec3;
use hirad_core::sink::{PatchResult, Sink};
use std::f32::consts::PI;

/// 5 m in front of the origin along +y, z up, 90 degrees vertically: on 40 x 20 pixels,
/// 1 m at distance d spans 10 / d pixels.
fn camera() -> Camera {
    Camera {
        name: None,
        position: Vec3::new(0.0, -5.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::Z,
        fovy_deg: 90.0,
    }
}

const SIZE: Size = Size {
    width: 40,
    height: 20,
};

/// A square in the plane y = `y`, half side `h`, centred on (`cx`, `y`, `cz`); its front
/// faces the camera (-y) unless `away`.
fn square(cx: f32, y: f32, cz: f32, h: f32, away: bool) -> (Vec<Vec3>, Vec3) {
    let mut c = vec![
        Vec3::new(cx - h, y, cz - h),
        Vec3::new(cx + h, y, cz - h),
        Vec3::new(cx + h, y, cz + h),
        Vec3::new(cx - h, y, cz + h),
    ];
    if away {
        c.reverse();
        (c, Vec3::Y)
    } else {
        (c, -Vec3::Y)
    }
}

struct Patch {
    corners: Vec<Vec3>,
    normal: Vec3,
    front: Vec<f32>,
    back: Vec<f32>,
}

fn patch((corners, normal): (Vec<Vec3>, Vec3), front: &[f32], back: &[f32]) -> Patch {
    Patch {
        corners,
        normal,
        front: front.to_vec(),
        back: back.to_vec(),
    }
}

fn feed(sink: &mut impl Sink<Error = anyhow::Error>, patches: &[Patch]) {
    for (id, p) in patches.iter().enumerate() {
        sink.patch(&PatchResult {
            id: id as u64,
            corners: &p.corners,
            normal: p.normal,
            material: 0,
            radiosity: [&p.front, &p.back],
        })
        .unwrap();
    }
}

fn render(size: Size, ss: u32, bands: usize, patches: &[Patch]) -> Frame {
    render_with(&camera(), size, ss, bands, patches)
}

fn render_with(c: &Camera, size: Size, ss: u32, bands: usize, patches: &[Patch]) -> Frame {
    let mut r = Rasterizer::new(c, size, ss, bands).unwrap();
    feed(&mut r, patches);
    r.frame(channel_names(bands, &[]))
}

/// Red (radiance 1) 1 m square at 5 m, green (radiance 2) 3 m square behind it at 7 m.
fn red_and_green() -> [Patch; 2] {
    [
        patch(square(0.0, 0.0, 0.0, 1.0, false), &[PI, 0.0, 0.0], &[]),
        patch(
            square(0.0, 2.0, 0.0, 3.0, false),
            &[0.0, 2.0 * PI, 0.0],
            &[],
        ),
    ]
}

#[test]
fn nearer_patch_wins_in_either_order() {
    let [red, green] = red_and_green();
    let a = render(SIZE, 1, 3, &[red, green]);
    let [red, green] = red_and_green();
    let b = render(SIZE, 1, 3, &[green, red]);
    assert_eq!(a, b);
    // Red covers pixels 18..=21 both ways, green 16..=23 (its edges at 20 -+ 30 / 7).
    assert_eq!(a.pixel(20, 10), &[1.0, 0.0, 0.0]);
    assert_eq!(a.pixel(18, 8), &[1.0, 0.0, 0.0]);
    assert_eq!(a.pixel(16, 10), &[0.0, 2.0, 0.0]);
    assert_eq!(a.pixel(23, 13), &[0.0, 2.0, 0.0]);
    assert_eq!(a.pixel(0, 0), &[0.0; 3]);
    assert_eq!(a.pixel(39, 19), &[0.0; 3]);
    assert_eq!(a.pixel(24, 10), &[0.0; 3]);
}

#[test]
fn a_point_lands_on_its_pixel_with_the_origin_top_left() {
    // (1.25, 0, 1.25) is 2.5 pixels right of and above the centre (20, 10): the centre of
    // pixel (22, 7). A 0.2 m square around it covers that pixel centre and no other.
    let f = render(
        SIZE,
        1,
        1,
        &[patch(square(1.25, 0.0, 1.25, 0.1, false), &[PI], &[])],
    );
    for y in 0..SIZE.height {
        for x in 0..SIZE.width {
            let want = if (x, y) == (22, 7) { 1.0 } else { 0.0 };
            assert_eq!(f.pixel(x, y), &[want], "pixel {x},{y}");
        }
    }
}

#[test]
fn the_side_facing_the_camera_shows() {
    let two = patch(
        square(0.0, 0.0, 0.0, 1.0, true),
        &[PI, PI, PI],
        &[0.0, 0.0, 3.0 * PI],
    );
    let f = render(SIZE, 1, 3, &[two]);
    assert_eq!(f.pixel(20, 10), &[0.0, 0.0, 3.0]);
    // A one-sided patch seen from behind is black and still hides what is behind it.
    let [_, green] = red_and_green();
    let one = patch(square(0.0, 0.0, 0.0, 1.0, true), &[PI, PI, PI], &[]);
    let f = render(SIZE, 1, 3, &[green, one]);
    assert_eq!(f.pixel(20, 10), &[0.0; 3]);
    assert_eq!(f.pixel(16, 10), &[0.0, 2.0, 0.0]);
}

#[test]
fn patches_through_the_eye_plane_are_clipped() {
    // A floor 1 m below the eye, from 5 m behind it to 15 m ahead.
    let floor = Patch {
        corners: vec![
            Vec3::new(-10.0, -10.0, -1.0),
            Vec3::new(10.0, -10.0, -1.0),
            Vec3::new(10.0, 10.0, -1.0),
            Vec3::new(-10.0, 10.0, -1.0),
        ],
        normal: Vec3::Z,
        front: vec![PI],
        back: vec![],
    };
    let f = render(SIZE, 1, 1, &[floor]);
    assert_eq!(f.pixel(20, 19), &[1.0]);
    assert_eq!(f.pixel(0, 19), &[1.0]);
    assert_eq!(f.pixel(20, 0), &[0.0]);
}

#[test]
fn supersampling_averages_samples() {
    // From 1 m, 90 degrees, 2 x 2 pixels: each pixel is 1 m of the plane y = 0. A strip
    // x in [-1, -0.5] covers the left half of the left pixels: 2 of their 4 samples.
    let c = Camera {
        position: Vec3::new(0.0, -1.0, 0.0),
        ..camera()
    };
    let strip = Patch {
        corners: vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(-0.5, 0.0, -1.0),
            Vec3::new(-0.5, 0.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
        ],
        normal: -Vec3::Y,
        front: vec![PI],
        back: vec![],
    };
    let size = Size {
        width: 2,
        height: 2,
    };
    let f = render_with(&c, size, 2, 1, &[strip]);
    assert_eq!(f.data, vec![0.5, 0.0, 0.5, 0.0]);
}

#[test]
fn bad_patches_and_settings_are_refused() {
    let mut r = Rasterizer::new(&camera(), SIZE, 1, 3).unwrap();
    let (corners, normal) = square(0.0, 0.0, 0.0, 1.0, false);
    let p = |front: &'static [f32], back: &'static [f32]| (front, back);
    for (front, back) in [
        p(&[1.0, 2.0], &[]),
        p(&[1.0; 3], &[1.0]),
        p(&[f32::NAN; 3], &[]),
    ] {
        let e = r.patch(&PatchResult {
            id: 9,
            corners: &corners,
            normal,
            material: 0,
            radiosity: [front, back],
        });
        assert!(e.unwrap_err().to_string().contains("polygon 9"));
    }
    assert!(r.draw(&corners[..2], normal, [&[1.0; 3], &[]]).is_err());
    assert!(Rasterizer::new(&camera(), SIZE, 0, 3).is_err());
    let flat = Size {
        width: 4,
        height: 0,
    };
    assert!(Rasterizer::new(&camera(), flat, 1, 3).is_err());
    assert!(Rasterizer::new(&camera(), SIZE, 9, 3).is_err());
    let huge = Size {
        width: 16384,
        height: 16384,
    };
    assert!(
        Rasterizer::new(&camera(), huge, 1, 1)
            .unwrap_err()
            .to_string()
            .contains("at most")
    );
}

#[test]
fn channel_names_follow_the_bands() {
    assert_eq!(channel_names(1, &["grey".into()]), ["Y"]);
    assert_eq!(channel_names(3, &[]), ["R", "G", "B"]);
    assert_eq!(
        channel_names(2, &["par".into(), "nir".into()]),
        ["par", "nir"]
    );
    assert_eq!(
        channel_names(2, &["a".into(), "a".into()]),
        ["band_0", "band_1"]
    );
    assert_eq!(
        channel_names(4, &[]),
        ["band_0", "band_1", "band_2", "band_3"]
    );
}

#[test]
fn exr_holds_linear_radiance() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("view.exr");
    let mut sink = ImageSink::new(&path, &camera(), SIZE, 1, 3, &[]).unwrap();
    feed(&mut sink, &red_and_green());
    let rendered = sink.frame();
    sink.finish().unwrap();
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["view.exr"], "no temporary file is left");

    let f = read_exr(&path).unwrap();
    assert_eq!((f.width, f.height), (40, 20));
    assert_eq!(f.channels, ["B", "G", "R"], "EXR stores channels sorted");
    let (r, g, b) = (
        f.channel("R").unwrap(),
        f.channel("G").unwrap(),
        f.channel("B").unwrap(),
    );
    for y in 0..20 {
        for x in 0..40 {
            let got = f.pixel(x, y);
            assert_eq!(
                [got[r], got[g], got[b]],
                rendered.pixel(x, y),
                "pixel {x},{y}"
            );
        }
    }
    assert_eq!(f.pixel(20, 10)[r], 1.0);
    assert_eq!(f.pixel(16, 10)[g], 2.0);
    assert_eq!(f.pixel(0, 0), &[0.0; 3]);

    // One band is channel Y.
    let path = dir.path().join("grey.exr");
    let mut sink = ImageSink::new(&path, &camera(), SIZE, 1, 1, &[]).unwrap();
    feed(
        &mut sink,
        &[patch(square(0.0, 0.0, 0.0, 1.0, false), &[2.0 * PI], &[])],
    );
    sink.finish().unwrap();
    let f = read_exr(&path).unwrap();
    assert_eq!(f.channels, ["Y"]);
    assert_eq!(f.pixel(20, 10), &[2.0]);
}

#[test]
fn png_is_an_srgb_preview_of_the_right_size() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("view.PNG");
    let mut sink = ImageSink::new(&path, &camera(), SIZE, 1, 3, &[]).unwrap();
    feed(&mut sink, &red_and_green());
    sink.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (40, 20));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let px = |x: usize, y: usize| &buf[(y * 40 + x) * 3..(y * 40 + x) * 3 + 3];
    assert!(px(20, 10)[0] > 100 && px(20, 10)[1] == 0 && px(20, 10)[2] == 0);
    assert!(px(16, 10)[1] > 200 && px(16, 10)[0] == 0);
    assert_eq!(px(0, 0), &[0, 0, 0]);
    assert!(ImageSink::new(&dir.path().join("x.tif"), &camera(), SIZE, 1, 3, &[]).is_err());
}

#[test]
fn tone_mapping() {
    // 1 band, values 0..=99 and 1000: 100 lit pixels, the 99th percentile is the value 99.
    let frame = Frame {
        width: 101,
        height: 1,
        channels: vec!["Y".into()],
        data: (0..=100)
            .map(|v| if v == 100 { 1000.0 } else { v as f32 })
            .collect(),
    };
    assert_eq!(exposure(&frame), 0.9 / 99.0);
    let rgb = tone_map(&frame);
    assert_eq!(rgb.len(), 303);
    assert_eq!(&rgb[..3], &[0, 0, 0]);
    assert_eq!(&rgb[300..], &[255, 255, 255], "above the percentile clips");
    let at99 = (srgb_encode(0.9) * 255.0 + 0.5) as u8;
    assert_eq!(&rgb[297..300], &[at99; 3]);
    // 2 bands: red = band 1, green = blue = band 0.
    let frame = Frame {
        width: 2,
        height: 1,
        channels: vec!["par".into(), "nir".into()],
        data: vec![1.0, 0.0, 0.0, 1.0],
    };
    let rgb = tone_map(&frame);
    assert!(rgb[0] == 0 && rgb[1] > 0 && rgb[1] == rgb[2]);
    assert!(rgb[3] > 0 && rgb[4] == 0 && rgb[5] == 0);
    assert_eq!(srgb_encode(0.0), 0.0);
    assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
    // A black frame keeps exposure 1.
    let black = Frame {
        width: 1,
        height: 1,
        channels: vec!["Y".into()],
        data: vec![0.0],
    };
    assert_eq!(exposure(&black), 1.0);
}
