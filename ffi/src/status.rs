//! The status every C function returns.

/// What a call did: `HIRAD_STATUS_OK` (0) or why it did not.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HiradStatus {
    /// Done.
    Ok = 0,
    /// A pointer the call needs was null.
    NullArgument = 1,
    /// The bytes are not a valid scene image (the handle's message says what is wrong and
    /// `hirad_scene_error_offset` at which byte).
    InvalidScene = 2,
    /// The handle holds no usable scene (its opening failed).
    NotOpen = 3,
    /// Memory for the handle could not be had.
    OutOfMemory = 4,
    /// A panic inside hirad was caught: a bug, reported rather than crossing the boundary.
    Internal = 5,
}

/// Runs `f`, turning a panic into [`HiradStatus::Internal`].
pub(crate) fn guarded(f: impl FnOnce() -> HiradStatus) -> HiradStatus {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or(HiradStatus::Internal)
}
