//! How much the closed instances of a level share their room with their siblings: the
//! polygon area of the siblings inside each one's (oriented) box, over its own polygon
//! area, from up to [`SAMPLES`] points an original spread over its polygons by area.
//!
//! An original's tables are measured on it alone: light it scatters inside its box is
//! assumed to meet only its own polygons. Where a sibling's branches fill the same room
//! (the branches of one tree start at one trunk), that light meets the sibling's polygons
//! too, and both count it: hi makes light (one forest branch1 with its branch2s closed
//! among each other gave +11% NIR to the leaves, +31% to the bark, and made 4% of the NIR;
//! with the branch2s expanded in place, -0.1% and +12%). The instancing printout says where
//! siblings fill much of a box (see `policy`); how much is harmful is not known yet (a
//! dense maize canopy's plants hold 4 to 10 times their own area of neighbours in their
//! boxes, and hi is within 1.5% of hr there).

use anyhow::{Result, anyhow};
use glam::Vec3;
use hirad_core::NodeId;
use hirad_core::OriginalId;
use hirad_core::geometry::{Aabb, Similarity};
use hirad_core::image::{SceneSource, SceneView};

/// Most points an original's polygons are sampled by (each carries its share of the area).
const SAMPLES: usize = 256;

/// Points on an original's polygons (its own frame, m) and the area each stands for (m^2).
type Samples = Vec<(Vec3, f32)>;

/// An instance directly in a holder's tree (not inside another instance's subtree): its
/// original and its place in the holder's frame.
type Direct = (u32, Similarity);

/// A closed instance of a level: its original, its place in the level's frame, and its
/// original's box (the original's frame, m).
struct Entry {
    original: u32,
    place: Similarity,
    lo: Vec3,
    hi: Vec3,
    /// The box in the level's frame (axis-aligned, holding the oriented one).
    world: Aabb,
}

/// Each original's samples (see [`Samples`]), inner originals first: its own polygons'
/// centres and areas, and its instances' originals' samples placed, thinned to
/// [`SAMPLES`].
fn samples<S: SceneSource>(view: &SceneView<S>, direct: &[Vec<Direct>]) -> Result<Vec<Samples>> {
    let n = direct.len();
    let err = |e| anyhow!("{e}");
    let mut out: Vec<Samples> = Vec::with_capacity(n);
    for (k, list) in direct.iter().enumerate() {
        let root = view.original(OriginalId(k as u32)).map_err(err)?.root;
        let mut all = own_polygons(view, root)?;
        for &(o, t) in list {
            // An original holds only originals before it (checked by `policy::facts`).
            if let Some(inner) = out.get(o as usize) {
                let s2 = t.scale * t.scale;
                all.extend(inner.iter().map(|&(p, a)| (t.point(p), a * s2)));
            }
        }
        out.push(thin(all));
    }
    Ok(out)
}

/// The centres and areas of the polygons in node `root`'s subtree but those inside
/// instances (each counts as its original placed, see [`instances_in`]).
fn own_polygons<S: SceneSource>(view: &SceneView<S>, root: u32) -> Result<Samples> {
    let err = |e| anyhow!("{e}");
    let end = view.node(NodeId(root)).map_err(err)?.subtree_end;
    let mut out = Vec::new();
    let mut i = root;
    while i < end {
        let rec = view.node(NodeId(i)).map_err(err)?;
        if i != root && rec.instance().is_some() {
            i = rec.subtree_end.max(i + 1);
            continue;
        }
        let mut polys = vec![hirad_core::image::PolygonRecord::default(); rec.poly_count as usize];
        view.polygons(hirad_core::PolyId(rec.poly_first), &mut polys)
            .map_err(err)?;
        let mut verts = vec![[0.0f32; 3]; rec.vert_count as usize];
        view.vertices(hirad_core::VertexId(rec.vert_first), &mut verts)
            .map_err(err)?;
        for p in &polys {
            let c: Vec<Vec3> = p.corners[..p.corner_count()]
                .iter()
                .filter_map(|&k| verts.get(k as usize).map(|v| Vec3::from(*v)))
                .collect();
            if c.len() < 3 {
                continue;
            }
            let mut twice = Vec3::ZERO;
            for k in 1..c.len() - 1 {
                twice += (c[k] - c[0]).cross(c[k + 1] - c[0]);
            }
            let centre = c.iter().copied().sum::<Vec3>() / c.len() as f32;
            out.push((centre, 0.5 * twice.length()));
        }
        i += 1;
    }
    Ok(out)
}

/// At most [`SAMPLES`] of `all`, picked evenly along their running area, each then standing
/// for an even share of the whole area (the sum is kept).
fn thin(all: Samples) -> Samples {
    if all.len() <= SAMPLES {
        return all;
    }
    let total: f64 = all.iter().map(|&(_, a)| a as f64).sum();
    if total <= 0.0 {
        return Vec::new();
    }
    let step = total / SAMPLES as f64;
    let mut out = Vec::with_capacity(SAMPLES);
    let (mut run, mut next) = (0.0f64, 0.5 * step);
    for (p, a) in all {
        run += a as f64;
        while next < run && out.len() < SAMPLES {
            out.push((p, step as f32));
            next += step;
        }
    }
    out
}

/// Per original, the mean over its closed instances in every level (the scene's and those
/// of the originals `closed` says are closed) of the polygon area of their siblings inside
/// their box over their own; `None` for one closed nowhere. `closed[k]` is false for
/// originals expanded in place.
pub fn overlaps<S: SceneSource>(view: &SceneView<S>, closed: &[bool]) -> Result<Vec<Option<f32>>> {
    let info = *view.info();
    let n = info.originals as usize;
    let err = |e| anyhow!("{e}");
    let mut direct: Vec<Vec<Direct>> = Vec::with_capacity(n);
    let mut boxes: Vec<(Vec3, Vec3)> = Vec::with_capacity(n);
    for k in 0..n {
        let root = view.original(OriginalId(k as u32)).map_err(err)?.root;
        direct.push(instances_in(view, root)?);
        let r = view.node(NodeId(root)).map_err(err)?;
        boxes.push((Vec3::from(r.bbox_min), Vec3::from(r.bbox_max)));
    }
    let scene = instances_in(view, info.scene_root.0)?;
    let samples = samples(view, &direct)?;
    let mut sum = vec![0.0f64; n];
    let mut count = vec![0u64; n];
    let holders = std::iter::once(&scene).chain(
        (0..n)
            .filter(|&k| closed.get(k).copied().unwrap_or(false))
            .map(|k| &direct[k]),
    );
    for list in holders {
        let mut level = Vec::new();
        flatten(
            list,
            &Similarity::IDENTITY,
            &direct,
            &boxes,
            closed,
            &mut level,
        );
        for (e, f) in level.iter().zip(shared(&level, &samples)) {
            if let Some(f) = f {
                sum[e.original as usize] += f as f64;
                count[e.original as usize] += 1;
            }
        }
    }
    Ok((0..n)
        .map(|k| (count[k] > 0).then(|| (sum[k] / count[k] as f64) as f32))
        .collect())
}

/// The instance nodes directly in node `root`'s subtree (their own subtrees skipped).
fn instances_in<S: SceneSource>(view: &SceneView<S>, root: u32) -> Result<Vec<Direct>> {
    let err = |e| anyhow!("{e}");
    let end = view.node(NodeId(root)).map_err(err)?.subtree_end;
    let mut out = Vec::new();
    let mut i = root + 1;
    while i < end {
        let rec = view.node(NodeId(i)).map_err(err)?;
        match rec.instance() {
            Some(id) => {
                // An approximate instance counts as its original placed (its own nodes are
                // its original's approximation).
                let inst = view.instance(id).map_err(err)?;
                out.push((inst.original, inst.transform()));
                i = rec.subtree_end.max(i + 1);
            }
            None => i += 1,
        }
    }
    Ok(out)
}

/// The closed instances of a level whose holder directly holds `list`, placed by `place`:
/// instances of originals expanded in place give their own, placed by both transforms.
fn flatten(
    list: &[Direct],
    place: &Similarity,
    direct: &[Vec<Direct>],
    boxes: &[(Vec3, Vec3)],
    closed: &[bool],
    out: &mut Vec<Entry>,
) {
    for &(o, t) in list {
        let here = place.compose(&t);
        let k = o as usize;
        if closed.get(k).copied().unwrap_or(false) {
            let (lo, hi) = boxes[k];
            out.push(Entry {
                original: o,
                place: here,
                lo,
                hi,
                world: here.aabb(&Aabb::new(lo, hi)),
            });
        } else if let Some(inner) = direct.get(k) {
            flatten(inner, &here, direct, boxes, closed, out);
        }
    }
}

/// Most entries of a level measured (evenly spread over it); the others are left out of
/// their original's mean, so that a forest of a thousand trees is measured in seconds.
const MEASURED: usize = 4096;

/// Most sample points tested against one entry's box: beyond it every k-th sample of each
/// neighbour is tested, standing for k.
const TESTS_PER_ENTRY: usize = 1 << 14;

// The test of sparser samples puts 299 neighbours of 64 points each between one and two
// entries' worth.
const _: () = assert!(299 * 64 > TESTS_PER_ENTRY && 299 * 64 <= 2 * TESTS_PER_ENTRY);

/// Per entry, the polygon area of the other entries inside its box over its own (from
/// each original's `samples`); `None` for entries not measured (see [`MEASURED`]).
fn shared(level: &[Entry], samples: &[Samples]) -> Vec<Option<f32>> {
    let n = level.len();
    // Candidates by x: an entry whose box starts within the widest box's width before this
    // one's and before its end.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| level[a].world.min.x.total_cmp(&level[b].world.min.x));
    let starts: Vec<f32> = order.iter().map(|&k| level[k].world.min.x).collect();
    let widest = level
        .iter()
        .map(|e| e.world.max.x - e.world.min.x)
        .fold(0.0f32, f32::max);
    let area = |e: &Entry| -> f64 {
        let s2 = (e.place.scale * e.place.scale) as f64;
        samples[e.original as usize]
            .iter()
            .map(|&(_, a)| a as f64 * s2)
            .sum()
    };
    let mut out = vec![None; n];
    let measured: Vec<usize> = if n <= MEASURED {
        (0..n).collect()
    } else {
        (0..MEASURED).map(|k| k * n / MEASURED).collect()
    };
    for a in measured {
        let e = &level[a];
        let first = starts.partition_point(|&x| x < e.world.min.x - widest);
        let last = starts.partition_point(|&x| x < e.world.max.x);
        let near: Vec<usize> = order[first..last]
            .iter()
            .copied()
            .filter(|&b| b != a && meets(&e.world, &level[b].world))
            .collect();
        let own = area(e);
        if near.is_empty() || own <= 0.0 {
            out[a] = Some(0.0);
            continue;
        }
        let points: usize = near
            .iter()
            .map(|&b| samples[level[b].original as usize].len())
            .sum();
        let step = points.div_ceil(TESTS_PER_ENTRY).max(1);
        let mut foreign = 0.0f64;
        for &b in &near {
            let o = &level[b];
            let s2 = (o.place.scale * o.place.scale) as f64 * step as f64;
            for &(p, w) in samples[o.original as usize].iter().step_by(step) {
                if holds(e, o.place.point(p)) {
                    foreign += w as f64 * s2;
                }
            }
        }
        out[a] = Some((foreign / own) as f32);
    }
    out
}

/// True when two boxes share some room (touching faces count as sharing none).
fn meets(a: &Aabb, b: &Aabb) -> bool {
    a.min.cmplt(b.max).all() && b.min.cmplt(a.max).all()
}

/// True when the level's point `w` lies in `e`'s box.
fn holds(e: &Entry, w: Vec3) -> bool {
    if !(e.world.min.cmple(w).all() && w.cmple(e.world.max).all()) {
        return false;
    }
    let s = e.place.scale;
    if s <= 0.0 {
        return false;
    }
    let p = e.place.rotation.inverse() * (w - e.place.translation) / s;
    let eps = 1e-6 * (e.hi - e.lo).max_element().max(1e-6);
    (e.lo - eps).cmple(p).all() && p.cmple(e.hi + eps).all()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    fn entry(original: u32, at: Vec3, rotation: Quat, scale: f32) -> Entry {
        let place = Similarity {
            rotation,
            translation: at,
            scale,
        };
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        Entry {
            original,
            place,
            lo,
            hi,
            world: place.aabb(&Aabb::new(lo, hi)),
        }
    }

    /// Two originals filling the unit box evenly: 4 x 4 x 4 points of 1/64 m^2 each, the
    /// second's points twice as heavy.
    fn filled() -> Vec<Samples> {
        let points: Vec<Vec3> = (0..64)
            .map(|k| {
                let f = |i: usize| (i as f32 + 0.5) / 4.0;
                Vec3::new(f(k % 4), f((k / 4) % 4), f(k / 16))
            })
            .collect();
        vec![
            points.iter().map(|&p| (p, 1.0 / 64.0)).collect(),
            points.iter().map(|&p| (p, 2.0 / 64.0)).collect(),
        ]
    }

    #[test]
    fn siblings_area_inside_a_box_over_its_own() {
        let s = filled();
        let id = Quat::IDENTITY;
        // Apart, touching, half over each other, a quarter, the same.
        for (shift, part) in [
            (Vec3::new(2.0, 0.0, 0.0), 0.0),
            (Vec3::new(1.0, 0.0, 0.0), 0.0),
            (Vec3::new(0.5, 0.0, 0.0), 0.5),
            (Vec3::new(0.5, 0.5, 0.0), 0.25),
            (Vec3::ZERO, 1.0),
        ] {
            let level = [entry(0, Vec3::ZERO, id, 1.0), entry(0, shift, id, 1.0)];
            assert_eq!(shared(&level, &s), vec![Some(part); 2], "{shift}");
            // A sibling of twice the area per volume counts twice; the other way half.
            let mixed = [entry(0, Vec3::ZERO, id, 1.0), entry(1, shift, id, 1.0)];
            assert_eq!(
                shared(&mixed, &s),
                vec![Some(2.0 * part), Some(0.5 * part)],
                "{shift}"
            );
        }
        // Scaled by 2: its area is four times, its box eight times the volume.
        let big = [entry(0, Vec3::ZERO, id, 1.0), entry(0, Vec3::ZERO, id, 2.0)];
        let f = shared(&big, &s);
        assert_eq!(f, vec![Some(0.5), Some(0.25)]);
        // Turned by 45 degrees about z beside the first: the world boxes meet, the oriented
        // boxes far less.
        let turned = [
            entry(0, Vec3::ZERO, id, 1.0),
            entry(
                0,
                Vec3::new(1.5, -0.2, 0.0),
                Quat::from_rotation_z(core::f32::consts::FRAC_PI_4),
                1.0,
            ),
        ];
        let f: Vec<f32> = shared(&turned, &s).into_iter().flatten().collect();
        let boxes = {
            let (a, b) = (turned[0].world, turned[1].world);
            let d = (a.max.min(b.max) - a.min.max(b.min)).max(Vec3::ZERO);
            d.x * d.y * d.z
        };
        assert!(
            f[0] < boxes - 0.05,
            "{f:?} against the world boxes' {boxes}"
        );
        // Three in a row, each half over the next: the middle one holds both halves.
        let row = [
            entry(0, Vec3::ZERO, id, 1.0),
            entry(0, Vec3::new(0.5, 0.0, 0.0), id, 1.0),
            entry(0, Vec3::new(1.0, 0.0, 0.0), id, 1.0),
        ];
        assert_eq!(shared(&row, &s), vec![Some(0.5), Some(1.0), Some(0.5)]);
    }

    #[test]
    fn large_levels_are_measured_in_part_and_sampled_sparser() {
        let s = filled();
        let id = Quat::IDENTITY;
        // A long row, each box half over the next: only MEASURED of them measured, evenly,
        // each inner one holding both halves of its neighbours.
        let row: Vec<Entry> = (0..3 * MEASURED)
            .map(|k| entry(0, Vec3::new(0.5 * k as f32, 0.0, 0.0), id, 1.0))
            .collect();
        let f = shared(&row, &s);
        assert_eq!(f.iter().flatten().count(), MEASURED);
        assert!(
            f[1..f.len() - 1].iter().flatten().all(|&x| x == 1.0),
            "{:?}",
            &f[..8]
        );
        // 300 boxes in one place: more neighbours' points than one entry may test; every
        // other one is tested, standing for two, and the sum is the same.
        let heap: Vec<Entry> = (0..300).map(|_| entry(0, Vec3::ZERO, id, 1.0)).collect();
        let f = shared(&heap, &s);
        assert!(f.iter().all(|x| x == &Some(299.0)), "{:?}", &f[..4]);
    }

    #[test]
    fn thinning_keeps_the_area_and_follows_it() {
        // 1,000 points of growing area along x: the thinned ones keep the sum, and more of
        // them fall where the area is.
        let all: Samples = (0..1000)
            .map(|k| (Vec3::new(k as f32, 0.0, 0.0), 1.0 + k as f32))
            .collect();
        let total: f32 = all.iter().map(|p| p.1).sum();
        let t = thin(all);
        assert_eq!(t.len(), SAMPLES);
        let sum: f32 = t.iter().map(|p| p.1).sum();
        assert!((sum - total).abs() < 1e-3 * total, "{sum} {total}");
        let upper = t.iter().filter(|p| p.0.x >= 500.0).count();
        assert!(upper > SAMPLES * 2 / 3, "{upper}");
        // Few points are kept as they are.
        let few: Samples = vec![(Vec3::ZERO, 2.0), (Vec3::ONE, 3.0)];
        assert_eq!(thin(few.clone()), few);
    }
}
