//! Rasterises leaf patches as the solver hands them over: a z-buffered pinhole image in
//! which each pixel shows the radiance (B / pi, W/m^2/sr) of the side of the nearest patch
//! that faces the camera. Only the framebuffer is held, never the patches.

use super::camera::{MAX_SIDE, OptionError, Projection, Size};
use super::frame::Frame;
use super::interp::corner_weights;
use crate::scene::Camera;
use anyhow::anyhow;
use glam::{DVec3, Vec3};
use hirad_core::sink::{PatchResult, PolygonResult, Sink};

/// Most samples (pixels times supersamples) a framebuffer may hold.
pub const MAX_SAMPLES: u64 = 1 << 26;

/// Most samples per pixel along each axis.
pub const MAX_SUPERSAMPLE: u32 = 8;

/// No patch covers the sample (see [`Rasterizer::track_owners`]).
const NO_OWNER: u32 = u32::MAX;

/// Points nearer the eye than this fraction of the eye-target distance are clipped.
pub const NEAR_REL: f64 = 1e-6;

/// A z-buffer and radiance buffer at `supersample x supersample` samples per pixel; a
/// [`Sink`] that draws every leaf patch.
#[derive(Clone, Debug)]
pub struct Rasterizer {
    projection: Projection,
    size: Size,
    supersample: u32,
    bands: usize,
    near: f64,
    /// Per sample: 1 / depth of the nearest patch so far (0: background).
    inv_depth: Vec<f32>,
    /// Per sample: `bands` radiance values.
    radiance: Vec<f32>,
    /// Per sample: the nearest patch shows the back of a one-sided polygon (black).
    back: Vec<bool>,
    clipped: Vec<DVec3>,
    colour: Vec<f32>,
    /// Whether the patch being drawn shows the back of a one-sided polygon.
    drawing_back: bool,
    /// Per sample: the index of the patch it shows; empty unless tracked.
    owner: Vec<u32>,
    /// Patches drawn so far.
    drawn: u32,
}

/// What the samples of an image show, in fractions of them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coverage {
    /// A surface with some light.
    pub lit: f64,
    /// The back of a one-sided polygon (which absorbs and shows nothing).
    pub backs: f64,
    /// Nothing at all (the background).
    pub empty: f64,
}

impl Rasterizer {
    /// An empty (black) image of `size` pixels seen by a checked camera, with
    /// `supersample x supersample` samples per pixel (1 for one sample at the pixel centre).
    pub fn new(
        camera: &Camera,
        size: Size,
        supersample: u32,
        bands: usize,
    ) -> Result<Self, OptionError> {
        let sides = [size.width, size.height];
        if !sides.iter().all(|s| (1..=MAX_SIDE).contains(s)) {
            return Err(OptionError(format!(
                "an image of {}x{} pixels: each side must be from 1 to {MAX_SIDE}",
                size.width, size.height
            )));
        }
        if !(1..=MAX_SUPERSAMPLE).contains(&supersample) {
            return Err(OptionError(format!(
                "supersampling {supersample} is not from 1 to {MAX_SUPERSAMPLE}"
            )));
        }
        let samples =
            u64::from(size.width) * u64::from(size.height) * u64::from(supersample).pow(2);
        if samples > MAX_SAMPLES {
            return Err(OptionError(format!(
                "an image of {}x{} pixels with {supersample}x{supersample} samples each has \
                 {samples} samples; at most {MAX_SAMPLES}",
                size.width, size.height
            )));
        }
        let fine = Size {
            width: size.width * supersample,
            height: size.height * supersample,
        };
        let samples = samples as usize;
        Ok(Rasterizer {
            projection: Projection::new(camera, fine),
            size,
            supersample,
            bands,
            near: NEAR_REL * (camera.target - camera.position).as_dvec3().length(),
            inv_depth: vec![0.0; samples],
            radiance: vec![0.0; samples * bands],
            back: vec![false; samples],
            clipped: Vec::new(),
            colour: vec![0.0; bands],
            drawing_back: false,
            owner: Vec::new(),
            drawn: 0,
        })
    }

    /// Draws one planar convex patch (world corners, front normal) with its radiosity
    /// `[front, back]` (W/m^2; an empty back is a one-sided material and shows black).
    pub fn draw(
        &mut self,
        corners: &[Vec3],
        normal: Vec3,
        radiosity: [&[f32]; 2],
    ) -> Result<(), String> {
        if corners.len() < 3 {
            return Err(format!("a patch with {} corners", corners.len()));
        }
        if !(corners.iter().all(|c| c.is_finite()) && normal.is_finite()) {
            return Err("a patch with a corner or normal that is not finite".into());
        }
        for (side, values) in radiosity.iter().enumerate() {
            let allowed = values.len() == self.bands || (side == 1 && values.is_empty());
            if !allowed {
                return Err(format!(
                    "{} {} radiosity values for {} bands",
                    values.len(),
                    ["front", "back"][side],
                    self.bands
                ));
            }
            if values.iter().any(|v| !v.is_finite()) {
                return Err("a radiosity value that is not finite".into());
            }
        }
        let towards_eye = self.projection.eye() - corners[0].as_dvec3();
        let side = usize::from(towards_eye.dot(normal.as_dvec3()) < 0.0);
        let values = radiosity[side];
        self.drawing_back = side == 1 && values.is_empty();
        for (b, c) in self.colour.iter_mut().enumerate() {
            *c = values.get(b).map_or(0.0, |v| v / std::f32::consts::PI);
        }
        self.clip(corners);
        if self.clipped.len() < 3 {
            self.drawn = self.drawn.wrapping_add(1);
            return Ok(());
        }
        // Image coordinates and 1/z, which is affine in image space for a planar polygon.
        let verts: Vec<[f64; 3]> = self
            .clipped
            .iter()
            .map(|&c| {
                let [x, y] = self.projection.to_image(c);
                [x, y, 1.0 / c.z]
            })
            .collect();
        for k in 1..verts.len() - 1 {
            self.triangle([verts[0], verts[k], verts[k + 1]]);
        }
        self.drawn = self.drawn.wrapping_add(1);
        Ok(())
    }

    /// Camera-space polygon clipped to the near plane `z >= near` (Sutherland-Hodgman).
    fn clip(&mut self, corners: &[Vec3]) {
        self.clipped.clear();
        let near = self.near;
        let n = corners.len();
        for i in 0..n {
            let a = self.projection.to_camera(corners[i].as_dvec3());
            let b = self.projection.to_camera(corners[(i + 1) % n].as_dvec3());
            let (a_in, b_in) = (a.z >= near, b.z >= near);
            if a_in {
                self.clipped.push(a);
            }
            if a_in != b_in {
                let t = (near - a.z) / (b.z - a.z);
                let mut p = a + (b - a) * t;
                p.z = near;
                self.clipped.push(p);
            }
        }
    }

    /// Fills the samples whose centres lie in (or on the edge of) a triangle of image-space
    /// vertices `[x, y, 1/z]`, where it is nearer than what is there.
    fn triangle(&mut self, v: [[f64; 3]; 3]) {
        let fine = self.fine();
        let bands = self.bands;
        let index = self.drawn;
        let track = !self.owner.is_empty();
        let Rasterizer {
            inv_depth,
            radiance,
            back,
            owner,
            colour,
            drawing_back,
            ..
        } = self;
        covered(fine, v, |at, l| {
            let inv_z = (l[0] * v[0][2] + l[1] * v[1][2] + l[2] * v[2][2]) as f32;
            if inv_z > inv_depth[at] {
                inv_depth[at] = inv_z;
                radiance[at * bands..(at + 1) * bands].copy_from_slice(colour);
                back[at] = *drawing_back;
                if track {
                    owner[at] = index;
                }
            }
        });
    }

    /// Samples per side of the framebuffer.
    fn fine(&self) -> [usize; 2] {
        [
            (self.size.width * self.supersample) as usize,
            (self.size.height * self.supersample) as usize,
        ]
    }

    /// Remembers from now on which patch each sample shows, so that [`Rasterizer::shade`]
    /// can colour the samples of a patch again.
    pub fn track_owners(&mut self) {
        self.owner = vec![NO_OWNER; self.inv_depth.len()];
    }

    /// Forgets which patch each sample shows (and the memory it took).
    pub fn stop_tracking(&mut self) {
        self.owner = Vec::new();
    }

    /// Patches drawn so far (the next patch's index for [`Rasterizer::shade`]).
    pub fn drawn(&self) -> u32 {
        self.drawn
    }

    /// Colours again the samples that show patch `index` (the `index`-th drawn since
    /// [`Rasterizer::track_owners`]), the same `corners` and `normal`, from radiosity at its
    /// corners: `values[side]` holds `bands` values (W/m^2) per corner, corner after corner
    /// (empty: the side keeps its flat colour). Values are interpolated across the patch
    /// in world space (barycentric for triangles, bilinear for quads, see
    /// [`super::interp`]).
    pub fn shade(&mut self, index: u32, corners: &[Vec3], normal: Vec3, values: [&[f32]; 2]) {
        let n = corners.len();
        if self.owner.is_empty() || !(3..=4).contains(&n) {
            return;
        }
        let towards_eye = self.projection.eye() - corners[0].as_dvec3();
        let side = usize::from(towards_eye.dot(normal.as_dvec3()) < 0.0);
        let values = values[side];
        if values.len() < n * self.bands {
            return;
        }
        // Corners in 2D coordinates of the patch's plane, in camera space (m).
        let cam: Vec<DVec3> = corners
            .iter()
            .map(|c| self.projection.to_camera(c.as_dvec3()))
            .collect();
        let axis_u = (cam[1] - cam[0]).normalize_or_zero();
        let n_cam = (cam[1] - cam[0]).cross(cam[n - 1] - cam[0]);
        let axis_v = n_cam.cross(axis_u).normalize_or_zero();
        let plane = |p: DVec3| [(p - cam[0]).dot(axis_u), (p - cam[0]).dot(axis_v)];
        let flat: Vec<[f64; 2]> = cam.iter().map(|&c| plane(c)).collect();
        self.clip(corners);
        if self.clipped.len() < 3 {
            return;
        }
        let clipped = self.clipped.clone();
        let verts: Vec<[f64; 3]> = clipped
            .iter()
            .map(|&c| {
                let [x, y] = self.projection.to_image(c);
                [x, y, 1.0 / c.z]
            })
            .collect();
        let fine = self.fine();
        let bands = self.bands;
        let mut weights = [0.0f64; 4];
        let Rasterizer {
            radiance, owner, ..
        } = self;
        for k in 1..verts.len() - 1 {
            let tri = [0, k, k + 1];
            let v = tri.map(|i| verts[i]);
            covered(fine, v, |at, l| {
                if owner[at] != index {
                    return;
                }
                // Perspective-correct point: camera-space position is affine in l / z.
                let lw = [l[0] * v[0][2], l[1] * v[1][2], l[2] * v[2][2]];
                let sum = lw[0] + lw[1] + lw[2];
                if sum.is_nan() || sum <= 0.0 {
                    return;
                }
                let p =
                    (clipped[tri[0]] * lw[0] + clipped[tri[1]] * lw[1] + clipped[tri[2]] * lw[2])
                        / sum;
                corner_weights(&flat, plane(p), &mut weights);
                let out = &mut radiance[at * bands..(at + 1) * bands];
                for (b, o) in out.iter_mut().enumerate() {
                    let b_sum: f64 = (0..n)
                        .map(|c| weights[c] * f64::from(values[c * bands + b]))
                        .sum();
                    *o = (b_sum / std::f64::consts::PI) as f32;
                }
            });
        }
    }

    /// The image: each pixel the mean of its samples (background samples count as 0).
    pub fn frame(&self, channels: Vec<String>) -> Frame {
        let (ss, bands) = (self.supersample as usize, self.bands);
        let (w, h) = (self.size.width as usize, self.size.height as usize);
        let stride = w * ss;
        let mut data = vec![0.0f32; w * h * bands];
        let mut sum = vec![0.0f64; bands];
        let norm = 1.0 / (ss * ss) as f64;
        for y in 0..h {
            for x in 0..w {
                sum.fill(0.0);
                for sy in 0..ss {
                    for sx in 0..ss {
                        let at = (y * ss + sy) * stride + x * ss + sx;
                        for (s, v) in sum.iter_mut().zip(&self.radiance[at * bands..]) {
                            *s += f64::from(*v);
                        }
                    }
                }
                let out = &mut data[(y * w + x) * bands..(y * w + x + 1) * bands];
                for (o, s) in out.iter_mut().zip(&sum) {
                    *o = (s * norm) as f32;
                }
            }
        }
        Frame {
            width: self.size.width,
            height: self.size.height,
            channels,
            data,
        }
    }

    /// Bands per pixel.
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// What the samples show so far.
    pub fn coverage(&self) -> Coverage {
        let n = self.inv_depth.len().max(1) as f64;
        let (mut lit, mut backs, mut empty) = (0usize, 0usize, 0usize);
        for (at, &d) in self.inv_depth.iter().enumerate() {
            if d <= 0.0 {
                empty += 1;
            } else if self.back[at] {
                backs += 1;
            } else if self.radiance[at * self.bands..(at + 1) * self.bands]
                .iter()
                .any(|&v| v > 0.0)
            {
                lit += 1;
            }
        }
        Coverage {
            lit: lit as f64 / n,
            backs: backs as f64 / n,
            empty: empty as f64 / n,
        }
    }
}

/// Calls `f(sample index, screen barycentrics)` for every sample of a `fine` = `[width,
/// height]` framebuffer whose centre lies in (or on the edge of) the triangle of image-space
/// vertices `[x, y, 1/z]`.
fn covered(fine: [usize; 2], v: [[f64; 3]; 3], mut f: impl FnMut(usize, [f64; 3])) {
    let edge = |a: [f64; 3], b: [f64; 3], x: f64, y: f64| {
        (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])
    };
    let area = edge(v[0], v[1], v[2][0], v[2][1]);
    if !(area.is_finite() && area != 0.0) {
        return;
    }
    let (w, h) = (fine[0] as f64, fine[1] as f64);
    let lo = |k: usize| v.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
    let hi = |k: usize| v.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
    let x0 = (lo(0) - 0.5).ceil().max(0.0);
    let x1 = (hi(0) - 0.5).floor().min(w - 1.0);
    let y0 = (lo(1) - 0.5).ceil().max(0.0);
    let y1 = (hi(1) - 0.5).floor().min(h - 1.0);
    if !(x0 <= x1 && y0 <= y1) {
        return;
    }
    let stride = fine[0];
    for y in y0 as usize..=y1 as usize {
        let py = y as f64 + 0.5;
        for x in x0 as usize..=x1 as usize {
            let px = x as f64 + 0.5;
            let l0 = edge(v[1], v[2], px, py) / area;
            let l1 = edge(v[2], v[0], px, py) / area;
            let l2 = edge(v[0], v[1], px, py) / area;
            if l0 < 0.0 || l1 < 0.0 || l2 < 0.0 {
                continue;
            }
            f(y * stride + x, [l0, l1, l2]);
        }
    }
}

impl Sink for Rasterizer {
    type Error = anyhow::Error;

    fn patch(&mut self, patch: &PatchResult<'_>) -> anyhow::Result<()> {
        self.draw(patch.corners, patch.normal, patch.radiosity)
            .map_err(|e| anyhow!("image: polygon {}: {e}", patch.id))
    }

    fn polygon(&mut self, _: &PolygonResult<'_>) -> anyhow::Result<()> {
        Ok(())
    }
}
