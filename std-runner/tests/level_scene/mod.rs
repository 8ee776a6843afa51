//! The scene of the level tests (`level_load`, `level_blocking`): originals in boxes, their
//! tables made up, and instances of them placed by similarities.
#![allow(dead_code)] // each test file uses a different subset

use glam::{Quat, Vec3};
use hirad::generate::palette::{diffuse, two_sided};
use hirad::generate::shapes::add_quad;
use hirad::scene::{Cluster, InstanceOf, Original, Scene, Similarity, Tables};
use hirad_core::image::{LightData, TABLE_MET, TableRecord};

/// Tables for an original of box `lo..hi`, with values that differ by original (`salt`)
/// and `scatterers` polygons kept apart on a grid of side 2.
pub fn tables(original: usize, lo: Vec3, hi: Vec3, salt: f32, scatterers: u32) -> Tables {
    let record = TableRecord {
        bands: 2,
        tau_side: 4,
        incoming_side: 2,
        outgoing_side: 3,
        flags: TABLE_MET,
        lo: lo.to_array(),
        hi: hi.to_array(),
        scatterers,
        single_side: if scatterers > 0 { 2 } else { 0 },
        ..TableRecord::default()
    };
    let [tau, albedo, shares, response, _] = record.lengths();
    let mut values = Vec::new();
    values.extend((0..tau).map(|i| (0.05 * i as f32 + salt).fract()));
    values.extend((0..albedo).map(|i| 0.1 + 0.3 * ((0.37 * i as f32 + salt).fract())));
    values.extend((0..shares).map(|i| 0.2 + 0.5 * ((0.13 * i as f32).fract())));
    values.extend((0..response).map(|i| 0.01 * (1 + i % 17) as f32 + salt));
    for p in 0..scatterers {
        values.extend([0.0, 0.6, 0.8, 0.01 * (1 + p) as f32]);
        for _ in 0..2 {
            values.extend([0.1, 0.2, 0.3]);
        }
    }
    let visible = (0..record.visible_bytes())
        .map(|i| (i * 53) as u8)
        .collect();
    Tables {
        original,
        record,
        values,
        visible,
    }
}

pub fn instance(original: usize, transform: Similarity) -> Cluster {
    Cluster {
        instance: Some(InstanceOf {
            original,
            exact: true,
            transform,
        }),
        ..Cluster::default()
    }
}

pub fn place(axis: Vec3, angle: f32, at: Vec3, scale: f32) -> Similarity {
    Similarity {
        rotation: Quat::from_axis_angle(axis.normalize(), angle),
        translation: at,
        scale,
    }
}

/// Ground, a row of `n` instances of a leaf under one cluster, a shrub (an original that
/// holds leaves) placed twice at the root, and an approximate instance of the leaf with
/// geometry of its own: what the top level closes.
pub fn scene(n: usize) -> (Scene, Vec<Similarity>) {
    let mut s = Scene::new(2);
    let soil = diffuse(&mut s, "soil", &[0.1, 0.2]);
    let leaf_m = two_sided(&mut s, "leaf", &[0.1, 0.4], &[0.1, 0.35], &[0.05, 0.4]);
    let mut leaf = Cluster::named("leaf");
    add_quad(
        &mut leaf,
        [
            Vec3::new(-0.1, -0.1, 0.0),
            Vec3::new(0.1, -0.1, 0.0),
            Vec3::new(0.1, 0.1, 0.02),
            Vec3::new(-0.1, 0.1, 0.02),
        ],
        leaf_m,
    );
    let mut shrub = Cluster::named("shrub");
    for k in 0..3 {
        shrub.children.push(instance(
            0,
            place(Vec3::Z, k as f32, Vec3::new(0.0, 0.0, 0.2 * k as f32), 1.0),
        ));
    }
    s.originals = vec![
        Original {
            name: "leaf".into(),
            root: leaf.clone(),
        },
        Original {
            name: "shrub".into(),
            root: shrub,
        },
    ];
    add_quad(
        &mut s.root,
        [
            Vec3::new(-5.0, -5.0, 0.0),
            Vec3::new(5.0, -5.0, 0.0),
            Vec3::new(5.0, 5.0, 0.0),
            Vec3::new(-5.0, 5.0, 0.0),
        ],
        soil,
    );
    let mut row = Cluster::named("row");
    let mut places = Vec::new();
    for k in 0..n {
        let p = place(
            Vec3::new(0.2, 1.0, 0.5 + k as f32),
            0.3 * k as f32,
            Vec3::new(-4.0 + 0.8 * k as f32, 1.0, 0.3),
            0.5 + 0.1 * (k % 5) as f32,
        );
        places.push(p);
        row.children.push(instance(0, p));
    }
    s.root.children.push(row);
    for k in 0..2 {
        let p = place(
            Vec3::X,
            0.5 * k as f32,
            Vec3::new(2.0, -2.0 + 3.0 * k as f32, 0.0),
            2.0,
        );
        places.push(p);
        s.root.children.push(instance(1, p));
    }
    let p = place(Vec3::Y, 1.0, Vec3::new(0.0, 3.0, 1.0), 1.5);
    places.push(p);
    s.root.children.push(Cluster {
        instance: Some(InstanceOf {
            original: 0,
            exact: false,
            transform: p,
        }),
        ..leaf
    });
    s.suns.push(LightData {
        towards: Vec3::new(0.3, 0.2, 0.9).normalize(),
        irradiance: [500.0, 400.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    });
    s.tables = vec![
        tables(
            0,
            Vec3::new(-0.1, -0.1, 0.0),
            Vec3::new(0.1, 0.1, 0.02),
            0.1,
            1,
        ),
        tables(
            1,
            Vec3::new(-0.2, -0.2, 0.0),
            Vec3::new(0.2, 0.2, 0.42),
            0.5,
            0,
        ),
    ];
    (s, places)
}

pub fn corners(lo: Vec3, hi: Vec3) -> impl Iterator<Item = Vec3> {
    (0..8).map(move |k| {
        Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    })
}
