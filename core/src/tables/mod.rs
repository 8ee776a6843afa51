//! Directional tables of originals: what a closed instance knows about its contents as
//! functions of direction (issue 17). The direction grid they are sampled on, the box's
//! projected area, the uncollided transmittance and its table baked to an error target, the
//! light leaving a box towards a direction, the phase table, and the polygons' first
//! scattering kept apart; and a closed instance: the tables placed by its transform, with the
//! light it received.

pub mod bake;
pub mod closed;
pub mod directional;
pub mod grid;
pub mod outgoing;
pub mod phase;
pub mod record;
pub mod single;
pub mod tau;

#[cfg(test)]
mod tests_bake;
#[cfg(test)]
mod tests_closed;
#[cfg(test)]
mod tests_grid;
#[cfg(test)]
mod tests_phase;
#[cfg(test)]
mod tests_single;
#[cfg(test)]
mod tests_tau;
