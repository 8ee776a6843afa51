//! hirad-core: the `#![no_std]`, allocation-free heart of hirad.
//!
//! * [`image`]: the binary scene image (`.hirb`), its records and a checked view that reads an
//!   untrusted image piece by piece through a [`image::SceneSource`].
//! * [`geometry`]: polygon shape checks, similarity transforms and boxes, shared by every
//!   loader so that a scene accepted anywhere is accepted everywhere.
//! * [`material`]: per-band material data and its physical checks.
//! * [`formfactor`], [`sampling`]: exact point-to-polygon form factors, deterministic sampling.
//! * [`bvh`]: a bounding-volume hierarchy built in caller storage, and visibility through it.
//! * [`hr`]: hierarchical radiosity with clustering in one caller-provided workspace.
//! * [`sink`], [`visibility`]: where results go and where rays come from.
//! * [`tables`]: directional tables of originals (the equal-area direction grid).
//!
//! Units: lengths in metres (any unit works as long as it is consistent: nothing in the core
//! uses an absolute tolerance), exitance, irradiance and radiosity in W/m^2.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

#[cfg(target_endian = "big")]
compile_error!(
    "hirad-core reads little-endian scene images in place; big-endian hosts are not supported yet"
);

pub mod bvh;
pub mod formfactor;
pub mod geometry;
pub mod handles;
pub mod hr;
pub mod image;
pub mod limits;
pub mod material;
pub mod sampling;
pub mod sink;
pub mod tables;
pub mod visibility;

pub use handles::*;
