//! Hooks for the tests of a level with closed instances while the level solve is built
//! (issue 18): load a level and look at what it holds. Not a stable interface.

use super::census::{Census, census_level, census_scratch_bytes};
use super::error::HrError;
use super::layout::Layout;
use super::plan::{aligned, sources};
use super::pool::read;
use super::settings::{Instancing, Settings};
use crate::geometry::{Aabb, Similarity};
use crate::image::{SceneSource, SceneView};
use crate::tables::closed::Placed;
use glam::{Quat, Vec3};

/// A closed instance of a loaded level.
#[derive(Clone, Copy, Debug)]
pub struct ClosedInstance<'a> {
    /// Its node in the image.
    pub node: u32,
    /// Its transform to world.
    pub place: Similarity,
    /// The world box the level keeps for it (m).
    pub bounds: Aabb,
    /// Its original's tables as the level reads them from its workspace, placed.
    pub placed: Placed<'a>,
    /// All the light it received (after loading, the direct light of suns and sky).
    pub received: &'a [f32],
    /// Links it receives.
    pub links: u32,
}

/// What a loaded level holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelCounts {
    /// The level's census.
    pub census: Census,
    /// Clusters, polygons and closed instances loaded.
    pub clusters: u32,
    pub polygons: u32,
    pub instances: u32,
    /// Table slots (originals with closed instances) loaded.
    pub slots: u32,
    /// True when every cluster's range of the instance order holds exactly the closed
    /// instances below it.
    pub order_consistent: bool,
}

/// A loaded level, to look at.
pub struct Level<'a> {
    st: &'a super::state::State,
    ws: &'a [u8],
}

impl Level<'_> {
    /// Closed instances loaded.
    pub fn instances(&self) -> u32 {
        self.st.instances
    }

    /// Closed instance `i` (in load order).
    pub fn instance(&self, i: u32) -> ClosedInstance<'_> {
        let leaf = self.st.instance(self.ws, i);
        ClosedInstance {
            node: leaf.node,
            place: Similarity {
                rotation: Quat::from_array(leaf.rotation),
                translation: leaf.translation.into(),
                scale: leaf.scale,
            },
            bounds: Aabb::new(Vec3::from(leaf.bbox_min), Vec3::from(leaf.bbox_max)),
            placed: self.st.placed(self.ws, i),
            received: self.st.received(self.ws, i),
            links: {
                let mut n = 0;
                let mut cur = self.st.links_head(
                    self.ws,
                    super::ids::Elem::new(super::ids::Kind::Instance, i),
                );
                while cur != crate::limits::NONE {
                    n += 1;
                    cur = self.st.link(self.ws, cur).next;
                }
                n
            },
        }
    }

    /// The links closed instance `i` receives: the emitter's handle (kind in the top three
    /// bits), the first coefficient and the flags.
    pub fn links_of(&self, i: u32, mut f: impl FnMut(u32, f32, u32)) {
        let mut cur = self.st.links_head(
            self.ws,
            super::ids::Elem::new(super::ids::Kind::Instance, i),
        );
        while cur != crate::limits::NONE {
            let l = self.st.link(self.ws, cur);
            f(l.emit, self.st.link_k(self.ws, cur)[0], l.flags);
            cur = l.next;
        }
    }

    /// What the closed instances let through along the segment `from..to` (polygons do not
    /// block here), but instance `skip`.
    pub fn transmittance(&self, from: Vec3, to: Vec3, skip: Option<u32>) -> f32 {
        let s = skip.map_or(crate::limits::NONE, |i| super::blockers::SKIP_INSTANCE | i);
        super::blockers::transmittance(self.st, self.ws, from, to, [s, crate::limits::NONE])
    }

    /// The closed instance the segment `from..to` meets first, but instance `skip`, and the
    /// parameter where (one with polygons of its own where the segment meets the first of
    /// them; one without at its box's entry, kept by the hash `h` with probability 1 - tau).
    pub fn first_instance(
        &self,
        from: Vec3,
        to: Vec3,
        skip: Option<u32>,
        h: u32,
    ) -> Option<(u32, f32)> {
        let skip = skip.unwrap_or(crate::limits::NONE);
        super::blockers::first_instance(self.st, self.ws, from, to, skip, h).map(|(i, t, _)| (i, t))
    }
}

/// Counts, lays out and loads the scene's top level under `instancing` into `workspace`
/// (its suggested size from the level's census is up to the caller: give plenty), builds the
/// core's BVH, lights the closed instances by the suns and sky, and lets `inspect` look at
/// it.
pub fn load_level<S: SceneSource>(
    view: &SceneView<S>,
    settings: &Settings,
    instancing: Instancing,
    workspace: &mut [u8],
    inspect: impl FnOnce(&Level<'_>),
) -> Result<LevelCounts, HrError> {
    settings.check()?;
    let ws = aligned(workspace);
    let need = census_scratch_bytes(view);
    if ws.len() < need {
        return Err(HrError::WorkspaceTooSmall {
            needed: need as u64,
        });
    }
    let c = census_level(
        view,
        settings.max_children,
        instancing,
        super::settings::Inline::NONE,
        super::settings::BlockingLimits::of(settings),
        &mut ws[..need],
    )?;
    let info = view.info();
    let lay = Layout::new(
        &c,
        info.materials,
        info.originals,
        sources(view),
        info.bands as usize,
        false,
        true,
        ws.len(),
    )
    .ok_or(HrError::WorkspaceTooSmall { needed: 0 })?;
    let (ws, bvh_bytes, scratch) = super::run::parts(&lay, ws, 0)?;
    let level = super::level::LevelRoot::scene(view);
    let mut st = super::load::load(view, settings, instancing, &level, &c, lay, ws)?;
    let vis: super::vis::Vis<'_, crate::visibility::Unoccluded> =
        super::vis::Vis::Internal(super::run::core_bvh(&st, ws, bvh_bytes)?);
    let mut ex = super::exec::Sequential;
    let mut seq = super::exec::Fallback {
        inner: &mut ex,
        scratch,
    };
    super::instance_light::light_instances(
        &mut st,
        ws,
        &vis,
        &mut seq,
        &mut super::exec::NoProgress,
    );
    let ws: &[u8] = ws;
    inspect(&Level { st: &st, ws });
    Ok(LevelCounts {
        census: c,
        clusters: st.clusters,
        polygons: st.polygons,
        instances: st.instances,
        slots: st.slots,
        order_consistent: order_consistent(&st, ws),
    })
}

/// Every cluster's instance range holds exactly the instances whose parent chain reaches
/// it, and the root's holds them all.
fn order_consistent(st: &super::state::State, ws: &[u8]) -> bool {
    if st.clusters == 0 {
        return st.instances == 0;
    }
    let root = st.cluster(ws, 0);
    if root.first_instance != 0 || root.instances != st.instances {
        return false;
    }
    for i in 0..st.clusters {
        let c = st.cluster(ws, i);
        for k in c.first_instance..c.first_instance + c.instances {
            let leaf: u32 = read(ws, st.lay.instance_order + 4 * k as usize);
            if leaf >= st.instances {
                return false;
            }
            // Walk up from the leaf's parent to the root: cluster i must be on the way.
            let mut cur = st.instance(ws, leaf).parent;
            let mut found = false;
            for _ in 0..=st.clusters {
                if cur == i {
                    found = true;
                    break;
                }
                if cur == crate::limits::NONE {
                    break;
                }
                cur = st.cluster(ws, cur).parent;
            }
            if !found {
                return false;
            }
        }
    }
    true
}

/// Solves the scene's top level under `instancing` with the core's BVH: refinement rounds,
/// then `inspect` looks at the level (its closed instances' light), then the level's
/// polygons go to `sink` and the stats come back.
pub fn solve_level<S, K, E>(
    view: &SceneView<S>,
    settings: &Settings,
    instancing: Instancing,
    workspace: &mut [u8],
    executor: &mut E,
    sink: &mut K,
    inspect: impl FnOnce(&Level<'_>),
) -> Result<super::Stats, super::SolveError<K::Error>>
where
    S: SceneSource,
    K: crate::sink::Sink,
    E: super::Executor,
{
    let mut progress = super::NoProgress;
    let mut run = super::run::Run::<crate::visibility::Unoccluded, E>::start(
        view,
        settings,
        instancing,
        &super::level::LevelRoot::scene(view),
        None,
        workspace,
        None,
        executor,
        &mut progress,
    )?;
    run.rounds(&mut progress);
    inspect(&Level {
        st: &run.st,
        ws: run.ws,
    });
    run.finish(&mut progress, sink)
}
