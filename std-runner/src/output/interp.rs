//! Weights of a planar patch's corners at a point inside it, for interpolating corner
//! values: barycentric for a triangle, bilinear for a quadrilateral (so that a quad's
//! values do not depend on how it would be split into triangles). Coordinates are 2D, in
//! the patch's plane, any unit.

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// Writes to `w` (one per corner, summing to 1, each in [0, 1]) the weights of corners `c`
/// (3 or 4, in order around the patch) at `p`. A point slightly outside (a sample on the
/// edge, rounding) is clamped to the patch. Other corner counts get equal weights.
pub fn corner_weights(c: &[[f64; 2]], p: [f64; 2], w: &mut [f64]) {
    match c.len() {
        3 => {
            let area = cross(sub(c[1], c[0]), sub(c[2], c[0]));
            if area == 0.0 || !area.is_finite() {
                w[..3].fill(1.0 / 3.0);
                return;
            }
            let mut l = [
                cross(sub(c[2], c[1]), sub(p, c[1])) / area,
                cross(sub(c[0], c[2]), sub(p, c[2])) / area,
                cross(sub(c[1], c[0]), sub(p, c[0])) / area,
            ];
            for x in &mut l {
                *x = x.max(0.0);
            }
            let s: f64 = l.iter().sum();
            for (wk, lk) in w.iter_mut().zip(l) {
                *wk = lk / s;
            }
        }
        4 => {
            let [u, v] = inverse_bilinear(c, p);
            w[0] = (1.0 - u) * (1.0 - v);
            w[1] = u * (1.0 - v);
            w[2] = u * v;
            w[3] = (1.0 - u) * v;
        }
        n => w[..n].fill(1.0 / n.max(1) as f64),
    }
}

/// The bilinear coordinates `[u, v]` (each clamped to [0, 1]) of `p` in the quadrilateral
/// `c`: `p = (1-u)(1-v) c0 + u (1-v) c1 + u v c2 + (1-u) v c3`.
pub fn inverse_bilinear(c: &[[f64; 2]], p: [f64; 2]) -> [f64; 2] {
    let e = sub(c[1], c[0]);
    let f = sub(c[3], c[0]);
    let g = [
        c[0][0] - c[1][0] + c[2][0] - c[3][0],
        c[0][1] - c[1][1] + c[2][1] - c[3][1],
    ];
    let h = sub(p, c[0]);
    // h = e u + f v + g u v; crossing with the vectors gives k2 v^2 + k1 v + k0 = 0.
    let k2 = cross(g, f);
    let k1 = cross(e, f) + cross(h, g);
    let k0 = cross(h, e);
    let scale = cross(e, f).abs().max(f64::MIN_POSITIVE);
    let v = if k2.abs() <= 1e-9 * scale {
        if k1 == 0.0 { 0.5 } else { -k0 / k1 }
    } else {
        let disc = (k1 * k1 - 4.0 * k0 * k2).max(0.0).sqrt();
        let a = (-k1 - disc) / (2.0 * k2);
        let b = (-k1 + disc) / (2.0 * k2);
        // The root inside the patch (the other belongs to the quad's extension).
        if (-1e-6..=1.0 + 1e-6).contains(&a) && !(-1e-6..=1.0 + 1e-6).contains(&b) {
            a
        } else if (-1e-6..=1.0 + 1e-6).contains(&b) {
            b
        } else if (a - 0.5).abs() < (b - 0.5).abs() {
            a
        } else {
            b
        }
    };
    let v = if v.is_finite() {
        v.clamp(0.0, 1.0)
    } else {
        0.5
    };
    // u from the component with the larger denominator.
    let dx = e[0] + g[0] * v;
    let dy = e[1] + g[1] * v;
    let u = if dx.abs() >= dy.abs() {
        (h[0] - f[0] * v) / dx
    } else {
        (h[1] - f[1] * v) / dy
    };
    let u = if u.is_finite() {
        u.clamp(0.0, 1.0)
    } else {
        0.5
    };
    [u, v]
}
