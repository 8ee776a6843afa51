//! hirad's C ABI (issue 19): scenes opened from a caller's bytes or read function, with the image's
//! validation errors and their byte offsets, behind opaque handles. Every function returns
//! a [`HiradStatus`]; a handle keeps the message of its last failure
//! ([`hirad_scene_message`]). No panic crosses the boundary: one caught is
//! [`HiradStatus::Internal`]. Null pointers are status codes, never undefined behaviour.
//! The C header is `include/hirad.h`, made by cbindgen (`cbindgen.toml`); CI fails when the
//! committed one differs from what the sources make.
//!
//! Ownership: a handle made by `hirad_*_open*` is the caller's until it passes it to its
//! `*_free`; strings a handle returns live as long as the handle and its next call.

mod scene;
mod status;

pub use scene::{
    HiradReadFn, HiradScene, HiradSceneInfo, hirad_scene_error_offset, hirad_scene_free,
    hirad_scene_info, hirad_scene_message, hirad_scene_open_memory, hirad_scene_open_reader,
};
pub use status::HiradStatus;
