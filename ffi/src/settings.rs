//! `HiradSettings`: what a C caller chooses, with the command line's defaults, checked
//! field by field before anything runs.

use crate::status::{Failure, HiradStatus};
use hirad::solve::policy::Policy;
use hirad_core::hr::Settings;

/// `HiradSettings::method`: as `hirad solve` without `--method`: hierarchical
/// instantiation where the instancing policy closes an original whose tables the scene
/// carries (or whose instances are too many to expand), else hierarchical radiosity.
pub const HIRAD_METHOD_AUTO: u32 = 0;
/// `HiradSettings::method`: hierarchical radiosity over the expanded scene.
pub const HIRAD_METHOD_HR: u32 = 1;
/// `HiradSettings::method`: hierarchical instantiation, level by level.
pub const HIRAD_METHOD_HI: u32 = 2;

/// `HiradSettings::instancing`: closed unless tables cannot stand for the original
/// (`--instancing auto`).
pub const HIRAD_INSTANCING_AUTO: u32 = 0;
/// `HiradSettings::instancing`: every instance closed, opened in turn (`all`).
pub const HIRAD_INSTANCING_ALL: u32 = 1;
/// `HiradSettings::instancing`: the instances at instancing depths 1, N + 1, 2N + 1, ...
/// closed, N = `instancing_every` (`every:N`).
pub const HIRAD_INSTANCING_EVERY: u32 = 2;
/// `HiradSettings::instancing`: every instance expanded (`none`: hierarchical radiosity).
pub const HIRAD_INSTANCING_NONE: u32 = 3;

/// `HiradSettings::final_rays` and `final_passes`: chosen from the scene.
pub const HIRAD_AUTO: u32 = u32::MAX;

/// What a solve does. Take `hirad_settings_default` and change fields: the defaults are
/// `hirad solve`'s. Units: epsilon, min_area and tolerance are fractions (see the fields),
/// counts are counts.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HiradSettings {
    /// `HIRAD_METHOD_AUTO` (default), `HIRAD_METHOD_HR` or `HIRAD_METHOD_HI`.
    pub method: u32,
    /// Which instances hierarchical instantiation keeps closed: `HIRAD_INSTANCING_AUTO`
    /// (default), `_ALL`, `_EVERY` (with `instancing_every`) or `_NONE`.
    pub instancing: u32,
    /// N of `HIRAD_INSTANCING_EVERY` (at least 1); ignored otherwise.
    pub instancing_every: u32,
    /// Worker threads, 1 to 1024; 0 (default): one per core. Results are identical for any
    /// count.
    pub threads: u32,
    /// Refinement threshold: a link is refined while its transfer exceeds epsilon times the
    /// scene's emitted power (dimensionless, default 1e-3; smaller is finer and slower).
    pub epsilon: f32,
    /// Smallest patch, as a fraction of the scene's total polygon area, in [0, 1).
    pub min_area: f32,
    /// Deepest quadtree subdivision of an input polygon (at most 24).
    pub max_depth: u32,
    /// Visibility rays per receiver point and per cluster link (1 to 1024).
    pub rays: u32,
    /// Convergence: iterations stop when the estimated remaining change of any radiosity is
    /// below this fraction of the largest radiosity (positive).
    pub tolerance: f32,
    /// Cap on iterations per solution (a solve that reaches it is not right).
    pub max_iterations: u32,
    /// Cap on refine-then-solve rounds.
    pub max_rounds: u32,
    /// Most children a cluster keeps before grouping levels are inserted (2 to 16).
    pub max_children: u32,
    /// Final gather rays per receiving side of every polygon: 0 none, `HIRAD_AUTO`
    /// (default) from epsilon, else at most 1,048,576.
    pub final_rays: u32,
    /// Final gather passes, 1 to 4, or `HIRAD_AUTO` (default).
    pub final_passes: u32,
    /// Sides suns and sky light directly: bit 0 fronts, bit 1 backs (default 3: both).
    pub sun_sides: u32,
    /// Closed instances whose original has at most this many polygons block rays with its
    /// polygons (hierarchical instantiation; default 16,384).
    pub blocking_polygons: u32,
    /// A level's closed approximate instances block with their own polygons when all of
    /// them hold at most this many (default 131,072).
    pub own_polygons: u32,
    /// The largest power imbalance (emitted + direct against absorbed + escaped) of any
    /// band, in percent, that a solve still calls right (default 5).
    pub max_imbalance_percent: f32,
    /// 1 (default): hierarchical instantiation makes the tables the scene lacks (minutes
    /// per original of a few thousand polygons; kept with the scene handle, in memory
    /// outside the workspace); 0: it refuses with `HIRAD_STATUS_NO_TABLES`.
    pub make_tables: u32,
    /// Largest side of every direction grid of tables made (4 to 128); 0 (default): those
    /// of `hirad tables`.
    pub table_max_side: u32,
}

impl Default for HiradSettings {
    fn default() -> Self {
        let s = Settings::default();
        HiradSettings {
            method: HIRAD_METHOD_AUTO,
            instancing: HIRAD_INSTANCING_AUTO,
            instancing_every: 2,
            threads: 0,
            epsilon: s.epsilon,
            min_area: s.min_area,
            max_depth: s.max_depth,
            rays: s.rays,
            tolerance: s.tolerance,
            max_iterations: s.max_iterations,
            max_rounds: s.max_rounds,
            max_children: s.max_children,
            final_rays: s.final_rays,
            final_passes: s.final_passes,
            sun_sides: u32::from(s.sun_sides),
            blocking_polygons: s.blocking_polygons,
            own_polygons: s.own_polygons,
            max_imbalance_percent: 5.0,
            make_tables: 1,
            table_max_side: 0,
        }
    }
}

/// The method asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Method {
    Auto,
    Hr,
    Hi,
}

/// Checked settings: the core's, and what the C ABI adds.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Checked {
    pub method: Method,
    /// `None` for `HIRAD_INSTANCING_NONE`.
    pub policy: Option<Policy>,
    /// True when the caller named a policy other than auto (which asks for hi, as
    /// `--instancing` does).
    pub policy_given: bool,
    pub threads: usize,
    pub core: Settings,
    pub max_imbalance_percent: f64,
    pub make_tables: bool,
    pub table_max_side: Option<u32>,
}

fn invalid(what: String) -> Failure {
    Failure::new(HiradStatus::InvalidSettings, what)
}

impl HiradSettings {
    /// Checks every field; the message names the first one out of range.
    pub(crate) fn check(&self) -> Result<Checked, Failure> {
        let method = match self.method {
            HIRAD_METHOD_AUTO => Method::Auto,
            HIRAD_METHOD_HR => Method::Hr,
            HIRAD_METHOD_HI => Method::Hi,
            m => {
                return Err(invalid(format!(
                    "method must be HIRAD_METHOD_AUTO (0), HIRAD_METHOD_HR (1) or HIRAD_METHOD_HI (2), not {m}"
                )));
            }
        };
        let policy = match self.instancing {
            HIRAD_INSTANCING_AUTO => Some(Policy::Auto),
            HIRAD_INSTANCING_ALL => Some(Policy::All),
            HIRAD_INSTANCING_EVERY if self.instancing_every >= 1 => {
                Some(Policy::Every(self.instancing_every))
            }
            HIRAD_INSTANCING_EVERY => {
                return Err(invalid(
                    "instancing_every must be at least 1 with HIRAD_INSTANCING_EVERY".into(),
                ));
            }
            HIRAD_INSTANCING_NONE => None,
            i => {
                return Err(invalid(format!(
                    "instancing must be HIRAD_INSTANCING_AUTO (0), _ALL (1), _EVERY (2) or _NONE (3), not {i}"
                )));
            }
        };
        if method == Method::Hr && self.instancing != HIRAD_INSTANCING_AUTO {
            return Err(invalid(
                "instancing chooses which instances HIRAD_METHOD_HI keeps closed; HIRAD_METHOD_HR expands every instance".into(),
            ));
        }
        if self.threads > 1024 {
            return Err(invalid(format!(
                "threads must lie in 0..=1024 (0: one per core), not {}",
                self.threads
            )));
        }
        let threads = match self.threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n as usize,
        };
        let Ok(sun_sides) = u8::try_from(self.sun_sides) else {
            return Err(invalid("sun_sides must lie in 1..=3".into()));
        };
        let core = Settings {
            epsilon: self.epsilon,
            min_area: self.min_area,
            max_depth: self.max_depth,
            rays: self.rays,
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
            max_rounds: self.max_rounds,
            max_children: self.max_children,
            final_rays: self.final_rays,
            final_passes: self.final_passes,
            sun_sides,
            blocking_polygons: self.blocking_polygons,
            own_polygons: self.own_polygons,
        };
        core.check().map_err(|e| invalid(e.to_string()))?;
        if !(self.max_imbalance_percent.is_finite() && self.max_imbalance_percent >= 0.0) {
            return Err(invalid(format!(
                "max_imbalance_percent must be a percentage of at least 0, not {}",
                self.max_imbalance_percent
            )));
        }
        let make_tables = match self.make_tables {
            0 => false,
            1 => true,
            m => return Err(invalid(format!("make_tables must be 0 or 1, not {m}"))),
        };
        let table_max_side = match self.table_max_side {
            0 => None,
            m @ 4..=128 => Some(m),
            m => {
                return Err(invalid(format!(
                    "table_max_side must be 0 (the defaults) or lie in 4..=128, not {m}"
                )));
            }
        };
        Ok(Checked {
            method,
            policy,
            policy_given: self.instancing != HIRAD_INSTANCING_AUTO,
            threads,
            core,
            max_imbalance_percent: f64::from(self.max_imbalance_percent),
            make_tables,
            table_max_side,
        })
    }
}

/// Writes the default settings (`hirad solve`'s) to `*settings`.
///
/// # Safety
/// `settings` must be null or point to writable storage for one `HiradSettings`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_settings_default(settings: *mut HiradSettings) -> HiradStatus {
    crate::status::guarded(|| {
        if settings.is_null() {
            return HiradStatus::NullArgument;
        }
        if !crate::status::aligned(settings) {
            return HiradStatus::Misaligned;
        }
        // SAFETY: non-null, aligned, and writable by the caller's promise.
        unsafe { settings.write(HiradSettings::default()) };
        HiradStatus::Ok
    })
}
