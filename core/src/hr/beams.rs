//! The light an opened instance's contents receive: what its closed self received, as beams
//! (W/m^2 on a plane facing each): every source of its level as it reached the instance,
//! and the links it received binned by direction on a grid of 64 (see `open`).

use super::error::HrError;
use super::ids::{Elem, Kind};
use super::level::beam_floats;
use super::state::State;
use crate::limits::{MAX_BANDS, NONE};
use crate::tables::grid::DirectionGrid;
use glam::Vec3;

/// Side of the direction grid the links into an instance are binned on (64 directions).
const BEAM_SIDE: u32 = 8;

/// Writes into `out` (from byte `at`) the beams that light closed instance `leaf`'s
/// contents: every source of the level as it reached the instance, then the links it
/// received binned by direction; returns how many.
pub(super) fn beams(
    st: &State,
    ws: &[u8],
    leaf: u32,
    out: &mut [u8],
    at: usize,
) -> Result<usize, HrError> {
    let nb = st.bands;
    let stride = beam_floats(nb);
    let grid = DirectionGrid::new(BEAM_SIDE).map_err(|_| HrError::SceneTooLarge)?;
    let cells = grid.cells() as usize;
    let n_max = st.sources as usize + cells;
    let need = at + 4 * n_max * stride;
    if out.len() < need {
        return Err(HrError::WorkspaceTooSmall {
            needed: need as u64,
        });
    }
    let floats: &mut [f32] = bytemuck::cast_slice_mut(&mut out[at..need]);
    let mut n = 0usize;
    for k in 0..st.sources {
        let src = Elem::new(Kind::Source, k);
        let super::state::Shape::Source { towards } = st.shape(ws, src) else {
            continue;
        };
        // Whole: the contents' own rays find what shades them in this level, and on
        // through the levels this one's rays go through for this source.
        let rec: super::records::Source = super::pool::read(ws, st.at(ws, src));
        let outer = if rec.outer == NONE {
            NONE
        } else {
            rec.outer + 1
        };
        let b = &mut floats[n * stride..(n + 1) * stride];
        b[..3].copy_from_slice(&towards.to_array());
        b[3] = f32::from_bits(outer);
        if let Some(irr) = st.b(ws, src, 0) {
            b[4..].copy_from_slice(irr);
        }
        n += 1;
    }
    // The links: per cell of the grid, the flux density and its mean direction.
    let mut sum = [[0.0f32; MAX_BANDS]; (BEAM_SIDE * BEAM_SIDE) as usize];
    let mut dir = [Vec3::ZERO; (BEAM_SIDE * BEAM_SIDE) as usize];
    let at_centre = super::instance_kernel::centre_of(st, ws, leaf);
    let mut cur = st.links_head(ws, Elem::new(Kind::Instance, leaf));
    while cur != NONE {
        let l = st.link(ws, cur);
        let mut s = [0.0f32; MAX_BANDS];
        super::instance_light::link_flux(
            st,
            ws,
            cur,
            at_centre,
            st.lay.strides.link_k,
            &mut s[..nb],
        );
        // Spread over the cone its emitter covers (see `instance_light::cone_directions`).
        let mut dirs = [Vec3::ZERO; super::instance_light::MAX_CONE];
        let m = super::instance_light::cone_directions(Vec3::from(l.dir), &mut dirs);
        for &d in &dirs[..m] {
            let c = grid.cell_of(d) as usize;
            let w = s[..nb].iter().copied().fold(0.0f32, f32::max) / m as f32;
            for (a, v) in sum[c].iter_mut().zip(&s[..nb]) {
                *a += v / m as f32;
            }
            dir[c] += d * w;
        }
        cur = l.next;
    }
    // The light of the level's other closed instances (see `exchange`).
    super::exchange::beams(st, ws, leaf, |d, e| {
        let c = grid.cell_of(d) as usize;
        let w = e.iter().copied().fold(0.0f32, f32::max);
        for (a, v) in sum[c].iter_mut().zip(e) {
            *a += v;
        }
        dir[c] += d * w;
    });
    for c in 0..cells {
        if sum[c][..nb].iter().all(|&v| v <= 0.0) {
            continue;
        }
        let d = if dir[c] != Vec3::ZERO {
            dir[c].normalize()
        } else {
            grid.direction(c as u32)
        };
        // Light that came through a link was shaded on its way: the contents' rays
        // towards it see only their own level.
        let b = &mut floats[n * stride..(n + 1) * stride];
        b[..3].copy_from_slice(&d.to_array());
        b[3] = f32::from_bits(0);
        b[4..].copy_from_slice(&sum[c][..nb]);
        n += 1;
    }
    Ok(n)
}
