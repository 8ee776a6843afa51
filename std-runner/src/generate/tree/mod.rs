//! Trees from their botanical structure, shared by `gen poplar`, `gen stand` and
//! `gen forest`.
//!
//! A tree is a trunk (axis kind 0) bearing branches of orders 1 to 3 and leafy shoots
//! (kind 4); every axis is a cluster carrying its kind and age (years). Each axis is grown in
//! its canonical frame ([`axis`]), and becomes an instance of an original chosen by kind and
//! age class ([`species::Class`]): approximate instances carrying their own geometry for the
//! paper's trees, exact instances of a few variants for forests ([`instancing`]).
//!
//! Units: metres, years, W/m^2.

pub mod axis;
pub mod frame;
pub mod instancing;
pub mod materials;
pub mod site;
pub mod species;

pub use axis::TreeMaterials;
pub use instancing::{Approximate, Exact, approximate_originals, exact_variants, grow};
pub use materials::Bands;
pub use species::{SHOOT, Species, TRUNK};
