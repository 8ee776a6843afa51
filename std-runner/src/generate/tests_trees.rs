//! Tests of the tree generators: `gen poplar`, `gen stand`, `gen forest`.

use crate::generate::Common;
use crate::generate::poplar::{self, Preset, tree};
use crate::scene::{Cluster, Scene};
use std::path::PathBuf;

fn common(seed: u64) -> Common {
    Common {
        seed,
        output: PathBuf::from("unused.hirb"),
        quiet: true,
    }
}

fn poplar_args(seed: u64, preset: Preset) -> poplar::Args {
    poplar::Args {
        common: common(seed),
        preset,
        age: None,
        height: None,
        leaves: None,
        bands: tree::Bands::ParNir,
        sun_elevation: 55.0,
        sun_azimuth: -120.0,
    }
}

/// Per instancing level of the stored scene tree (0 = the scene, 1 = instances directly in
/// it, ...): number of instances opened at that level, their own polygons, and their child
/// instances.
#[derive(Clone, Copy, Debug, Default)]
struct Level {
    nodes: u64,
    own: u64,
    instances: u64,
}

fn levels(c: &Cluster, level: usize, out: &mut Vec<Level>) {
    if out.len() <= level {
        out.resize(level + 1, Level::default());
    }
    let mut own = 0;
    let mut inst = 0;
    let mut stack: Vec<&Cluster> = vec![c];
    // The content of this level: own polygons of plain sub-clusters count here.
    while let Some(n) = stack.pop() {
        own += n.polygons.len() as u64;
        for k in &n.children {
            if k.instance.is_some() {
                inst += 1;
                levels(k, level + 1, out);
            } else {
                stack.push(k);
            }
        }
    }
    out[level].nodes += 1;
    out[level].own += own;
    out[level].instances += inst;
}

fn print_levels(s: &Scene) {
    let mut out = Vec::new();
    levels(&s.root, 0, &mut out);
    for (i, l) in out.iter().enumerate() {
        println!(
            "level {i}: {} nodes, {:.1} own polygons, {:.1} instances each",
            l.nodes,
            l.own as f64 / l.nodes as f64,
            l.instances as f64 / l.nodes as f64
        );
    }
}

#[test]
#[ignore = "prints the structure of the paper poplar"]
fn show_poplar() {
    let s = poplar::generate(&poplar_args(1, Preset::Paper)).unwrap();
    print_levels(&s);
}
