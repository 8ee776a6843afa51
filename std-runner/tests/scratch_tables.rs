use glam::Vec3;
use hirad::solve::RayonExecutor;
use hirad::tables::{Alone, TableSettings, sample_at};

#[test]
#[ignore]
fn sweep() {
    let loaded = hirad::files::load_scene(std::path::Path::new("/work/exp/canopy.hirb")).unwrap();
    let scene = loaded.scene;
    let alone = Alone::new(&scene, 1).unwrap();
    eprintln!(
        "box {:?} {:?} polys {}",
        alone.lo,
        alone.hi,
        alone.polygons.len()
    );
    let mut settings = TableSettings::default();
    settings.solve.epsilon = 1e-3;
    let mut exec = RayonExecutor::new(2).unwrap();
    for k in 0..=24 {
        let th = (k as f32) * std::f32::consts::PI / 24.0;
        let d = Vec3::new(th.sin() * 0.8, th.sin() * 0.6, th.cos());
        let s = sample_at(&alone, d, &settings, &mut exec).unwrap();
        eprintln!(
            "theta {:5.1} area {:.4} tau {:.4} direct {:.4} {:.4} scat {:.4} {:.4} abs {:.4} {:.4} links {} imb {:.4}",
            th.to_degrees(),
            s.area,
            s.tau,
            s.direct[0],
            s.direct[1],
            s.scattered[0],
            s.scattered[1],
            s.absorbed[0],
            s.absorbed[1],
            s.lit.stats.links,
            s.lit.stats.balance.relative_imbalance(0)
        );
    }
}

#[test]
#[ignore]
fn interp() {
    use hirad_core::tables::grid::DirectionGrid;
    for side in [4u32, 8, 16, 32] {
        let g = DirectionGrid::new(side).unwrap();
        let f = |d: Vec3| 1.0 + 0.5 * d.x + 0.3 * d.z * d.z + 0.2 * d.y * d.z;
        let vals: Vec<f32> = (0..g.cells()).map(|c| f(g.direction(c))).collect();
        let mut worst = (0.0f32, Vec3::ZERO);
        let mut mean = 0.0;
        for k in 0..20000u32 {
            let (a, b) = hirad_core::sampling::unit2(hirad_core::sampling::hash3(3, k, 9));
            let z = 1.0 - 2.0 * a;
            let r = (1.0 - z * z).sqrt();
            let p = std::f32::consts::TAU * b;
            let d = Vec3::new(r * p.cos(), r * p.sin(), z);
            let e = (g.interpolate(&vals, d) - f(d)).abs();
            mean += e / 20000.0;
            if e > worst.0 {
                worst = (e, d);
            }
        }
        eprintln!(
            "side {side} worst {:.4} at {:?} mean {:.5}",
            worst.0, worst.1, mean
        );
    }
}

#[test]
#[ignore]
fn one() {
    use hirad_core::tables::grid::{DirectionGrid, sphere_to_square};
    let g = DirectionGrid::new(16).unwrap();
    let d = Vec3::new(-0.5939677, -0.0071086516, 0.80445755);
    eprintln!("square {:?}", sphere_to_square(d));
    for (c, w) in g.weights(d) {
        eprintln!(
            "cell {c} ({}, {}) w {w} dir {:?}",
            c % 16,
            c / 16,
            g.direction(c)
        );
    }
}

#[test]
#[ignore]
fn checks() {
    use hirad_core::tables::grid::DirectionGrid;
    use hirad_core::tables::tau::projected_area;
    let loaded = hirad::files::load_scene(std::path::Path::new("/work/exp/canopy.hirb")).unwrap();
    let scene = loaded.scene;
    let alone = Alone::new(&scene, 1).unwrap();
    let mut settings = TableSettings::default();
    settings.solve.epsilon = 1e-3;
    let mut exec = RayonExecutor::new(2).unwrap();
    let g = DirectionGrid::new(8).unwrap();
    let mut p = vec![0.0f32; g.cells() as usize];
    for c in 0..g.cells() {
        let s = sample_at(&alone, g.direction(c), &settings, &mut exec).unwrap();
        p[c as usize] = s.scattered[1] * s.area;
    }
    for k in 0..8 {
        let d = hirad::tables::uniform_direction(1, k, 0x7AB1E);
        let s = sample_at(&alone, d, &settings, &mut exec).unwrap();
        let pred = g.interpolate(&p, d) / projected_area(alone.lo, alone.hi, d);
        let w = g.weights(d);
        eprintln!(
            "d {d:?} meas {:.5} pred {:.5} err {:.2}% weights {:?} neighbours {:?}",
            s.scattered[1],
            pred,
            100.0 * (pred - s.scattered[1]) / s.scattered[1],
            w,
            w.iter()
                .map(|(c, _)| p[*c as usize] / projected_area(alone.lo, alone.hi, g.direction(*c)))
                .collect::<Vec<_>>()
        );
    }
}

#[test]
#[ignore]
fn timing() {
    let loaded = hirad::files::load_scene(std::path::Path::new("/work/exp/canopy.hirb")).unwrap();
    let scene = loaded.scene;
    let alone = Alone::new(&scene, 1).unwrap();
    for (eps, fr, th) in [
        (1e-3f32, None, 2usize),
        (1e-3, Some(0u32), 2),
        (1e-3, None, 1),
        (1e-4, None, 2),
        (1e-4, Some(0), 2),
    ] {
        let mut settings = TableSettings::default();
        settings.solve.epsilon = eps;
        if let Some(f) = fr {
            settings.solve.final_rays = f;
        }
        let mut exec = RayonExecutor::new(th).unwrap();
        let t = std::time::Instant::now();
        let mut sc = 0.0;
        for k in 0..10 {
            let d = hirad::tables::uniform_direction(1, k, 0x7AB1E);
            let s = sample_at(&alone, d, &settings, &mut exec).unwrap();
            sc += s.scattered[1] / s.direct[1];
        }
        eprintln!(
            "eps {eps} final {fr:?} threads {th}: {:.3} s per solve, mean albedo {:.5}",
            t.elapsed().as_secs_f64() / 10.0,
            sc / 10.0
        );
    }
}
