//! The room itself: a parquet floor, a suspended ceiling of 0.6 m tiles with recessed light
//! panels, four plaster walls (all fronts facing into the room), two windows in the back
//! wall whose panes glow with diffuse daylight, and skirting boards.
//!
//! Room frame: metres, z up, the floor is the rectangle from the origin to (length, width)
//! at z = 0; the back wall (windows) is at y = width.

use super::mesh::quad_facing;
use crate::generate::shapes::cuboid;
use crate::scene::Cluster;
use glam::{Vec2, Vec3};

/// Materials of the room (indices into the scene's materials).
#[derive(Clone, Copy, Debug)]
pub struct ShellMaterials {
    /// Walls.
    pub plaster: u32,
    /// Ceiling tiles.
    pub ceiling: u32,
    /// The two woods of the parquet.
    pub parquet: [u32; 2],
    /// Skirting boards, window frames and light frames.
    pub trim: u32,
    /// Light panels (emitting).
    pub lamp: u32,
    /// Window panes (emitting daylight).
    pub daylight: u32,
}

/// Side of a ceiling tile (m).
pub const CEILING_TILE: f32 = 0.6;

/// Side of a parquet square (m).
const PARQUET: f32 = 0.4;

/// Width, height and sill height of a window (m), and the depth of its reveal.
const WINDOW: (f32, f32, f32, f32) = (2.0, 1.4, 0.9, 0.2);

/// Cuts [0, len] into pieces of at most `step`: the boundaries.
fn cuts(len: f32, step: f32) -> Vec<f32> {
    let n = (len / step - 1e-3).ceil().max(1.0) as u32;
    (0..=n).map(|i| (i as f32 * step).min(len)).collect()
}

/// An axis-aligned rectangle in a plane of constant `axis` coordinate `at`, spanning
/// `a` and `b` on the other two axes (in x, y, z order), facing `normal`.
fn rect(c: &mut Cluster, axis: usize, at: f32, a: [f32; 2], b: [f32; 2], normal: Vec3, m: u32) {
    let (u, v) = match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let corner = |x: f32, y: f32| {
        let mut p = [0.0; 3];
        p[axis] = at;
        p[u] = x;
        p[v] = y;
        Vec3::from(p)
    };
    quad_facing(
        c,
        [
            corner(a[0], b[0]),
            corner(a[1], b[0]),
            corner(a[1], b[1]),
            corner(a[0], b[1]),
        ],
        normal,
        m,
    );
}

/// Centres (x) of the windows in the back wall of a room `length` long.
fn window_centres(length: f32) -> Vec<f32> {
    let n = ((length / 4.0).floor() as u32).clamp(1, 4);
    (0..n)
        .map(|i| length * (2 * i + 1) as f32 / (2 * n) as f32)
        .collect()
}

/// The shell of a room of `size` (length x, width y, height z) (m).
pub fn shell(size: Vec3, m: ShellMaterials) -> Cluster {
    let (l, w, h) = (size.x, size.y, size.z);

    let mut floor = Cluster::named("floor");
    let (xs, ys) = (cuts(l, PARQUET), cuts(w, PARQUET));
    for (i, xw) in xs.windows(2).enumerate() {
        for (j, yw) in ys.windows(2).enumerate() {
            let wood = m.parquet[(i + j) % 2];
            rect(
                &mut floor,
                2,
                0.0,
                [xw[0], xw[1]],
                [yw[0], yw[1]],
                Vec3::Z,
                wood,
            );
        }
    }

    let mut ceiling = Cluster::named("ceiling");
    let mut lights = Cluster::named("lights");
    let (xs, ys) = (cuts(l, CEILING_TILE), cuts(w, CEILING_TILE));
    let (nx, ny) = (xs.len() as u32 - 1, ys.len() as u32 - 1);
    // Light panels: every third tile in each direction, symmetric about the middle of the
    // room (tile i and tile n - 1 - i alike: 2 i = n - 1 modulo 3), none at the walls.
    let is_light = |i: u32, n: u32| i % 3 == 2 * (n - 1) % 3 && i > 0 && i + 1 < n;
    for (i, xw) in xs.windows(2).enumerate() {
        for (j, yw) in ys.windows(2).enumerate() {
            let (x, y) = ([xw[0], xw[1]], [yw[0], yw[1]]);
            if is_light(i as u32, nx) && is_light(j as u32, ny) {
                // A recessed panel: a frame of trim at the ceiling around the emitter,
                // which sits 2 mm lower.
                let b = 0.15;
                let (xi, yi) = ([x[0] + b, x[1] - b], [y[0] + b, y[1] - b]);
                rect(&mut lights, 2, h - 0.002, xi, yi, -Vec3::Z, m.lamp);
                rect(&mut lights, 2, h, x, [y[0], yi[0]], -Vec3::Z, m.trim);
                rect(&mut lights, 2, h, x, [yi[1], y[1]], -Vec3::Z, m.trim);
                rect(&mut lights, 2, h, [x[0], xi[0]], yi, -Vec3::Z, m.trim);
                rect(&mut lights, 2, h, [xi[1], x[1]], yi, -Vec3::Z, m.trim);
            } else {
                rect(&mut ceiling, 2, h, x, y, -Vec3::Z, m.ceiling);
            }
        }
    }

    let mut walls = Cluster::named("walls");
    let mut windows = Cluster::named("windows");
    rect(&mut walls, 1, 0.0, [0.0, l], [0.0, h], Vec3::Y, m.plaster);
    rect(&mut walls, 0, 0.0, [0.0, w], [0.0, h], Vec3::X, m.plaster);
    rect(&mut walls, 0, l, [0.0, w], [0.0, h], -Vec3::X, m.plaster);
    // The back wall around its windows.
    let (ww, wh, sill, depth) = WINDOW;
    let (z0, z1) = (sill, sill + wh);
    rect(&mut walls, 1, w, [0.0, l], [0.0, z0], -Vec3::Y, m.plaster);
    rect(&mut walls, 1, w, [0.0, l], [z1, h], -Vec3::Y, m.plaster);
    let mut x = 0.0;
    for cx in window_centres(l) {
        let (x0, x1) = (cx - ww * 0.5, cx + ww * 0.5);
        rect(&mut walls, 1, w, [x, x0], [z0, z1], -Vec3::Y, m.plaster);
        x = x1;
        let mut win = Cluster::named("window");
        let (y0, y1) = (w, w + depth);
        // Reveals, facing into the opening.
        rect(&mut win, 0, x0, [y0, y1], [z0, z1], Vec3::X, m.plaster);
        rect(&mut win, 0, x1, [y0, y1], [z0, z1], -Vec3::X, m.plaster);
        rect(&mut win, 2, z0, [x0, x1], [y0, y1], Vec3::Z, m.trim);
        rect(&mut win, 2, z1, [x0, x1], [y0, y1], -Vec3::Z, m.plaster);
        // Four panes behind a cross of glazing bars.
        let yp = y1 - 0.05;
        for (xa, xb) in [(x0, cx), (cx, x1)] {
            for (za, zb) in [(z0, z0 + wh * 0.5), (z0 + wh * 0.5, z1)] {
                rect(&mut win, 1, yp, [xa, xb], [za, zb], -Vec3::Y, m.daylight);
            }
        }
        let bar = 0.025;
        cuboid(
            &mut win,
            Vec3::new(cx - bar, yp - 2.0 * bar, z0),
            Vec3::new(cx + bar, yp, z1),
            m.trim,
            false,
        );
        let zm = z0 + wh * 0.5;
        cuboid(
            &mut win,
            Vec3::new(x0, yp - 2.0 * bar, zm - bar),
            Vec3::new(x1, yp, zm + bar),
            m.trim,
            false,
        );
        // The sill board, standing 4 cm into the room.
        cuboid(
            &mut win,
            Vec3::new(x0 - 0.06, w - 0.04, z0 - 0.03),
            Vec3::new(x1 + 0.06, w, z0),
            m.trim,
            false,
        );
        windows.children.push(win);
    }
    rect(&mut walls, 1, w, [x, l], [z0, z1], -Vec3::Y, m.plaster);

    let mut skirting = Cluster::named("skirting");
    let (t, sh) = (0.015, 0.08);
    for (min, max) in [
        (Vec2::new(0.0, 0.0), Vec2::new(l, t)),
        (Vec2::new(0.0, w - t), Vec2::new(l, w)),
        (Vec2::new(0.0, t), Vec2::new(t, w - t)),
        (Vec2::new(l - t, t), Vec2::new(l, w - t)),
    ] {
        cuboid(
            &mut skirting,
            min.extend(0.0),
            max.extend(sh),
            m.trim,
            false,
        );
    }

    Cluster {
        name: Some("room".into()),
        children: vec![floor, ceiling, lights, walls, windows, skirting],
        ..Cluster::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hirad_core::geometry::polygon_shape;

    #[test]
    fn shell_faces_in_and_has_lights_and_windows() {
        let m = ShellMaterials {
            plaster: 0,
            ceiling: 1,
            parquet: [2, 3],
            trim: 4,
            lamp: 5,
            daylight: 6,
        };
        let size = Vec3::new(10.8, 7.8, 3.0);
        let s = shell(size, m);
        let inside = Vec3::new(5.0, 4.0, 1.5);
        for part in &s.children[..4] {
            assert!(!part.polygons.is_empty());
            for p in &part.polygons {
                let k: Vec<Vec3> = p.corners[..p.corner_count()]
                    .iter()
                    .map(|&i| part.vertices[i as usize])
                    .collect();
                let n = polygon_shape(&k).unwrap().normal;
                assert!(n.dot(inside - k[0]) > 0.0, "{:?}", part.name);
            }
        }
        let lamps = s.children[2]
            .polygons
            .iter()
            .filter(|p| p.material == 5)
            .count();
        assert_eq!(lamps, 6 * 3);
        assert_eq!(s.children[4].children.len(), 2);
        // Wall area: the whole box less the two windows.
        let area = |c: &Cluster| -> f32 {
            c.polygons
                .iter()
                .map(|p| {
                    let k: Vec<Vec3> = p.corners[..p.corner_count()]
                        .iter()
                        .map(|&i| c.vertices[i as usize])
                        .collect();
                    polygon_shape(&k).unwrap().area
                })
                .sum()
        };
        let walls = 2.0 * (10.8 + 7.8) * 3.0 - 2.0 * 2.0 * 1.4;
        assert!((area(&s.children[3]) - walls).abs() < 1e-3);
        assert!((area(&s.children[0]) - 10.8 * 7.8).abs() < 1e-2);
    }
}
