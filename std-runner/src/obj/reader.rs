//! The OBJ statements: vertices, faces, objects and groups, material libraries and
//! `usemtl`. Builds the scene as it reads; see the module documentation of `obj` for the rules.

use super::clusters::Clusters;
use super::diag::{Warnings, error};
use super::face::{Defined, read_corners};
use super::lex::{Lexer, Line, Pos};
use super::materials::Materials;
use super::mtl::{OBJ_BANDS, parse_mtl};
use super::number::parse_f32;
use super::split::{MAX_CLIPPED_CORNERS, Piece, split};
use super::{ObjCounts, ObjError, ObjImport};
use crate::scene::Scene;
use glam::Vec3;
use hirad_core::geometry::{ShapeError, below_f32_resolution, polygon_shape};
use hirad_core::limits::{MAX_NAME_BYTES, NONE};

/// Statements of free-form geometry (curves and surfaces), skipped as one kind.
const FREE_FORM: &[&str] = &[
    "vp", "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm", "trim", "hole", "scrv",
    "sp", "end", "con", "ctech", "stech",
];

/// The error for a carriage return inside a line.
pub(crate) const BARE_CR: &str =
    "carriage return inside a line: lines must end in \\n or \\r\\n (not \\r alone)";

/// Why a face of which no piece survives is skipped: too large or too small for f32 (the
/// core's rule, see [`polygon_shape`]), or degenerate.
fn skip_reason(points: &[Vec3]) -> &'static str {
    let first = points.first().copied().unwrap_or_default();
    if points.iter().any(|p| !(*p - first).is_finite()) {
        return "face too large to measure in 32-bit floats skipped";
    }
    let too_small = |p: &[Vec3]| polygon_shape(p) == Err(ShapeError::TooSmall);
    if points.len() >= 3
        && (below_f32_resolution(points)
            || too_small(points)
            || (1..points.len() - 1).any(|i| too_small(&[first, points[i], points[i + 1]])))
    {
        return "face too small for 32-bit floats at its position skipped";
    }
    "degenerate face skipped"
}

/// The state of an import in progress.
struct Reader<'a> {
    load_mtl: &'a mut dyn FnMut(&str) -> Result<Vec<u8>, String>,
    positions: Vec<Vec3>,
    defined: Defined,
    materials: Materials,
    /// Material of the next faces; `None` before any `usemtl`.
    material: Option<u32>,
    clusters: Clusters,
    warnings: Warnings,
    counts: ObjCounts,
    /// The face number of every polygon added so far (see `ObjImport::faces`).
    faces: Vec<u64>,
    corners: Vec<usize>,
    points: Vec<Vec3>,
    pieces: Vec<Piece>,
    piece_corners: Vec<usize>,
}

/// Reads a whole OBJ file.
pub(crate) fn read(
    obj: &[u8],
    load_mtl: &mut dyn FnMut(&str) -> Result<Vec<u8>, String>,
) -> Result<ObjImport, ObjError> {
    let mut r = Reader {
        load_mtl,
        positions: Vec::new(),
        defined: Defined::default(),
        materials: Materials::default(),
        material: None,
        clusters: Clusters::new(),
        warnings: Warnings::default(),
        counts: ObjCounts::default(),
        faces: Vec::new(),
        corners: Vec::new(),
        points: Vec::new(),
        pieces: Vec::new(),
        piece_corners: Vec::new(),
    };
    let mut lexer = Lexer::new(obj);
    let mut line = Line::default();
    while lexer.next_line(&mut line) {
        r.statement(&line)?;
    }
    let mut scene = Scene::new(OBJ_BANDS);
    scene.materials = r.materials.finish();
    scene.root = r.clusters.finish();
    if let Err(e) = scene.check() {
        let end = Pos {
            line: lexer.last_line().max(1),
            col: 1,
        };
        return Err(error(
            "",
            end,
            format!("internal error: the imported scene fails its check: {e}"),
        ));
    }
    Ok(ObjImport {
        scene,
        faces: std::mem::take(&mut r.faces),
        warnings_total: r.warnings.total(),
        warnings: r.warnings.finish(),
        counts: r.counts,
    })
}

/// A name made of the tokens after the keyword, or `None` when there are none.
fn name_of(line: &Line) -> Result<Option<String>, ObjError> {
    if line.len() < 2 {
        return Ok(None);
    }
    let name = line.joined(1);
    if name.len() > MAX_NAME_BYTES {
        return Err(error(
            "",
            line.pos(1),
            format!("name is longer than {MAX_NAME_BYTES} bytes"),
        ));
    }
    Ok(Some(name))
}

impl Reader<'_> {
    fn statement(&mut self, line: &Line) -> Result<(), ObjError> {
        if let Some(at) = line.bare_cr {
            return Err(error("", at, BARE_CR));
        }
        if line.invalid_utf8 {
            self.warnings.once(
                "",
                "utf8",
                line.pos(0),
                "not valid UTF-8: invalid bytes replaced by U+FFFD",
            );
        }
        let keyword = line.tok(0);
        match keyword {
            "v" => self.vertex(line),
            "vt" => {
                self.defined.texcoords += 1;
                self.counts.texture_coords += 1;
                Ok(())
            }
            "vn" => {
                self.defined.normals += 1;
                self.counts.normals += 1;
                Ok(())
            }
            "f" => self.face(line),
            "o" => {
                let name = name_of(line)?;
                self.clusters.start_object(name);
                Ok(())
            }
            "g" => {
                // A bare `g` is the OBJ "default" group.
                let name = name_of(line)?.unwrap_or_else(|| "default".to_string());
                self.clusters.start_group(Some(name));
                Ok(())
            }
            "usemtl" => self.usemtl(line),
            "mtllib" => self.mtllib(line),
            "s" => Ok(()),
            "l" => {
                self.warnings
                    .once("", "l", line.pos(0), "line elements (l) ignored");
                Ok(())
            }
            "p" => {
                self.warnings
                    .once("", "p", line.pos(0), "point elements (p) ignored");
                Ok(())
            }
            k if FREE_FORM.contains(&k) => {
                self.warnings.once(
                    "",
                    "free-form",
                    line.pos(0),
                    format!("free-form curves and surfaces ({k}, ...) ignored"),
                );
                Ok(())
            }
            k => {
                self.warnings.once(
                    "",
                    &format!("keyword {k}"),
                    line.pos(0),
                    format!("statement '{k}' ignored"),
                );
                Ok(())
            }
        }
    }

    /// `v x y z [w]`; further values (vertex colours) are ignored.
    fn vertex(&mut self, line: &Line) -> Result<(), ObjError> {
        if line.len() < 4 {
            return Err(error(
                "",
                line.end(),
                format!(
                    "v needs x y z coordinates, found {} value(s)",
                    line.len() - 1
                ),
            ));
        }
        if self.positions.len() >= NONE as usize - 1 {
            return Err(error("", line.pos(0), "too many vertices"));
        }
        let mut p = [0.0f32; 3];
        for (k, c) in p.iter_mut().enumerate() {
            *c = parse_f32(line.tok(1 + k)).map_err(|m| error("", line.pos(1 + k), m))?;
        }
        self.positions.push(Vec3::from_array(p));
        self.defined.vertices += 1;
        self.counts.vertices += 1;
        Ok(())
    }

    fn face(&mut self, line: &Line) -> Result<(), ObjError> {
        let at = line.pos(0);
        read_corners(line, self.defined, &mut self.corners)?;
        if self.corners.len() < 3 {
            return Err(error(
                "",
                at,
                format!(
                    "a face needs at least 3 corners, found {}",
                    self.corners.len()
                ),
            ));
        }
        self.counts.faces += 1;
        // A corner repeated at once (`f 1 2 3 3`) adds nothing: drop the repeat.
        self.corners.dedup();
        while self.corners.len() > 1 && self.corners.first() == self.corners.last() {
            self.corners.pop();
        }
        self.points.clear();
        self.points
            .extend(self.corners.iter().map(|&i| self.positions[i]));
        let skipped = split(&self.points, &mut self.pieces).map_err(|_| {
            error(
                "",
                at,
                format!(
                    "the face has {} corners and is not convex and planar: at most \
                     {MAX_CLIPPED_CORNERS} can be triangulated",
                    self.corners.len()
                ),
            )
        })?;
        if self.pieces.is_empty() {
            self.counts.skipped_faces += 1;
            self.warnings.add("", at, skip_reason(&self.points));
            return Ok(());
        }
        if skipped > 0 {
            self.warnings.add(
                "",
                at,
                if skipped == 1 {
                    "a degenerate part of the split face skipped".to_string()
                } else {
                    format!("{skipped} degenerate parts of the split face skipped")
                },
            );
        }
        let material = match self.material {
            Some(m) => m,
            None => self.materials.default_material(),
        };
        for piece in &self.pieces {
            self.piece_corners.clear();
            self.piece_corners
                .extend(piece.corners().iter().map(|&k| self.corners[k]));
            self.clusters
                .add(&self.positions, &self.piece_corners, material)
                .map_err(|_| error("", at, "too many polygons or vertices in one group"))?;
            self.counts.polygons += 1;
            // Clusters follow the file (every `o` and `g` starts a new one), so polygons are
            // added in global-id order.
            self.faces.push(self.counts.faces);
        }
        Ok(())
    }

    fn usemtl(&mut self, line: &Line) -> Result<(), ObjError> {
        if line.len() < 2 {
            return Err(error("", line.end(), "usemtl needs a material name"));
        }
        let name = line.joined(1);
        match self.materials.lookup(&name) {
            Some(i) => {
                self.material = Some(i);
                Ok(())
            }
            None => Err(error(
                "",
                line.pos(1),
                format!("unknown material '{name}' (no mtllib read so far defines it)"),
            )),
        }
    }

    /// `mtllib a.mtl [b.mtl ...]`: reads each file once. When a file of the list cannot be
    /// read and the whole rest of the line names a file (a name with spaces), that is used.
    fn mtllib(&mut self, line: &Line) -> Result<(), ObjError> {
        if line.len() < 2 {
            self.warnings
                .add("", line.pos(0), "mtllib without a file name ignored");
            return Ok(());
        }
        let mut loaded: Vec<(String, Vec<u8>)> = Vec::new();
        let mut failed: Option<(usize, String)> = None;
        for t in 1..line.len() {
            let name = line.tok(t);
            if self.materials.has_file(name) || loaded.iter().any(|(n, _)| n == name) {
                continue;
            }
            match (self.load_mtl)(name) {
                Ok(bytes) => loaded.push((name.to_string(), bytes)),
                Err(m) => {
                    failed = Some((t, m));
                    break;
                }
            }
        }
        if let Some((t, message)) = failed {
            let whole = line.rest(1);
            if line.len() > 2 && self.materials.has_file(whole) {
                return Ok(());
            }
            let whole_read = if line.len() > 2 {
                (self.load_mtl)(whole).ok()
            } else {
                None
            };
            match whole_read {
                Some(bytes) => loaded = vec![(whole.to_string(), bytes)],
                None => {
                    return Err(error(
                        "",
                        line.pos(t),
                        format!("cannot read material library '{}': {message}", line.tok(t)),
                    ));
                }
            }
        }
        for (name, bytes) in loaded {
            let materials = parse_mtl(&bytes, &name, &mut self.warnings)?;
            self.materials
                .add_file(&name, materials, &mut self.warnings);
        }
        Ok(())
    }
}
