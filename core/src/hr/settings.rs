//! What the caller chooses (`Settings`) and what a solve reports (`Stats`).

use super::balance::Balance;
use super::error::HrError;

/// Which instances a solve expands into their contents and which stay closed, standing for
/// their contents through their originals' directional tables (paper section 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Instancing {
    /// Every instance expanded: hierarchical radiosity over the whole scene.
    #[default]
    None,
    /// Every instance below the level's root stays closed: the levels of hierarchical
    /// instantiation ([`super::solve_hi`]), each opened in turn.
    Top,
}

/// The originals whose instances a level of hierarchical instantiation expands in place,
/// in the level of their parent, instead of closing them (the paper's skipped levels,
/// section 4 "Instantiation policy"): one bit per original, bit `k % 8` of byte `k / 8`
/// for original `k`, in storage the caller owns. An original past the bits is closed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Inline<'a> {
    bits: &'a [u8],
}

impl<'a> Inline<'a> {
    /// No original expanded in place: every instance below a level's root stays closed.
    pub const NONE: Inline<'static> = Inline { bits: &[] };

    /// The originals whose bits are set in `bits` are expanded in place.
    pub const fn new(bits: &'a [u8]) -> Self {
        Inline { bits }
    }

    /// True when instances of original `original` are expanded in place.
    pub fn expands(&self, original: u32) -> bool {
        self.bits
            .get(original as usize / 8)
            .is_some_and(|b| b & (1 << (original % 8)) != 0)
    }

    /// Bytes of a bit set over `originals` originals.
    pub const fn bytes(originals: u32) -> usize {
        (originals as usize).div_ceil(8)
    }
}

/// What the caller chooses: speed against accuracy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Refinement threshold: a link is refined while its transfer exceeds `epsilon` times the
    /// scene's emitted power (dimensionless). Smaller is finer and slower.
    pub epsilon: f32,
    /// Smallest patch, as a fraction of the scene's total polygon area.
    pub min_area: f32,
    /// Deepest quadtree subdivision of an input polygon.
    pub max_depth: u32,
    /// Visibility rays per receiver quadrature point (per side) and per cluster link.
    pub rays: u32,
    /// Convergence: stop iterating when the estimated remaining change of any radiosity is
    /// below this fraction of the largest radiosity.
    pub tolerance: f32,
    /// Cap on gather / push-pull iterations per solution.
    pub max_iterations: u32,
    /// Cap on refine-then-solve rounds.
    pub max_rounds: u32,
    /// Most children a cluster keeps before grouping levels are inserted (2..=16).
    pub max_children: u32,
    /// Final gather rays per receiving side of every input polygon (see `final_gather`):
    /// 0 leaves each polygon the hierarchy's irradiance, [`Settings::AUTO`] spreads
    /// 1e3 / epsilon rays over the scene (a million at the default epsilon), at least 64 and
    /// at most 0.65 / epsilon per side. Rounded to a square.
    pub final_rays: u32,
    /// Final gather passes (1..=4, or [`Settings::AUTO`]): with more than one, every leaf
    /// patch first gathers its own light that many times less one (with half the rays of the
    /// polygons' gather), and the polygons' gather reads those radiosities; the first such
    /// pass solves the hierarchy again with what it changed, so the links carry the change
    /// on (see `relight::relight`). `AUTO` relights
    /// at least once and goes on (up to 4 passes in all) while a pass still moves the light
    /// leaving the surfaces by more than 0.5% of what enters (`relight::SETTLED`).
    pub final_passes: u32,
    /// Sides of the polygons that suns and sky light directly: bit 0 the fronts, bit 1 the
    /// backs ([`Settings::BOTH_SIDES`], the default: both, as light does). `hirad tables`
    /// lights one side at a time to learn how an original scatters the light that falls on
    /// the fronts and on the backs of its leaves, which reflect differently.
    pub sun_sides: u8,
    /// Closed instances whose original has at most this many polygons (once expanded) block
    /// rays with the original's own polygons, placed (a two-level BVH, as ray tracers
    /// instance), so that their shadows are the contents' own; larger ones block as a
    /// medium, by the transmittance `tau` of the ray's direction. 0: every closed instance
    /// blocks by `tau`. Costs about 120 bytes per polygon of each such original, once per
    /// level.
    pub blocking_polygons: u32,
    /// A level's closed approximate instances (their own polygons are in the file, their
    /// original only stands in for them through its tables) block rays with their own
    /// polygons, each of at most [`Settings::blocking_polygons`], when all of them together
    /// hold at most this many: a ray then meets the leaves an instance really has where it
    /// stands, not its original's placed there. Else they block as their original does.
    /// 0: never. Costs about 120 bytes per polygon, per level.
    pub own_polygons: u32,
}

/// How many polygons closed instances may block with (see [`Settings::blocking_polygons`]
/// and [`Settings::own_polygons`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockingLimits {
    /// Most polygons of an original, or of an approximate instance's own.
    pub each: u32,
    /// Most own polygons of a level's approximate instances together.
    pub own: u32,
}

impl BlockingLimits {
    /// The limits `settings` asks for.
    pub fn of(settings: &Settings) -> Self {
        BlockingLimits {
            each: settings.blocking_polygons,
            own: settings.own_polygons,
        }
    }

    /// No polygons: every closed instance blocks by `tau`.
    pub const NONE: BlockingLimits = BlockingLimits { each: 0, own: 0 };
}

/// Most final gather passes.
pub const MAX_FINAL_PASSES: u32 = 4;

impl Settings {
    /// [`Settings::final_rays`] or [`Settings::final_passes`] chosen from the scene.
    pub const AUTO: u32 = u32::MAX;
    /// [`Settings::sun_sides`]: suns and sky light fronts and backs.
    pub const BOTH_SIDES: u8 = 3;
    /// Most final gather rays per side one may ask for.
    pub const MAX_FINAL_RAYS: u32 = 1 << 20;
    /// Default of [`Settings::blocking_polygons`].
    pub const BLOCKING_POLYGONS: u32 = 16_384;
    /// Default of [`Settings::own_polygons`].
    pub const OWN_POLYGONS: u32 = 1 << 17;

    /// Checks every setting's range.
    pub fn check(&self) -> Result<(), HrError> {
        if !(self.epsilon.is_finite() && self.epsilon > 0.0) {
            return Err(HrError::Settings("epsilon must be a positive number"));
        }
        if !(self.min_area.is_finite() && (0.0..1.0).contains(&self.min_area)) {
            return Err(HrError::Settings("min_area must lie in [0, 1)"));
        }
        if self.max_depth > 24 {
            return Err(HrError::Settings("max_depth must be at most 24"));
        }
        if self.rays == 0 || self.rays > 1024 {
            return Err(HrError::Settings("rays must lie in 1..=1024"));
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(HrError::Settings("tolerance must be a positive number"));
        }
        if !(2..=16).contains(&self.max_children) {
            return Err(HrError::Settings("max_children must lie in 2..=16"));
        }
        if !(1..=MAX_FINAL_PASSES).contains(&self.final_passes) && self.final_passes != Self::AUTO {
            return Err(HrError::Settings(
                "final_passes must lie in 1..=4 (or be Settings::AUTO)",
            ));
        }
        if self.final_rays > Self::MAX_FINAL_RAYS && self.final_rays != Self::AUTO {
            return Err(HrError::Settings(
                "final_rays must lie in 0..=1048576 (or be Settings::AUTO)",
            ));
        }
        if !(1..=Self::BOTH_SIDES).contains(&self.sun_sides) {
            return Err(HrError::Settings(
                "sun_sides must lie in 1..=3 (bit 0 fronts, bit 1 backs)",
            ));
        }
        Ok(())
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            epsilon: 1e-3,
            min_area: 1e-6,
            max_depth: 12,
            rays: 4,
            tolerance: 1e-4,
            max_iterations: 20_000,
            max_rounds: 24,
            max_children: 8,
            final_rays: Settings::AUTO,
            final_passes: Settings::AUTO,
            sun_sides: Settings::BOTH_SIDES,
            blocking_polygons: Settings::BLOCKING_POLYGONS,
            own_polygons: Settings::OWN_POLYGONS,
        }
    }
}

/// What a solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Input polygons (after expansion).
    pub polygons: u64,
    /// Clusters (grouping levels included).
    pub clusters: u64,
    /// Patches (input polygons and their sub-patches).
    pub patches: u64,
    /// Links at the end.
    pub links: u64,
    /// Most links alive at once.
    pub peak_links: u64,
    /// Link coefficients computed.
    pub evaluations: u64,
    /// Visibility rays cast.
    pub rays: u64,
    /// Of `rays`, those of each phase.
    pub rays_by_phase: RaysByPhase,
    /// Gather / push-pull iterations, all rounds.
    pub iterations: u64,
    /// Refine-then-solve rounds.
    pub rounds: u32,
    /// Refinement passes, all rounds.
    pub refinement_passes: u64,
    /// Peak workspace bytes in use.
    pub peak_bytes: u64,
    /// Workspace bytes provided.
    pub workspace_bytes: u64,
    /// True when refinement stopped because the workspace was full.
    pub budget_limited: bool,
    /// True when the last solution stopped at the iteration cap before converging.
    pub iteration_capped: bool,
    /// The power epsilon was relative to at the end (W, largest band): what leaves all
    /// surfaces, emitted and reflected.
    pub emitted_power: f32,
    /// True when the last solution met the tolerance (false: it stopped at the iteration
    /// cap, see `remaining_change`).
    pub converged: bool,
    /// The estimated change still to come in the last solution, relative to the largest
    /// radiosity (the geometric tail of the last iterations' changes).
    pub remaining_change: f32,
    /// True when a radiosity grew without bound (not finite): the solution is meaningless and
    /// `converged` is false.
    pub diverged: bool,
    /// Where the power went, per band.
    pub balance: Balance,
    /// Final gather passes made, the polygons' own included (0 without the gather).
    pub final_passes: u32,
    /// How much the last relighting pass moved the light leaving the surfaces, relative to
    /// what enters (largest band; 0 with fewer than two passes).
    pub final_change: f32,
    /// Levels solved (hierarchical instantiation: the top level and every instance opened;
    /// 0 for a solve of the expanded scene).
    pub levels: u64,
    /// The deepest level opened (the top level is 0).
    pub level_depth: u32,
    /// Closed instances over all levels.
    pub closed_instances: u64,
    /// Closed approximate instances that blocked rays with the polygons they hold, over all
    /// levels (see [`Settings::own_polygons`]).
    pub own_blocking_instances: u64,
    /// Levels solved in jobs beside their siblings' (see [`super::Executor::run_jobs`]),
    /// the levels opened inside them included.
    pub levels_together: u64,
    /// Instances opened again alone after their job's part of the workspace proved too
    /// small.
    pub opened_again: u64,
    /// The most leaf elements (leaf patches and closed instances) of one level.
    pub largest_level: u64,
    /// Levels by their leaf elements (leaf patches and closed instances: what one local
    /// solve holds, the paper's figure 4, right): entry `k` counts the levels with
    /// `2^k <= leaves < 2^(k+1)` (entry 0 also those with none).
    pub leaf_histogram: [u64; 32],
    /// Per level depth (the top level is 0; depths past the last entry count there), the
    /// most workspace bytes in use while a level of that depth was solved: its own and its
    /// ancestors' below it on the stack.
    pub peak_bytes_by_depth: [u64; 32],
    /// Where the top level's workspace goes (hierarchical instantiation; zero otherwise).
    pub top_regions: WorkspaceRegions,
}

/// A level's workspace by what it holds (bytes), as laid out; the exchange's entries as
/// written (the rest of their region is never touched, so never resident).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WorkspaceRegions {
    /// Materials, polygons, clusters and their children, sources, the walkers' stacks.
    pub scene: u64,
    /// Closed instances' records, their BVH and their transmittance towards each source.
    pub instances: u64,
    /// The light the closed instances received (three parts each).
    pub received: u64,
    /// The closed originals' tables.
    pub tables: u64,
    /// The polygons and BVHs of the originals whose closed instances block with them.
    pub blocking: u64,
    /// The light between closed instances, as laid out (for every ray) ...
    pub exchange: u64,
    /// ... and as written.
    pub exchange_written: u64,
    /// The radiance closed instances show gather rays, per direction.
    pub radiance: u64,
    /// Patches, links and bins: the blocks used and the pools' block tables.
    pub blocks: u64,
    /// The core's own BVH over the level's polygons and the executor's scratch.
    pub bvh_scratch: u64,
}

impl Stats {
    /// The entry of [`Stats::leaf_histogram`] that counts a level of `leaves` leaf elements.
    pub fn leaf_bin(leaves: u64) -> usize {
        (63 - leaves.max(1).leading_zeros()) as usize
    }
}

/// Visibility rays per phase of a solve (what the ray count of [`Stats`] is spent on).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RaysByPhase {
    /// Direct light of suns and sky on every patch, its buried points, the closed-scene test.
    pub lighting: u64,
    /// Visibility of links.
    pub links: u64,
    /// The final gather: relighting passes and the polygons' own gather.
    pub final_gather: u64,
}
