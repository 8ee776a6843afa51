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
use crate::geometry::Similarity;
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

/// The opened levels a gather ray has come out of, innermost first: each one's field and
/// the box (in the level it was opened in) where it is read. A ray that leaves an opened
/// branch, crosses the branch's parent level and meets a closed sibling one level further
/// out still reads the innermost level whose box holds the point.
#[derive(Clone, Copy)]
pub(crate) struct Inside<'a> {
    /// The opened level's field (`None` where it was not noted).
    pub field: Option<LocalField<'a>>,
    /// The opened instance's box in its own frame (m), and its placement in the world.
    pub lo: Vec3,
    pub hi: Vec3,
    pub place: Similarity,
    /// The level the one above was opened from, if it is itself an opened level.
    pub inner: Option<&'a Inside<'a>>,
}

/// What the chain of opened levels knows at a point.
pub(crate) enum Around {
    /// The point lies in no opened box.
    Outside,
    /// Inside an opened box, but no level there knows the light of that class around it.
    Unknown,
    /// Inside an opened box: the light around (written out).
    Known,
}

impl Inside<'_> {
    /// Whether the opened instance's box holds the point `x` (world, m).
    fn holds(&self, x: Vec3) -> bool {
        let p = crate::tables::closed::local_point(&self.place, x);
        p.cmpge(self.lo).all() && p.cmple(self.hi).all()
    }

    /// Whether any opened box of the chain holds `x` (world, m): the cheap test before a
    /// polygon's class is looked up.
    pub(crate) fn any_holds(&self, x: Vec3) -> bool {
        self.holds(x) || self.inner.is_some_and(|i| i.any_holds(x))
    }

    /// The mean reflected radiosity of the class around `x` (W/m^2 per band, into `out`)
    /// in the innermost opened level whose box holds `x` and whose field knows it.
    pub(crate) fn radiosity(&self, x: Vec3, two_sided: bool, out: &mut [f32]) -> Around {
        let inner = match self.inner {
            Some(i) => i.radiosity(x, two_sided, out),
            None => Around::Outside,
        };
        if let Around::Known = inner {
            return inner;
        }
        if !self.holds(x) {
            return inner;
        }
        match self.field {
            Some(f) if f.radiosity(x, two_sided, out) => Around::Known,
            _ => Around::Unknown,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate alloc;
    use alloc::vec;
    use alloc::vec::Vec;

    /// A one-band field over the unit cube at `lo` holding `patches` two-sided patches of
    /// radiosity `b` in every cell.
    fn field(lo: Vec3, patches: f32, b: f32) -> Vec<f32> {
        let pc = per(1);
        let mut f = vec![0.0f32; HEAD + CELLS * CLASSES * pc];
        f[..3].copy_from_slice(&lo.to_array());
        f[3..6].copy_from_slice(&[1.0 / SIDE as f32; 3]);
        f[6] = 1.0;
        for cell in 0..CELLS {
            let o = HEAD + (cell * CLASSES + 1) * pc;
            f[o] = patches;
            f[o + 1] = patches * 0.01;
            f[o + 2] = patches * 0.01 * b;
        }
        f
    }

    fn unit_box_at<'a>(
        f: Option<LocalField<'a>>,
        at: Vec3,
        inner: Option<&'a Inside<'a>>,
    ) -> Inside<'a> {
        Inside {
            field: f,
            lo: Vec3::ZERO,
            hi: Vec3::ONE,
            place: Similarity {
                translation: at,
                ..Similarity::IDENTITY
            },
            inner,
        }
    }

    fn read(chain: &Inside<'_>, x: Vec3) -> (u8, f32) {
        let mut out = [0.0f32; 1];
        let r = match chain.radiosity(x, true, &mut out) {
            Around::Outside => 0,
            Around::Unknown => 1,
            Around::Known => 2,
        };
        (r, out[0])
    }

    #[test]
    fn innermost_box_holding_the_point_is_read_first() {
        // An inner level in the cube at the origin (radiosity 1), inside an outer level in
        // the cube at (0.5, 0, 0) (radiosity 5): where both boxes hold the point the inner
        // level's light is read, where only the outer's the outer's, elsewhere nothing.
        let (fi, fo) = (field(Vec3::ZERO, 9.0, 1.0), field(Vec3::X * 0.5, 9.0, 5.0));
        let inner = unit_box_at(Some(LocalField { f: &fi, bands: 1 }), Vec3::ZERO, None);
        let outer = unit_box_at(
            Some(LocalField { f: &fo, bands: 1 }),
            Vec3::X * 0.5,
            Some(&inner),
        );
        for (x, want) in [
            (Vec3::new(0.7, 0.5, 0.5), (2, 1.0)),
            (Vec3::new(0.2, 0.1, 0.9), (2, 1.0)),
            (Vec3::new(1.3, 0.5, 0.5), (2, 5.0)),
            (Vec3::new(1.7, 0.5, 0.5), (0, 0.0)),
            (Vec3::new(0.7, 1.5, 0.5), (0, 0.0)),
        ] {
            let (r, v) = read(&outer, x);
            assert_eq!(r, want.0, "at {x}");
            assert!((v - want.1).abs() < 1e-6, "at {x}: {v}");
        }
    }

    #[test]
    fn an_inner_level_without_light_of_the_class_leaves_it_to_the_outer() {
        // The inner level holds too few patches: the outer one, whose box holds the point
        // too, is read; with no outer field either the point is inside but unknown.
        let (fi, fo) = (field(Vec3::ZERO, 0.0, 1.0), field(Vec3::ZERO, 9.0, 3.0));
        let inner = unit_box_at(Some(LocalField { f: &fi, bands: 1 }), Vec3::ZERO, None);
        let outer = unit_box_at(
            Some(LocalField { f: &fo, bands: 1 }),
            Vec3::ZERO,
            Some(&inner),
        );
        assert_eq!(read(&outer, Vec3::splat(0.5)), (2, 3.0));
        let bare = unit_box_at(None, Vec3::ZERO, Some(&inner));
        assert_eq!(read(&bare, Vec3::splat(0.5)), (1, 0.0));
        // One-sided light is not two-sided light.
        let mut out = [0.0f32];
        assert!(matches!(
            outer.radiosity(Vec3::splat(0.5), false, &mut out),
            Around::Unknown
        ));
    }
}
