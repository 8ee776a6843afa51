//! Planning: the workspace a scene needs for a setting, from its census.

use super::census::{Census, census};
use super::error::HrError;
use super::layout::{ALIGN, Layout};
use super::settings::Settings;
use crate::image::{SceneSource, SceneView};

/// What a scene needs, in bytes of workspace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    /// The expanded scene's counts.
    pub census: Census,
    /// Bytes of the static part (everything but the growing pools) at `min_bytes`.
    pub static_bytes: u64,
    /// The least workspace that holds the coarsest solution (input polygons, initial links).
    pub min_bytes: u64,
    /// A workspace that usually lets refinement finish at this epsilon (an estimate: the run
    /// reports whether the budget limited it).
    pub suggested_bytes: u64,
    /// What refinement at this epsilon is estimated to take (`suggested_bytes` before its
    /// floor of 16 MiB): the room an opened level is planned for.
    pub estimated_bytes: u64,
    /// Bytes per patch of a one-sided / two-sided polygon.
    pub patch_bytes: [u64; 2],
    /// Bytes per link.
    pub link_bytes: u64,
}

/// Aligns the workspace start; returns the usable part.
pub(super) fn aligned(ws: &mut [u8]) -> &mut [u8] {
    let skip = ws.as_ptr().align_offset(ALIGN).min(ws.len());
    &mut ws[skip..]
}

/// Plans a solve: the exact minimum and a suggested workspace size. `scratch` must hold
/// [`super::census_scratch_bytes`]. `internal_bvh`: whether the solve will build the core's own BVH
/// in the workspace (no visibility given to [`super::solve`]) rather than use the caller's.
pub fn plan<S: SceneSource>(
    view: &SceneView<S>,
    settings: &Settings,
    internal_bvh: bool,
    scratch: &mut [u8],
) -> Result<Plan, HrError> {
    settings.check()?;
    let c = census(view, settings.max_children, scratch)?;
    plan_level(view, settings, internal_bvh, &c, sources(view), false)
}

pub(super) fn sources<S: SceneSource>(view: &SceneView<S>) -> u32 {
    view.info().suns + view.info().sky
}

/// The plan of a level of census `c` lit by `n_sources` directional sources (`nested`: an
/// opened instance's level, see `Strides::links_apart`).
pub(super) fn plan_level<S: SceneSource>(
    view: &SceneView<S>,
    settings: &Settings,
    internal: bool,
    c: &Census,
    n_sources: u32,
    nested: bool,
) -> Result<Plan, HrError> {
    let info = view.info();
    let bands = info.bands as usize;
    // The layout of a workspace of `total` bytes.
    let layout = |total: usize| {
        Layout::new(
            c,
            info.materials,
            info.originals,
            n_sources,
            bands,
            nested,
            internal,
            total,
        )
    };
    let lay0 = layout(usize::MAX / 4).ok_or(HrError::SceneTooLarge)?;
    let st = lay0.strides;
    let fits = |total: u64| -> bool {
        let Some(lay) = layout(total as usize) else {
            return false;
        };
        let per = |stride: usize| (lay.block_size / stride) as u64;
        let blocks = |n: u64, stride: usize| {
            if n == 0 {
                0
            } else {
                n.div_ceil(per(stride).max(1))
            }
        };
        let links = 2 + n_sources as u64 + 64;
        let total = blocks(c.polys_one_sided, st.patch1)
            + blocks(c.polys_two_sided, st.patch2)
            + blocks(links, st.link);
        per(st.patch2) > 0 && per(st.link) > 0 && total <= lay.block_count as u64
    };
    // The smallest workspace whose layout holds the coarsest solution.
    let mut lo = lay0.fixed_bytes as u64;
    let mut hi = lo.saturating_mul(2).saturating_add(1 << 20);
    while !fits(hi) {
        lo = hi;
        hi = hi.checked_mul(2).ok_or(HrError::SceneTooLarge)?;
    }
    while lo + 1024 < hi {
        let mid = lo + (hi - lo) / 2;
        if fits(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let min_bytes = hi + ALIGN as u64;
    // Measured at epsilon 1e-3 (BENCHMARKS.md): plant and furniture scenes end near 1.3
    // patches and 1 to 5 links per polygon; large surfaces (walls, floors) add some thousands
    // of each, growing as 1/epsilon, the per-polygon part more slowly. Twice that, never less
    // than 16 MiB (nothing on a desktop; embedded callers set their own budget).
    let s = (1e-3 / settings.epsilon.max(1e-9)).clamp(0.1, 1000.0) as f64;
    let polys = c.polygons() as f64;
    let patches = 2.0 * (2.0 * polys * libm::sqrt(s) + 8000.0 * s);
    let links = 2.0 * (8.0 * polys * libm::sqrt(s) + 12000.0 * s);
    let patch_avg = if polys > 0.0 {
        (c.polys_one_sided as f64 * st.patch1 as f64 + c.polys_two_sided as f64 * st.patch2 as f64)
            / polys
    } else {
        st.patch1 as f64
    };
    // Emission bins (power and area): at most one cluster in 16 polygons is large enough to
    // keep them.
    let bins = polys / 16.0 * 2.0 * st.bins as f64;
    let grow = patches * patch_avg + links * st.link as f64 + bins;
    let estimated = (min_bytes as f64 + grow * 1.05).min(u64::MAX as f64 / 2.0) as u64;
    let suggested = estimated.max(16 << 20);
    let at_min = layout(min_bytes as usize).ok_or(HrError::SceneTooLarge)?;
    Ok(Plan {
        census: *c,
        static_bytes: at_min.static_bytes as u64,
        min_bytes,
        suggested_bytes: suggested.max(min_bytes),
        estimated_bytes: estimated.max(min_bytes),
        patch_bytes: [st.patch1 as u64, st.patch2 as u64],
        link_bytes: st.link as u64,
    })
}
