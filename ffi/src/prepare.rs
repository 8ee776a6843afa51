//! What a plan and a solve share: the method the settings come to on this scene (the
//! instancing policy applied as `hirad solve` applies it), the tables hierarchical
//! instantiation needs (made when the scene lacks them), and the workspace bytes it takes.

use crate::callbacks::ProgressCb;
use crate::scene::{HiradScene, Source};
use crate::settings::{Checked, Method};
use crate::status::{Failure, HiradStatus};
use hirad::solve::RayonExecutor;
use hirad::solve::policy::{self, Decision};
use hirad_core::hr::{self, HrError};
use hirad_core::image::SceneView;

/// The method a scene and settings come to: `Some(decision)` solves by hierarchical
/// instantiation, `None` by hierarchical radiosity.
pub(crate) struct Prepared {
    pub hi: Option<Decision>,
    /// Tables were made: the handle's `completed` image is the one to solve.
    pub completed: bool,
    /// Originals whose tables were made now.
    pub tables_made: u32,
    /// Seconds spent making them.
    pub table_seconds: f64,
}

impl Prepared {
    /// The image to solve.
    pub(crate) fn view<'s>(&self, scene: &'s HiradScene) -> Option<&'s SceneView<Source>> {
        if self.completed {
            scene.completed.as_ref().map(|(v, _)| v)
        } else {
            scene.view.as_ref()
        }
    }
}

/// A core error as a status and message.
pub(crate) fn failure(e: HrError) -> Failure {
    let status = match e {
        HrError::Image(_)
        | HrError::SceneTooLarge
        | HrError::NoLight
        | HrError::Empty
        | HrError::BadGeometry { .. }
        | HrError::NoSteadyState { .. } => HiradStatus::InvalidScene,
        HrError::NoTables { .. } => HiradStatus::NoTables,
        HrError::WorkspaceTooSmall { .. } => HiradStatus::WorkspaceTooSmall,
        HrError::Settings(_) => HiradStatus::InvalidSettings,
        HrError::Diverged { .. } => HiradStatus::NotRight,
        HrError::Cancelled => HiradStatus::Cancelled,
        HrError::ScratchTooSmall => HiradStatus::Internal,
    };
    Failure::new(status, e.to_string())
}

/// Applies the settings' method and instancing policy to `scene` as `hirad solve` does, and
/// makes the tables hierarchical instantiation needs and the image lacks (telling
/// `progress`). `caster`: the caller gave its ray caster, which serves hr only (refused
/// before any table is made).
pub(crate) fn prepare(
    scene: &mut HiradScene,
    c: &Checked,
    caster: bool,
    progress: &mut ProgressCb,
    exec: &mut RayonExecutor<'_>,
) -> Result<Prepared, Failure> {
    let view = scene.open_view()?;
    let policy = match c.method {
        Method::Hr => None,
        Method::Auto | Method::Hi => c.policy,
    };
    let decision = match policy {
        Some(p) => Some(
            policy::decide(view, p, &[])
                .map_err(|e| Failure::new(HiradStatus::InvalidScene, format!("{e:#}")))?,
        ),
        None => None,
    };
    let hi = match (c.method, &decision) {
        (Method::Hr, _) | (_, None) => false,
        (Method::Hi, Some(_)) => true,
        (Method::Auto, Some(_)) if c.policy_given => true,
        (Method::Auto, Some(d)) => d.hi_by_default(),
    };
    let mut prepared = Prepared {
        hi: None,
        completed: false,
        tables_made: 0,
        table_seconds: 0.0,
    };
    let Some(d) = decision.filter(|_| hi) else {
        return Ok(prepared);
    };
    if caster {
        return Err(Failure::new(
            HiradStatus::InvalidSettings,
            "a caller's ray caster serves HIRAD_METHOD_HR only: hierarchical instantiation casts rays through each level's own BVH and its closed instances (these settings come to HIRAD_METHOD_HI on this scene: set method to HIRAD_METHOD_HR, or give no caster)",
        ));
    }
    if let Some(e) = d.closed_emitter() {
        return Err(Failure::new(
            HiradStatus::InvalidSettings,
            format!(
                "instancing {} closes the instances of '{}', which emit light: tables carry no emission, so their light would be lost (HIRAD_INSTANCING_AUTO expands them in place)",
                d.policy, e.name
            ),
        ));
    }
    let mut missing = Vec::new();
    for k in d.closed() {
        let has = view
            .table_of(hirad_core::OriginalId(k as u32))
            .map_err(|e| Failure::new(HiradStatus::InvalidScene, e.to_string()))?
            .is_some();
        if !has {
            missing.push(k);
        }
    }
    if !missing.is_empty() {
        let names: Vec<&str> = missing
            .iter()
            .map(|&k| d.originals[k].name.as_str())
            .collect();
        if !c.make_tables {
            return Err(Failure::new(
                HiradStatus::NoTables,
                format!(
                    "the scene has no directional tables for {}, whose instances hierarchical instantiation closes: set make_tables to 1 (or make them once with `hirad tables SCENE -o OUT.hirb`), or solve with HIRAD_METHOD_HR",
                    names.join(", ")
                ),
            ));
        }
        let side = c.table_max_side.unwrap_or(0);
        if !matches!(scene.completed, Some((_, s)) if s == side) {
            let start = std::time::Instant::now();
            let mut model = hirad::scene::decompile(view)
                .map_err(|e| Failure::new(HiradStatus::InvalidScene, e.to_string()))?;
            hirad::tables::complete_with(
                &mut model,
                &missing,
                exec,
                c.table_max_side,
                None,
                &mut |what: &str, done: u64, total: u64| {
                    progress.tell(what, done, total);
                },
            )
            .map_err(|e| {
                Failure::new(
                    HiradStatus::TablesFailed,
                    format!(
                        "making the directional tables of {}: {e:#}",
                        names.join(", ")
                    ),
                )
            })?;
            let bytes = hirad::scene::compile(&model)
                .map_err(|e| Failure::new(HiradStatus::Internal, e.to_string()))?;
            let made = SceneView::open(Source::Owned(bytes.into_boxed_slice()))
                .map_err(|e| Failure::new(HiradStatus::Internal, e.to_string()))?;
            scene.completed = Some((made, side));
            prepared.tables_made = missing.len() as u32;
            prepared.table_seconds = start.elapsed().as_secs_f64();
        }
        prepared.completed = true;
    }
    prepared.hi = Some(d);
    Ok(prepared)
}

/// Workspace bytes: the least a solve starts with, what surely suffices to open every level
/// at its coarsest, and the suggestion (see `HiradPlan`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bytes {
    pub min: u64,
    pub sure: u64,
    pub suggested: u64,
}

/// The workspace `prepared` needs on `scene` with `c` (`caster`: the caller casts rays,
/// so no BVH is built in the workspace).
pub(crate) fn bytes(
    scene: &HiradScene,
    prepared: &Prepared,
    c: &Checked,
    caster: bool,
) -> Result<Bytes, Failure> {
    let Some(view) = prepared.view(scene) else {
        return Err(Failure::new(HiradStatus::NotOpen, "no open scene"));
    };
    match &prepared.hi {
        None => {
            let mut scratch = vec![0u8; hr::census_scratch_bytes(view)];
            let p = hr::plan(view, &c.core, !caster, &mut scratch).map_err(failure)?;
            Ok(Bytes {
                min: p.min_bytes,
                sure: p.min_bytes,
                suggested: p.suggested_bytes,
            })
        }
        Some(d) => {
            let inline = d.inline();
            let (_, p) = hirad::solve::hi_budget_plan(view, c.core, inline, None, &mut |_| {})
                .map_err(failure)?;
            // The least with every fallback of a small budget taken.
            let (_, q) = hirad::solve::hi_budget_plan(view, c.core, inline, Some(0), &mut |_| {})
                .map_err(failure)?;
            Ok(Bytes {
                min: q.bare_min_bytes.min(p.bare_min_bytes),
                sure: p.min_bytes,
                suggested: p.suggested_bytes,
            })
        }
    }
}
