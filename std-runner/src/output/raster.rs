//! Rasterises leaf patches as the solver hands them over: a z-buffered pinhole image in
//! which each pixel shows the radiance (B / pi, W/m^2/sr) of the side of the nearest patch
//! that faces the camera. Only the framebuffer is held, never the patches.

use super::camera::{MAX_SIDE, OptionError, Projection, Size};
use super::frame::Frame;
use crate::scene::Camera;
use anyhow::anyhow;
use glam::{DVec3, Vec3};
use hirad_core::sink::{PatchResult, PolygonResult, Sink};

/// Most samples (pixels times supersamples) a framebuffer may hold.
pub const MAX_SAMPLES: u64 = 1 << 26;

/// Most samples per pixel along each axis.
pub const MAX_SUPERSAMPLE: u32 = 8;

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
        let edge = |a: [f64; 3], b: [f64; 3], x: f64, y: f64| {
            (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])
        };
        let area = edge(v[0], v[1], v[2][0], v[2][1]);
        if !(area.is_finite() && area != 0.0) {
            return;
        }
        let (w, h) = (
            f64::from(self.size.width * self.supersample),
            f64::from(self.size.height * self.supersample),
        );
        let lo = |k: usize| v.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let hi = |k: usize| v.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        let x0 = (lo(0) - 0.5).ceil().max(0.0);
        let x1 = (hi(0) - 0.5).floor().min(w - 1.0);
        let y0 = (lo(1) - 0.5).ceil().max(0.0);
        let y1 = (hi(1) - 0.5).floor().min(h - 1.0);
        if !(x0 <= x1 && y0 <= y1) {
            return;
        }
        let stride = w as usize;
        let bands = self.bands;
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
                let inv_z = (l0 * v[0][2] + l1 * v[1][2] + l2 * v[2][2]) as f32;
                let at = y * stride + x;
                if inv_z > self.inv_depth[at] {
                    self.inv_depth[at] = inv_z;
                    self.radiance[at * bands..(at + 1) * bands].copy_from_slice(&self.colour);
                    self.back[at] = self.drawing_back;
                }
            }
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
