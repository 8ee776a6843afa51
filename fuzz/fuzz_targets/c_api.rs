//! The C ABI on arbitrary bytes: the first byte picks how the image is given (copied from
//! memory, or through a read function that fails from some offset on), the rest is the
//! image. Every call must return a status (no panic, no crash), the handle must agree with
//! the core's own verdict on the bytes it was given, and freeing it must be clean.
#![no_main]

use hirad_core::image::{SceneView, SliceSource};
use hirad_ffi::*;
use libfuzzer_sys::fuzz_target;
use std::ffi::{CStr, c_void};
use std::ptr;

struct Disk<'a> {
    bytes: &'a [u8],
    fails_from: u64,
}

unsafe extern "C" fn read(user: *mut c_void, offset: u64, buf: *mut u8, len: usize) -> i32 {
    let disk = unsafe { &*(user as *const Disk<'_>) };
    let end = offset.saturating_add(len as u64);
    if end > disk.fails_from || end > disk.bytes.len() as u64 {
        return 7;
    }
    let from = offset as usize;
    unsafe { ptr::copy_nonoverlapping(disk.bytes[from..from + len].as_ptr(), buf, len) };
    0
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, image)) = data.split_first() else {
        return;
    };
    let mut scene: *mut HiradScene = ptr::null_mut();
    // Reads fail from an offset set by the mode byte (modes 0 and 1: never), the reader
    // alive as long as the handle.
    let fails_from = match mode % 3 {
        2 => (image.len() as u64 * (mode as u64 / 3)) / 85,
        _ => u64::MAX,
    };
    let disk = Disk {
        bytes: image,
        fails_from,
    };
    let status = match mode % 3 {
        0 => unsafe { hirad_scene_open_memory(image.as_ptr(), image.len(), &mut scene) },
        _ => unsafe {
            hirad_scene_open_reader(
                Some(read),
                &disk as *const Disk<'_> as *mut c_void,
                image.len() as u64,
                &mut scene,
            )
        },
    };
    assert!(!scene.is_null(), "a handle is made whatever the bytes");
    let core = SceneView::open(SliceSource(image));
    let message = unsafe { CStr::from_ptr(hirad_scene_message(scene)) }
        .to_str()
        .expect("messages are UTF-8")
        .to_string();
    match (&core, status) {
        (Ok(view), HiradStatus::Ok) => {
            assert!(message.is_empty());
            let mut info = HiradSceneInfo::default();
            assert_eq!(
                unsafe { hirad_scene_info(scene, &mut info) },
                HiradStatus::Ok
            );
            assert_eq!(info.expanded_polygons, view.info().expanded_polygons);
        }
        (Err(e), HiradStatus::InvalidScene) if fails_from == u64::MAX => {
            assert_eq!(message, format!("byte {}: {}", e.offset, e.kind));
            assert_eq!(unsafe { hirad_scene_error_offset(scene) }, e.offset);
        }
        // A failing reader refuses what the bytes alone would pass.
        (_, HiradStatus::InvalidScene) if fails_from != u64::MAX => {
            assert!(!message.is_empty());
        }
        (c, s) => panic!("core {c:?}, C ABI {s:?}: {message}"),
    }
    unsafe { hirad_scene_free(scene) };
});
