//! The room's furniture originals: a dining chair and a dining table, each a small cluster
//! hierarchy of parts (so that the solver can open them level by level), with turned legs,
//! an upholstered seat with rounded edges, and a curved slatted back.
//!
//! Local frames (metres, z up, origin on the floor at the middle of the footprint): the chair
//! faces -y (its back is towards +y); the table's length runs along x and its top is at
//! [`TABLE_TOP`].

use super::mesh::{self, Slab, bar, lathe, turned_profile};
use crate::generate::shapes::{cuboid, cylinder};
use crate::scene::Cluster;
use glam::{Vec2, Vec3};

/// Materials of the furniture (indices into the scene's materials).
#[derive(Clone, Copy, Debug)]
pub struct FurnitureMaterials {
    /// Chair frame.
    pub chair_wood: u32,
    /// Seat upholstery.
    pub fabric: u32,
    /// Table.
    pub table_wood: u32,
}

/// Height of the table's top surface above the floor (m).
pub const TABLE_TOP: f32 = 0.755;

/// Half length (x) and half depth (y) of the table top (m).
pub const TABLE_HALF: Vec2 = Vec2::new(0.9, 0.45);

/// Facets around a turned leg of the chair.
const CHAIR_LEG_SIDES: u32 = 14;

/// Facets around a turned leg of the table.
const TABLE_LEG_SIDES: u32 = 16;

/// Height of the chair's seat frame, where the legs end (m).
const SEAT_Z: f32 = 0.43;

/// Positions of the chair's legs (x, y) (m): front left, front right, rear left, rear right.
const CHAIR_LEGS: [Vec2; 4] = [
    Vec2::new(-0.19, -0.17),
    Vec2::new(0.19, -0.17),
    Vec2::new(-0.19, 0.17),
    Vec2::new(0.19, 0.17),
];

/// Backward lean of the chair's back posts from the vertical (radians, ~10 degrees).
const BACK_LEAN: f32 = 0.175;

/// Length of the back posts above the seat frame (m).
const POST_LENGTH: f32 = 0.52;

/// Where the back at height `z` (above the seat frame) and across position `x` lies in y:
/// the posts' lean, a bow of 3 cm towards the back in the middle, and (for slats) a lumbar
/// curve of `lumbar` metres.
fn back_y(x: f32, z: f32, lumbar: f32) -> f32 {
    let dz = (z - SEAT_Z).max(0.0);
    let bow = 0.03 * (1.0 - (x / 0.19).powi(2)).max(0.0);
    let t = ((z - 0.56) / (0.84 - 0.56)).clamp(0.0, 1.0);
    0.17 + dz * BACK_LEAN.tan() + bow + lumbar * (t * std::f32::consts::PI).sin()
}

/// The dining chair: seat (cushion and frame), legs, stretchers, and back (posts, rails,
/// slats); about 1,500 polygons.
pub fn chair(m: FurnitureMaterials) -> Cluster {
    let mut seat = Cluster::named("seat");
    let mut cushion = Cluster::named("cushion");
    Slab {
        bottom: Vec3::new(0.0, -0.035, SEAT_Z),
        half: Vec2::new(0.225, 0.18),
        corner_radius: 0.05,
        thickness: 0.05,
        edge_radius: 0.018,
        corner_segments: 4,
        edge_segments: 3,
    }
    .build(&mut cushion, m.fabric);
    let mut frame = Cluster::named("frame");
    // Seat rails between the legs, just under the cushion.
    for (min, max) in [
        (
            Vec3::new(-0.17, -0.18, 0.36),
            Vec3::new(0.17, -0.16, SEAT_Z),
        ),
        (Vec3::new(-0.17, 0.16, 0.36), Vec3::new(0.17, 0.18, SEAT_Z)),
        (Vec3::new(-0.2, -0.15, 0.36), Vec3::new(-0.18, 0.15, SEAT_Z)),
        (Vec3::new(0.18, -0.15, 0.36), Vec3::new(0.2, 0.15, SEAT_Z)),
    ] {
        cuboid(&mut frame, min, max, m.chair_wood, false);
    }
    seat.children = vec![cushion, frame];

    let mut legs = Cluster::named("legs");
    for (i, p) in CHAIR_LEGS.iter().enumerate() {
        let mut leg = Cluster::named(&format!("leg{i}"));
        let profile = turned_profile(SEAT_Z, 0.017, 12, &[0.22, 0.55, 0.8]);
        lathe(
            &mut leg,
            p.extend(0.0),
            Vec3::Z,
            &profile,
            CHAIR_LEG_SIDES,
            m.chair_wood,
        );
        legs.children.push(leg);
    }

    let mut stretchers = Cluster::named("stretchers");
    let h = Vec3::new(0.0, 0.0, 0.15);
    for (a, b) in [(0, 2), (1, 3)] {
        cylinder(
            &mut stretchers,
            CHAIR_LEGS[a].extend(0.0) + h,
            CHAIR_LEGS[b].extend(0.0) + h,
            0.009,
            0.009,
            8,
            m.chair_wood,
        );
    }
    cylinder(
        &mut stretchers,
        Vec3::new(-0.19, 0.0, 0.15),
        Vec3::new(0.19, 0.0, 0.15),
        0.008,
        0.008,
        8,
        m.chair_wood,
    );

    let mut back = Cluster::named("back");
    let mut posts = Cluster::named("posts");
    let lean = Vec3::new(0.0, BACK_LEAN.sin(), BACK_LEAN.cos());
    for (i, p) in CHAIR_LEGS[2..].iter().enumerate() {
        let mut post = Cluster::named(&format!("post{i}"));
        let mut profile = turned_profile(POST_LENGTH - 0.04, 0.016, 10, &[0.15, 0.9]);
        // A finial: a small ball that closes the top.
        profile.extend([
            (POST_LENGTH - 0.025, 0.019),
            (POST_LENGTH - 0.01, 0.014),
            (POST_LENGTH, 0.0),
        ]);
        lathe(
            &mut post,
            p.extend(SEAT_Z),
            lean,
            &profile,
            CHAIR_LEG_SIDES,
            m.chair_wood,
        );
        posts.children.push(post);
    }
    let mut rails = Cluster::named("rails");
    for (z, height, segments) in [(0.56, 0.04, 12), (0.84, 0.07, 16)] {
        let spine: Vec<Vec3> = (0..=segments)
            .map(|k| {
                let x = -0.18 + 0.36 * k as f32 / segments as f32;
                Vec3::new(x, back_y(x, z, 0.0), z)
            })
            .collect();
        bar(&mut rails, &spine, Vec3::Z, height, 0.022, m.chair_wood);
    }
    let mut slats = Cluster::named("slats");
    for k in 0..5 {
        let x = -0.12 + 0.06 * k as f32;
        let mut slat = Cluster::named(&format!("slat{k}"));
        let spine: Vec<Vec3> = (0..=6)
            .map(|j| {
                let z = 0.58 + (0.805 - 0.58) * j as f32 / 6.0;
                Vec3::new(x, back_y(x, z, 0.012), z)
            })
            .collect();
        bar(&mut slat, &spine, Vec3::X, 0.035, 0.012, m.chair_wood);
        slats.children.push(slat);
    }
    back.children = vec![posts, rails, slats];

    Cluster {
        name: Some("chair".into()),
        children: vec![seat, legs, stretchers, back],
        ..Cluster::default()
    }
}

/// The dining table: a top with rounded edges, an apron, and four turned legs with square
/// blocks under the apron; about 1,300 polygons.
pub fn table(m: FurnitureMaterials) -> Cluster {
    let thickness = 0.035;
    let mut top = Cluster::named("top");
    Slab {
        bottom: Vec3::new(0.0, 0.0, TABLE_TOP - thickness),
        half: TABLE_HALF,
        corner_radius: 0.06,
        thickness,
        edge_radius: 0.012,
        corner_segments: 5,
        edge_segments: 3,
    }
    .build(&mut top, m.table_wood);

    let (lx, ly) = (TABLE_HALF.x - 0.12, TABLE_HALF.y - 0.1);
    let apron_z = (TABLE_TOP - thickness - 0.1, TABLE_TOP - thickness);
    let mut apron = Cluster::named("apron");
    for (min, max) in [
        (
            Vec3::new(-lx, -ly - 0.01, apron_z.0),
            Vec3::new(lx, -ly + 0.01, apron_z.1),
        ),
        (
            Vec3::new(-lx, ly - 0.01, apron_z.0),
            Vec3::new(lx, ly + 0.01, apron_z.1),
        ),
        (
            Vec3::new(-lx - 0.01, -ly, apron_z.0),
            Vec3::new(-lx + 0.01, ly, apron_z.1),
        ),
        (
            Vec3::new(lx - 0.01, -ly, apron_z.0),
            Vec3::new(lx + 0.01, ly, apron_z.1),
        ),
    ] {
        cuboid(&mut apron, min, max, m.table_wood, false);
    }

    let mut legs = Cluster::named("legs");
    let block = apron_z.0 - 0.04;
    for (i, (sx, sy)) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
        .into_iter()
        .enumerate()
    {
        let mut leg = Cluster::named(&format!("leg{i}"));
        let p = Vec2::new(sx * lx, sy * ly);
        let profile = turned_profile(block, 0.026, 17, &[0.08, 0.35, 0.62, 0.93]);
        lathe(
            &mut leg,
            p.extend(0.0),
            Vec3::Z,
            &profile,
            TABLE_LEG_SIDES,
            m.table_wood,
        );
        cuboid(
            &mut leg,
            p.extend(block) - Vec3::new(0.028, 0.028, 0.0),
            p.extend(apron_z.1) + Vec3::new(0.028, 0.028, 0.0),
            m.table_wood,
            false,
        );
        legs.children.push(leg);
    }

    Cluster {
        name: Some("table".into()),
        children: vec![top, apron, legs],
        ..Cluster::default()
    }
}

/// Polygons of one chair and one table (for the summary and tests).
pub fn counts(m: FurnitureMaterials) -> (usize, usize) {
    (
        mesh::polygon_count(&chair(m)),
        mesh::polygon_count(&table(m)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const M: FurnitureMaterials = FurnitureMaterials {
        chair_wood: 0,
        fabric: 1,
        table_wood: 2,
    };

    #[test]
    fn chair_and_table_have_their_parts_and_size() {
        let c = chair(M);
        let names: Vec<_> = c.children.iter().map(|k| k.name.clone().unwrap()).collect();
        assert_eq!(names, ["seat", "legs", "stretchers", "back"]);
        let b = mesh::bounds(&c);
        assert!(
            b.min.z.abs() < 1e-6 && (0.9..1.0).contains(&b.max.z),
            "{b:?}"
        );
        assert!(b.min.y > -0.25 && b.max.y < 0.3 && b.max.x < 0.24, "{b:?}");
        let t = table(M);
        let b = mesh::bounds(&t);
        assert!((b.max.z - TABLE_TOP).abs() < 1e-5 && (b.max.x - TABLE_HALF.x).abs() < 1e-5);
        let (nc, nt) = counts(M);
        assert!(
            (1000..2000).contains(&nc) && (1000..2000).contains(&nt),
            "{nc} {nt}"
        );
    }
}
