//! The status every C function returns.

/// What a call did: `HIRAD_STATUS_OK` (0) or why it did not. A handle's message
/// (`hirad_scene_message`) says more after any status but OK.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HiradStatus {
    /// Done.
    Ok = 0,
    /// A pointer the call needs was null.
    NullArgument = 1,
    /// The bytes are not a valid scene image (the handle's message says what is wrong and
    /// `hirad_scene_error_offset` at which byte), or the scene cannot be solved as it is
    /// (nothing emits light, no polygons, a polygon unusable once placed).
    InvalidScene = 2,
    /// The handle holds no usable scene (its opening failed).
    NotOpen = 3,
    /// Memory outside the workspace (the handle, tables being made, names) could not be had.
    OutOfMemory = 4,
    /// A panic inside hirad was caught: a bug, reported rather than crossing the boundary.
    Internal = 5,
    /// A field of `HiradSettings` is out of range, or the settings ask for something the
    /// method cannot do (the message names the field).
    InvalidSettings = 6,
    /// The workspace is below the least the plan gives (the message says how many bytes
    /// it needs), or a level found too little room in it while solving.
    WorkspaceTooSmall = 7,
    /// A pointer to a struct is not aligned for it.
    Misaligned = 8,
    /// The progress callback asked to stop: no further polygon was handed to the sink.
    Cancelled = 9,
    /// The polygon callback returned non-zero: the solve stopped there (its code is in the
    /// message).
    SinkFailed = 10,
    /// The solve finished and every polygon was handed over, but the numbers are not what
    /// was asked: the solution did not converge within `max_iterations`, or a band's power
    /// balance is off by more than `max_imbalance_percent` (the message says which; the
    /// stats hold the figures).
    NotRight = 11,
    /// The scene lacks directional tables for originals hierarchical instantiation would
    /// close, and `make_tables` is 0 (the message names them).
    NoTables = 12,
    /// Making an original's directional tables failed (the message says why).
    TablesFailed = 13,
    /// A caller's buffer is shorter than what the call writes.
    ShortBuffer = 14,
    /// The caller's ray caster named a polygon id past the scene's polygons.
    CasterFailed = 15,
}

/// Runs `f`, turning a panic into [`HiradStatus::Internal`].
pub(crate) fn guarded(f: impl FnOnce() -> HiradStatus) -> HiradStatus {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or(HiradStatus::Internal)
}

/// A call's failure: its status and the message the handle keeps.
#[derive(Debug)]
pub(crate) struct Failure {
    pub status: HiradStatus,
    pub message: String,
}

impl Failure {
    pub(crate) fn new(status: HiradStatus, message: impl Into<String>) -> Self {
        Failure {
            status,
            message: message.into(),
        }
    }
}

/// True when `p` is null or aligned for `T` (a misaligned struct pointer is refused, never
/// read).
pub(crate) fn aligned<T>(p: *const T) -> bool {
    p.is_null() || p.is_aligned()
}
