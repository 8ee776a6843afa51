//! Hooks for the benchmarks (`benches/hr.rs`): one phase of a solve at a time, from a state
//! that can be copied with its workspace and run again. Not a stable interface.

use super::plan::aligned;
use super::run::parts;
use super::*;

/// A solve stopped between phases (the workspace bytes hold the rest).
#[derive(Clone, Debug)]
pub struct Snapshot(state::State);

fn resume<'w, V: Visibility + ?Sized, E: Executor>(
    snap: &Snapshot,
    workspace: &'w mut [u8],
    vis: &'w V,
    executor: &'w mut E,
) -> Run<'w, V, E> {
    let ws = aligned(workspace);
    let (ws, _, scratch) = parts(&snap.0.lay, ws, 0).expect("the workspace of the snapshot");
    Run {
        st: snap.0.clone(),
        ws,
        vis: vis::Vis::External(vis),
        seq: exec::Fallback {
            inner: executor,
            scratch,
        },
    }
}

/// Loads and lights the scene and evaluates its first links.
pub fn start<S: SceneSource, V: Visibility + ?Sized, E: Executor>(
    view: &SceneView<S>,
    settings: &Settings,
    workspace: &mut [u8],
    vis: &V,
    executor: &mut E,
) -> Result<Snapshot, HrError> {
    let run = Run::start(
        view,
        settings,
        Instancing::None,
        &super::level::LevelRoot::scene(view),
        None,
        workspace,
        Some(vis),
        executor,
        &mut NoProgress,
    )?;
    Ok(Snapshot(run.st))
}

/// One refinement round (refinement passes until stable, closure, solution); returns
/// whether the rounds are over.
pub fn round<V: Visibility + ?Sized, E: Executor>(
    snap: &mut Snapshot,
    workspace: &mut [u8],
    vis: &V,
    executor: &mut E,
) -> bool {
    let mut run = resume(snap, workspace, vis, executor);
    let round = run.st.stats.rounds;
    let over = run.round(round, &mut NoProgress);
    snap.0 = run.st;
    over
}

/// One iteration of the solution: gather, push, pull.
pub fn gather<V: Visibility + ?Sized, E: Executor>(
    snap: &mut Snapshot,
    workspace: &mut [u8],
    vis: &V,
    executor: &mut E,
) {
    let mut run = resume(snap, workspace, vis, executor);
    solve::gather(&mut run.st, run.ws, &mut run.seq, false, false);
    solve::push(&run.st, run.ws);
    solve::pull(&run.st, run.ws);
    snap.0 = run.st;
}

/// Links alive.
pub fn links(snap: &Snapshot) -> u64 {
    snap.0.links.live() as u64
}

/// At `x` (receiving normal `n`), the visible form factor of the cluster that holds `poly`
/// `up` levels above it: by descent (`rays` samples) and by hit-or-miss cosine rays.
#[allow(clippy::too_many_arguments)]
pub fn probe_gather<V: Visibility + ?Sized>(
    snap: &Snapshot,
    workspace: &mut [u8],
    vis: &V,
    poly: u32,
    up: u32,
    x: glam::Vec3,
    n: glam::Vec3,
    rays: u32,
) -> (u32, f32, f32) {
    let ws = aligned(workspace);
    let (ws, _, _) = parts(&snap.0.lay, ws, 0).expect("the workspace of the snapshot");
    let st = &snap.0;
    let mut at = ids::Elem(st.patch(ws, ids::Elem(st.polygon(ws, poly).root)).parent);
    for _ in 0..up {
        at = ids::Elem::new(ids::Kind::Cluster, st.cluster(ws, at.index()).parent);
    }
    let (k, _, _, _) = cluster_kernel::gathered(
        st,
        ws,
        at,
        x,
        cluster_kernel::Plane::Facing(n),
        crate::limits::NONE,
        7,
        rays,
        true,
        vis,
    );
    // Hit or miss.
    let c = st.cluster(ws, at.index());
    let mut hits = 0u32;
    for j in 0..rays {
        let (u, v) = crate::sampling::unit2(crate::sampling::hash3(j, 99, 3));
        let d = super::sample::cosine_direction(n, u, v);
        if let Some((hit, _)) = vis.first_hit(x, st.beyond(x, d), [crate::limits::NONE; 2]) {
            let mut inside = false;
            for k in c.first_polygon..c.first_polygon + c.polygons {
                if st.ordered(ws, k) == hit {
                    inside = true;
                    break;
                }
            }
            let rec = st.polygon(ws, hit);
            let side = if glam::Vec3::from(rec.normal).dot(d) < 0.0 {
                0
            } else {
                1
            };
            if inside && side < state::State::sides(ids::Elem(rec.root)) {
                hits += 1;
            }
        }
    }
    (at.index(), k, hits as f32 / rays as f32)
}

/// Evaluates the link `recv <- emit` (raw handles) afresh: coefficients, open, seen.
pub fn probe_link<V: Visibility + ?Sized>(
    snap: &Snapshot,
    workspace: &mut [u8],
    vis: &V,
    recv: u32,
    emit: u32,
) -> ([[f32; 2]; 2], f32, f32, bool) {
    let ws = aligned(workspace);
    let (ws, _, _) = parts(&snap.0.lay, ws, 0).expect("the workspace of the snapshot");
    let c = eval::evaluate(&snap.0, ws, ids::Elem(recv), ids::Elem(emit), vis);
    (c.k, c.open, c.seen, c.exact)
}

/// The transport estimate of link `recv <- emit` with the given seed and rays.
pub fn probe_link_seeded<V: Visibility + ?Sized>(
    snap: &Snapshot,
    workspace: &mut [u8],
    vis: &V,
    recv: u32,
    emit: u32,
    seed: u32,
    rays: u32,
) -> [[f32; 2]; 2] {
    let ws = aligned(workspace);
    let (ws, _, _) = parts(&snap.0.lay, ws, 0).expect("the workspace of the snapshot");
    eval::evaluate_seeded(
        &snap.0,
        ws,
        ids::Elem(recv),
        ids::Elem(emit),
        vis,
        seed,
        rays,
        true,
    )
    .k
}

/// An element as the diagnostics see it: 0 cluster, 1 one-sided patch, 2 two-sided
/// patch; the input polygons below it (smallest and largest id, count); its area (m^2).
#[derive(Clone, Copy, Debug)]
pub struct ElemInfo {
    /// 0 cluster, 1 one-sided patch, 2 two-sided patch, 3 source.
    pub kind: u8,
    /// Smallest input polygon id below it.
    pub first: u32,
    /// Largest input polygon id below it.
    pub last: u32,
    /// Input polygons below it.
    pub polygons: u32,
    /// Surface area (m^2).
    pub area: f32,
    /// The element's raw handle.
    pub elem: u32,
}

fn info(st: &state::State, ws: &[u8], e: ids::Elem) -> ElemInfo {
    use ids::Kind;
    match e.kind() {
        Kind::Cluster => {
            let c = st.cluster(ws, e.index());
            let (mut lo, mut hi) = (u32::MAX, 0u32);
            for k in c.first_polygon..c.first_polygon + c.polygons {
                let p = st.ordered(ws, k);
                lo = lo.min(p);
                hi = hi.max(p);
            }
            ElemInfo {
                kind: 0,
                first: lo,
                last: hi,
                polygons: c.polygons,
                area: c.area,
                elem: e.0,
            }
        }
        Kind::Source => ElemInfo {
            kind: 3,
            first: 0,
            last: 0,
            polygons: 0,
            area: 0.0,
            elem: e.0,
        },
        k => {
            let p = st.patch(ws, e);
            ElemInfo {
                kind: if k == Kind::Patch2 { 2 } else { 1 },
                first: p.poly,
                last: p.poly,
                polygons: 1,
                area: p.area,
                elem: e.0,
            }
        }
    }
}

/// Every live link: receiver, emitter, its coefficients (receiving side x emitting
/// side), its open and seen coefficients (the refinement's), and its flags.
pub fn each_link(
    snap: &Snapshot,
    workspace: &mut [u8],
    mut f: impl FnMut(ElemInfo, ElemInfo, [[f32; 2]; 2], [f32; 2], u32),
) {
    let ws = aligned(workspace);
    let (ws, _, _) = parts(&snap.0.lay, ws, 0).expect("the workspace of the snapshot");
    let st = &snap.0;
    for i in 0..st.links.len {
        let l = st.link(ws, i);
        if l.flags & records::FREE != 0 {
            continue;
        }
        let k = st.link_k(ws, i);
        let kk = if k.len() == 1 {
            [[k[0], 0.0], [0.0, 0.0]]
        } else {
            [[k[0], k[1]], [k[2], k[3]]]
        };
        f(
            info(st, ws, ids::Elem(l.recv)),
            info(st, ws, ids::Elem(l.emit)),
            kk,
            [l.k_open, l.k_seen],
            l.flags,
        );
    }
}

/// Slots a link audit needs (`links x bands` for each of `audit`'s buffers).
pub fn link_slots(snap: &Snapshot) -> (usize, usize) {
    (snap.0.links.len as usize, snap.0.bands)
}

/// Per link (`[link * bands + band]`, W): the power it carries in the current solution and
/// the power that `rays` rays traced forward from the emitters take through it (see
/// `audit`); what no link carries comes back by where it went.
pub fn audit<V: Visibility + ?Sized>(
    snap: &Snapshot,
    workspace: &mut [u8],
    vis: &V,
    rays: u32,
    carried: &mut [f64],
    traced: &mut [f64],
) -> audit::Leftover {
    let ws = aligned(workspace);
    let (ws, _, _) = parts(&snap.0.lay, ws, 0).expect("the workspace of the snapshot");
    audit::carried(&snap.0, ws, carried);
    audit::traced(&snap.0, ws, vis, rays, traced)
}

/// What links into clusters hand their polygons in all (W per band; see `audit`).
pub fn distributed(snap: &Snapshot, workspace: &mut [u8]) -> [f64; 8] {
    let ws = aligned(workspace);
    let (ws, _, _) = parts(&snap.0.lay, ws, 0).expect("the workspace of the snapshot");
    audit::distributed(&snap.0, ws)
}

/// [`ElemInfo`] and flags of link `i`, or `None` for a free slot.
pub fn link_info(
    snap: &Snapshot,
    workspace: &mut [u8],
    i: u32,
) -> Option<(ElemInfo, ElemInfo, u32)> {
    let ws = aligned(workspace);
    let (ws, _, _) = parts(&snap.0.lay, ws, 0).expect("the workspace of the snapshot");
    let l = snap.0.link(ws, i);
    if l.flags & records::FREE != 0 {
        return None;
    }
    Some((
        info(&snap.0, ws, ids::Elem(l.recv)),
        info(&snap.0, ws, ids::Elem(l.emit)),
        l.flags,
    ))
}
