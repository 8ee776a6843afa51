//! Document-level statements: `hirad`, `bands`, `material`, `camera`, `sun`, `sky`,
//! `original` and `scene`. Bodies are read by `body.rs`; names are resolved by `resolve.rs`.

use super::TextError;
use super::cursor::Cursor;
use super::lexer::{Pos, Tok};
use super::symbols::Symbols;
use super::units::unit_direction;
use crate::scene::{Camera, Cluster, LightData, Material, MaterialData, Original, Scene};
use glam::{Vec3, Vec4};
use hirad_core::geometry::camera_ok;
use hirad_core::limits::MAX_BANDS;
use hirad_core::material::MaterialError;

/// An instance met while parsing a tree, kept for the checks that need every original.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Entry {
    /// The `instance` keyword.
    pub pos: Pos,
    /// The original: a provisional id until resolved, then an index into the originals.
    pub target: usize,
    /// Exact or approximate.
    pub exact: bool,
    /// The nearest enclosing instance in the same tree (an index into the tree's entries).
    pub parent: Option<usize>,
}

/// What the later checks need to know about one tree (an original or the scene).
#[derive(Clone, Debug, Default)]
pub(crate) struct TreeInfo {
    /// Instances in document order (parents before their children).
    pub entries: Vec<Entry>,
    /// Polygons stored in the tree itself.
    pub polygons: u64,
}

/// The state of one parse.
pub(crate) struct Parser<'a> {
    /// Tokens.
    pub cur: Cursor<'a>,
    /// The scene built so far (materials and originals referenced by provisional ids).
    pub scene: Scene,
    /// Set by the `bands` statement.
    pub bands: Option<u8>,
    /// Material names.
    pub materials: Symbols,
    /// Original names.
    pub originals: Symbols,
    /// One per original, in definition order.
    pub original_trees: Vec<TreeInfo>,
    /// The scene's tree.
    pub scene_tree: TreeInfo,
    /// The tree being read.
    pub tree: TreeInfo,
    scene_seen: Option<Pos>,
}

/// The only format version this reader knows (`hirad 1`).
const VERSION: u32 = 1;

impl<'a> Parser<'a> {
    /// A parser over `src`.
    pub fn new(src: &'a [u8]) -> Result<Self, TextError> {
        Ok(Parser {
            cur: Cursor::new(src)?,
            scene: Scene::new(1),
            bands: None,
            materials: Symbols::new("material"),
            originals: Symbols::new("original"),
            original_trees: Vec::new(),
            scene_tree: TreeInfo::default(),
            tree: TreeInfo::default(),
            scene_seen: None,
        })
    }

    /// Reads the whole document (names not yet resolved).
    pub fn document(&mut self) -> Result<(), TextError> {
        self.header()?;
        loop {
            let t = self.cur.next()?;
            let kw = match &t.tok {
                Tok::End => break,
                Tok::Word(w) => w.as_str(),
                _ => "",
            };
            match kw {
                "bands" => self.bands_statement(t.pos)?,
                "material" => self.material(t.pos)?,
                "camera" => self.camera(t.pos)?,
                "sun" | "sky" => self.light(kw == "sun", t.pos)?,
                "original" => self.original()?,
                "scene" => self.scene_statement(t.pos)?,
                "hirad" => return Err(t.pos.error("'hirad' may only appear once, first")),
                _ => {
                    return Err(t.pos.error(format!(
                        "expected a statement (bands, material, camera, sun, sky, original or scene), found {}",
                        t.describe()
                    )));
                }
            }
        }
        let end = self.cur.peek()?.pos;
        if self.bands.is_none() {
            return Err(end.error("the file has no 'bands' statement (e.g. 'bands 3')"));
        }
        if self.scene_seen.is_none() {
            return Err(end.error("the file has no 'scene { ... }' statement"));
        }
        Ok(())
    }

    /// `hirad 1`.
    fn header(&mut self) -> Result<(), TextError> {
        let t = self.cur.next()?;
        if !t.is_word("hirad") {
            return Err(t.pos.error(format!(
                "a .hir file starts with 'hirad {VERSION}', found {}",
                t.describe()
            )));
        }
        let (v, at) = self.cur.integer("hirad", "the format version")?;
        if v != VERSION {
            return Err(at.error(format!(
                "format version {v} is not supported: this reader knows version {VERSION}"
            )));
        }
        Ok(())
    }

    /// The scene's band count, or an error at `at` if `bands` has not been given yet.
    pub fn band_count(&self, at: Pos, what: &str) -> Result<usize, TextError> {
        match self.bands {
            Some(b) => Ok(b as usize),
            None => Err(at.error(format!(
                "'bands' must come before the first {what} (e.g. 'bands 3' after 'hirad 1')"
            ))),
        }
    }

    /// `bands N` or `bands NAME...`.
    fn bands_statement(&mut self, at: Pos) -> Result<(), TextError> {
        if self.bands.is_some() {
            return Err(at.error("'bands' may only be given once"));
        }
        let count = if matches!(self.cur.peek()?.tok, Tok::Num(_)) {
            let (n, npos) = self.cur.integer("bands", "the number of bands")?;
            if n == 0 || n as usize > MAX_BANDS {
                return Err(npos.error(format!("{n} bands: a scene has 1 to {MAX_BANDS} bands")));
            }
            n as usize
        } else {
            let mut names = Vec::new();
            while self.cur.at_name()? {
                let (name, npos) = self.cur.name("band name")?;
                if names.len() == MAX_BANDS {
                    return Err(npos.error(format!(
                        "too many band names: a scene has 1 to {MAX_BANDS} bands"
                    )));
                }
                names.push(name);
            }
            if names.is_empty() {
                let t = self.cur.peek()?;
                return Err(t.pos.error(format!(
                    "expected the number of bands or their names after 'bands', found {}",
                    t.describe()
                )));
            }
            let n = names.len();
            self.scene.band_names = names;
            n
        };
        self.bands = Some(count as u8);
        self.scene.bands = count as u8;
        Ok(())
    }

    /// `material NAME rho V... [emit V...] [back_rho V...] [tau V...] [back_emit V...]`.
    fn material(&mut self, at: Pos) -> Result<(), TextError> {
        let n = self.band_count(at, "material")?;
        let (name, npos) = self.cur.name("material name")?;
        self.materials
            .define(&name, npos, self.scene.materials.len())?;
        const FIELDS: [&str; 5] = ["rho", "emit", "back_rho", "tau", "back_emit"];
        let mut values: [Option<Vec<(f32, Pos)>>; 5] = Default::default();
        loop {
            let t = self.cur.peek()?;
            let Some(k) = FIELDS.iter().position(|f| t.is_word(f)) else {
                break;
            };
            let kpos = self.cur.next()?.pos;
            let Some(slot) = values.get_mut(k) else {
                break;
            };
            if slot.is_some() {
                return Err(kpos.error(format!(
                    "'{}' is given twice for material '{name}'",
                    FIELDS[k]
                )));
            }
            let detail = format!("(the scene has {n} band{})", if n == 1 { "" } else { "s" });
            *slot = Some(self.cur.numbers(FIELDS[k], kpos, n, &detail)?);
        }
        let [rho, emit, back_rho, tau, back_emit] = values;
        let Some(rho) = rho else {
            return Err(at.error(format!(
                "material '{name}' needs 'rho' followed by {n} reflectance value{}",
                if n == 1 { "" } else { "s" }
            )));
        };
        let mut data = MaterialData::black(n as u8);
        data.two_sided = back_rho.is_some() || tau.is_some() || back_emit.is_some();
        // Two-sided without 'back_rho': the back reflects like the front.
        let back_rho = match back_rho {
            Some(v) => v,
            None if data.two_sided => rho.clone(),
            None => Vec::new(),
        };
        let [emit, tau, back_emit] = [emit, tau, back_emit].map(Option::unwrap_or_default);
        let (rho_v, emit_v, back_rho_v, tau_v, back_emit_v) = (
            rho.as_slice(),
            emit.as_slice(),
            back_rho.as_slice(),
            tau.as_slice(),
            back_emit.as_slice(),
        );
        for (dst, src) in [
            (&mut data.rho_front, rho_v),
            (&mut data.emit_front, emit_v),
            (&mut data.rho_back, back_rho_v),
            (&mut data.tau, tau_v),
            (&mut data.emit_back, back_emit_v),
        ] {
            for (d, (v, _)) in dst.iter_mut().zip(src) {
                *d = *v;
            }
        }
        if let Err(e) = data.check() {
            let fields = [rho_v, emit_v, back_rho_v, tau_v, back_emit_v];
            let pos = material_error_pos(e, &fields).unwrap_or(at);
            return Err(pos.error(format!("material '{name}': {e}")));
        }
        self.scene.materials.push(Material { name, data });
        Ok(())
    }

    /// `camera [NAME] pos X Y Z target X Y Z up X Y Z fovy DEG` (attributes in any order).
    fn camera(&mut self, at: Pos) -> Result<(), TextError> {
        let name = if self.cur.at_name()? {
            Some(self.cur.name("camera name")?.0)
        } else {
            None
        };
        const FIELDS: [(&str, usize, &str); 4] = [
            ("pos", 3, "(x y z of the eye)"),
            ("target", 3, "(x y z of the point looked at)"),
            ("up", 3, "(x y z of the up direction)"),
            ("fovy", 1, "(vertical field of view in degrees)"),
        ];
        let mut values: [Option<Vec<f32>>; 4] = Default::default();
        loop {
            let t = self.cur.peek()?;
            let Some(k) = FIELDS.iter().position(|f| t.is_word(f.0)) else {
                break;
            };
            let kpos = self.cur.next()?.pos;
            let (kw, n, detail) = FIELDS[k];
            let Some(slot) = values.get_mut(k) else {
                break;
            };
            if slot.is_some() {
                return Err(kpos.error(format!("'{kw}' is given twice for this camera")));
            }
            let v = self.cur.numbers(kw, kpos, n, detail)?;
            *slot = Some(v.into_iter().map(|x| x.0).collect());
        }
        let mut got = [Vec3::ZERO; 4];
        for (k, v) in values.iter().enumerate() {
            let Some(v) = v else {
                let t = self.cur.peek()?;
                return Err(t.pos.error(format!(
                    "expected '{}' for the camera started at line {}, found {}",
                    FIELDS[k].0,
                    at.line,
                    t.describe()
                )));
            };
            got[k] = Vec3::new(
                v.first().copied().unwrap_or(0.0),
                v.get(1).copied().unwrap_or(0.0),
                v.get(2).copied().unwrap_or(0.0),
            );
        }
        let [position, target, up, fov] = got;
        let camera = Camera {
            name,
            position,
            target,
            up,
            fovy_deg: fov.x,
        };
        if !camera_ok(camera.position, camera.target, camera.up, camera.fovy_deg) {
            return Err(at.error(
                "unusable camera: the eye must be away from the target, 'up' must not point along the view, and 0 < fovy < 180",
            ));
        }
        self.scene.cameras.push(camera);
        Ok(())
    }

    /// `sun from X Y Z irradiance V...` or the same with `sky` (in any order).
    fn light(&mut self, sun: bool, at: Pos) -> Result<(), TextError> {
        let kind = if sun { "sun" } else { "sky" };
        let n = self.band_count(at, kind)?;
        let mut from: Option<Vec3> = None;
        let mut irradiance: Option<Vec<(f32, Pos)>> = None;
        loop {
            if let Some(kpos) = self.cur.eat_word("from")? {
                if from.is_some() {
                    return Err(kpos.error(format!("'from' is given twice for this {kind}")));
                }
                let d = self.vec3("from", kpos, "(x y z of the direction towards the source)")?;
                let Some(u) = unit_direction(d) else {
                    return Err(kpos.error("the direction 'from' must not be zero"));
                };
                from = Some(u);
            } else if let Some(kpos) = self.cur.eat_word("irradiance")? {
                if irradiance.is_some() {
                    return Err(kpos.error(format!("'irradiance' is given twice for this {kind}")));
                }
                let detail = format!("(the scene has {n} band{})", if n == 1 { "" } else { "s" });
                let v = self.cur.numbers("irradiance", kpos, n, &detail)?;
                if let Some((x, p)) = v.iter().find(|(x, _)| *x < 0.0) {
                    return Err(p.error(format!("irradiance must be >= 0, found {x}")));
                }
                irradiance = Some(v);
            } else {
                break;
            }
        }
        let (Some(towards), Some(irr)) = (from, irradiance) else {
            let missing = if from.is_none() { "from" } else { "irradiance" };
            let t = self.cur.peek()?;
            return Err(t.pos.error(format!(
                "expected '{missing}' for the {kind} at line {}, found {}",
                at.line,
                t.describe()
            )));
        };
        let values: Vec<f32> = irr.iter().map(|x| x.0).collect();
        let l = crate::scene::light(towards, &values);
        let list: &mut Vec<LightData> = if sun {
            &mut self.scene.suns
        } else {
            &mut self.scene.sky
        };
        list.push(l);
        Ok(())
    }

    /// `original NAME [name ROOT] [axis N] [age A] { BODY }`.
    fn original(&mut self) -> Result<(), TextError> {
        let (name, npos) = self.cur.name("original name")?;
        self.originals
            .define(&name, npos, self.scene.originals.len())?;
        let mut root = Cluster::default();
        self.cluster_attributes(&mut root, &["name", "axis", "age"])?;
        let open = self
            .cur
            .open(&format!("to open the body of original '{name}'"))?;
        self.tree = TreeInfo::default();
        self.body(&mut root, open, 1, None)?;
        self.original_trees.push(std::mem::take(&mut self.tree));
        self.scene.originals.push(Original { name, root });
        Ok(())
    }

    /// `scene [NAME] [axis N] [age A] { BODY }`.
    fn scene_statement(&mut self, at: Pos) -> Result<(), TextError> {
        if let Some(first) = self.scene_seen {
            return Err(at.error(format!(
                "'scene' may only be given once (first at line {}, column {})",
                first.line, first.column
            )));
        }
        self.scene_seen = Some(at);
        let mut root = Cluster::default();
        if self.cur.at_name()? {
            root.name = Some(self.cur.name("scene name")?.0);
        }
        self.cluster_attributes(&mut root, &["axis", "age"])?;
        let open = self.cur.open("to open the body of the scene")?;
        self.tree = TreeInfo::default();
        self.body(&mut root, open, 1, None)?;
        self.scene_tree = std::mem::take(&mut self.tree);
        self.scene.root = root;
        Ok(())
    }

    /// Reads `x y z` after a keyword as a vector.
    pub fn vec3(&mut self, kw: &str, at: Pos, detail: &str) -> Result<Vec3, TextError> {
        let v = self.cur.numbers(kw, at, 3, detail)?;
        let c = |i: usize| v.get(i).map_or(0.0, |x| x.0);
        Ok(Vec3::new(c(0), c(1), c(2)))
    }

    /// Reads `a b c d` after a keyword.
    pub fn vec4(&mut self, kw: &str, at: Pos, detail: &str) -> Result<Vec4, TextError> {
        let v = self.cur.numbers(kw, at, 4, detail)?;
        let c = |i: usize| v.get(i).map_or(0.0, |x| x.0);
        Ok(Vec4::new(c(0), c(1), c(2), c(3)))
    }
}

/// The value a material error is about: `fields` are the values after `rho`, `emit`,
/// `back_rho`, `tau` and `back_emit` (empty when absent).
fn material_error_pos(e: MaterialError, fields: &[&[(f32, Pos)]; 5]) -> Option<Pos> {
    let [rho, emit, back_rho, tau, back_emit] = *fields;
    let at = |f: &[(f32, Pos)], band: u8| f.get(band as usize).copied();
    let first_bad = |candidates: [&[(f32, Pos)]; 2], band: u8, bad: fn(f32) -> bool| {
        candidates
            .iter()
            .filter_map(|f| at(f, band))
            .find(|(v, _)| bad(*v))
            .map(|(_, p)| p)
    };
    match e {
        MaterialError::NonFinite { .. } | MaterialError::Unused | MaterialError::Bands => None,
        MaterialError::Reflectance { band } => {
            first_bad([rho, back_rho], band, |v| !(0.0..=1.0).contains(&v))
        }
        MaterialError::Transmittance { band } | MaterialError::EnergyNotConserved { band } => {
            at(tau, band).map(|(_, p)| p)
        }
        MaterialError::Emission { band } => first_bad([emit, back_emit], band, |v| v < 0.0),
    }
}
