//! no_std canary: uses the core's checked view with a panic handler of its own.
#![no_std]

use hirad_core::image::{SceneView, SliceSource};

/// Validates an image held in flash and returns its expanded polygon count (0 if refused).
pub fn expanded_polygons(image: &'static [u8]) -> u64 {
    match SceneView::open(SliceSource(image)) {
        Ok(v) => v.info().expanded_polygons,
        Err(_) => 0,
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}
