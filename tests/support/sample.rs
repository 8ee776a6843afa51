//! The model's sample scene (every feature in a few polygons), re-exported for the tests.

pub use hirad::scene::sample;
