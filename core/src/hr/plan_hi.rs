//! Planning a solve by hierarchical instantiation (`open::solve_hi`): the workspace that
//! opens every level at least (the top level and one path of levels below it, each at its
//! least) and a suggestion (the top level's estimated plan and the estimated room of its
//! widest closed instance, for as many as open side by side), from the census of its levels
//! alone. What the expanded scene would need does not enter: a level holds its closed
//! instances as leaves, and the scene's other levels are opened one path at a time.

use super::census::Census;
use super::error::HrError;
use super::layout::ALIGN;
use super::room::{Rooms, scratch_bytes as room_scratch_bytes};
use super::settings::{Inline, Settings};
use super::siblings::ROOMS_KEPT;
use crate::image::{SceneSource, SceneView};

/// The workspace a solve by hierarchical instantiation needs (bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HiPlan {
    /// A workspace that opens every level at its coarsest: the solve's own records, the top
    /// level's least (with the margin every level's least room has) and the least room of
    /// the widest path of levels below it. A solve refused for want of workspace names at
    /// least this.
    pub min_bytes: u64,
    /// A workspace that usually lets every level refine at this epsilon: the top level's
    /// estimated plan and, above it, the estimated room of its widest closed instance for as
    /// many as `threads` open side by side (an estimate: the run reports whether the budget
    /// limited a level).
    pub suggested_bytes: u64,
    /// The top level's own part of the suggestion (bytes).
    pub top_level_bytes: u64,
    /// The room left above the top level for its closed instances (bytes).
    pub children_bytes: u64,
    /// The solve's own records, the top level's least without the margin and the least
    /// room of the widest path below it (bytes): a workspace below it surely fails, one
    /// between it and `min_bytes` may open every level (most need less than their margin).
    pub bare_min_bytes: u64,
}

/// Bytes of scratch [`plan_hi`] needs.
pub fn plan_hi_scratch_bytes<S: SceneSource>(view: &SceneView<S>) -> usize {
    rooms_bytes(view).next_multiple_of(ALIGN) + room_scratch_bytes(view) + ALIGN
}

/// The least workspace of a solve whose records take `origin` bytes, whose top level's least
/// is `top_min` and whose widest path of levels below it needs `children_min` (bytes): the
/// top level with the margin every level's least room has (see `room::least_with_margin`).
pub(crate) fn least(origin: u64, top_min: u64, children_min: u64) -> u64 {
    origin
        .saturating_add(super::room::least_with_margin(top_min))
        .saturating_add(children_min)
        .saturating_add(ALIGN as u64)
}

fn rooms_bytes<S: SceneSource>(view: &SceneView<S>) -> usize {
    view.info().originals as usize * core::mem::size_of::<Rooms>()
}

/// Plans a solve of `view` by hierarchical instantiation with `settings`, the originals
/// `inline` names expanded in place. The plan is the same for any number of threads, as
/// the results are. `scratch` holds [`plan_hi_scratch_bytes`].
pub fn plan_hi<S: SceneSource>(
    view: &SceneView<S>,
    settings: &Settings,
    inline: Inline<'_>,
    scratch: &mut [u8],
) -> Result<HiPlan, HrError> {
    settings.check()?;
    let scratch = super::plan::aligned(scratch);
    let n = rooms_bytes(view);
    let at = n.next_multiple_of(ALIGN);
    if scratch.len() < at + room_scratch_bytes(view) {
        return Err(HrError::ScratchTooSmall);
    }
    let (rooms, rest) = scratch.split_at_mut(at);
    let rooms: &mut [Rooms] = if n == 0 {
        &mut []
    } else {
        bytemuck::try_cast_slice_mut(&mut rooms[..n]).map_err(|_| HrError::ScratchTooSmall)?
    };
    let (children, top) = super::room::rooms(view, settings, inline, rooms, rest)?;
    // What `open::solve_hi` keeps below the top level: every original's census and room.
    let originals = view.info().originals as usize;
    let origin = ((originals * core::mem::size_of::<Census>()).next_multiple_of(ALIGN)
        + n.next_multiple_of(ALIGN)) as u64;
    // As `open::level` leaves room (see `siblings::ROOMS_KEPT`).
    let children_bytes = children.suggested.saturating_mul(ROOMS_KEPT);
    // Its least with the margin of every level's least room, and what it is estimated to
    // grow by: `open::level` leaves its children the rest (see `room::capped_total`).
    let top_level_bytes = super::room::least_with_margin(top.min_bytes)
        .saturating_add(top.estimated_bytes.saturating_sub(top.min_bytes));
    Ok(HiPlan {
        min_bytes: least(origin, top.min_bytes, children.min),
        suggested_bytes: origin
            .saturating_add(top_level_bytes)
            .saturating_add(children_bytes)
            .saturating_add(ALIGN as u64),
        top_level_bytes,
        children_bytes,
        bare_min_bytes: origin
            .saturating_add(top.min_bytes)
            .saturating_add(children.min)
            .saturating_add(ALIGN as u64),
    })
}
