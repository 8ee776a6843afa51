//! Directional tables of originals: what a closed instance knows about its contents as
//! functions of direction (issue 17). So far the direction grid they are sampled on.

pub mod grid;

#[cfg(test)]
mod tests_grid;
