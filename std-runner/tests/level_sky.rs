//! An opened level's polygons see the sky with as many samples as hr gives them, however
//! much light the links bring its instance (issue 18): the links' beams are drawn apart from
//! the scene's sky directions. Leaves under slats that cover a known share of each, in
//! instances over a ground that sends them strong near infrared (the beams) while the sky
//! lights them in PAR alone, straight down: each leaf's PAR irradiance is the sky's times
//! its uncovered share, from the geometry alone.

mod common;

use common::{coarse_tables, hirad, s, write};

/// Leaves of a slats original: 8 up-facing 0.15 m squares at z = 0.5, leaf `k` uncovered
/// over the share `(k + 0.5) / 8` of its width by a down-facing slat at z = 0.8.
const LEAVES: usize = 8;

fn uncovered(k: usize) -> f64 {
    (k as f64 + 0.5) / LEAVES as f64
}

/// The scene: a ground 10 m square (PAR 2%, NIR 90%), a NIR-only sun and a PAR-only sky
/// straight down, and `instances` slats instances turned about z. The leaves are two-sided
/// and the slats reflect 90% of the NIR: the ground's NIR reaches the leaves' backs, and
/// the slats' undersides send it down on their fronts, as strong beams from every side.
fn scene(instances: u32) -> String {
    let mut t = String::from(
        "hirad 1\nbands par nir\nmaterial soil rho 0.02 0.9\nmaterial leaf rho 0.05 0.05 tau 0.01 0.01\n\
         material slat rho 0.02 0.9\n\
         sun from 0.3 0.2 0.932 irradiance 0 1000\nsky from 0 0 1 irradiance 100 0\n\
         original slats {\n",
    );
    let mut v = 0;
    for k in 0..LEAVES {
        let x0 = 0.2 * k as f64;
        // The leaf (normal +z), then the slat over all but its uncovered share (normal -z).
        let s0 = x0 + 0.15 * uncovered(k);
        t += &format!(
            "  v {x0} 0 0.5\n  v {} 0 0.5\n  v {} 0.15 0.5\n  v {x0} 0.15 0.5\n  quad leaf {} {} {} {}\n",
            x0 + 0.15,
            x0 + 0.15,
            v,
            v + 1,
            v + 2,
            v + 3
        );
        t += &format!(
            "  v {s0} -0.05 0.8\n  v {s0} 0.2 0.8\n  v {} 0.2 0.8\n  v {} -0.05 0.8\n  quad slat {} {} {} {}\n",
            x0 + 0.15,
            x0 + 0.15,
            v + 4,
            v + 5,
            v + 6,
            v + 7
        );
        v += 8;
    }
    t += "}\nscene field {\n  v -5 -5 0\n  v 5 -5 0\n  v 5 5 0\n  v -5 5 0\n  quad soil 0 1 2 3\n";
    for i in 0..instances {
        t += &format!(
            "  instance slats exact translate {} {} 0 rotate 0 0 1 {}\n",
            -3.0 + 2.0 * i as f64,
            -1.0 + 0.7 * i as f64,
            37 * i
        );
    }
    t + "}\n"
}

/// Every row's PAR front irradiance and material, by id.
fn rows(csv: &str) -> Vec<(f64, String)> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (irr, material) = (col("irr_par_W_m2"), col("material"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[irr].parse().unwrap_or(f64::NAN), f[material].to_string())
        })
        .collect()
}

#[test]
fn opened_leaves_see_the_sky_through_gaps_as_hr_does() {
    let dir = tempfile::tempdir().unwrap();
    for instances in [1u32, 3] {
        let text = write(
            dir.path(),
            &format!("slats_{instances}.hir"),
            &scene(instances),
        );
        let image = dir.path().join(format!("slats_{instances}.hirb"));
        let out = coarse_tables(&text, &image);
        assert!(image.exists(), "{}", String::from_utf8_lossy(&out.stderr));
        // Each method's leaves' errors against the uncovered shares (W/m^2), in global-id
        // order: the soil first, then each instance's 8 leaves and 8 slats in turn.
        let errors = |method: &str| -> Vec<f64> {
            let csv = dir.path().join(format!("{method}_{instances}.csv"));
            let mut args = vec!["solve", s(&image), "--results", s(&csv), "-q"];
            args.extend(["--method", method]);
            if method == "hi" {
                args.extend(["--instancing", "all"]);
            }
            let out = hirad(&args);
            assert!(
                out.status.success(),
                "{method}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            let got = rows(&std::fs::read_to_string(&csv).unwrap());
            let leaves: Vec<f64> = got
                .iter()
                .filter(|(_, m)| m == "leaf")
                .map(|(v, _)| *v)
                .collect();
            assert_eq!(leaves.len(), LEAVES * instances as usize);
            leaves
                .iter()
                .enumerate()
                .map(|(j, v)| v - 100.0 * uncovered(j % LEAVES))
                .collect()
        };
        let (hi, hr) = (errors("hi"), errors("hr"));
        // (The slats' undersides, lit by the soil's 2% of the sky, add a little.) Drawn
        // with the beams, the sky's samples of a leaf fell to a few: +47 W/m^2 on one.
        for (j, e) in hi.iter().enumerate() {
            assert!(
                e.abs() <= 6.0,
                "{instances} instances, leaf {j}: {e:+} W/m^2 from {}",
                100.0 * uncovered(j % LEAVES)
            );
        }
        let mean = |v: &[f64]| v.iter().map(|e| e.abs()).sum::<f64>() / v.len() as f64;
        assert!(
            mean(&hi) <= 1.5 * mean(&hr) + 0.5,
            "{instances} instances: hi's mean error {} W/m^2, hr's {}",
            mean(&hi),
            mean(&hr)
        );
    }
}
