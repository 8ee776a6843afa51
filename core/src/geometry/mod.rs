//! Geometry shared by every loader and by the solver: polygon shapes, similarity transforms,
//! axis-aligned boxes. All tolerances are relative to the size of what they act on.

mod aabb;
mod camera;
mod polygon;
mod transform;

pub use aabb::Aabb;
pub use camera::camera_ok;
pub use polygon::{PolygonShape, ShapeError, polygon_shape, DEGENERATE_REL, PLANAR_REL};
pub use transform::{Similarity, TransformError};
