//! Where a level starts and what lights it: the scene's root under the scene's suns and sky,
//! or an opened instance's contents, placed, under the light that reached the instance
//! (see `open`).

use super::room::Room;
use super::settings::Inline;
use crate::geometry::Similarity;
use crate::image::{SceneSource, SceneView};

/// Floats of one beam for `bands` bands: the unit direction towards its source, how many
/// outer levels its rays go through (the bits of a u32: NONE for all, see
/// `records::Source::outer`), then its irradiance per band (W/m^2 on a plane facing the
/// source).
pub(crate) const fn beam_floats(bands: usize) -> usize {
    4 + bands
}

/// Beam `k`'s outer levels (see [`beam_floats`]).
pub(crate) fn beam_outer(beams: &[f32], k: usize, bands: usize) -> u32 {
    beams
        .get(k * beam_floats(bands) + 3)
        .map_or(crate::limits::NONE, |v| v.to_bits())
}

/// A level's root and light.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LevelRoot<'b> {
    /// The node whose subtree the level holds (its closed instances stop it).
    pub node: u32,
    /// The transform of that node's frame to world.
    pub place: Similarity,
    /// The scene's suns and sky (`None`), or these beams (see [`beam_floats`]) with how many
    /// of them, first, are suns.
    pub beams: Option<(&'b [f32], u32)>,
    /// The originals whose instances the level expands in place (the policy, the same for
    /// every level of a solve).
    pub inline: Inline<'b>,
    /// The workspace its closed instances need to be opened, which it leaves free when it
    /// refines (see `room`).
    pub children: Room,
    /// What the level itself is estimated to grow by above its least (bytes; see
    /// `room::capped_total`).
    pub own_growth: u64,
    /// Most passes of its final gather when their number is automatic (see
    /// `State::most_passes`).
    pub most_passes: u32,
}

impl<'b> LevelRoot<'b> {
    /// The whole scene.
    pub(crate) fn scene<S: SceneSource>(view: &SceneView<S>) -> Self {
        LevelRoot {
            node: view.info().scene_root.0,
            place: Similarity::IDENTITY,
            beams: None,
            inline: Inline::NONE,
            children: Room::default(),
            own_growth: u64::MAX,
            most_passes: super::settings::MAX_FINAL_PASSES,
        }
    }

    /// Directional sources: suns, then sky directions or beams.
    pub(crate) fn sources<S: SceneSource>(&self, view: &SceneView<S>) -> u32 {
        match self.beams {
            None => view.info().suns + view.info().sky,
            Some((b, _)) => (b.len() / beam_floats(view.info().bands as usize)) as u32,
        }
    }

    /// Of those, suns.
    pub(crate) fn suns<S: SceneSource>(&self, view: &SceneView<S>) -> u32 {
        match self.beams {
            None => view.info().suns,
            Some((_, suns)) => suns,
        }
    }
}
