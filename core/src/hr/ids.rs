//! Element handles: one `u32` whose top two bits say which pool the element lives in.

use crate::limits::NONE;

/// Which pool an element lives in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// A cluster (scene node, expanded instance, or an inserted grouping level).
    Cluster = 0,
    /// A patch of a one-sided polygon (the polygon itself or a sub-patch).
    Patch1 = 1,
    /// A patch of a two-sided polygon.
    Patch2 = 2,
    /// A directional source (sun or sky direction): emits only.
    Source = 3,
}

/// An element: pool in the top two bits, index below.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct Elem(pub u32);

impl Elem {
    pub(crate) const NONE: Elem = Elem(NONE);
    pub(crate) const MAX_INDEX: u32 = (1 << 30) - 1;

    pub(crate) fn new(kind: Kind, index: u32) -> Elem {
        debug_assert!(index <= Self::MAX_INDEX);
        Elem(((kind as u32) << 30) | (index & Self::MAX_INDEX))
    }

    pub(crate) fn kind(self) -> Kind {
        match self.0 >> 30 {
            0 => Kind::Cluster,
            1 => Kind::Patch1,
            2 => Kind::Patch2,
            _ => Kind::Source,
        }
    }

    pub(crate) fn index(self) -> u32 {
        self.0 & Self::MAX_INDEX
    }

    pub(crate) fn is_patch(self) -> bool {
        matches!(self.kind(), Kind::Patch1 | Kind::Patch2)
    }
}
