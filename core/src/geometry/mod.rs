//! Geometry shared by every loader and by the solver: polygon shapes, similarity transforms,
//! axis-aligned boxes. All tolerances are relative to the size of what they act on.

mod aabb;
mod camera;
mod polygon;
mod transform;

pub use aabb::Aabb;
pub use camera::camera_ok;
pub use polygon::{
    DEGENERATE_REL, MIN_AREA, PLANAR_REL, PolygonShape, RESOLUTION_REL, ShapeError,
    below_f32_resolution, polygon_shape,
};
pub use transform::{Similarity, TransformError, UNIT_TOLERANCE};
