//! Throughput of the runner's ray caster on a scene: `cargo run --release --example raybench
//! SCENE [RAYS]` casts RAYS (default 2,000,000) segments from the centres of polygons drawn
//! at random, in cosine-distributed directions about +z, 100 m long, in random order (no
//! coherence between one ray and the next, unlike the solver's), one thread, and prints the
//! time per ray of the any-hit test (`transmittance`) and of the nearest hit (`first_hit`),
//! and the bytes the grids of the scene's suns take (see `ObvhsVisibility::with_directions`).

use glam::Vec3;
use hirad::solve::world_polygons;
use hirad::visibility::ObvhsVisibility;
use hirad_core::limits::NONE;
use hirad_core::sampling::{hash3, unit2};
use hirad_core::visibility::Visibility;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: raybench SCENE [RAYS]");
        std::process::exit(2);
    };
    let n: u32 = args.get(2).map_or(2_000_000, |s| s.parse().expect("RAYS"));
    let scene = hirad::files::load_scene(std::path::Path::new(path))
        .expect("scene")
        .scene;
    let polys = world_polygons(&scene);
    let t = Instant::now();
    let suns: Vec<Vec3> = scene.suns.iter().map(|l| l.towards).collect();
    let vis = ObvhsVisibility::new(&polys)
        .expect("visibility")
        .with_directions(&polys, &suns);
    println!(
        "{} polygons, built in {:.2} s; {} sun grid bytes ({:.1} per polygon)",
        polys.len(),
        t.elapsed().as_secs_f64(),
        vis.directional_bytes(),
        vis.directional_bytes() as f64 / polys.len() as f64
    );
    let segments: Vec<(Vec3, Vec3, u32)> = (0..n)
        .map(|i| {
            let id = hash3(i, 0, 0xB7) as usize % polys.len();
            let p = &polys[id];
            let x = p.iter().copied().sum::<Vec3>() / p.len() as f32;
            let (u, v) = unit2(hash3(i, 1, 0xB7));
            let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u).max(0.0).sqrt());
            (x, x + d * 100.0, id as u32)
        })
        .collect();
    let t = Instant::now();
    let clear: f32 = segments
        .iter()
        .map(|&(x, y, id)| vis.transmittance(x, y, [id, NONE]))
        .sum();
    let any = t.elapsed().as_secs_f64() / n as f64 * 1e6;
    let t = Instant::now();
    let hits = segments
        .iter()
        .filter(|&&(x, y, id)| vis.first_hit(x, y, [id, NONE]).is_some())
        .count();
    let first = t.elapsed().as_secs_f64() / n as f64 * 1e6;
    println!(
        "any hit {any:.3} us/ray ({:.3} clear), first hit {first:.3} us/ray ({:.3} hit)",
        clear / n as f32,
        hits as f64 / n as f64
    );
}
