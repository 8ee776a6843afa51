//! Camera sanity shared by every loader.

use glam::Vec3;

/// True if a camera can form an image: finite, eye away from target (relative to their
/// distance from the origin), up not along the view, field of view strictly inside (0, 180).
pub fn camera_ok(position: Vec3, target: Vec3, up: Vec3, fovy_deg: f32) -> bool {
    if !(position.is_finite() && target.is_finite() && up.is_finite() && fovy_deg.is_finite()) {
        return false;
    }
    let view = target - position;
    let scale = position.abs().max_element().max(target.abs().max_element());
    let side = view.cross(up);
    view.length() > 1e-6 * scale
        && view.length() > 0.0
        && side.length() > 1e-4 * view.length() * up.length()
        && fovy_deg > 0.0
        && fovy_deg < 180.0
}
