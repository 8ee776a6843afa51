//! hirad's C ABI (issue 19): scenes opened from a caller's bytes or read function, with the
//! image's validation errors and their byte offsets; planning the workspace a solve needs;
//! solving into a workspace the caller owns, with its progress (which may cancel), its sink
//! for every finished polygon and, optionally, its own ray caster. Every function returns a
//! [`HiradStatus`]; a handle keeps the message of its last failure
//! ([`hirad_scene_message`]). No panic crosses the boundary: one caught is
//! [`HiradStatus::Internal`]. Null and misaligned pointers are status codes, never
//! undefined behaviour. The C header is `include/hirad.h`, made by cbindgen
//! (`cbindgen.toml`); CI fails when the committed one differs from what the sources make.
//!
//! Ownership: a handle made by `hirad_*_open*` is the caller's until it passes it to its
//! `*_free`; strings a handle returns live as long as the handle (the message: until its
//! next call). One call at a time per handle; distinct handles may be used from distinct
//! threads at once.

mod callbacks;
mod executor;
mod labels;
mod prepare;
mod scene;
mod settings;
mod solve;
mod status;

pub use callbacks::{
    HiradCallbacks, HiradFirstHitFn, HiradPolygon, HiradPolygonFn, HiradProgressFn,
    HiradTransmittanceFn,
};
pub use labels::{
    HiradWorldPolygon, hirad_format_float, hirad_scene_material_name, hirad_scene_results_header,
    hirad_scene_world_polygons,
};
pub use scene::{
    HiradReadFn, HiradScene, HiradSceneInfo, hirad_scene_error_offset, hirad_scene_free,
    hirad_scene_info, hirad_scene_message, hirad_scene_open_memory, hirad_scene_open_reader,
};
pub use settings::{
    HIRAD_AUTO, HIRAD_INSTANCING_ALL, HIRAD_INSTANCING_AUTO, HIRAD_INSTANCING_EVERY,
    HIRAD_INSTANCING_NONE, HIRAD_METHOD_AUTO, HIRAD_METHOD_HI, HIRAD_METHOD_HR, HiradSettings,
    hirad_settings_default,
};
pub use solve::{HIRAD_MAX_BANDS, HiradPlan, HiradStats, hirad_plan, hirad_solve};
pub use status::HiradStatus;
