//! Link audit (diagnostic): `cargo run --release --example audit SCENE [RAYS] [EPSILON]`.
//! Per kind of link, the power links carry against the power rays traced from the emitters
//! take through them.
use hirad::scene::{compile, read_image};
use hirad::solve::{RayonExecutor, world_polygons};
use hirad::visibility::ObvhsVisibility;
use hirad_core::hr::{self, Settings, bench};
use std::collections::BTreeMap;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = hirad::files::load_scene(std::path::Path::new(&args[1]))
        .unwrap()
        .scene;
    let rays: u32 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(4_000_000);
    let epsilon: f32 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(1e-3);
    let settings = Settings {
        epsilon,
        final_rays: 0,
        ..Settings::default()
    };
    let bytes = compile(&scene).unwrap();
    let view = read_image(&bytes).unwrap();
    let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
    let plan = hr::plan(&view, &settings, false, &mut scratch).unwrap();
    let mut ws = vec![0u8; plan.suggested_bytes as usize];
    let vis = ObvhsVisibility::new(&world_polygons(&scene)).unwrap();
    let mut exec = RayonExecutor::new(2).unwrap();
    let mut snap = bench::start(&view, &settings, &mut ws, &vis, &mut exec).unwrap();
    while !bench::round(&mut snap, &mut ws, &vis, &mut exec) {}
    for _ in 0..3 {
        bench::gather(&mut snap, &mut ws, &vis, &mut exec);
    }
    if let Ok(l) = std::env::var("LINK") {
        let ids: Vec<u32> = l.split(',').map(|s| s.parse().unwrap()).collect();
        let mut ks: Vec<f32> = (0..400)
            .map(|s| {
                bench::probe_link_seeded(&snap, &mut ws, &vis, ids[0], ids[1], s * 7919 + 13, 4)[0]
                    [0]
            })
            .collect();
        ks.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mean: f32 = ks.iter().sum::<f32>() / ks.len() as f32;
        println!(
            "mean {mean:.4} q: {:?}",
            [0, 40, 100, 200, 300, 360, 390, 396, 399].map(|i| ks[i])
        );
        return;
    }
    let (links, nb) = bench::link_slots(&snap);
    let mut carried = vec![0.0f64; links * nb];
    let mut traced = vec![0.0f64; links * nb];
    let left = bench::audit(&snap, &mut ws, &vis, rays, &mut carried, &mut traced);
    let band = std::env::var("AUDIT_BAND")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(nb - 1);
    let dist = bench::distributed(&snap, &mut ws)[band];
    let mut into_clusters = 0.0;
    for i in 0..links as u32 {
        if let Some((r, _, _)) = bench::link_info(&snap, &mut ws, i)
            && r.kind == 0
        {
            into_clusters += carried[i as usize * nb + band];
        }
    }
    println!(
        "links into clusters carry {into_clusters:.4}, their polygons take {dist:.4} ({:+.2}%)",
        100.0 * (dist - into_clusters) / into_clusters
    );
    // SOIL_AREA=a: clusters whose polygons average a (m^2), the soil tiles of a canopy.
    let soil: f32 = std::env::var("SOIL_AREA")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(-1.0);
    let mut groups: BTreeMap<String, (u64, f64, f64, f64)> = BTreeMap::new();
    let mut worst: Vec<(f64, u32)> = Vec::new();
    let (mut tc, mut tt) = (0.0, 0.0);
    for i in 0..links as u32 {
        let Some((r, e, flags)) = bench::link_info(&snap, &mut ws, i) else {
            continue;
        };
        let c = carried[i as usize * nb + band];
        let t = traced[i as usize * nb + band];
        tc += c;
        tt += t;
        let kind = |x: &bench::ElemInfo| match x.kind {
            0 if (x.area / x.polygons.max(1) as f32 - soil).abs() < 1e-4 => "cl_soil".to_string(),
            0 if x.polygons <= 32 => "cl_small".to_string(),
            0 => "cl_large".to_string(),
            3 => "source".to_string(),
            _ => "patch".to_string(),
        };
        let key = format!(
            "{:9} <- {:9} exact={}",
            kind(&r),
            kind(&e),
            (flags >> 4) & 1
        );
        let g = groups.entry(key).or_default();
        g.0 += 1;
        g.1 += c;
        g.2 += t;
        worst.push((c - t, i));
        if std::env::var("SEEDS").is_ok() && r.kind == 0 && c > 0.0 {
            let (k, _, _, _) = bench::probe_link(&snap, &mut ws, &vis, r.elem, e.elem);
            if k[0][0] > 0.0 {
                let m = seeds_mean(&snap, &mut ws, &vis, r.elem, e.elem, 4);
                g.3 += c * m / k[0][0] as f64;
            }
        }
    }
    println!(
        "band {band}: carried {tc:.3} traced {tt:.3} ({:+.2}%)",
        100.0 * (tc - tt) / tt
    );
    println!(
        "left: escaped {:.3} backs {:.3} uncovered {:.3} overlapped {:.3} self {:.3}",
        left.escaped[band],
        left.backs[band],
        left.uncovered[band],
        left.overlapped[band],
        left.self_linked[band]
    );
    for (k, (n, c, t, m)) in &groups {
        println!(
            "{k:40} n={n:7} carried {c:10.3} traced {t:10.3} diff {:+9.3} ({:+.1}%) seeds-mean {m:.3}",
            c - t,
            100.0 * (c - t) / t.max(1e-12)
        );
    }
    worst.sort_by(|a, b| b.0.abs().partial_cmp(&a.0.abs()).unwrap());
    for (d, i) in worst.iter().take(15) {
        let (r, e, f) = bench::link_info(&snap, &mut ws, *i).unwrap();
        println!(
            "link {i}: diff {d:+.3} carried {:.3} traced {:.3} recv {:?} emit {:?} flags {f}",
            carried[*i as usize * nb + band],
            traced[*i as usize * nb + band],
            r,
            e
        );
        if r.kind == 0 {
            let (k, _, _, _) = bench::probe_link(&snap, &mut ws, &vis, r.elem, e.elem);
            let m4 = seeds_mean(&snap, &mut ws, &vis, r.elem, e.elem, 4);
            let m64 = seeds_mean(&snap, &mut ws, &vis, r.elem, e.elem, 64);
            println!(
                "   k now {:.5} mean over seeds: rays 4 {:.5} rays 64 {:.5}",
                k[0][0], m4, m64
            );
        }
    }
}

#[allow(dead_code)]
fn seeds_mean(
    snap: &bench::Snapshot,
    ws: &mut [u8],
    vis: &ObvhsVisibility,
    recv: u32,
    emit: u32,
    rays: u32,
) -> f64 {
    let mut s = 0.0f64;
    for seed in 0..SEEDN {
        s += bench::probe_link_seeded(snap, ws, vis, recv, emit, seed * 7919 + 13, rays)[0][0]
            as f64;
    }
    s / SEEDN as f64
}

const SEEDN: u32 = 40;
