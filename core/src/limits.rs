//! Hard limits every loader enforces, so that untrusted input can never drive the core into
//! unbounded work or stack use.

/// Largest number of spectral bands a scene may have (1 grey, 2 PAR/NIR, 3 RGB, ...).
pub const MAX_BANDS: usize = 8;

/// Deepest nesting of clusters inside one tree (an original or the scene), root = depth 1.
pub const MAX_NODE_DEPTH: usize = 64;

/// Most instances nested inside each other along one path of the expanded scene.
pub const MAX_INSTANCING_DEPTH: u32 = 64;

/// Longest name (material, original, cluster, camera, band) in bytes of UTF-8.
pub const MAX_NAME_BYTES: usize = 1024;

/// Marker for "no index" in `u32` index fields of the binary image.
pub const NONE: u32 = u32::MAX;
