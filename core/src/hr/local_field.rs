//! An opened level's light by place: the mean reflected radiosity of its leaf patches in
//! each cell of a coarse grid over them, one-sided and two-sided apart. A gather ray from
//! the opened level that meets a closed sibling's polygon *inside* the opened level's box
//! reads it there (inside the opened instance's own box only, see `blockers::light_along`)
//! instead of the sibling's tables (DESIGN.md "Instances inside a level"):
//! the tables give what an observer outside the sibling's box sees (its sunlit outer
//! leaves), where a point among the opened level's own polygons lies in their light
//! (shaded inner leaves where the boxes overlap). Nine copies of a poplar branch 0.5 m
//! apart absorbed 20.6% too much NIR with the tables read there.

use super::ids::{Elem, Kind};
use super::state::State;
use crate::limits::{MAX_BANDS, NONE};
use glam::Vec3;

/// Cells along each side of the grid.
const SIDE: usize = 8;
/// Cells of the grid.
const CELLS: usize = SIDE * SIDE * SIDE;
/// Classes kept apart: one-sided, two-sided polygons (bark and leaves of a plant: their
/// reflectances differ most).
const CLASSES: usize = 2;
/// Floats before the cells: the grid's low corner, its cell size per axis (m), valid flag.
const HEAD: usize = 8;

/// Least leaf patches a cell (or its neighbourhood) holds of a class to be read.
const MIN_PATCHES: f32 = 4.0;

/// Floats per cell and class: patches, area (m^2), area times radiosity per band.
fn per(bands: usize) -> usize {
    2 + bands
}

/// Bytes of the field of a level of `bands` bands.
pub(crate) fn bytes_needed(bands: usize) -> usize {
    4 * (HEAD + CELLS * CLASSES * per(bands))
}

fn cell_at(c: [usize; 3]) -> usize {
    (c[2] * SIDE + c[1]) * SIDE + c[0]
}

/// Notes the field from the leaf patches' radiosities as they stand (W/m^2, less their
/// emission): before each pass of the final gather, so that what the rays read follows the
/// level's own light.
pub(crate) fn note(st: &State, ws: &mut [u8]) {
    let nb = st.bands;
    let at = st.lay.local_field;
    let pc = per(nb);
    let len = HEAD + CELLS * CLASSES * pc;
    // The box of the leaf patches' centres.
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in patches(st).filter_map(|e| leaf(st, ws, e)) {
        let c = centre(&p);
        lo = lo.min(c);
        hi = hi.max(c);
    }
    let mut head = [0.0f32; HEAD];
    let valid = lo.x <= hi.x && (hi - lo).is_finite();
    let size = ((hi - lo) / SIDE as f32).max(Vec3::splat(1e-6));
    if valid {
        head[..3].copy_from_slice(&lo.to_array());
        head[3..6].copy_from_slice(&size.to_array());
        head[6] = 1.0;
    }
    {
        let f = super::pool::floats_mut(ws, at, len);
        f.fill(0.0);
        f[..HEAD].copy_from_slice(&head);
    }
    if !valid {
        return;
    }
    for e in patches(st) {
        let Some(p) = leaf(st, ws, e) else {
            continue;
        };
        let sides = State::sides(e);
        let m = st.material(ws, st.polygon(ws, p.poly).material);
        let mut v = [0.0f32; MAX_BANDS];
        for side in 0..sides {
            if let Some(b) = st.b(ws, e, side) {
                for k in 0..nb {
                    v[k] += (b[k] - m.emit[side][k]).max(0.0) / sides as f32;
                }
            }
        }
        let o = HEAD + (cell_of(lo, size, centre(&p)) * CLASSES + sides - 1) * pc;
        let f = super::pool::floats_mut(ws, at, len);
        f[o] += 1.0;
        f[o + 1] += p.area;
        for k in 0..nb {
            f[o + 2 + k] += p.area * v[k];
        }
    }
}

fn centre(p: &super::records::Patch) -> Vec3 {
    let k = p.corner_count();
    let mut c = Vec3::ZERO;
    for x in &p.corners[..k] {
        c += Vec3::from(*x);
    }
    c / k.max(1) as f32
}

/// Every patch of the level (one-sided, then two-sided).
fn patches(st: &State) -> impl Iterator<Item = Elem> + '_ {
    [Kind::Patch1, Kind::Patch2]
        .into_iter()
        .flat_map(move |kind| (0..st.pool(kind).len).map(move |i| Elem::new(kind, i)))
}

/// Patch `e`'s record if it is a leaf of positive area.
fn leaf(st: &State, ws: &[u8], e: Elem) -> Option<super::records::Patch> {
    let p = st.patch(ws, e);
    (p.first_child == NONE && p.area > 0.0).then_some(p)
}

fn cell_of(lo: Vec3, size: Vec3, x: Vec3) -> usize {
    let r = (x - lo) / size;
    let c = |v: f32| (v.max(0.0) as usize).min(SIDE - 1);
    cell_at([c(r.x), c(r.y), c(r.z)])
}

/// The noted field of a level, read by gather rays.
#[derive(Clone, Copy)]
pub(crate) struct LocalField<'a> {
    f: &'a [f32],
    bands: usize,
}

impl<'a> LocalField<'a> {
    /// The field noted in `st`'s workspace, if one was.
    pub(crate) fn of(st: &State, ws: &'a [u8]) -> Option<Self> {
        let nb = st.bands;
        let len = HEAD + CELLS * CLASSES * per(nb);
        let f = super::pool::floats(ws, st.lay.local_field, len);
        (f[6] == 1.0).then_some(LocalField { f, bands: nb })
    }

    /// The mean reflected radiosity (W/m^2 per band) of the level's polygons of the class
    /// (`two_sided`) around the point `x` (world), into `out`: the cell's where it holds
    /// enough of them, else its neighbourhood's; `false` where `x` lies outside the grid
    /// or too few lie around.
    pub(crate) fn radiosity(&self, x: Vec3, two_sided: bool, out: &mut [f32]) -> bool {
        let lo = Vec3::new(self.f[0], self.f[1], self.f[2]);
        let size = Vec3::new(self.f[3], self.f[4], self.f[5]);
        let r = (x - lo) / size;
        if !(r.min_element() >= 0.0 && r.max_element() <= SIDE as f32) {
            return false;
        }
        let c = |v: f32| (v as usize).min(SIDE - 1);
        let at = [c(r.x), c(r.y), c(r.z)];
        let class = usize::from(two_sided);
        let pc = per(self.bands);
        for reach in 0..2usize {
            let mut sum = [0.0f32; MAX_BANDS + 2];
            for dz in -(reach as isize)..=reach as isize {
                for dy in -(reach as isize)..=reach as isize {
                    for dx in -(reach as isize)..=reach as isize {
                        let p = [
                            at[0] as isize + dx,
                            at[1] as isize + dy,
                            at[2] as isize + dz,
                        ];
                        if p.iter().any(|&v| v < 0 || v >= SIDE as isize) {
                            continue;
                        }
                        let cell = cell_at([p[0] as usize, p[1] as usize, p[2] as usize]);
                        let o = HEAD + (cell * CLASSES + class) * pc;
                        for (s, v) in sum[..pc].iter_mut().zip(&self.f[o..o + pc]) {
                            *s += v;
                        }
                    }
                }
            }
            if sum[0] >= MIN_PATCHES && sum[1] > 0.0 {
                for (k, o) in out.iter_mut().enumerate().take(self.bands) {
                    *o = sum[2 + k] / sum[1];
                }
                return true;
            }
        }
        false
    }
}
