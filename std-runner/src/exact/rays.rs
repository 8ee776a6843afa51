//! How the form factor matrix casts its visibility rays: through any
//! [`Visibility`](hirad_core::visibility::Visibility) one segment at a time, or, with an
//! [`ObvhsVisibility`], per pair of elements: the polygons whose boxes reach the pair's box
//! are the only ones that can block a segment between the two, so a pair with none is
//! known clear without casting, and a pair with a few tests only those. The answers are the
//! same as casting every ray through the BVH (the same exact test decides), only cheaper.

use crate::visibility::ObvhsVisibility;
use glam::Vec3;
use hirad_core::visibility::Visibility;

/// Longest candidate list tested directly; longer ones go through the BVH.
const DIRECT_CANDIDATES: usize = 16;

/// What is known about the segments between a pair of elements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pair {
    /// Nothing can block them.
    Clear,
    /// Only the listed candidates can block them.
    Among,
    /// Anything may: cast through the visibility itself.
    Any,
}

/// Ray casting as the matrix uses it.
pub trait PairRays: Sync {
    /// Classifies the segments lying in the box `lo..hi` (m), ignoring `skip`; may fill
    /// `candidates`.
    fn pair(&self, lo: Vec3, hi: Vec3, skip: [u32; 2], candidates: &mut Vec<u32>) -> Pair;

    /// Transmittance of one segment of a pair classified as `pair` (never `Clear`).
    fn cast(&self, from: Vec3, to: Vec3, skip: [u32; 2], pair: Pair, candidates: &[u32]) -> f32;
}

/// Any visibility, one segment at a time.
pub struct Plain<'a, V: ?Sized>(pub &'a V);

impl<V: Visibility + ?Sized> PairRays for Plain<'_, V> {
    fn pair(&self, _: Vec3, _: Vec3, _: [u32; 2], _: &mut Vec<u32>) -> Pair {
        Pair::Any
    }

    fn cast(&self, from: Vec3, to: Vec3, skip: [u32; 2], _: Pair, _: &[u32]) -> f32 {
        self.0.transmittance(from, to, skip)
    }
}

impl PairRays for ObvhsVisibility {
    fn pair(&self, lo: Vec3, hi: Vec3, skip: [u32; 2], candidates: &mut Vec<u32>) -> Pair {
        self.candidates(lo, hi, skip, candidates);
        match candidates.len() {
            0 => Pair::Clear,
            n if n <= DIRECT_CANDIDATES => Pair::Among,
            _ => Pair::Any,
        }
    }

    fn cast(&self, from: Vec3, to: Vec3, skip: [u32; 2], pair: Pair, candidates: &[u32]) -> f32 {
        match pair {
            Pair::Clear => 1.0,
            Pair::Among => self.transmittance_among(from, to, candidates),
            Pair::Any => self.transmittance(from, to, skip),
        }
    }
}
