//! A scene image opened from the caller's bytes (copied: the caller may free its buffer at
//! once) or from the caller's read function, checked whole when opened.

use crate::status::{HiradStatus, guarded};
use hirad_core::image::{SceneSource, SceneView, SourceError};
use std::ffi::{CString, c_char, c_void};

/// Reads `len` bytes of the scene image at byte `offset` into `buf`: 0 when done, any other
/// value an error code of the caller's (reported in the message). Several threads of one
/// solve may call it at once with the same `user`.
pub type HiradReadFn =
    Option<unsafe extern "C" fn(user: *mut c_void, offset: u64, buf: *mut u8, len: usize) -> i32>;

/// Where a handle's image bytes come from.
pub(crate) enum Source {
    /// A copy of the caller's buffer.
    Owned(Box<[u8]>),
    /// The caller's read function, its pointer and the image's length (bytes).
    Reader {
        read: unsafe extern "C" fn(*mut c_void, u64, *mut u8, usize) -> i32,
        user: *mut c_void,
        len: u64,
    },
}

// SAFETY: `Owned` is plain bytes; for `Reader` the caller of `hirad_scene_open_reader`
// promised a function that may be called from several threads at once with its `user`
// (solves read the image from their worker threads).
unsafe impl Sync for Source {}
// SAFETY: as for `Sync`: the pointer is only handed back to the caller's function.
unsafe impl Send for Source {}

impl SceneSource for Source {
    fn len(&self) -> u64 {
        match self {
            Source::Owned(b) => b.len() as u64,
            Source::Reader { len, .. } => *len,
        }
    }

    fn read_at(&self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
        match self {
            Source::Owned(b) => hirad_core::image::SliceSource(b).read_at(offset, buf),
            Source::Reader { read, user, len } => {
                let end = offset.checked_add(buf.len() as u64);
                if end.is_none_or(|e| e > *len) {
                    return Err(SourceError::OutOfRange);
                }
                if buf.is_empty() {
                    return Ok(());
                }
                // SAFETY: the caller of `hirad_scene_open_reader` promised a function that
                // fills `len` bytes at `buf` (a live slice of that length here).
                match unsafe { read(*user, offset, buf.as_mut_ptr(), buf.len()) } {
                    0 => Ok(()),
                    code => Err(SourceError::Io(code)),
                }
            }
        }
    }
}

/// An opened scene, or the reason it could not be opened (opaque to C). One call at a time
/// per handle.
pub struct HiradScene {
    pub(crate) view: Option<SceneView<Source>>,
    /// The last failure's message ("" after a success), NUL-terminated.
    pub(crate) message: CString,
    /// Byte offset of the image fault, or `u64::MAX` where none applies.
    pub(crate) offset: u64,
    /// The image with the directional tables it lacked, made for hierarchical
    /// instantiation, and the `table_max_side` they were made with (0: the defaults).
    pub(crate) completed: Option<(SceneView<Source>, u32)>,
    /// The scene's structure (no table values), for labels and world polygons.
    pub(crate) model: Option<std::sync::Arc<hirad::scene::Scene>>,
    /// Strings handed out (names, the results header): they live as long as the handle.
    pub(crate) strings: Vec<CString>,
}

impl HiradScene {
    fn new(view: Option<SceneView<Source>>, message: CString, offset: u64) -> Self {
        HiradScene {
            view,
            message,
            offset,
            completed: None,
            model: None,
            strings: Vec::new(),
        }
    }

    /// Keeps `text` as the handle's message.
    pub(crate) fn say(&mut self, text: &str) {
        self.message = message(text);
    }

    /// The open image, or `NotOpen` (saying so).
    pub(crate) fn open_view(&self) -> Result<&SceneView<Source>, crate::status::Failure> {
        match &self.view {
            Some(v) => Ok(v),
            None => Err(crate::status::Failure::new(
                HiradStatus::NotOpen,
                "the scene handle holds no open scene (its opening failed)",
            )),
        }
    }

    /// The scene's structure, decompiled from the image on first need.
    pub(crate) fn model(
        &mut self,
    ) -> Result<std::sync::Arc<hirad::scene::Scene>, crate::status::Failure> {
        if let Some(m) = &self.model {
            return Ok(m.clone());
        }
        let view = self.open_view()?;
        let m = hirad::scene::decompile_records(view)
            .map_err(|e| crate::status::Failure::new(HiradStatus::InvalidScene, format!("{e}")))?;
        let m = std::sync::Arc::new(m);
        self.model = Some(m.clone());
        Ok(m)
    }
}

/// What an opened scene holds (counts of the image's records).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HiradSceneInfo {
    /// Spectral bands (1 to 8).
    pub bands: u32,
    /// Polygons stored in the image.
    pub polygons: u32,
    /// Polygons once every instance is expanded: the rows of a solve's results.
    pub expanded_polygons: u64,
    /// Originals (shared subtrees that instances place).
    pub originals: u32,
    /// Instances stored (exact and approximate).
    pub instances: u32,
    /// Most instances nested along one path.
    pub instancing_depth: u32,
    /// Directional suns.
    pub suns: u32,
    /// Sky directions.
    pub sky: u32,
    /// Materials.
    pub materials: u32,
}

pub(crate) fn message(text: &str) -> CString {
    CString::new(text.replace('\0', " ")).unwrap_or_default()
}

/// Opens the scene image in `bytes[0..len]` (copied) into a new handle at `*out`. The
/// handle is made even when the image is not valid (status `HIRAD_STATUS_INVALID_SCENE`): its
/// message and byte offset say what is wrong, and it must be freed as any other. `out`
/// is left untouched where the status is `HIRAD_STATUS_NULL_ARGUMENT` or
/// `HIRAD_STATUS_OUT_OF_MEMORY`.
///
/// # Safety
/// `bytes` must point to `len` readable bytes (or be anything when `len` is 0); `out` must
/// be null or point to writable storage for one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_scene_open_memory(
    bytes: *const u8,
    len: usize,
    out: *mut *mut HiradScene,
) -> HiradStatus {
    guarded(|| {
        if out.is_null() || (bytes.is_null() && len > 0) {
            return HiradStatus::NullArgument;
        }
        let copy: Box<[u8]> = if len == 0 {
            Box::default()
        } else {
            // SAFETY: the caller promises `len` readable bytes at `bytes` (non-null here).
            let src = unsafe { std::slice::from_raw_parts(bytes, len) };
            let mut v = Vec::new();
            if v.try_reserve_exact(len).is_err() {
                return HiradStatus::OutOfMemory;
            }
            v.extend_from_slice(src);
            v.into_boxed_slice()
        };
        // SAFETY: `out` is non-null and the caller promises it is writable.
        unsafe { opened(Source::Owned(copy), out) }
    })
}

/// Opens the scene image that `read` gives (`len` bytes; see `HiradReadFn`) into a new
/// handle at `*out`, as `hirad_scene_open_memory` does; the whole image is read and checked
/// now, and read again while solving: `user` and what it reads must outlive the handle. A
/// read that fails makes the status `HIRAD_STATUS_INVALID_SCENE`, its code and byte offset
/// in the handle's message.
///
/// # Safety
/// `read` must be null or a function that writes `len` bytes at `buf` (or returns non-zero)
/// and may be called from several threads at once; `out` null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_scene_open_reader(
    read: HiradReadFn,
    user: *mut c_void,
    len: u64,
    out: *mut *mut HiradScene,
) -> HiradStatus {
    guarded(|| {
        let (Some(read), false) = (read, out.is_null()) else {
            return HiradStatus::NullArgument;
        };
        // SAFETY: `out` is non-null and the caller promises it is writable.
        unsafe { opened(Source::Reader { read, user, len }, out) }
    })
}

/// Checks `source` as a scene image and puts the handle (open, or holding why not) at
/// `*out`.
///
/// # Safety
/// `out` must be non-null and writable.
unsafe fn opened(source: Source, out: *mut *mut HiradScene) -> HiradStatus {
    let (scene, status) = match SceneView::open(source) {
        Ok(view) => (
            HiradScene::new(Some(view), CString::default(), u64::MAX),
            HiradStatus::Ok,
        ),
        Err(e) => (
            HiradScene::new(
                None,
                message(&format!("byte {}: {}", e.offset, e.kind)),
                e.offset,
            ),
            HiradStatus::InvalidScene,
        ),
    };
    // SAFETY: the caller's promise.
    unsafe { *out = Box::into_raw(Box::new(scene)) };
    status
}

/// Runs `f` on the live handle `scene` (refusing null and misaligned pointers, catching a
/// panic), keeping its failure's message there ("" on success).
///
/// # Safety
/// `scene` null or a live handle.
pub(crate) unsafe fn on_scene(
    scene: *mut HiradScene,
    f: impl FnOnce(&mut HiradScene) -> Result<(), crate::status::Failure>,
) -> HiradStatus {
    guarded(|| {
        if !crate::status::aligned(scene) {
            return HiradStatus::Misaligned;
        }
        // SAFETY: null or a live handle, by the caller's promise.
        let Some(s) = (unsafe { scene.as_mut() }) else {
            return HiradStatus::NullArgument;
        };
        match f(s) {
            Ok(()) => {
                s.say("");
                HiradStatus::Ok
            }
            Err(e) => {
                s.say(&e.message);
                e.status
            }
        }
    })
}

/// Frees a handle made by `hirad_scene_open_memory` or `hirad_scene_open_reader` (null:
/// nothing).
///
/// # Safety
/// `scene` must be null or a handle not freed before.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_scene_free(scene: *mut HiradScene) {
    if !scene.is_null() {
        // SAFETY: made by `Box::into_raw` in `hirad_scene_open_memory`, not freed before.
        let _ = std::panic::catch_unwind(|| drop(unsafe { Box::from_raw(scene) }));
    }
}

/// The handle's last failure as text ("" when there is none; a static "" for a null
/// handle), valid until the handle's next call or its free.
///
/// # Safety
/// `scene` must be null or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_scene_message(scene: *const HiradScene) -> *const c_char {
    // SAFETY: null or a live handle, by the caller's promise.
    match unsafe { scene.as_ref() } {
        Some(s) => s.message.as_ptr(),
        None => c"".as_ptr(),
    }
}

/// The byte offset of the image fault that made opening fail, or `UINT64_MAX` where none
/// applies (an open scene, a null handle).
///
/// # Safety
/// `scene` must be null or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_scene_error_offset(scene: *const HiradScene) -> u64 {
    // SAFETY: null or a live handle, by the caller's promise.
    unsafe { scene.as_ref() }.map_or(u64::MAX, |s| s.offset)
}

/// Writes what the opened scene holds to `*info`.
///
/// # Safety
/// `scene` must be null or a live handle; `info` null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn hirad_scene_info(
    scene: *const HiradScene,
    info: *mut HiradSceneInfo,
) -> HiradStatus {
    guarded(|| {
        // SAFETY: null or a live handle, by the caller's promise.
        let (Some(s), false) = (unsafe { scene.as_ref() }, info.is_null()) else {
            return HiradStatus::NullArgument;
        };
        let Some(view) = &s.view else {
            return HiradStatus::NotOpen;
        };
        let i = view.info();
        let out = HiradSceneInfo {
            bands: i.bands,
            polygons: i.polygons,
            expanded_polygons: i.expanded_polygons,
            originals: i.originals,
            instances: i.exact_instances.saturating_add(i.approximate_instances),
            instancing_depth: i.instancing_depth,
            suns: i.suns,
            sky: i.sky,
            materials: i.materials,
        };
        // SAFETY: `info` is non-null and the caller promises it is writable.
        unsafe { info.write(out) };
        HiradStatus::Ok
    })
}
