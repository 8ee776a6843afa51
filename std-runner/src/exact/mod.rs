//! The exact reference solver: classic full-matrix radiosity on a uniformly subdivided mesh,
//! for scenes up to a few thousand elements. It is what the hierarchical solver's accuracy is
//! measured against, so it favours exactness over speed and memory:
//!
//! * every instance is expanded; each polygon is split uniformly into `4^level` elements,
//!   levels chosen so that elements have about equal areas and the total stays within
//!   [`ExactSettings::max_elements`];
//! * form factors are exact point-to-polygon form factors
//!   ([`hirad_core::formfactor::point_polygon_f64`]) integrated by quadrature over the receiver,
//!   times the fraction of deterministic jittered rays that reach the emitter, for both
//!   sides of two-sided (translucent) materials;
//! * suns and sky directions light every element directly, with shadow rays;
//! * quadrature points buried inside closed objects (a floor under a box) are left out (see
//!   below);
//! * `B = E + rho H + tau H_other` is solved per band by Gauss-Seidel with a contraction-based
//!   error estimate (closed scenes with rho = 0.99 converge slowly).
//!
//! **Buried points.** A floor polygon that runs on under a box (which has no bottom face) has
//! elements straddling the box's footprint, and the part under the box receives no light. Its
//! area mean would make such an element too dark for the part the box's faces see right beside
//! them, at large form factors, and the faces would come out a few percent too dark,
//! converging only slowly with the mesh. So a quadrature point of a one-sided element whose
//! rays all meet the backs of one-sided polygons is *buried* (`buried`) and dropped from the
//! element's quadrature:
//!
//! * an element receives the mean over its exposed points (weights renormalised; nothing when
//!   all are buried), so its `H` and `B = E + rho H` are those of its exposed part;
//! * as an emitter it gives a receiver `B` times the form factor to the whole element times
//!   the visibility, unchanged: the buried part is hidden from every receiver by the faces
//!   around it (rays to it are blocked) or lies behind the receiver's own plane (those faces
//!   themselves, whose form factor clips it away), so what arrives is `B` times the form
//!   factor to the exposed part, and the element's power is `B` times its exposed area
//!   `f a` (`f` the exposed fraction, the plain weight of its exposed points). Scaling `B` by
//!   `f` as well would remove the buried part twice. Whatever a buried part emits goes into
//!   the object and is absorbed by the backs of its faces: no receiver sees it;
//! * the results table counts buried parts as unlit (irradiance 0, radiosity `E`): a
//!   polygon's means are `sum(a f H) / A` and `sum(a (f B + (1 - f) E)) / A`, the area means
//!   a particle tracer measures.
//!
//! The hierarchical solver applies the same rule, so both converge to the same answer.
//!
//! Results are bit-identical for any thread count: rows are computed independently in
//! parallel, each in a fixed order, and the iteration is sequential.
//!
//! Units: metres, W/m^2.

mod balance;
mod buried;
mod direct;
mod error;
mod matrix;
mod mesh;
mod output;
mod quadrature;
mod rays;
mod solve;

pub use balance::RAYS_PER_SIDE;
pub use error::ExactError;

use crate::output::Progress;
use crate::scene::Scene;
use crate::visibility::ObvhsVisibility;
use hirad_core::sink::Sink;
use hirad_core::visibility::Visibility;
use mesh::Mesh;
use quadrature::Quadrature;
use rays::{PairRays, Plain};
use std::time::Instant;

/// Most elements the solver accepts (its matrix is dense in the worst case).
pub const MAX_ELEMENTS: usize = 20_000;

/// Most bytes the worst-case (dense) matrix may need; larger scenes are refused up front.
pub const MAX_MATRIX_BYTES: u64 = 4 << 30;

/// Most visibility rays per quadrature point and emitter element.
pub const MAX_RAYS: u32 = 1024;

/// Most extra receiver splits for the quadrature (each multiplies the points by 4).
pub const MAX_QUADRATURE_SPLIT: u32 = 3;

/// How finely and how long the reference solver works.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactSettings {
    /// Element budget (the input polygons are always kept, even above it). Default 3000.
    pub max_elements: usize,
    /// Visibility rays per receiver quadrature point and emitter element. Default 16.
    pub rays: u32,
    /// Extra splits of each receiver element for its quadrature (0: the core's 4-point
    /// Gauss / 3-point rule on the element itself). Default 0.
    pub quadrature_split: u32,
    /// Convergence: largest change and estimated remaining error, relative to the largest
    /// radiosity of each band. Default 1e-7.
    pub tolerance: f64,
    /// Gauss-Seidel sweeps before giving up with [`ExactError::NotConverged`]. Default 20000.
    pub max_iterations: u32,
}

impl Default for ExactSettings {
    fn default() -> Self {
        ExactSettings {
            max_elements: 3000,
            rays: 16,
            quadrature_split: 0,
            tolerance: 1e-7,
            max_iterations: 20_000,
        }
    }
}

impl ExactSettings {
    /// Checks every setting's range.
    pub fn check(&self) -> Result<(), String> {
        if self.max_elements == 0 || self.max_elements > MAX_ELEMENTS {
            return Err(format!("max_elements must lie in 1..={MAX_ELEMENTS}"));
        }
        if self.rays == 0 || self.rays > MAX_RAYS {
            return Err(format!("rays must lie in 1..={MAX_RAYS}"));
        }
        if self.quadrature_split > MAX_QUADRATURE_SPLIT {
            return Err(format!(
                "quadrature_split must lie in 0..={MAX_QUADRATURE_SPLIT}"
            ));
        }
        if !(self.tolerance >= 1e-12 && self.tolerance < 1.0) {
            return Err("tolerance must lie in [1e-12, 1)".to_string());
        }
        if self.max_iterations == 0 {
            return Err("max_iterations must be at least 1".to_string());
        }
        Ok(())
    }
}

/// What a solve did and cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExactReport {
    /// Input polygons after expansion.
    pub polygons: usize,
    /// Elements (the polygons' uniform pieces).
    pub elements: usize,
    /// Radiosity unknowns per band: one per element side that can emit or receive.
    pub slots: usize,
    /// Element pairs whose form factor was computed.
    pub form_factors: u64,
    /// Non-zero form factors stored.
    pub entries: u64,
    /// Visibility rays cast (form factors, direct light and the buried test).
    pub rays: u64,
    /// Element pairs known unoccluded without rays (no other polygon reaches their box).
    pub clear_pairs: u64,
    /// Receiver quadrature points found buried inside closed objects (left out).
    pub buried_points: u64,
    /// Gauss-Seidel sweeps.
    pub iterations: u32,
    /// Estimated remaining error relative to the largest radiosity.
    pub error: f64,
    /// Wall-clock time of the whole solve (s).
    pub seconds: f64,
    /// Time spent computing form factors (s).
    pub matrix_seconds: f64,
    /// Bytes of the stored matrix.
    pub matrix_bytes: u64,
    /// Where the power went (see `balance`), by the hierarchical solver's accounting.
    pub balance: hirad_core::hr::Balance,
    /// Rays the balance cast (not counted in `rays`).
    pub balance_rays: u64,
}

/// Solves `scene` with `visibility` (polygon ids = global ids of the expanded scene) and
/// streams every polygon to `sink` in global-id order.
pub fn solve_exact<S: Sink, V: Visibility + ?Sized>(
    scene: &Scene,
    settings: &ExactSettings,
    visibility: &V,
    sink: &mut S,
) -> Result<ExactReport, ExactError<S::Error>> {
    let start = Instant::now();
    settings.check().map_err(ExactError::Settings)?;
    let mesh = Mesh::build(scene, settings)?;
    run(
        scene,
        settings,
        &mesh,
        &Plain(visibility),
        visibility,
        sink,
        start,
        &Progress::new(true),
    )
}

/// [`solve_exact`] with an [`ObvhsVisibility`] built over the expanded scene. Pairs of
/// elements that no other polygon comes near are known visible without casting rays.
pub fn solve_exact_obvhs<S: Sink>(
    scene: &Scene,
    settings: &ExactSettings,
    sink: &mut S,
) -> Result<ExactReport, ExactError<S::Error>> {
    solve_exact_obvhs_with(scene, settings, sink, &Progress::new(true))
}

/// [`solve_exact_obvhs`] reporting its phases to `progress`: the form factors row by row
/// (most of the time), the iterations as they run.
pub fn solve_exact_obvhs_with<S: Sink>(
    scene: &Scene,
    settings: &ExactSettings,
    sink: &mut S,
    progress: &Progress,
) -> Result<ExactReport, ExactError<S::Error>> {
    let start = Instant::now();
    progress.phase("meshing", None);
    settings.check().map_err(ExactError::Settings)?;
    let mesh = Mesh::build(scene, settings)?;
    let polygons: Vec<&[glam::Vec3]> = mesh.polygons.iter().map(|p| p.corners()).collect();
    let visibility = ObvhsVisibility::new(&polygons).map_err(ExactError::Visibility)?;
    run(
        scene,
        settings,
        &mesh,
        &visibility,
        &visibility,
        sink,
        start,
        progress,
    )
}

/// The solve proper, after the mesh exists: `rays` for the form factors, `visibility` for
/// the buried points and the direct light (the same polygons).
#[allow(clippy::too_many_arguments)]
fn run<S: Sink, R: PairRays + ?Sized, V: Visibility + ?Sized>(
    scene: &Scene,
    settings: &ExactSettings,
    mesh: &Mesh,
    rays: &R,
    visibility: &V,
    sink: &mut S,
    start: Instant,
    progress: &Progress,
) -> Result<ExactReport, ExactError<S::Error>> {
    let worst = (mesh.slots as u64).pow(2) * size_of::<matrix::Entry>() as u64;
    if worst > MAX_MATRIX_BYTES {
        return Err(ExactError::TooLarge {
            what: "bytes of form factor matrix (worst case)",
            count: worst,
            limit: MAX_MATRIX_BYTES,
        });
    }
    let mut quad = Quadrature::new(mesh, settings.quadrature_split);
    progress.phase("finding buried points", None);
    let exposure = buried::bury(scene, mesh, &mut quad, visibility);
    let matrix_start = Instant::now();
    progress.phase("form factors (elements)", Some(mesh.elements.len() as u64));
    let m = matrix::build(mesh, &quad, settings.rays, rays, progress);
    let matrix_seconds = matrix_start.elapsed().as_secs_f64();
    progress.phase("direct light", None);
    let (direct, direct_rays) = direct::direct(scene, mesh, &exposure.exposed, visibility);
    progress.phase("solving (iterations)", None);
    let solution = solve::solve(
        scene,
        mesh,
        &m.rows,
        &direct,
        settings.tolerance,
        settings.max_iterations,
        progress,
    )
    .map_err(|(iterations, error)| ExactError::NotConverged { iterations, error })?;
    progress.phase("power balance", None);
    let (power, balance_rays) = balance::balance(
        scene,
        mesh,
        &quad,
        &solution,
        &direct,
        &exposure.exposed,
        visibility,
    );
    progress.phase("writing", None);
    output::emit(scene, mesh, &solution, &exposure.exposed, sink).map_err(ExactError::Sink)?;
    Ok(ExactReport {
        polygons: mesh.polygons.len(),
        elements: mesh.elements.len(),
        slots: mesh.slots,
        form_factors: m.pairs,
        entries: m.entries(),
        rays: m.rays + direct_rays + exposure.rays,
        clear_pairs: m.clear_pairs,
        buried_points: exposure.buried_points,
        iterations: solution.iterations,
        error: solution.error,
        seconds: start.elapsed().as_secs_f64(),
        matrix_seconds,
        matrix_bytes: m.bytes(),
        balance: power,
        balance_rays,
    })
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_contact;
