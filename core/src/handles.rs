//! Typed `u32` handles into the flat arrays of a scene image.
//!
//! A handle is only an index; it says which array it indexes so that a polygon index can never
//! be passed where a node index is expected.

macro_rules! handle {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
        #[repr(transparent)]
        pub struct $name(pub u32);

        impl $name {
            /// The index as a `usize`, for slicing caller-side arrays.
            #[inline]
            pub const fn index(self) -> usize {
                self.0 as usize
            }
        }

        impl From<$name> for u32 {
            #[inline]
            fn from(h: $name) -> u32 {
                h.0
            }
        }
    };
}

handle!(
    /// A cluster node (plain cluster or instance) in the depth-first node array.
    NodeId
);
handle!(
    /// A stored polygon (triangle or quad); not the same as its global id after expansion.
    PolyId
);
handle!(
    /// A vertex position.
    VertexId
);
handle!(
    /// A material.
    MaterialId
);
handle!(
    /// An original: a cluster hierarchy shared by instances, with its directional tables.
    OriginalId
);
handle!(
    /// An instance record (original + similarity transform).
    InstanceId
);
handle!(
    /// A directional source (sun) or one sky direction.
    LightId
);
handle!(
    /// A camera.
    CameraId
);
handle!(
    /// A string (name) in the image's string table.
    StringId
);
