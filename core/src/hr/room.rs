//! The room a closed instance needs to be opened (hierarchical instantiation's memory bound):
//! its level's plan (coarsest and suggested) and its beams, plus, above them, the room of the
//! largest of its own closed instances. A level that refines leaves the room of its children
//! free above its part of the workspace (see `open::level`), so that a budget the top level
//! could fill alone still opens every level below it.

use super::census::{census_at, census_scratch_bytes, closed_bits};
use super::error::HrError;
use super::level::beam_floats;
use super::plan::plan_level;
use super::settings::{Inline, Instancing, Settings};
use crate::OriginalId;
use crate::image::{SceneSource, SceneView};
use bytemuck::{Pod, Zeroable};

/// Beams an opened level is planned for beyond the top level's sources: 64 binned link
/// directions a level, for levels up to 4 deep (a bound for planning; a deeper level's
/// beams only take more of the room left to it).
const PLANNED_BEAMS: u32 = 4 * 64;

/// Bytes added to every level's least room (see `rooms`).
pub(crate) const MARGIN: u64 = 64 << 10;

/// Workspace bytes: the least that opens a level (coarsest solutions all the way down) and
/// what usually lets its refinement finish at the solve's epsilon.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Room {
    pub min: u64,
    pub suggested: u64,
}

impl Room {
    fn max(self, o: Room) -> Room {
        Room {
            min: self.min.max(o.min),
            suggested: self.suggested.max(o.suggested),
        }
    }

    fn add(self, o: Room) -> Room {
        Room {
            min: self.min.saturating_add(o.min),
            suggested: self.suggested.saturating_add(o.suggested),
        }
    }
}

/// Per original: the room to open one of its instances, and the room its level leaves its
/// own closed instances.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct Rooms {
    pub open: Room,
    pub below: Room,
}

/// Bytes of workspace [`rooms`] needs besides its output (one [`Rooms`] per original).
pub(crate) fn scratch_bytes<S: SceneSource>(view: &SceneView<S>) -> usize {
    3 * Inline::bytes(view.info().originals) + census_scratch_bytes(view)
}

/// Fills `out` (one per original) with the rooms of the originals closed anywhere under the
/// policy `inline` (zero for the others) and returns the room the top level leaves its
/// closed instances, and the top level's own plan. `scratch` holds [`scratch_bytes`].
pub(crate) fn rooms<S: SceneSource>(
    view: &SceneView<S>,
    settings: &Settings,
    inline: Inline<'_>,
    out: &mut [Rooms],
    scratch: &mut [u8],
) -> Result<(Room, super::plan::Plan), HrError> {
    let info = *view.info();
    let n = info.originals as usize;
    if out.len() < n || scratch.len() < scratch_bytes(view) {
        return Err(HrError::ScratchTooSmall);
    }
    let bits = Inline::bytes(info.originals);
    // The census's scratch first: it starts with records that must stay aligned.
    let (census_scratch, rest) = scratch.split_at_mut(census_scratch_bytes(view));
    let (seen, rest) = rest.split_at_mut(bits);
    let (top_bits, rest) = rest.split_at_mut(bits);
    let mine = &mut rest[..bits];
    seen.fill(0);
    out[..n].fill(Rooms::default());
    let census = |root: u32, scratch: &mut [u8]| {
        census_at(
            view,
            settings.max_children,
            Instancing::Top,
            inline,
            super::settings::BlockingLimits::of(settings),
            root,
            scratch,
        )
    };
    // The top level's closed originals start the walk.
    let top = census(info.scene_root.0, census_scratch)?;
    top_bits.copy_from_slice(closed_bits(view, census_scratch));
    seen.copy_from_slice(top_bits);
    let top_plan = plan_level(view, settings, true, &top, info.suns + info.sky, false)?;
    let sources = info.suns + info.sky + PLANNED_BEAMS;
    let beams = (sources as usize * beam_floats(info.bands as usize) * 4) as u64;
    // Each pass computes every seen original's room from its children's of the pass before:
    // as many passes as levels are nested settle them (originals form no cycle).
    for _ in 0..=n {
        let mut changed = false;
        for k in 0..n {
            if seen[k / 8] & (1 << (k % 8)) == 0 {
                continue;
            }
            let root = view.original(OriginalId(k as u32))?.root;
            let c = census(root, census_scratch)?;
            mine.copy_from_slice(closed_bits(view, census_scratch));
            let plan = plan_level(view, settings, true, &c, sources, true)?;
            // The least with a margin: a level laid out in more than its least workspace
            // takes a little more for itself (block tables, alignment), and what it leaves
            // its children is counted in whole blocks.
            let own = Room {
                min: least_with_margin(plan.min_bytes) + beams,
                suggested: plan.estimated_bytes + beams,
            };
            let below = widest(out, mine);
            let r = Rooms {
                open: own.add(below),
                below,
            };
            for (s, m) in seen.iter_mut().zip(mine.iter()) {
                changed |= *s | m != *s;
                *s |= m;
            }
            if out[k] != r {
                out[k] = r;
                changed = true;
            }
        }
        if !changed {
            return Ok((widest(out, top_bits), top_plan));
        }
    }
    Err(HrError::SceneTooLarge)
}

/// A level's least workspace with the margin a level laid out in more than its least takes
/// for itself (block tables, alignment; what it leaves its children is counted in whole
/// blocks): a quarter more and 64 KiB.
pub(crate) fn least_with_margin(min_bytes: u64) -> u64 {
    min_bytes
        .saturating_add(min_bytes / 4)
        .saturating_add(MARGIN)
}

/// What a level opened from rooms `r` is estimated to grow by above its least (bytes): its
/// own suggested room less its own least, its children's taken out.
pub(crate) fn own_growth(r: &Rooms) -> u64 {
    let suggested = r.open.suggested.saturating_sub(r.below.suggested);
    let min = r.open.min.saturating_sub(r.below.min);
    suggested.saturating_sub(min)
}

/// The largest room of the originals whose bits are set.
fn widest(rooms: &[Rooms], bits: &[u8]) -> Room {
    let mut r = Room::default();
    for (k, x) in rooms.iter().enumerate() {
        if bits.get(k / 8).is_some_and(|b| b & (1 << (k % 8)) != 0) {
            r = r.max(x.open);
        }
    }
    r
}

/// Caps the refinement of a level whose blocks are `blocks` (of `size` bytes, `used` taken)
/// so that room for its children stays free: the children's suggested room for `together`
/// of them at once (they open side by side), else for one, else their least room for
/// `together`, else for one, whichever first leaves the level what it is estimated to grow
/// by (`own`, bytes) or half of what it has free, the less of the two; the least room for
/// one when none does but it fits. Returns the new block total.
pub(crate) fn capped_total(
    total: u32,
    used: u32,
    size: usize,
    children: Room,
    together: u64,
    own: u64,
) -> u32 {
    if children == Room::default() || size == 0 {
        return total;
    }
    let spare = (total.saturating_sub(used)) as u64 * size as u64;
    let mine = own.min(spare / 2);
    let wanted = [
        children.suggested.saturating_mul(together),
        children.suggested,
        children.min.saturating_mul(together),
        children.min,
    ];
    let keep = match wanted.iter().find(|&&r| r <= spare - mine) {
        Some(&r) => r,
        None if children.min <= spare => children.min,
        None => return total,
    };
    total - keep.div_ceil(size as u64) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_level_keeps_half_of_what_is_free_and_its_children_the_rest() {
        let kids = Room {
            min: 1_000,
            suggested: 10_000,
        };
        // Plenty: two children's suggested rooms kept free.
        assert_eq!(capped_total(1_000, 0, 100, kids, 2, u64::MAX), 800);
        // Less: one suggested room.
        assert_eq!(capped_total(300, 100, 100, kids, 2, u64::MAX), 200);
        // Less still: the least room for two, then for one.
        assert_eq!(capped_total(140, 100, 100, kids, 2, u64::MAX), 120);
        assert_eq!(capped_total(120, 100, 100, kids, 2, u64::MAX), 110);
        // Not even half for the least room: it all the same, when it fits.
        assert_eq!(capped_total(115, 100, 100, kids, 2, u64::MAX), 105);
        // It does not fit: nothing capped (the children will say what they need).
        assert_eq!(capped_total(105, 100, 100, kids, 2, u64::MAX), 105);
        // No children: nothing capped.
        assert_eq!(
            capped_total(105, 100, 100, Room::default(), 2, u64::MAX),
            105
        );
    }

    #[test]
    fn a_level_estimated_to_grow_little_leaves_its_children_more_than_half() {
        let kids = Room {
            min: 1_000,
            suggested: 10_000,
        };
        // 30,000 bytes free: half is not room for two suggested rooms, but the level is
        // estimated to grow by 5,000 only: two kept, the level refines in the rest.
        assert_eq!(capped_total(400, 100, 100, kids, 2, 5_000), 200);
        assert_eq!(capped_total(400, 100, 100, kids, 2, u64::MAX), 300);
        // Estimated to grow by more than half: as before, half at least.
        assert_eq!(capped_total(400, 100, 100, kids, 2, 20_000), 300);
        // Growth estimated at nothing: every option is weighed against all that is free.
        assert_eq!(capped_total(300, 100, 100, kids, 2, 0), 100);
    }
}
