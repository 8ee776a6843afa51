//! `hirad tables --plot DIR`: one PNG per original and band with three maps over the sphere
//! of directions, each with its colour bar and unit (in the spirit of the paper's figure
//! 3d): `tau` towards the sun, the power scattered out per W/m^2 of sun (the uniform phase
//! function, m^2), and the bidirectional intensity towards each observer for one sun
//! (m^2/sr, the sun marked by a white cross).
//!
//! Labels use the pictures' small font (capitals, digits, `+ - . / ^ ( ) _`).
//!
//! Maps are equirectangular in the original's frame: azimuth from +x towards +y across
//! (0 to 360 degrees), elevation above the x-y plane up (+90 at the top, -90 at the bottom).

use super::OriginalTables;
use crate::output::colorbar::{Scale, draw_titled_bar, layout, tick_labels};
use crate::output::colormap::viridis_u8;
use crate::output::font::{HEIGHT, draw_text};
use crate::output::png_file::write_rgb_png;
use anyhow::{Context, Result};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// Pixels per degree of the maps.
const PX_PER_DEGREE: u32 = 2;
/// Width of a map (pixels).
const MAP_W: u32 = 360 * PX_PER_DEGREE;
/// Height of a map (pixels).
const MAP_H: u32 = 180 * PX_PER_DEGREE;
/// Left margin for the elevation labels, and the rows of a panel's title and of the
/// azimuth labels (pixels).
const LEFT: u32 = 40;
const TOP: u32 = 2 * (HEIGHT + 4);
const BOTTOM: u32 = HEIGHT + 8;

/// The sun of the bidirectional map: azimuth 45 degrees, elevation 60 degrees.
pub fn plot_sun() -> Vec3 {
    direction(45.0, 60.0)
}

/// The unit direction at azimuth `az` and elevation `el` (degrees).
fn direction(az: f32, el: f32) -> Vec3 {
    let (a, e) = (az.to_radians(), el.to_radians());
    Vec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin())
}

/// The direction at the centre of pixel (`x`, `y`) of a map.
fn pixel_direction(x: u32, y: u32) -> Vec3 {
    let az = (x as f32 + 0.5) / PX_PER_DEGREE as f32;
    let el = 90.0 - (y as f32 + 0.5) / PX_PER_DEGREE as f32;
    direction(az, el)
}

/// One map: its title lines, unit, values per pixel and fixed top (None: from the values).
struct Map {
    title: String,
    unit: &'static str,
    values: Vec<f32>,
    top: Option<f64>,
    mark: Option<Vec3>,
}

/// The three maps of `t`'s band `band` (see the module).
fn maps(t: &OriginalTables, band: usize) -> [Map; 3] {
    let view = t.view();
    let pixels = (MAP_W * MAP_H) as usize;
    let each = |f: &dyn Fn(Vec3) -> f32| -> Vec<f32> {
        (0..pixels as u32)
            .map(|i| f(pixel_direction(i % MAP_W, i / MAP_W)))
            .collect()
    };
    let sun = plot_sun();
    [
        Map {
            title: "TAU TOWARDS THE SUN (UNCOLLIDED TRANSMITTANCE)".into(),
            unit: "1",
            values: each(&|d| view.tau(d)),
            top: Some(1.0),
            mark: None,
        },
        Map {
            title: "SCATTERED POWER BY SUN DIRECTION (UNIFORM PHASE)".into(),
            unit: "W PER W/m^2",
            values: each(&|d| view.scattered(d, band)),
            top: None,
            mark: None,
        },
        Map {
            title: "INTENSITY TO THE OBSERVER - SUN AT AZ 45 EL 60 (BIDIRECTIONAL)".into(),
            unit: "W/SR PER W/m^2",
            values: each(&|o| view.intensity(sun, o, band)),
            top: None,
            mark: Some(sun),
        },
    ]
}

/// Draws one map panel: title, map, axis labels, colour bar. Returns its pixels and width.
fn panel(map: &Map, height: u32) -> (Vec<u8>, u32) {
    let high = map.top.unwrap_or_else(|| {
        map.values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0f32, f32::max) as f64
    });
    let scale = Scale::new(high);
    let title = vec![map.unit.to_string()];
    // The bar's panel width, from a layout of a wide image of this height.
    let probe = 10 * MAP_W;
    let bar_w = layout(probe, height, &tick_labels(&scale), &title).map_or(0, |l| probe - l.panel);
    let width = LEFT + MAP_W + 8 + bar_w;
    let mut rgb = vec![0u8; (width * height * 3) as usize];
    let white = [255, 255, 255];
    draw_text(
        &mut rgb,
        width,
        height,
        LEFT.into(),
        2,
        1,
        &map.title,
        white,
    );
    for y in 0..MAP_H {
        for x in 0..MAP_W {
            let v = map.values[(y * MAP_W + x) as usize];
            let c = viridis_u8((v as f64 / scale.top) as f32);
            let at = (((TOP + y) * width + LEFT + x) * 3) as usize;
            rgb[at..at + 3].copy_from_slice(&c);
        }
    }
    if let Some(d) = map.mark {
        let az = d.y.atan2(d.x).to_degrees().rem_euclid(360.0);
        let el = d.z.clamp(-1.0, 1.0).asin().to_degrees();
        let (cx, cy) = (
            (az * PX_PER_DEGREE as f32) as i64,
            ((90.0 - el) * PX_PER_DEGREE as f32) as i64,
        );
        for k in -6i64..=6 {
            for (x, y) in [(cx + k, cy), (cx, cy + k)] {
                if (0..MAP_W as i64).contains(&x) && (0..MAP_H as i64).contains(&y) {
                    let at = (((TOP as i64 + y) * width as i64 + LEFT as i64 + x) * 3) as usize;
                    rgb[at..at + 3].copy_from_slice(&white);
                }
            }
        }
    }
    // Axes: elevation at the left, azimuth below.
    for el in [90i32, 45, 0, -45, -90] {
        let y = TOP as i64 + ((90 - el) as u32 * PX_PER_DEGREE) as i64 - HEIGHT as i64 / 2;
        let y = y.clamp(0, (TOP + MAP_H) as i64 - HEIGHT as i64);
        draw_text(&mut rgb, width, height, 2, y, 1, &format!("{el:+}"), white);
    }
    for az in (0..=360).step_by(45) {
        let x = (LEFT + az * PX_PER_DEGREE) as i64 - 6;
        let label = if az == 360 {
            "360 AZ".to_string()
        } else {
            az.to_string()
        };
        let x = x.min((LEFT + MAP_W) as i64 - 6 * label.len() as i64);
        draw_text(
            &mut rgb,
            width,
            height,
            x,
            (TOP + MAP_H + 3).into(),
            1,
            &label,
            white,
        );
    }
    // The bar in the panel's right part, which `layout` places there for this width.
    draw_titled_bar(&mut rgb, width, height, &title, &scale);
    (rgb, width)
}

/// Rows of the header line above the panels.
const HEAD: u32 = HEIGHT * 2 + 8;

/// Where the direction at azimuth `az` and elevation `el` (degrees) is drawn in map `panel`
/// (0 tau, 1 scattered power, 2 bidirectional) of a [`picture`]: its pixel column and row.
pub fn map_pixel(panel: u32, az: f32, el: f32) -> (u32, u32) {
    let x = ((az.rem_euclid(360.0) * PX_PER_DEGREE as f32) as u32).min(MAP_W - 1);
    let y = (((90.0 - el) * PX_PER_DEGREE as f32) as u32).min(MAP_H - 1);
    (LEFT + x, HEAD + panel * (TOP + MAP_H + BOTTOM) + TOP + y)
}

/// The picture of `t`'s band `band`: a header line and the three panels stacked.
pub fn picture(t: &OriginalTables, band: usize, band_name: &str) -> (u32, u32, Vec<u8>) {
    let panel_h = TOP + MAP_H + BOTTOM;
    let panels: Vec<(Vec<u8>, u32)> = maps(t, band).iter().map(|m| panel(m, panel_h)).collect();
    let width = panels.iter().map(|p| p.1).max().unwrap_or(MAP_W);
    let head = HEAD;
    let height = head + 3 * panel_h;
    let mut rgb = vec![0u8; (width * height * 3) as usize];
    let header = format!(
        "{} - {} - {} POLYGONS - BOX {:.2} X {:.2} X {:.2} M - Z UP",
        t.name.to_uppercase(),
        band_name.to_uppercase(),
        t.polygons,
        t.hi.x - t.lo.x,
        t.hi.y - t.lo.y,
        t.hi.z - t.lo.z,
    );
    draw_text(&mut rgb, width, height, 4, 4, 2, &header, [255, 255, 255]);
    for (k, (p, w)) in panels.iter().enumerate() {
        let y0 = head + k as u32 * panel_h;
        for y in 0..panel_h {
            let from = (y * w * 3) as usize;
            let to = (((y0 + y) * width) * 3) as usize;
            rgb[to..to + (w * 3) as usize].copy_from_slice(&p[from..from + (w * 3) as usize]);
        }
    }
    (width, height, rgb)
}

/// Writes `DIR/ORIGINAL_BAND.png` for every table and band (each through a temporary file
/// renamed into place); returns the paths written.
pub fn write_plots(
    dir: &Path,
    tables: &[OriginalTables],
    names: &[String],
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut written = Vec::new();
    for t in tables {
        for b in 0..t.bands {
            let band = names.get(b).cloned().unwrap_or_else(|| format!("band{b}"));
            let (w, h, rgb) = picture(t, b, &band);
            let path = dir.join(format!("{}_{}.png", file_part(&t.name), file_part(&band)));
            crate::files::write_atomic(&path, |out| write_rgb_png(w, h, &rgb, out))?;
            written.push(path);
        }
    }
    Ok(written)
}

/// A name made safe for a file name: letters, digits, `-` and `_` kept, the rest `_`.
fn file_part(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
