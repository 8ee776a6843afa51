//! Directional tables of originals: what a closed instance knows about its contents as
//! functions of direction (issue 17). So far the direction grid they are sampled on, the
//! box's projected area, the uncollided transmittance and its table baked to an error
//! target.

pub mod bake;
pub mod grid;
pub mod tau;

#[cfg(test)]
mod tests_bake;
#[cfg(test)]
mod tests_grid;
#[cfg(test)]
mod tests_tau;
