//! The C functions on scene images, called as C would: a valid image opens and tells its
//! counts; a corrupt one gives `HIRAD_INVALID_SCENE` with the same message and byte offset
//! the core's checked view reports; null pointers are status codes.

use hirad_ffi::*;
use std::ffi::{CStr, c_void};
use std::ptr;

/// The small plant fixture compiled to an image.
fn plant() -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/small_plant.hir");
    let scene = hirad::files::load_scene(&path).unwrap().scene;
    hirad::scene::compile(&scene).unwrap()
}

fn open(bytes: &[u8]) -> (HiradStatus, *mut HiradScene) {
    let mut scene: *mut HiradScene = ptr::null_mut();
    let status = unsafe { hirad_scene_open_memory(bytes.as_ptr(), bytes.len(), &mut scene) };
    (status, scene)
}

fn message(scene: *const HiradScene) -> String {
    unsafe { CStr::from_ptr(hirad_scene_message(scene)) }
        .to_str()
        .unwrap()
        .to_string()
}

#[test]
fn a_valid_image_opens_and_tells_its_counts() {
    let bytes = plant();
    let (status, scene) = open(&bytes);
    assert_eq!(status, HiradStatus::Ok, "{}", message(scene));
    assert_eq!(message(scene), "");
    assert_eq!(unsafe { hirad_scene_error_offset(scene) }, u64::MAX);
    let mut info = HiradSceneInfo::default();
    assert_eq!(
        unsafe { hirad_scene_info(scene, &mut info) },
        HiradStatus::Ok
    );
    let view = hirad_core::image::SceneView::open(hirad_core::image::SliceSource(&bytes)).unwrap();
    let i = view.info();
    assert_eq!(info.bands, i.bands);
    assert_eq!(info.polygons, i.polygons);
    assert_eq!(info.expanded_polygons, i.expanded_polygons);
    assert_eq!(info.instances, i.exact_instances + i.approximate_instances);
    // The plant: twigs in branches.
    assert_eq!(info.originals, 2);
    assert_eq!(info.instancing_depth, 2);
    assert!(info.instances >= 25, "{info:?}");
    unsafe { hirad_scene_free(scene) };
}

#[test]
fn a_corrupt_image_says_what_and_where_as_the_core_does() {
    let good = plant();
    // Every byte of the header, and a sweep through the rest, flipped one at a time: where
    // the core refuses the image, the handle carries its message and offset.
    let mut refused = 0;
    let step = (good.len() / 200).max(1);
    for at in (0..64).chain((64..good.len()).step_by(step)) {
        let mut bad = good.clone();
        bad[at] ^= 0x5A;
        let core = hirad_core::image::SceneView::open(hirad_core::image::SliceSource(&bad));
        let (status, scene) = open(&bad);
        assert!(!scene.is_null());
        match core {
            Ok(_) => assert_eq!(status, HiradStatus::Ok, "byte {at}"),
            Err(e) => {
                refused += 1;
                assert_eq!(status, HiradStatus::InvalidScene, "byte {at}");
                assert_eq!(unsafe { hirad_scene_error_offset(scene) }, e.offset);
                assert_eq!(message(scene), format!("byte {}: {}", e.offset, e.kind));
                let mut info = HiradSceneInfo::default();
                assert_eq!(
                    unsafe { hirad_scene_info(scene, &mut info) },
                    HiradStatus::NotOpen
                );
            }
        }
        unsafe { hirad_scene_free(scene) };
    }
    assert!(refused > 20, "{refused}");
    // Too short, empty: refused at their end.
    for bytes in [&good[..10], &[][..]] {
        let (status, scene) = open(bytes);
        assert_eq!(status, HiradStatus::InvalidScene);
        assert_eq!(
            unsafe { hirad_scene_error_offset(scene) },
            bytes.len() as u64
        );
        assert!(message(scene).contains("too short"), "{}", message(scene));
        unsafe { hirad_scene_free(scene) };
    }
}

#[test]
fn null_pointers_are_status_codes() {
    let bytes = plant();
    let mut scene: *mut HiradScene = ptr::null_mut();
    unsafe {
        assert_eq!(
            hirad_scene_open_memory(bytes.as_ptr(), bytes.len(), ptr::null_mut()),
            HiradStatus::NullArgument
        );
        assert_eq!(
            hirad_scene_open_memory(ptr::null(), 10, &mut scene),
            HiradStatus::NullArgument
        );
        assert!(scene.is_null());
        // No bytes at a null pointer is an empty image: invalid, not a null argument.
        assert_eq!(
            hirad_scene_open_memory(ptr::null(), 0, &mut scene),
            HiradStatus::InvalidScene
        );
        hirad_scene_free(scene);
        let mut info = HiradSceneInfo::default();
        assert_eq!(
            hirad_scene_info(ptr::null(), &mut info),
            HiradStatus::NullArgument
        );
        let (_, open) = open(&bytes);
        assert_eq!(
            hirad_scene_info(open, ptr::null_mut()),
            HiradStatus::NullArgument
        );
        hirad_scene_free(open);
        assert_eq!(
            CStr::from_ptr(hirad_scene_message(ptr::null())).to_bytes(),
            b""
        );
        assert_eq!(hirad_scene_error_offset(ptr::null()), u64::MAX);
        hirad_scene_free(ptr::null_mut());
    }
}

/// What the test reader reads from: the bytes, and the offset from which every read fails.
struct Disk {
    bytes: Vec<u8>,
    fails_from: u64,
}

unsafe extern "C" fn read_disk(user: *mut c_void, offset: u64, buf: *mut u8, len: usize) -> i32 {
    let disk = unsafe { &*(user as *const Disk) };
    if offset + len as u64 > disk.fails_from {
        return 5;
    }
    let from = offset as usize;
    unsafe { std::ptr::copy_nonoverlapping(disk.bytes[from..from + len].as_ptr(), buf, len) };
    0
}

fn open_reader(disk: &Disk, len: u64) -> (HiradStatus, *mut HiradScene) {
    let mut scene: *mut HiradScene = ptr::null_mut();
    let status = unsafe {
        hirad_scene_open_reader(
            Some(read_disk),
            disk as *const Disk as *mut c_void,
            len,
            &mut scene,
        )
    };
    (status, scene)
}

#[test]
fn a_reader_opens_what_the_bytes_open_and_its_failures_are_reported() {
    let bytes = plant();
    let n = bytes.len() as u64;
    let disk = Disk {
        bytes: bytes.clone(),
        fails_from: u64::MAX,
    };
    let (status, scene) = open_reader(&disk, n);
    assert_eq!(status, HiradStatus::Ok, "{}", message(scene));
    let (_, from_memory) = open(&bytes);
    let (mut a, mut b) = (HiradSceneInfo::default(), HiradSceneInfo::default());
    unsafe {
        assert_eq!(hirad_scene_info(scene, &mut a), HiradStatus::Ok);
        assert_eq!(hirad_scene_info(from_memory, &mut b), HiradStatus::Ok);
        hirad_scene_free(scene);
        hirad_scene_free(from_memory);
    }
    assert_eq!(a, b);
    // A read that fails anywhere: the scene is refused with the reader's code and the byte
    // of the record being read (reads go ahead by windows of records).
    for fails_from in [0, 8, 64, n / 3, n / 2, n - 1] {
        let disk = Disk {
            bytes: bytes.clone(),
            fails_from,
        };
        let (status, scene) = open_reader(&disk, n);
        assert_eq!(status, HiradStatus::InvalidScene, "from {fails_from}");
        let m = message(scene);
        assert!(m.contains("error code 5"), "from {fails_from}: {m}");
        assert!(unsafe { hirad_scene_error_offset(scene) } < n, "{m}");
        unsafe { hirad_scene_free(scene) };
    }
    // A length other than the image's own: refused, never read past.
    for len in [n - 1, n + 1, 10] {
        let (status, scene) = open_reader(&disk, len);
        assert_eq!(status, HiradStatus::InvalidScene, "length {len}");
        unsafe { hirad_scene_free(scene) };
    }
    // No function: a null argument.
    let mut scene: *mut HiradScene = ptr::null_mut();
    let status = unsafe { hirad_scene_open_reader(None, ptr::null_mut(), n, &mut scene) };
    assert_eq!(status, HiradStatus::NullArgument);
    assert!(scene.is_null());
}
