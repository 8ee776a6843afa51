//! One original taken out of its scene to be measured: its expanded geometry in its own
//! frame, a ray caster over it, and hr solves of it alone under a sun of 1 W/m^2.

use crate::output::ResultsTable;
use crate::scene::{self, Scene};
use crate::solve::{RayonExecutor, world_polygons};
use crate::visibility::ObvhsVisibility;
use anyhow::{Result, anyhow};
use glam::Vec3;
use hirad_core::hr::{self, NoProgress, Settings, SolveError, Stats};
use hirad_core::limits::MAX_BANDS;
use hirad_core::tables::outgoing::visible_fraction;

/// An original alone, expanded, in its own frame (metres).
pub struct Alone {
    /// The scene that holds only the original (its root as the scene's root), no lights.
    pub scene: Scene,
    /// World corners of every polygon, in global-id order of `scene`.
    pub polygons: Vec<Vec<Vec3>>,
    /// Unit front normal per polygon.
    pub normals: Vec<Vec3>,
    /// Area per polygon (m^2).
    pub areas: Vec<f32>,
    /// Material index per polygon.
    pub materials: Vec<u32>,
    /// The bounding box of the polygons (m).
    pub lo: Vec3,
    /// Upper corner.
    pub hi: Vec3,
    /// Rays against the polygons.
    pub vis: ObvhsVisibility,
}

/// A solve of an original under one sun.
pub struct Lit {
    /// Per polygon: radiosity and irradiance, front and back (W/m^2 per W/m^2 of sun).
    pub table: ResultsTable,
    /// The solver's statistics (its power balance: direct, absorbed, escaped).
    pub stats: Stats,
}

impl Alone {
    /// Takes original `index` of `scene` out: its tree with every instance inside expanded.
    pub fn new(scene: &Scene, index: usize) -> Result<Self> {
        let o = scene
            .originals
            .get(index)
            .ok_or_else(|| anyhow!("no original {index}"))?;
        let alone = Scene {
            bands: scene.bands,
            band_names: scene.band_names.clone(),
            materials: scene.materials.clone(),
            originals: scene.originals.clone(),
            root: o.root.clone(),
            suns: Vec::new(),
            sky: Vec::new(),
            cameras: Vec::new(),
            tables: Vec::new(),
        };
        let polygons = world_polygons(&alone);
        let materials = polygon_materials(&alone);
        if polygons.is_empty() {
            return Err(anyhow!("original '{}' has no polygon", o.name));
        }
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for c in polygons.iter().flatten() {
            lo = lo.min(*c);
            hi = hi.max(*c);
        }
        let normals = polygons.iter().map(|p| normal(p)).collect();
        let areas = polygons
            .iter()
            .map(|p| {
                hirad_core::geometry::polygon_shape(p)
                    .map(|s| s.area)
                    .unwrap_or(0.0)
            })
            .collect();
        let vis = ObvhsVisibility::new(&polygons).map_err(|e| anyhow!("{e}"))?;
        Ok(Self {
            scene: alone,
            polygons,
            normals,
            areas,
            materials,
            lo,
            hi,
            vis,
        })
    }

    /// A length that takes a ray from any point of the box past all of it (m).
    pub fn reach(&self) -> f32 {
        2.0 * (self.hi - self.lo).length() + 1e-3
    }

    /// Per polygon, the fraction of its area from which a ray towards `towards` leaves
    /// unblocked, from `k x k` points (see `visible_fraction`).
    pub fn visible(&self, towards: Vec3, k: u32, seed: u32) -> Vec<f32> {
        (0..self.polygons.len())
            .map(|p| {
                visible_fraction(
                    &self.vis,
                    &self.polygons[p],
                    p as u32,
                    towards,
                    self.reach(),
                    k,
                    seed,
                )
            })
            .collect()
    }

    /// Bands of the scene.
    pub fn bands(&self) -> usize {
        self.scene.bands as usize
    }

    /// Solves the original under a sun of 1 W/m^2 in every band towards `source` (unit, in
    /// the original's frame), with `settings`.
    pub fn solve(
        &self,
        source: Vec3,
        settings: &Settings,
        exec: &mut RayonExecutor,
    ) -> Result<Lit> {
        let sun = scene::light(source, &[1.0; MAX_BANDS][..self.bands()]);
        self.solve_lights(vec![sun], Vec::new(), settings, exec)
    }

    /// Solves the original under the suns `suns` and sky directions `sky` (its own frame).
    pub fn solve_lights(
        &self,
        suns: Vec<scene::LightData>,
        sky: Vec<scene::LightData>,
        settings: &Settings,
        exec: &mut RayonExecutor,
    ) -> Result<Lit> {
        let box_area = |l: &scene::LightData| {
            hirad_core::tables::tau::projected_area(self.lo, self.hi, l.towards)
        };
        if suns.iter().chain(&sky).all(|l| box_area(l) <= 0.0) {
            // Every light runs along the plane of a flat original: nothing is lit (the
            // solver would refuse a scene that receives no power).
            return self.dark();
        }
        let mut s = self.scene.clone();
        s.suns = suns;
        s.sky = sky;
        self.solve_scene(&s, settings, exec)
    }

    /// Solves the original under one sun of 1 W/m^2 in every band towards each of
    /// `sources` (unit, its own frame), several suns per solve: each sun lights its own
    /// copy of the bands (materials repeated), so a solve carries `MAX_BANDS / bands` of
    /// them, their links refined where any of them needs it (refinement and convergence
    /// are per band). Each sun's light is returned apart, in the order of `sources`.
    pub fn solve_many(
        &self,
        sources: &[Vec3],
        settings: &Settings,
        exec: &mut RayonExecutor,
    ) -> Result<Vec<Lit>> {
        let nb = self.bands();
        let per = (MAX_BANDS / nb).max(1);
        let mut out = Vec::with_capacity(sources.len());
        for chunk in sources.chunks(per) {
            if chunk.len() == 1 {
                out.push(self.solve(chunk[0], settings, exec)?);
                continue;
            }
            let k = chunk.len();
            let mut s = self.scene.clone();
            s.bands = (nb * k) as u8;
            s.band_names = (0..k)
                .flat_map(|j| {
                    self.scene
                        .band_names
                        .iter()
                        .map(move |n| format!("{n}_{j}"))
                })
                .collect();
            for m in &mut s.materials {
                let d = &mut m.data;
                d.bands = (nb * k) as u8;
                for v in [
                    &mut d.rho_front,
                    &mut d.rho_back,
                    &mut d.tau,
                    &mut d.emit_front,
                    &mut d.emit_back,
                ] {
                    for b in nb..nb * k {
                        v[b] = v[b % nb];
                    }
                }
            }
            let area = |d: Vec3| hirad_core::tables::tau::projected_area(self.lo, self.hi, d);
            s.suns = chunk
                .iter()
                .enumerate()
                .filter(|(_, d)| area(**d) > 0.0)
                .map(|(j, d)| {
                    let mut irr = [0.0f32; MAX_BANDS];
                    irr[j * nb..(j + 1) * nb].fill(1.0);
                    scene::light(*d, &irr[..nb * k])
                })
                .collect();
            if s.suns.is_empty() {
                for _ in chunk {
                    out.push(self.dark()?);
                }
                continue;
            }
            let packed = self.solve_scene(&s, settings, exec)?;
            for j in 0..k {
                out.push(packed.band_slice(j * nb, nb));
            }
        }
        Ok(out)
    }

    /// Solves `s`, a copy of the original's scene with lights.
    fn solve_scene(&self, s: &Scene, settings: &Settings, exec: &mut RayonExecutor) -> Result<Lit> {
        let bytes = scene::compile(s).map_err(|e| anyhow!("{e}"))?;
        let view = scene::read_image(&bytes).map_err(|e| anyhow!("{e}"))?;
        let mut scratch = vec![0u8; hr::census_scratch_bytes(&view)];
        let plan = hr::plan(&view, settings, false, &mut scratch).map_err(|e| anyhow!("{e}"))?;
        let mut ws = vec![0u8; plan.suggested_bytes as usize];
        let two_sided = s.materials.iter().any(|m| m.data.two_sided);
        let mut table = ResultsTable::new(s.bands as usize, two_sided);
        let stats = hr::solve(
            &view,
            settings,
            &mut ws,
            Some(&self.vis),
            exec,
            &mut NoProgress,
            &mut table,
        )
        .map_err(|e| match e {
            SolveError::Hr(e) => anyhow!("{e}"),
            SolveError::Sink(e) => e,
        })?;
        if table.len() != self.polygons.len() {
            return Err(anyhow!(
                "the solve gave {} polygons of {}",
                table.len(),
                self.polygons.len()
            ));
        }
        Ok(Lit { table, stats })
    }
}

impl Alone {
    /// The solve of an original that no light reaches: every value 0.
    fn dark(&self) -> Result<Lit> {
        let bands = self.bands();
        let two_sided = self.scene.materials.iter().any(|m| m.data.two_sided);
        let mut table = ResultsTable::new(bands, two_sided);
        let zeros = [0.0f32; MAX_BANDS];
        for p in 0..self.polygons.len() {
            let two = self.scene.materials[self.materials[p] as usize]
                .data
                .two_sided;
            let back: &[f32] = if two { &zeros[..bands] } else { &[] };
            table
                .push(&hirad_core::sink::PolygonResult {
                    id: p as u64,
                    area: self.areas[p],
                    two_sided: two,
                    radiosity: [&zeros[..bands], back],
                    irradiance: [&zeros[..bands], back],
                })
                .map_err(|e| anyhow!("{e}"))?;
        }
        Ok(Lit {
            table,
            stats: Stats::default(),
        })
    }
}

impl Lit {
    /// The `n` bands from `first` of a solve whose bands hold several suns' (see
    /// [`Alone::solve_many`]): one sun's light, its balance and the shared statistics.
    fn band_slice(&self, first: usize, n: usize) -> Lit {
        let t = &self.table;
        let cut = |v: &[f32]| -> Vec<f32> {
            v.chunks(t.bands)
                .flat_map(|row| row[first..first + n].iter().copied())
                .collect()
        };
        let table = ResultsTable {
            bands: n,
            two_sided: t.two_sided,
            ids: t.ids.clone(),
            areas: t.areas.clone(),
            radiosity: [cut(&t.radiosity[0]), cut(&t.radiosity[1])],
            irradiance: [cut(&t.irradiance[0]), cut(&t.irradiance[1])],
        };
        let mut stats = self.stats;
        let b = &mut stats.balance;
        for v in [
            &mut b.emitted,
            &mut b.direct,
            &mut b.absorbed,
            &mut b.absorbed_backs,
            &mut b.escaped,
        ] {
            let mut w = [0.0f64; MAX_BANDS];
            w[..n].copy_from_slice(&v[first..first + n]);
            *v = w;
        }
        Lit { table, stats }
    }

    /// The intensity (W/sr per band) leaving the original towards the unit `towards`, given
    /// each polygon's visible fraction that way: radiance x area x |cosine| x fraction.
    pub fn intensity(
        &self,
        alone: &Alone,
        towards: Vec3,
        visible: impl Fn(usize) -> f32,
    ) -> [f32; MAX_BANDS] {
        let bands = alone.bands();
        let mut sum = [0.0f64; MAX_BANDS];
        for p in 0..alone.polygons.len() {
            let cos = alone.normals[p].dot(towards).abs();
            if cos == 0.0 {
                continue;
            }
            let v = visible(p);
            if v == 0.0 {
                continue;
            }
            let mut l = [0.0f32; MAX_BANDS];
            self.radiance(alone, p as u32, towards, &mut l);
            let w = (alone.areas[p] * cos * v) as f64;
            for (s, x) in sum.iter_mut().zip(&l).take(bands) {
                *s += w * *x as f64;
            }
        }
        let mut out = [0.0f32; MAX_BANDS];
        for (o, s) in out.iter_mut().zip(&sum) {
            *o = *s as f32;
        }
        out
    }

    /// The radiance (W/m^2/sr) polygon `poly` sends towards the unit `towards` from the side
    /// facing it, into the first bands of `out`.
    pub fn radiance(&self, alone: &Alone, poly: u32, towards: Vec3, out: &mut [f32; MAX_BANDS]) {
        let p = poly as usize;
        let side = if alone.normals[p].dot(towards) >= 0.0 {
            0
        } else {
            1
        };
        if side == 1 && !self.table.two_sided {
            return;
        }
        for (o, b) in out.iter_mut().zip(self.table.radiosity(p, side)) {
            *o = b / std::f32::consts::PI;
        }
    }
}

/// The material of every polygon of the expanded scene, in global-id order.
fn polygon_materials(scene: &Scene) -> Vec<u32> {
    struct Collect(Vec<u32>);
    impl crate::scene::ExpandVisitor for Collect {
        type Error = std::convert::Infallible;
        fn node(&mut self, n: &crate::scene::ExpandedNode<'_>) -> Result<(), Self::Error> {
            self.0.extend(n.cluster.polygons.iter().map(|p| p.material));
            Ok(())
        }
    }
    let mut c = Collect(Vec::new());
    let _ = scene::expand(scene, &mut c);
    c.0
}

/// The unit front normal of a polygon (counter-clockwise corners seen from the front).
fn normal(c: &[Vec3]) -> Vec3 {
    let n = if c.len() == 4 {
        (c[2] - c[0]).cross(c[3] - c[1])
    } else {
        (c[1] - c[0]).cross(c[2] - c[0])
    };
    n.normalize_or_zero()
}
