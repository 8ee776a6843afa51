//! What a level and the levels opened in it add up to: the solve's stats, counts and
//! balance, each opened instance's tallied apart and added to its parent's in order.

use super::settings::Stats;
use crate::limits::MAX_BANDS;

/// What a level and the levels opened in it add up to. Each opened instance's levels are
/// tallied apart and added to their parent's in order, whether siblings open one at a time
/// or together: the sums do not depend on the thread count.
#[derive(Clone, Copy)]
pub(super) struct Tally {
    /// The top level's stats, with counts over all levels.
    pub stats: Stats,
    pub levels: u64,
    /// The levels' balances (see `balance::Scope::Level`).
    pub balance: super::balance::Balance,
    /// What the polygons handed out absorbed, from their gathered light (W per band); `None`
    /// once a level hands them out without a gather.
    pub absorbed: Option<[f64; MAX_BANDS]>,
}

impl Tally {
    pub fn new() -> Self {
        Tally {
            stats: Stats {
                converged: true,
                ..Stats::default()
            },
            levels: 0,
            balance: super::balance::Balance::default(),
            absorbed: Some([0.0; MAX_BANDS]),
        }
    }

    /// Adds the tally of an instance opened in this one's level.
    pub fn add(&mut self, o: &Tally) {
        let (t, l) = (&mut self.stats, &o.stats);
        add_level(t, l, 0, false);
        t.level_depth = t.level_depth.max(l.level_depth);
        t.closed_instances += l.closed_instances;
        t.own_blocking_instances += l.own_blocking_instances;
        t.levels_together += l.levels_together;
        t.opened_again += l.opened_again;
        t.largest_level = t.largest_level.max(l.largest_level);
        for (a, b) in t.leaf_histogram.iter_mut().zip(&l.leaf_histogram) {
            *a += b;
        }
        for (a, b) in t.peak_bytes_by_depth.iter_mut().zip(&l.peak_bytes_by_depth) {
            *a = (*a).max(*b);
        }
        self.levels += o.levels;
        self.balance.add(&o.balance);
        self.absorbed = match (self.absorbed, o.absorbed) {
            (Some(mut sum), Some(a)) => {
                for (s, x) in sum.iter_mut().zip(a) {
                    *s += x;
                }
                Some(sum)
            }
            _ => None,
        };
    }
}

/// Adds a level's counts to the solve's; the top level's stats stand for the solve.
pub(super) fn add_level(total: &mut Stats, level: &Stats, origin: usize, top: bool) {
    if top {
        let keep = (
            total.peak_bytes,
            total.level_depth,
            total.closed_instances,
            total.own_blocking_instances,
            total.largest_level,
            total.leaf_histogram,
            total.peak_bytes_by_depth,
            total.top_regions,
        );
        *total = *level;
        (
            total.peak_bytes,
            total.level_depth,
            total.closed_instances,
            total.own_blocking_instances,
            total.largest_level,
            total.leaf_histogram,
            total.peak_bytes_by_depth,
            total.top_regions,
        ) = keep;
    } else {
        total.polygons += level.polygons;
        total.clusters += level.clusters;
        total.patches += level.patches;
        total.links += level.links;
        total.evaluations += level.evaluations;
        total.rays += level.rays;
        total.rays_by_phase.lighting += level.rays_by_phase.lighting;
        total.rays_by_phase.links += level.rays_by_phase.links;
        total.rays_by_phase.final_gather += level.rays_by_phase.final_gather;
        total.iterations += level.iterations;
        total.budget_limited |= level.budget_limited;
        total.iteration_capped |= level.iteration_capped;
        total.converged &= level.converged;
    }
    total.peak_bytes = total.peak_bytes.max(origin as u64 + level.peak_bytes);
}
