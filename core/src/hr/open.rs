//! Hierarchical instantiation (the paper's section 3, figure 2): the scene is solved level by
//! level on a stack in one workspace. A level holds a node's subtree down to the next
//! instances, which stay closed (see `tables::closed`); once it is solved, its polygons and
//! its instances are handed out depth first, in global-id order: runs of its own polygons
//! go to the sink, and each instance in turn is opened: its contents become a level of their
//! own, solved in the workspace left free above the parent's, under the light that reached
//! the instance, then recursively handed out, then dropped.
//!
//! The light an opened instance's contents receive is what its closed self received, as
//! beams: the suns and sky seen from its box (the same visibility through the level's
//! polygons and the other closed instances that lit it), and every link that arrived on it,
//! binned by direction into a few sky directions. The outside stays fixed, as in the paper;
//! the contents see it as distant light, as they did when their tables were made.
//! (Where the paper copies the links themselves onto the new root and refines them against
//! the parent's elements, these beams keep the parent's state out of the child's
//! workspace: only what the beams carry crosses the boundary.) The final gather of an opened
//! level then reads the levels around through the stack, and takes their emitting polygons
//! directly (see `emitters::emitters_through`): a lamp beside an opened chair is no beam
//! from afar there.

use super::census::{Census, expanded_originals, subtree_polygons};
use super::error::{HrError, SolveError};
use super::exec::{Executor, Fallback, Progress};
use super::ids::{Elem, Kind};
use super::level::LevelRoot;
use super::room::Rooms;
use super::run::Run;
use super::settings::{Inline, Instancing, Settings, Stats};
use super::siblings::{BATCH_PER_WORKER, Batch, Entry, Item, MAX_JOBS, ROOMS_KEPT, open_batch};
use super::state::State;
use super::tally::{Tally, add_level};
use crate::NodeId;
use crate::geometry::Similarity;
use crate::image::{SceneSource, SceneView};
use crate::limits::{MAX_NODE_DEPTH, NONE};
use crate::sink::Sink;
use crate::visibility::Unoccluded;

/// Solves the scene level by level (see the module documentation) with the core's own BVH,
/// and hands every polygon to `sink` in global-id order. Instances of the originals
/// `inline` names are expanded in place in their parent's level instead of being closed
/// (the paper's skipped levels; [`Inline::NONE`]: every level of instances closed).
#[allow(clippy::too_many_arguments)]
pub fn solve_hi<S, K, E, P>(
    view: &SceneView<S>,
    settings: &Settings,
    inline: Inline<'_>,
    workspace: &mut [u8],
    executor: &mut E,
    progress: &mut P,
    sink: &mut K,
) -> Result<Stats, SolveError<K::Error>>
where
    S: SceneSource + Sync,
    K: Sink,
    E: Executor,
    P: Progress,
{
    settings.check()?;
    // Every original's expanded polygon count, kept for the whole solve (global ids).
    let originals = view.info().originals as usize;
    let memo_bytes = originals * core::mem::size_of::<Census>();
    let ws = super::plan::aligned(workspace);
    if ws.len() < memo_bytes {
        return Err(HrError::WorkspaceTooSmall {
            needed: memo_bytes as u64,
        }
        .into());
    }
    let (memo, rest) = ws.split_at_mut(memo_bytes.next_multiple_of(super::layout::ALIGN));
    let memo: &mut [Census] = if memo.is_empty() {
        &mut []
    } else {
        bytemuck::try_cast_slice_mut(&mut memo[..memo_bytes])
            .map_err(|_| HrError::ScratchTooSmall)?
    };
    expanded_originals(view, memo)?;
    let memo: &[Census] = memo;
    // Per original, the room its instances need to be opened, kept for the whole solve.
    let rooms_bytes = originals * core::mem::size_of::<Rooms>();
    let room_scratch = super::room::scratch_bytes(view);
    if rest.len() < rooms_bytes.next_multiple_of(super::layout::ALIGN) + room_scratch {
        return Err(HrError::WorkspaceTooSmall {
            needed: (memo_bytes + rooms_bytes + room_scratch) as u64,
        }
        .into());
    }
    let (rooms, rest) = rest.split_at_mut(rooms_bytes.next_multiple_of(super::layout::ALIGN));
    let rooms: &mut [Rooms] = if rooms_bytes == 0 {
        &mut []
    } else {
        bytemuck::try_cast_slice_mut(&mut rooms[..rooms_bytes])
            .map_err(|_| HrError::ScratchTooSmall)?
    };
    let (children, top) =
        super::room::rooms(view, settings, inline, rooms, &mut rest[..room_scratch])?;
    let top_min = top.min_bytes;
    let rooms: &[Rooms] = rooms;
    // The whole scene's receiving sides (the final gather's rays are spread over them).
    let need = super::census::census_scratch_bytes(view);
    if rest.len() < need {
        return Err(HrError::WorkspaceTooSmall {
            needed: (memo_bytes + need) as u64,
        }
        .into());
    }
    let whole = super::census::census(view, settings.max_children, &mut rest[..need])?;
    let scene_sides = whole.polys_one_sided + 2 * whole.polys_two_sided;
    let origin = memo_bytes.next_multiple_of(super::layout::ALIGN)
        + rooms_bytes.next_multiple_of(super::layout::ALIGN);
    let root = LevelRoot {
        inline,
        children,
        own_growth: top.estimated_bytes.saturating_sub(top.min_bytes),
        ..LevelRoot::scene(view)
    };
    let shared = Shared {
        view,
        settings,
        memo,
        rooms,
        unit_power: 0.0,
        scene_sides,
    };
    let mut ctx = Ctx::new(shared, progress, sink);
    // A level that found its part too small says what it lacked there; the whole solve
    // needs at least the top level and one path of its children, all at their least.
    let least = super::plan_hi::least(origin as u64, top_min, children.min);
    level(&mut ctx, &root, None, rest, origin, executor, 0, 0).map_err(|e| match e {
        SolveError::Hr(HrError::WorkspaceTooSmall { needed }) => {
            SolveError::Hr(HrError::WorkspaceTooSmall {
                needed: needed.max(least),
            })
        }
        e => e,
    })?;
    let Tally {
        stats: mut total,
        levels,
        mut balance,
        absorbed,
    } = ctx.tally;
    // As hr's: absorption from the light every polygon gathered, where it gathered.
    if let Some(a) = absorbed {
        balance.absorbed = a;
    }
    total.balance = balance;
    total.workspace_bytes = workspace.len() as u64;
    total.levels = levels;
    Ok(total)
}

/// What every level of a solve reads: the scene, the settings, and what was counted of
/// them before the first level.
pub(super) struct Shared<'a, S: SceneSource> {
    pub view: &'a SceneView<S>,
    pub settings: &'a Settings,
    pub memo: &'a [Census],
    /// Per original, the room to open its instances (see `room`).
    pub rooms: &'a [Rooms],
    /// The top level's power (W, epsilon's unit for every level).
    pub unit_power: f32,
    /// The whole scene's receiving sides (see `State::scene_sides`).
    pub scene_sides: u64,
}

// By hand: derived, they would ask the scene's source to be `Copy` too.
impl<S: SceneSource> Clone for Shared<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: SceneSource> Copy for Shared<'_, S> {}

/// What every level of a solve shares, where its results go, and what the levels solved
/// under it add up to.
pub(super) struct Ctx<'a, S: SceneSource, K: Sink, P: Progress> {
    pub shared: Shared<'a, S>,
    pub progress: &'a mut P,
    pub sink: &'a mut K,
    pub tally: Tally,
}

impl<'a, S: SceneSource, K: Sink, P: Progress> Ctx<'a, S, K, P> {
    /// A context with nothing tallied yet.
    pub(super) fn new(shared: Shared<'a, S>, progress: &'a mut P, sink: &'a mut K) -> Self {
        Ctx {
            shared,
            progress,
            sink,
            tally: Tally::new(),
        }
    }
}

/// Solves the level `root` in `ws` (which starts `origin` bytes into the caller's
/// workspace), its polygons' global ids from `first_id` on, then hands it out depth first,
/// opening its instances.
#[allow(clippy::too_many_arguments)]
pub(super) fn level<S, K, E, P>(
    ctx: &mut Ctx<'_, S, K, P>,
    root: &LevelRoot<'_>,
    outer: Option<&super::vis::Outer<'_>>,
    ws: &mut [u8],
    origin: usize,
    executor: &mut E,
    first_id: u64,
    depth: usize,
) -> Result<(), SolveError<K::Error>>
where
    S: SceneSource + Sync,
    K: Sink,
    E: Executor,
    P: Progress,
{
    if depth >= MAX_NODE_DEPTH {
        return Err(HrError::SceneTooLarge.into());
    }
    let view = ctx.shared.view;
    let mut run = Run::<Unoccluded, E>::start(
        view,
        ctx.shared.settings,
        Instancing::Top,
        root,
        outer,
        ws,
        None,
        executor,
        ctx.progress,
    )
    .map_err(|e| at_origin(e, origin))?;
    // Refined by the scene's threshold: the top level's power, not the contents' own; in
    // what the workspace holds once its children's room is left free.
    run.st.unit_power = ctx.shared.unit_power;
    // Room for its children as `siblings::ROOMS_KEPT` says, whatever the threads: a level
    // refines alike whether it is opened alone or as a job, on one thread or many.
    let b = run.st.blocks;
    run.st.blocks.total = super::room::capped_total(
        b.total,
        b.used,
        b.size,
        root.children,
        ROOMS_KEPT,
        root.own_growth,
    );
    run.st.scene_sides = ctx.shared.scene_sides;
    run.rounds(ctx.progress);
    // Every level's patches relit by the final gather's rays, as hr's are: the light the
    // closed instances send the level's polygons through links (an isotropic kernel from
    // each instance's centre) left the soil under 48 plants 18% short in NIR, and the
    // opened plants' gather rays read that soil; an opened level's own patches, lit by
    // binned beams, are read by its polygons' rays the same way.
    run.relight(ctx.progress);
    if ctx.progress.cancelled() || run.seq.inner.cancelled() {
        return Err(HrError::Cancelled.into());
    }
    let Run {
        mut st,
        ws,
        vis,
        seq,
    } = run;
    if depth == 0 {
        ctx.shared.unit_power = st.power;
    }
    if st.stats.diverged {
        return Err(SolveError::Hr(HrError::Diverged {
            iterations: st.stats.iterations,
        }));
    }
    let exec = seq.inner;
    let scratch = seq.scratch;
    st.stats.links = st.links.live() as u64;
    st.stats.clusters = st.clusters as u64;
    st.stats.patches = st.patches[0].len as u64 + st.patches[1].len as u64;
    st.stats.peak_bytes = st.stats.peak_bytes.max(st.bytes_in_use() as u64);
    st.stats.emitted_power = st.power;
    ctx.tally.levels += 1;
    // The solve's balance is the levels' sum: each level's leaves (a closed instance is
    // counted by the level it opens into), their light escaping only out of the scene.
    {
        let mut seq = Fallback {
            inner: &mut *exec,
            scratch: &mut *scratch,
        };
        let rays = 4 * st.settings.rays;
        let scope = super::balance::Scope::Level;
        let balance = super::balance::measure(&st, ws, &vis, &mut seq, rays, scope, ctx.progress);
        ctx.tally.balance.add(&balance);
        // What its closed instances show gather rays, here and from the levels opened in it.
        super::blockers::note_radiance(&st, ws, &mut seq);
        // What its polygons' gather rays read of its own light among its siblings.
        if outer.is_some() {
            super::local_field::note(&st, ws);
        }
    }
    let total = &mut ctx.tally.stats;
    add_level(total, &st.stats, origin, depth == 0);
    total.level_depth = total.level_depth.max(depth as u32);
    total.closed_instances += st.instances as u64;
    total.own_blocking_instances += (0..st.instances)
        .filter(|&i| st.instance(ws, i).own_polygons != 0)
        .count() as u64;
    if depth == 0 {
        let written = super::exchange::bytes_written(&st, ws);
        total.top_regions = st.lay.regions(st.blocks.used, written);
    }
    let leaves = leaf_elements(&st, ws);
    total.largest_level = total.largest_level.max(leaves);
    total.leaf_histogram[Stats::leaf_bin(leaves)] += 1;
    let d = depth.min(total.peak_bytes_by_depth.len() - 1);
    let peak = origin as u64 + st.stats.peak_bytes;
    total.peak_bytes_by_depth[d] = total.peak_bytes_by_depth[d].max(peak);
    // The parent's part of the workspace stays as it is; children open above it.
    let used = st.lay.blocks_base + st.blocks.used as usize * st.blocks.size;
    let (mine, free) = ws.split_at_mut(used.min(ws.len()));
    let mine: &[u8] = mine;
    let mut polygon = 0u32;
    let mut next_id = first_id;
    // Level polygons not yet handed out: from `polygon - pending` on.
    let mut pending = 0u32;
    // The level's nodes depth first, as `load` walked them: instances expanded in place
    // entered (and numbered, see `InstanceLeaf::pass`) in the same order.
    let mut stack: heapless::Vec<Walk, MAX_NODE_DEPTH> = heapless::Vec::new();
    let mut passes = 0u32;
    // Closed instances waiting to be opened, with the level's own polygons between them
    // (handed out in order after the instances before them): as jobs, BATCH_PER_WORKER for
    // each job the executor runs at once (workers take them one by one, so that uneven
    // siblings keep them all busy), or one by one alone.
    let mut batch: Batch<'_> = heapless::Vec::new();
    let mut waiting = 0usize;
    let together = match exec.parallelism().clamp(1, MAX_JOBS) {
        1 => 1,
        n => (n * BATCH_PER_WORKER).min(MAX_JOBS),
    };
    // Opens the waiting instances and hands out the polygons between them, if any (when
    // the batch is full, and at the end).
    macro_rules! open_pending {
        () => {
            if !batch.is_empty() {
                open_batch(
                    ctx,
                    &st,
                    mine,
                    &vis,
                    free,
                    origin + used,
                    exec,
                    scratch,
                    &batch,
                    depth,
                )?;
                batch.clear();
            }
        };
    }
    let enter = |node: u32, pass: u32, stack: &mut heapless::Vec<Walk, MAX_NODE_DEPTH>| {
        let rec = view.node(NodeId(node))?;
        stack
            .push(Walk {
                next: node + 1,
                end: rec.subtree_end,
                pass,
            })
            .map_err(|_| HrError::SceneTooLarge)?;
        Ok::<u32, HrError>(rec.poly_count)
    };
    let own = enter(root.node, 0, &mut stack)?;
    polygon += own;
    pending += own;
    next_id += own as u64;
    while let Some(top) = stack.last_mut() {
        if top.next >= top.end {
            stack.pop();
            continue;
        }
        let i = top.next;
        let pass = top.pass;
        let rec = view.node(NodeId(i))?;
        top.next = rec.subtree_end.max(i + 1);
        let mut node = i;
        let mut pass_in = pass;
        if let Some(id) = rec.instance() {
            let inst = view.instance(id)?;
            if root.inline.expands(inst.original) {
                // Expanded in place: its contents are part of this level.
                passes += 1;
                pass_in = passes;
                if inst.is_exact() {
                    node = view.original(inst.original())?.root;
                }
            } else {
                // Closed: opened below, together with the siblings that follow it, after
                // the level's polygons before it.
                if pending > 0 {
                    let _ = batch.push(Entry::Own {
                        polygon,
                        count: core::mem::take(&mut pending),
                        next_id,
                    });
                }
                let leaf = find_instance(&st, mine, i, pass);
                let (node, place) = contents(view, &st, mine, leaf, i)?;
                let count = subtree_polygons(view, node, ctx.shared.memo)?;
                if count > 0 {
                    let _ = batch.push(Entry::Child(Item {
                        leaf,
                        node,
                        place,
                        first_id: next_id,
                        inline: root.inline,
                        original: inst.original,
                    }));
                    waiting += 1;
                    if waiting >= together {
                        open_pending!();
                        waiting = 0;
                    }
                }
                next_id += count;
                continue;
            }
        }
        // The level's own polygons, in load order (its nodes depth first).
        let own = enter(node, pass_in, &mut stack)?;
        polygon += own;
        pending += own;
        next_id += own as u64;
    }
    open_pending!();
    flush(
        ctx,
        &st,
        mine,
        &vis,
        exec,
        scratch,
        polygon,
        &mut pending,
        next_id,
    )?;
    Ok(())
}

/// Hands the `pending` level polygons before `polygon` to the sink, the last of them with
/// global id `next_id - 1`.
#[allow(clippy::too_many_arguments)]
pub(super) fn flush<S, K, E, P>(
    ctx: &mut Ctx<'_, S, K, P>,
    st: &State,
    ws: &[u8],
    vis: &super::vis::Vis<'_, Unoccluded>,
    exec: &mut E,
    scratch: &mut [f32],
    polygon: u32,
    pending: &mut u32,
    next_id: u64,
) -> Result<(), SolveError<K::Error>>
where
    S: SceneSource,
    K: Sink,
    E: Executor,
    P: Progress,
{
    let count = core::mem::take(pending);
    if count == 0 {
        return Ok(());
    }
    let first = polygon - count;
    let id_offset = next_id - count as u64 - first as u64;
    let mut seq = Fallback {
        inner: exec,
        scratch,
    };
    let written = super::output::emit_range(
        st,
        ws,
        vis,
        &mut seq,
        ctx.progress,
        ctx.sink,
        first,
        count,
        id_offset,
    )
    .map_err(SolveError::Sink)?;
    if written.cancelled {
        return Err(HrError::Cancelled.into());
    }
    ctx.tally.absorbed = match (ctx.tally.absorbed, written.absorbed) {
        (Some(mut sum), Some(a)) => {
            for (s, x) in sum.iter_mut().zip(a) {
                *s += x;
            }
            Some(sum)
        }
        _ => None,
    };
    Ok(())
}

/// A node of a level being handed out: the next child node, the end of its subtree and
/// the instance expanded in place it lies in (see `InstanceLeaf::pass`).
#[derive(Clone, Copy)]
struct Walk {
    next: u32,
    end: u32,
    pass: u32,
}

/// The closed instance of node `node` in expansion `pass` (NONE when the level has none: it
/// was loaded as such, so it cannot happen).
fn find_instance(st: &State, ws: &[u8], node: u32, pass: u32) -> u32 {
    (0..st.instances)
        .find(|&k| {
            let l = st.instance(ws, k);
            l.node == node && l.pass == pass
        })
        .unwrap_or(NONE)
}

/// The node whose subtree an opened instance's contents are, and its transform to world:
/// an exact instance's original's root, an approximate one's own node, placed as the leaf.
fn contents<S: SceneSource>(
    view: &SceneView<S>,
    st: &State,
    ws: &[u8],
    leaf: u32,
    node: u32,
) -> Result<(u32, Similarity), HrError> {
    if leaf == NONE {
        return Err(HrError::SceneTooLarge);
    }
    let l = st.instance(ws, leaf);
    let place = Similarity {
        rotation: glam::Quat::from_array(l.rotation),
        translation: l.translation.into(),
        scale: l.scale,
    };
    let rec = view.node(NodeId(node))?;
    let id = rec.instance().ok_or(HrError::SceneTooLarge)?;
    let inst = view.instance(id)?;
    if inst.is_exact() {
        Ok((view.original(inst.original())?.root, place))
    } else {
        Ok((node, place))
    }
}

/// The leaf elements of a solved level: its leaf patches and its closed instances.
fn leaf_elements(st: &State, ws: &[u8]) -> u64 {
    let mut n = st.instances as u64;
    for kind in [Kind::Patch1, Kind::Patch2] {
        for i in 0..st.pool(kind).len {
            if st.patch(ws, Elem::new(kind, i)).first_child == NONE {
                n += 1;
            }
        }
    }
    n
}

/// A level's error, with a workspace it found too small counted from the start of the
/// caller's workspace (`origin` bytes below the level's part), not from its part's.
pub(super) fn at_origin(e: HrError, origin: usize) -> HrError {
    match e {
        HrError::WorkspaceTooSmall { needed } => HrError::WorkspaceTooSmall {
            needed: needed.saturating_add(origin as u64),
        },
        e => e,
    }
}
