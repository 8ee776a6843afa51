//! Links that geometry alone proves dark are never made: a receiving patch gathers only from
//! what lies in front of its plane (both sides for a two-sided one), and nothing arrives along
//! the plane. A flat ground's own clusters were kept as links to its tiles, carrying exactly
//! nothing (three quarters of the links at the top level of a canopy). The light stays what
//! it was: the scenes here have no interreflection at all, so every tile shows rho x its
//! direct light, and a scene whose tiles do see each other keeps its links.

use glam::{Quat, Vec3};
use hirad::generate::palette::{diffuse, two_sided};
use hirad::generate::shapes::add_quad;
use hirad::output::{Progress, ResultsTable};
use hirad::scene::{Cluster, Scene, light};
use hirad::solve::{VisibilityChoice, solve_hr};
use hirad_core::hr::Settings;

const RHO: f32 = 0.3;

/// An `n x n` grid of tiles of side `tile` in the plane z = `z`, its blocks of 4 x 4 tiles in
/// clusters of their own, turned by `turn` (about the origin); facing +z, or -z if `down`.
fn sheet(n: u32, tile: f32, z: f32, turn: Quat, m: u32, name: &str, down: bool) -> Cluster {
    let mut sheet = Cluster::named(name);
    let h = 0.5 * n as f32 * tile;
    for bi in 0..n.div_ceil(4) {
        for bj in 0..n.div_ceil(4) {
            let mut block = Cluster::named("block");
            for i in (4 * bi)..(4 * bi + 4).min(n) {
                for j in (4 * bj)..(4 * bj + 4).min(n) {
                    let (x, y) = (i as f32 * tile - h, j as f32 * tile - h);
                    let mut c = [
                        Vec3::new(x, y, z),
                        Vec3::new(x + tile, y, z),
                        Vec3::new(x + tile, y + tile, z),
                        Vec3::new(x, y + tile, z),
                    ]
                    .map(|p| turn * p);
                    if down {
                        c.reverse();
                    }
                    add_quad(&mut block, c, m);
                }
            }
            sheet.children.push(block);
        }
    }
    sheet
}

/// Solves `s` by hr at a fine threshold: (links kept, results).
fn solve(s: &Scene) -> (u64, ResultsTable) {
    let mut table = ResultsTable::new(s.bands as usize, true);
    let settings = Settings {
        epsilon: 1e-5,
        ..Settings::default()
    };
    let run = solve_hr(
        s,
        &settings,
        2,
        None,
        VisibilityChoice::Core,
        &Progress::new(true),
        &mut table,
    )
    .unwrap();
    (run.stats.links, table)
}

/// A scene of one band lit by a sun of 100 W/m^2 that lies towards `sun`.
fn lit(sun: Vec3) -> Scene {
    let mut s = Scene::new(1);
    s.suns.push(light(sun.normalize(), &[100.0]));
    s
}

/// Every polygon's front radiosity is rho x its direct light, none from other polygons.
fn only_direct(t: &ResultsTable, rho: f32, what: &str) {
    for i in 0..t.len() {
        for side in 0..2 {
            let (b, e) = (t.radiosity(i, side)[0], t.irradiance(i, side)[0]);
            assert!(
                (b - rho * e).abs() <= 1e-5 * (1.0 + e),
                "{what}: polygon {i} side {side} shows {b} W/m^2 under {e} W/m^2"
            );
        }
    }
}

#[test]
fn a_flat_ground_links_nothing_to_itself_at_any_size_and_turn() {
    // Sizes, tile counts (blocks of 4 and a ragged last block) and turns about the vertical,
    // the sun always above. (A plane tilted off the axes keeps links between its own
    // clusters, whose boxes are not flat; they carry nothing, as `only_direct` checks, but
    // are not yet left out.)
    for (n, tile, angle) in [(8u32, 0.5f32, 0.0f32), (13, 0.2, 17.0), (16, 2.0, 63.0)] {
        let turn = Quat::from_rotation_z(angle.to_radians());
        let mut s = lit(turn * Vec3::new(0.2, 0.1, 1.0));
        let m = diffuse(&mut s, "ground", &[RHO]);
        s.root
            .children
            .push(sheet(n, tile, 0.0, turn, m, "ground", false));
        let (links, t) = solve(&s);
        only_direct(&t, RHO, "ground");
        assert_eq!(t.len(), (n * n) as usize);
        assert_eq!(
            links, 0,
            "{n} x {n} tiles of {tile} m turned {angle} degrees"
        );
        only_direct(&t, RHO, "ground");
        assert!(t.irradiance(0, 0)[0] > 0.0);
    }
}

#[test]
fn a_two_sided_sheet_links_nothing_to_itself() {
    let turn = Quat::from_rotation_z(0.4);
    let mut s = lit(turn * Vec3::new(0.0, 0.3, 1.0));
    let m = two_sided(&mut s, "leaf", &[RHO], &[RHO], &[0.2]);
    s.root
        .children
        .push(sheet(12, 0.1, 0.0, turn, m, "sheet", false));
    let (links, _) = solve(&s);
    assert_eq!(links, 0);
}

#[test]
fn one_sided_sheets_back_to_back_link_nothing_and_facing_ones_do() {
    // Two sheets 1 m apart, the lower facing down and the upper up: each one's face sees
    // only what lies behind it.
    let turn = Quat::from_rotation_z(0.3);
    let sun = turn * Vec3::new(0.1, 0.0, 1.0);
    let mut s = lit(sun);
    let m = diffuse(&mut s, "ground", &[RHO]);
    s.root
        .children
        .push(sheet(8, 0.25, 0.0, turn, m, "low", true));
    s.root
        .children
        .push(sheet(8, 0.25, 1.0, turn, m, "high", false));
    let (links, t) = solve(&s);
    assert_eq!(links, 0);
    only_direct(&t, RHO, "back to back");
    // Facing each other (the lower up, the upper down): the light the lower one reflects
    // where the slanting sun reaches it lights the upper one's face through links.
    let mut s = lit(sun);
    let m = diffuse(&mut s, "ground", &[RHO]);
    s.root
        .children
        .push(sheet(8, 0.25, 0.0, turn, m, "low", false));
    s.root
        .children
        .push(sheet(8, 0.25, 1.0, turn, m, "high", true));
    let (links, t) = solve(&s);
    assert!(links > 0);
    assert!((64..128).any(|i| t.irradiance(i, 0)[0] > 0.0));
}
