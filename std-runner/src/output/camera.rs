//! The view of an image: `--camera` and `--size` option strings, camera checks, and a
//! default camera for scenes that have none.

use crate::scene::{Camera, Cluster, Scene, Up};
use glam::{DVec3, Vec3};
use hirad_core::geometry::{Aabb, camera_ok};
use hirad_core::limits::NONE;
use std::fmt;

/// Largest image side (pixels).
pub const MAX_SIDE: u32 = 16384;

/// Vertical field of view of the default camera (degrees).
pub const DEFAULT_FOVY_DEG: f32 = 45.0;

/// Direction from the scene's centre towards the default camera (z up): in front (-y), to
/// the right (+x) and above (+z), at equal angles.
pub const DEFAULT_VIEW_FROM: Vec3 = Vec3::new(1.0, -1.0, 1.0);

/// A bad option value or an unusable camera.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OptionError(pub String);

impl fmt::Display for OptionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for OptionError {}

/// An image size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
}

impl Size {
    /// Width over height.
    pub fn aspect(&self) -> f64 {
        f64::from(self.width) / f64::from(self.height)
    }
}

/// Parses `--size WxH` (for example `1280x720`): two whole numbers from 1 to [`MAX_SIDE`].
pub fn parse_size(s: &str) -> Result<Size, OptionError> {
    let bad = || {
        OptionError(format!(
            "--size: expected WIDTHxHEIGHT in pixels, such as 1280x720; found `{s}`"
        ))
    };
    let (w, h) = s.trim().split_once(['x', 'X']).ok_or_else(bad)?;
    let side = |what: &str, text: &str| match text.trim().parse::<u32>() {
        Ok(v) if (1..=MAX_SIDE).contains(&v) => Ok(v),
        _ => Err(OptionError(format!(
            "--size: {what} `{text}` is not a whole number of pixels from 1 to {MAX_SIDE}"
        ))),
    };
    Ok(Size {
        width: side("width", w)?,
        height: side("height", h)?,
    })
}

/// Names of the ten numbers of `--camera`, in order.
pub const CAMERA_FIELDS: [&str; 10] = [
    "px", "py", "pz", "tx", "ty", "tz", "ux", "uy", "uz", "fovy_deg",
];

/// Parses `--camera "px,py,pz,tx,ty,tz,ux,uy,uz,fovy_deg"`: eye position, target point (m),
/// up direction and vertical field of view (degrees), then checks it with [`check_camera`].
pub fn parse_camera(s: &str) -> Result<Camera, OptionError> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != CAMERA_FIELDS.len() {
        return Err(OptionError(format!(
            "--camera: expected 10 comma-separated numbers ({}), found {}",
            CAMERA_FIELDS.join(","),
            parts.len()
        )));
    }
    let mut v = [0.0f32; 10];
    for (i, (text, name)) in parts.iter().zip(CAMERA_FIELDS).enumerate() {
        v[i] = match text.trim().parse::<f32>() {
            Ok(x) if x.is_finite() => x,
            _ => {
                return Err(OptionError(format!(
                    "--camera: number {} ({name}) `{}` is not a finite number",
                    i + 1,
                    text.trim()
                )));
            }
        };
    }
    let camera = Camera {
        name: None,
        position: Vec3::new(v[0], v[1], v[2]),
        target: Vec3::new(v[3], v[4], v[5]),
        up: Vec3::new(v[6], v[7], v[8]),
        fovy_deg: v[9],
    };
    check_camera(&camera).map_err(|e| OptionError(format!("--camera: {e}")))?;
    Ok(camera)
}

/// A camera as the `--camera` value that gives it back ([`parse_camera`]): shortest decimal
/// forms, which read back to the same f32 values.
pub fn camera_arg(c: &Camera) -> String {
    let v = [
        c.position.x,
        c.position.y,
        c.position.z,
        c.target.x,
        c.target.y,
        c.target.z,
        c.up.x,
        c.up.y,
        c.up.z,
        c.fovy_deg,
    ];
    v.iter()
        .map(|x| format!("{}", x + 0.0))
        .collect::<Vec<_>>()
        .join(",")
}

/// Checks that a camera can form an image ([`camera_ok`]), saying what is wrong if not.
pub fn check_camera(c: &Camera) -> Result<(), OptionError> {
    if camera_ok(c.position, c.target, c.up, c.fovy_deg) {
        return Ok(());
    }
    let view = c.target - c.position;
    let why = if !(c.fovy_deg > 0.0 && c.fovy_deg < 180.0) {
        format!(
            "the field of view {} degrees is not strictly between 0 and 180",
            c.fovy_deg
        )
    } else if !(c.position.is_finite() && c.target.is_finite() && c.up.is_finite()) {
        "the camera has a number that is not finite".to_string()
    } else if view.length()
        <= 1e-6
            * c.position
                .abs()
                .max_element()
                .max(c.target.abs().max_element())
        || view.length() == 0.0
    {
        "the eye is at the target".to_string()
    } else {
        "the up direction is zero or along the view direction".to_string()
    };
    Err(OptionError(format!("unusable camera: {why}")))
}

/// A camera that sees the whole box `bounds`: it looks at the box's centre from
/// [`DEFAULT_VIEW_FROM`] (z up), with a [`DEFAULT_FOVY_DEG`] vertical field of view, far
/// enough that the box's bounding sphere fits the narrower of the two fields of view.
pub fn default_camera(bounds: &Aabb, size: Size) -> Result<Camera, OptionError> {
    default_camera_up(bounds, size, Up::Z)
}

/// [`default_camera`] for a scene whose up axis is `up` (+y for OBJ, see `scene::Up`): the
/// view comes from above and to the side whichever axis is up.
pub fn default_camera_up(bounds: &Aabb, size: Size, up: Up) -> Result<Camera, OptionError> {
    if !bounds.is_finite_nonempty() {
        return Err(OptionError(
            "the scene has no geometry for a default camera to look at".into(),
        ));
    }
    let (min, max) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
    let centre = (min + max) * 0.5;
    let mut radius = (max - min).length() * 0.5;
    if radius <= 0.0 {
        // A single point: look at it from a distance relative to its own magnitude.
        radius = centre.abs().max_element().max(1.0) * 1e-3;
    }
    let half_y = f64::from(DEFAULT_FOVY_DEG).to_radians() * 0.5;
    let half_x = (half_y.tan() * size.aspect()).atan();
    let distance = radius / half_y.min(half_x).sin() * 1.02;
    let from = up.from_z_up(DEFAULT_VIEW_FROM.as_dvec3()).normalize();
    let camera = Camera {
        name: None,
        position: (centre + from * distance).as_vec3(),
        target: centre.as_vec3(),
        up: up.vector().as_vec3(),
        fovy_deg: DEFAULT_FOVY_DEG,
    };
    check_camera(&camera).map_err(|e| OptionError(format!("default camera: {e}")))?;
    Ok(camera)
}

/// The world-space box of the expanded scene, computed on the compact (instanced) form: each
/// original's box once, placed by every instance's transform (a box of boxes, so it may be
/// a little larger than the tightest box under rotation).
pub fn scene_bounds(scene: &Scene) -> Aabb {
    let mut memo = vec![Memo::Todo; scene.originals.len()];
    cluster_box(scene, &scene.root, &mut memo)
}

#[derive(Clone, Copy)]
enum Memo {
    Todo,
    Busy,
    Done(Aabb),
}

/// Box of a cluster's content (own vertices used by polygons and children), in its content
/// frame.
fn cluster_box(scene: &Scene, c: &Cluster, memo: &mut [Memo]) -> Aabb {
    let mut b = Aabb::EMPTY;
    for p in &c.polygons {
        for &corner in p.corners.iter().filter(|&&k| k != NONE) {
            if let Some(&v) = c.vertices.get(corner as usize) {
                b.include(v);
            }
        }
    }
    for child in &c.children {
        let child_box = match &child.instance {
            None => cluster_box(scene, child, memo),
            Some(i) => {
                let local = if i.exact {
                    original_box(scene, i.original, memo)
                } else {
                    cluster_box(scene, child, memo)
                };
                i.transform.aabb(&local)
            }
        };
        b = b.union(child_box);
    }
    b
}

/// Box of an original in its own frame, computed once; a cycle (refused by the scene checks
/// anyway) contributes nothing instead of recursing forever.
fn original_box(scene: &Scene, original: usize, memo: &mut [Memo]) -> Aabb {
    match memo.get(original) {
        Some(Memo::Done(b)) => *b,
        Some(Memo::Todo) => {
            memo[original] = Memo::Busy;
            let b = cluster_box(scene, &scene.originals[original].root, memo);
            memo[original] = Memo::Done(b);
            b
        }
        Some(Memo::Busy) | None => Aabb::EMPTY,
    }
}

/// The camera's frame and projection onto an image of `size` pixels, pixel (0, 0) at the
/// top left, pixel centres at half-integer coordinates. Computed in f64.
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    eye: DVec3,
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    /// Pixels per unit of `x / z` and `y / z` in camera space.
    scale_x: f64,
    scale_y: f64,
    width: f64,
    height: f64,
}

impl Projection {
    /// The projection of a checked camera (see [`check_camera`]) onto `size` pixels.
    pub fn new(camera: &Camera, size: Size) -> Self {
        let eye = camera.position.as_dvec3();
        let forward = (camera.target.as_dvec3() - eye).normalize();
        let right = forward.cross(camera.up.as_dvec3()).normalize();
        let up = right.cross(forward);
        let tan_half = (f64::from(camera.fovy_deg).to_radians() * 0.5).tan();
        let (width, height) = (f64::from(size.width), f64::from(size.height));
        Projection {
            eye,
            right,
            up,
            forward,
            scale_x: 0.5 * width / (tan_half * size.aspect()),
            scale_y: 0.5 * height / tan_half,
            width,
            height,
        }
    }

    /// The eye (m).
    pub fn eye(&self) -> DVec3 {
        self.eye
    }

    /// A point in camera space: (right, up, distance along the view) (m).
    pub fn to_camera(&self, p: DVec3) -> DVec3 {
        let d = p - self.eye;
        DVec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.forward))
    }

    /// Image coordinates (pixels, x right, y down) of a camera-space point in front of the
    /// eye (`c.z > 0`).
    pub fn to_image(&self, c: DVec3) -> [f64; 2] {
        [
            0.5 * self.width + self.scale_x * c.x / c.z,
            0.5 * self.height - self.scale_y * c.y / c.z,
        ]
    }

    /// Image coordinates of a world point, or `None` when it is not in front of the eye.
    pub fn pixel(&self, p: Vec3) -> Option<[f64; 2]> {
        let c = self.to_camera(p.as_dvec3());
        (c.z > 0.0).then(|| self.to_image(c))
    }
}
