//! A lamp cut by the plane of a face lights that face with the part in front of it only, in
//! the final gather as in the hierarchy. The Cornell box's lamp straddles the plane of a
//! face of the tall block: the final gather lit that face's direct light 2.7 times too
//! brightly (the part of the lamp behind the face counted, by reciprocity), and the box made
//! 1.4% more light than its lamp sent.
//!
//! Black surfaces, so a face's irradiance is the lamp's direct light alone; the reference is
//! the area mean over the face of the point-to-lamp integral, by the midpoint rule in f64 on
//! fine grids over both, written here apart from the solver.

use glam::DVec3;
use hirad_core::hr::{NoProgress, Settings};
use hirad_tests::Rng;

/// Corners of a square of side `size` centred at `c`, normal `n` (counter-clockwise seen
/// from the front).
fn square(c: DVec3, n: DVec3, size: f64) -> [DVec3; 4] {
    let t = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = n.cross(t).normalize() * (0.5 * size);
    let v = n.cross(u);
    [c - u - v, c + u - v, c + u + v, c - u + v]
}

/// The mean irradiance (W/m^2) over `face` (normal `nf`) from a Lambertian lamp (normal
/// `nl`) of exitance `e`, unoccluded, counting only lamp points in front of the face's plane
/// and face points in front of the lamp's. The lamp is the parallelogram `lamp`, or with
/// `triangle` its half `lamp[0], lamp[1], lamp[3]`.
fn reference(
    face: &[DVec3; 4],
    nf: DVec3,
    lamp: &[DVec3; 4],
    triangle: bool,
    nl: DVec3,
    e: f64,
) -> f64 {
    let (nr, ne) = (16, 48);
    let at = |q: &[DVec3; 4], u: f64, v: f64| q[0] + (q[1] - q[0]) * u + (q[3] - q[0]) * v;
    let mid = |i: usize, n: usize| (i as f64 + 0.5) / n as f64;
    let da = (lamp[1] - lamp[0]).cross(lamp[3] - lamp[0]).length() / (ne * ne) as f64;
    let mut sum = 0.0;
    for i in 0..nr {
        for j in 0..nr {
            let x = at(face, mid(i, nr), mid(j, nr));
            let mut h = 0.0;
            for a in 0..ne {
                for b in 0..ne {
                    let (u, v) = (mid(a, ne), mid(b, ne));
                    // Cells on the triangle's diagonal count half.
                    let w = if !triangle || a + b + 1 < ne {
                        1.0
                    } else if a + b + 1 == ne {
                        0.5
                    } else {
                        0.0
                    };
                    let d = at(lamp, u, v) - x;
                    let r2 = d.length_squared();
                    let (cf, cl) = (nf.dot(d), -nl.dot(d));
                    if w > 0.0 && cf > 0.0 && cl > 0.0 {
                        h += w * cf * cl / (r2 * r2) * da;
                    }
                }
            }
            sum += e / std::f64::consts::PI * h;
        }
    }
    sum / (nr * nr) as f64
}

fn quad_text(mat: &str, q: &[DVec3]) -> String {
    let kind = if q.len() == 3 { "tri" } else { "quad" };
    let mut t = format!("{kind} {mat}");
    for p in q {
        t += &format!("  {} {} {}", p.x, p.y, p.z);
    }
    t + "\n"
}

fn unit(r: &mut Rng) -> DVec3 {
    loop {
        let v = DVec3::new(
            r.range(-1.0, 1.0) as f64,
            r.range(-1.0, 1.0) as f64,
            r.range(-1.0, 1.0) as f64,
        );
        if v.length() > 0.2 && v.length() < 1.0 {
            return v.normalize();
        }
    }
}

/// The face split into `n x n` quads (separate polygons), row by row.
fn pieces(face: &[DVec3; 4], n: usize) -> Vec<[DVec3; 4]> {
    let at = |u: f64, v: f64| face[0] + (face[1] - face[0]) * u + (face[3] - face[0]) * v;
    let mut out = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (u0, u1) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
            let (v0, v1) = (j as f64 / n as f64, (j + 1) as f64 / n as f64);
            out.push([at(u0, v0), at(u1, v0), at(u1, v1), at(u0, v1)]);
        }
    }
    out
}

#[test]
fn faces_whose_plane_cuts_the_lamp_get_the_light_of_the_part_in_front() {
    let mut r = Rng(0x57AD, 0);
    let e = 100.0;
    for case in 0..16 {
        let scale = 10f64.powf(r.range(-2.0, 2.0) as f64);
        let lamp_size = scale * r.range(0.5, 1.5) as f64;
        let nl = unit(&mut r);
        let lamp = square(DVec3::ZERO, nl, lamp_size);
        // A face 2 to 6 lamp sizes away, larger or smaller than the lamp (the gather
        // integrates from the smaller of the two), in front of the lamp or across its plane
        // (its centre in front), its own plane through a point of the lamp away from the
        // lamp's centre. Split into pieces, so that pieces across the lamp's plane are
        // measured each.
        let dir = loop {
            let d = unit(&mut r);
            if d.dot(nl) > 0.05 {
                break d;
            }
        };
        let centre = dir * lamp_size * r.range(2.0, 6.0) as f64;
        // Every other lamp a triangle (OBJ lamps are): the gather integrates triangles and
        // quads apart.
        let triangle = case % 2 == 1;
        let (mut u, mut v) = (r.range(0.1, 0.9) as f64, r.range(0.1, 0.9) as f64);
        if triangle && u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let through = lamp[0] + (lamp[1] - lamp[0]) * u + (lamp[3] - lamp[0]) * v;
        let along = (through - centre).normalize();
        let nf = loop {
            let n = unit(&mut r);
            let n = n - along * n.dot(along);
            if n.length() > 0.3 {
                break n.normalize();
            }
        };
        let face_size = lamp_size * r.range(0.3, 2.5) as f64;
        let face = square(centre, nf, face_size);
        let split = 1 + (case % 3);
        let parts = pieces(&face, split);
        let mut text = String::from("hirad 1\nbands 1\nmaterial black rho 0\n");
        text += &format!("material lamp rho 0 emit {e}\nscene {{\n");
        for p in &parts {
            text += &quad_text("black", p);
        }
        if triangle {
            text += &quad_text("lamp", &[lamp[0], lamp[1], lamp[3]]);
        } else {
            text += &quad_text("lamp", &lamp);
        }
        text += "}\n";
        let scene = hirad::text::parse(text.as_bytes()).unwrap();
        let (table, _) =
            hirad_tests::solve_hr(&scene, &Settings::default(), &mut NoProgress).unwrap();
        let want: Vec<f64> = parts
            .iter()
            .map(|p| reference(p, nf, &lamp, triangle, nl, e))
            .collect();
        let peak = want.iter().copied().fold(0.0, f64::max);
        assert!(peak > 0.0, "case {case}: the lamp lights nothing\n{text}");
        let (mut got_sum, mut want_sum) = (0.0, 0.0);
        for (k, &w) in want.iter().enumerate() {
            let got = table.irradiance(k, 0)[0] as f64;
            got_sum += got;
            want_sum += w;
            // Pieces the lamp barely reaches (a sliver in front of its plane) are judged
            // against the face's brightest.
            let err = (got - w) / w.max(0.1 * peak);
            assert!(
                err.abs() < 0.02,
                "case {case}, piece {k} of {}: {got} W/m^2 from the lamp, the integral {w} ({:+.2}%)\n{text}",
                parts.len(),
                100.0 * err
            );
        }
        let err = got_sum / want_sum - 1.0;
        assert!(
            err.abs() < 0.01,
            "case {case}: the face gets {:+.2}% of the lamp's light on it\n{text}",
            100.0 * err
        );
    }
}
