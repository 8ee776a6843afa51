//! What closed instances show gather rays (DESIGN.md "Instances inside a level"): each one's
//! radiance noted by direction cell and band after a level's solution, with the shape its
//! multiply scattered light takes over its height, read by `blockers::light_along` where a
//! ray meets an instance as a medium.

use super::exec::{Executor, Fallback, run_chunks_scaled};
use super::state::State;
use crate::limits::MAX_BANDS;
use glam::Vec3;

/// The grid of directions closed instances' radiance is noted on (256 cells).
pub(super) const RADIANCE_GRID: crate::tables::grid::DirectionGrid =
    crate::tables::grid::DirectionGrid::SIDE_16;

/// Cells of [`RADIANCE_GRID`].
const RADIANCE_CELLS: usize = 256;
const _: () = assert!(RADIANCE_CELLS == 16 * 16);

/// Bytes of the noted radiance of `n` closed instances (see [`note_radiance`]): by cell as
/// half floats of the instance's largest value (2 bytes, within 0.05% of each value, far
/// below what the tables know; scaled so that no radiosity overflows them), by height
/// slice as floats, then each instance's scale.
pub(crate) fn radiance_bytes(n: u32, bands: usize) -> usize {
    radiance_cells_bytes(n, bands) + 4 * n as usize * (HEIGHT_BINS * bands + 1)
}

/// Bytes of the noted radiance by cell, padded to 4.
fn radiance_cells_bytes(n: u32, bands: usize) -> usize {
    (2 * n as usize * RADIANCE_GRID.cells() as usize * bands).next_multiple_of(4)
}

/// Where closed instance `i`'s scale of its noted radiance lies (W/m^2).
fn scale_at(st: &State, i: u32) -> usize {
    let n = st.instances;
    st.lay.radiance
        + radiance_cells_bytes(n, st.bands)
        + 4 * (n as usize * HEIGHT_BINS * st.bands + i as usize)
}

/// Slices of a closed instance's height (its original's box, along the original's z) by
/// which the light it scattered more than once is shaped (see [`note_profile`]).
const HEIGHT_BINS: usize = 8;

/// Where closed instance `i`'s factor for height slice `bin` in band `band` lies.
pub(super) fn profile_at(st: &State, i: u32, bin: usize, band: usize) -> usize {
    st.lay.radiance
        + radiance_cells_bytes(st.instances, st.bands)
        + 4 * ((i as usize * HEIGHT_BINS + bin) * st.bands + band)
}

/// The height slice of polygon `q` of closed instance `i` (see [`HEIGHT_BINS`]).
pub(super) fn height_bin(st: &State, ws: &[u8], i: u32, q: u32) -> usize {
    let leaf = st.instance(ws, i);
    let Some(g) = st.original_geometry(ws, leaf.slot) else {
        return 0;
    };
    let Some((p, _)) = g.point_on(q, 0.5, 0.5) else {
        return 0;
    };
    height_bin_at(st, ws, i, p)
}

/// The height slice of the point `x` in closed instance `i`'s contents' frame (see
/// [`HEIGHT_BINS`]).
pub(super) fn height_bin_at(st: &State, ws: &[u8], i: u32, x: Vec3) -> usize {
    let r = st.slot(ws, st.instance(ws, i).slot).record;
    let (lo, hi) = (r.lo[2], r.hi[2]);
    let f = if hi > lo { (x.z - lo) / (hi - lo) } else { 0.0 };
    ((f.max(0.0) * HEIGHT_BINS as f32) as usize).min(HEIGHT_BINS - 1)
}

/// Notes every closed instance's factors by height slice (see [`note_profile`]): once lit,
/// while its light is its direct light alone.
pub(crate) fn note_profiles(st: &State, ws: &mut [u8]) {
    for i in 0..st.instances {
        note_profile(st, ws, i);
    }
}

/// Notes closed instance `i`'s factors by height slice: the mean direct irradiance of suns
/// and sky on its polygons in each slice (both sides), over that of all its polygons (1
/// where unknown). The tables give the light scattered more than once as a mean over the
/// whole instance, as it was measured alone; among neighbours the light around it fades
/// downwards as the direct light does (the soil under a dense maize canopy read 19% too
/// much NIR from the plants' lower leaves without this).
fn note_profile(st: &State, ws: &mut [u8], i: u32) {
    let nb = st.bands;
    let mut f = [[1.0f32; crate::limits::MAX_BANDS]; HEIGHT_BINS];
    if keeps_polygons(st, ws, i) {
        let placed = st.placed(ws, i);
        if let (Ok(all), Some(single)) = (
            crate::tables::closed::Received::over(&placed, st.received(ws, i)),
            placed.tables().single(),
        ) {
            // Called while its whole light is its direct light.
            let direct = |q: usize, side: usize, band: usize| all.first_irradiance(q, side, band);
            let mut sum = [[0.0f64; crate::limits::MAX_BANDS]; HEIGHT_BINS];
            let mut area = [0.0f64; HEIGHT_BINS];
            let (mut total, mut total_area) = ([0.0f64; crate::limits::MAX_BANDS], 0.0f64);
            for q in 0..single.polygons() {
                let a = single.polygon(q, 0).1 as f64;
                let h = height_bin(st, ws, i, q as u32);
                area[h] += a;
                total_area += a;
                for band in 0..nb {
                    let e = direct(q, 0, band) + direct(q, 1, band);
                    sum[h][band] += a * e.max(0.0) as f64;
                    total[band] += a * e.max(0.0) as f64;
                }
            }
            for h in 0..HEIGHT_BINS {
                for band in 0..nb {
                    if area[h] > 0.0 && total[band] > 0.0 && total_area > 0.0 {
                        f[h][band] = ((sum[h][band] / area[h]) / (total[band] / total_area)) as f32;
                    }
                }
            }
        }
    }
    for (h, x) in f.iter().enumerate() {
        for (band, v) in x.iter().enumerate().take(nb) {
            super::pool::write(ws, profile_at(st, i, h, band), v);
        }
    }
}

/// Where closed instance `i`'s noted radiance in cell `cell` and band `band` lies.
fn radiance_at(st: &State, i: u32, cell: u32, band: usize) -> usize {
    let cells = RADIANCE_GRID.cells() as usize;
    st.lay.radiance + 2 * ((i as usize * cells + cell as usize) * st.bands + band)
}

pub(super) fn radiance(st: &State, ws: &[u8], i: u32, cell: u32, band: usize) -> f32 {
    let at = radiance_at(st, i, cell, band);
    let scale: f32 = super::pool::read(ws, scale_at(st, i));
    scale * half::f16::from_bits(u16::from_le_bytes([ws[at], ws[at + 1]])).to_f32()
}

/// True when a ray that meets closed instance `i` meets one of its polygons and reads that
/// polygon's own first scattering (it blocks with its polygons and its tables keep them
/// apart): its noted radiance is then that of its light scattered more than once, else
/// that of all its light.
fn shows_polygons(st: &State, ws: &[u8], i: u32) -> bool {
    st.instance(ws, i).own_polygons == 0 && keeps_polygons(st, ws, i)
}

/// True when closed instance `i`'s tables keep its original's polygons' first scattering
/// apart and it has those polygons (its light's height profile is known, see
/// [`note_profile`]).
fn keeps_polygons(st: &State, ws: &[u8], i: u32) -> bool {
    let slot = st.instance(ws, i).slot;
    st.slot(ws, slot).polygons_kept != 0 && st.original_geometry(ws, slot).is_some()
}

/// Notes, for every closed instance, the radiosity (`pi` times the radiance, W/m^2 per
/// band) its contents show an observer in each cell's direction: its tables' intensity
/// that way over its cross-section, from the light it holds now; for one whose rays meet
/// its polygons (see [`shows_polygons`]) only that of its light scattered more than once
/// (its intensity less the first scattering's), which, times the factor of the met
/// polygon's height slice (see [`note_profile`]), is added to the first scattering of the
/// one polygon a ray meets. Gather rays read it (see
/// [`light_along`]) once the level is solved: the tables' sum over all their cells for
/// every ray was four fifths of a canopy's gather.
pub(crate) fn note_radiance<E: Executor>(st: &State, ws: &mut [u8], ex: &mut Fallback<'_, E>) {
    let nb = st.bands;
    let per = radiance_chunk_floats(nb);
    let mut ctx = NoteCtx { st, ws };
    // An instance a chunk, its cells on the executor's threads (the tables' intensity in
    // each cell's direction is the costly part); each writes only its own instance's.
    run_chunks_scaled(
        ex,
        &mut ctx,
        st.instances as usize,
        1,
        per,
        |c: &NoteCtx<'_>, i, buf| {
            let (st, ws) = (c.st, &*c.ws);
            let i = i as u32;
            let part = usize::from(shows_polygons(st, ws, i));
            let (noted, largest) = buf.split_at_mut(RADIANCE_CELLS * nb);
            noted.fill(0.0);
            largest[0] = 0.0;
            let placed = st.placed(ws, i);
            let Ok(r) = crate::tables::closed::Received::over(&placed, st.received(ws, i)) else {
                return;
            };
            for (cell, out) in noted.chunks_exact_mut(nb).enumerate() {
                let o = RADIANCE_GRID.direction(cell as u32);
                let shadow = placed.shadow(o);
                // (Not `<= 0.0`: a shadow that is not a number notes nothing either.)
                if !matches!(shadow.partial_cmp(&0.0), Some(core::cmp::Ordering::Greater)) {
                    continue;
                }
                let (mut all, mut once) = ([0.0f32; MAX_BANDS], [0.0f32; MAX_BANDS]);
                r.intensity_parts_all(&placed, o, &mut all[..nb], &mut once[..nb]);
                for (band, x) in out.iter_mut().enumerate() {
                    let v = if part == 0 {
                        all[band]
                    } else {
                        all[band] - once[band]
                    };
                    *x = core::f32::consts::PI * v.max(0.0) / shadow;
                    if x.is_finite() {
                        largest[0] = largest[0].max(*x);
                    }
                }
            }
        },
        |c: &mut NoteCtx<'_>, i, buf| {
            let (st, ws) = (c.st, &mut *c.ws);
            let i = i as u32;
            let (noted, largest) = buf.split_at(RADIANCE_CELLS * nb);
            let largest = largest[0];
            super::pool::write(ws, scale_at(st, i), &largest);
            for (cell, x) in noted.chunks_exact(nb).enumerate() {
                for (band, v) in x.iter().enumerate() {
                    let h = if largest > 0.0 {
                        (v / largest).min(1.0)
                    } else {
                        0.0
                    };
                    let at = radiance_at(st, i, cell as u32, band);
                    ws[at..at + 2].copy_from_slice(&half::f16::from_f32(h).to_bits().to_le_bytes());
                }
            }
        },
        &mut |_, _| {},
    );
}

/// Floats [`note_radiance`] hands back per closed instance: its radiosity per cell and
/// band, and the largest (the executor's scratch holds at least this many).
pub(crate) fn radiance_chunk_floats(bands: usize) -> usize {
    RADIANCE_CELLS * bands + 1
}

/// The state shared by [`note_radiance`]'s chunks.
struct NoteCtx<'a> {
    st: &'a State,
    ws: &'a mut [u8],
}
