//! Element handles: one `u32` whose top three bits say which pool the element lives in.
//!
//! The kinds of a fully expanded scene keep the codes they had when two bits held them
//! (clusters `000`, one-sided patches `010`, two-sided `100`, sources `110`), so that every
//! handle, and every sample seeded by handles, is what it always was; closed instances
//! take `001`.

use crate::limits::NONE;

/// Which pool an element lives in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// A cluster (scene node, expanded instance, or an inserted grouping level).
    Cluster = 0,
    /// A closed instance: a leaf that stands for its contents through its original's
    /// directional tables (see `tables::closed`).
    Instance = 1,
    /// A patch of a one-sided polygon (the polygon itself or a sub-patch).
    Patch1 = 2,
    /// A patch of a two-sided polygon.
    Patch2 = 4,
    /// A directional source (sun or sky direction): emits only.
    Source = 6,
}

/// An element: pool in the top three bits, index below.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct Elem(pub u32);

impl Elem {
    pub(crate) const NONE: Elem = Elem(NONE);
    pub(crate) const MAX_INDEX: u32 = (1 << 29) - 1;

    pub(crate) fn new(kind: Kind, index: u32) -> Elem {
        debug_assert!(index <= Self::MAX_INDEX);
        Elem(((kind as u32) << 29) | (index & Self::MAX_INDEX))
    }

    pub(crate) fn kind(self) -> Kind {
        match self.0 >> 29 {
            0 => Kind::Cluster,
            1 => Kind::Instance,
            2 => Kind::Patch1,
            4 => Kind::Patch2,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn handles_keep_their_two_bit_codes() {
        for (kind, two_bits) in [
            (Kind::Cluster, 0u32),
            (Kind::Patch1, 1),
            (Kind::Patch2, 2),
            (Kind::Source, 3),
        ] {
            for i in [0u32, 1, 77, Elem::MAX_INDEX] {
                let e = Elem::new(kind, i);
                assert_eq!(e.0, (two_bits << 30) | i);
                assert_eq!((e.kind(), e.index()), (kind, i));
            }
        }
        let e = Elem::new(Kind::Instance, 5);
        assert_eq!((e.kind(), e.index()), (Kind::Instance, 5));
        assert!(!e.is_patch());
    }
}
