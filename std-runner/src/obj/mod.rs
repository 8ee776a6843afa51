//! Wavefront OBJ + MTL: import into the scene model, and export of the expanded scene.
//!
//! # Import
//! The input is untrusted: every fault is an [`ObjError`] located by file, line and column
//! (1-based, in characters), and nothing is allocated from a size the file claims.
//!
//! * Statements: `v x y z [w ...]`, `vt` and `vn` (counted; their indices in faces are
//!   checked), `f` (`v`, `v/vt`, `v//vn`, `v/vt/vn`, negative indices count back from the
//!   last element), `o`, `g`, `usemtl`, `mtllib`. `s` is ignored; `l`, `p`, free-form
//!   geometry and unknown statements are ignored with one warning per kind.
//! * Faces keep their file order. Triangles stay triangles, accepted quads stay quads, other
//!   faces are split (see `split.rs`); a corner repeated at once (`f 1 2 3 3`) is dropped.
//!   Degenerate faces and parts are skipped with a warning.
//! * Clusters: faces before any `o`/`g` belong to the unnamed root; `o` starts a child of the
//!   root, `g` a child of the current `o` (or of the root); a bare `g` is the group `default`.
//!   Each cluster holds the vertices its faces use; clusters without faces are dropped.
//! * Materials: 3 bands (R, G, B). `Kd` is the front reflectance, `Ke` the emitted exitance
//!   (W/m^2), `Tf` the diffuse transmittance of a two-sided material whose back reflectance
//!   is `Kd`, except `Tf 1 1 1`, which Maya and 3ds Max write for opaque materials and is
//!   ignored with a warning. A material without `Kd` reflects 0.5. Faces before any `usemtl`
//!   use [`DEFAULT_MATERIAL`] (reflectance 0.5, unless an MTL file defines that name).
//! * `mtllib a.mtl b.mtl` reads each file once; when one of the list cannot be read, the
//!   whole rest of the line is tried as one name (names with spaces). A material defined
//!   twice keeps its first definition, with a warning.
//! * Lines end in `\n` or `\r\n`; a `\r` anywhere else is an error (classic Mac OS files
//!   would otherwise read as one line). Bytes that are not UTF-8 are replaced, with a warning.
//!
//! # Export
//! The expansion of the scene is streamed: never held in memory. Face k (1-based) is the
//! polygon of global id k-1.

mod clusters;
mod diag;
mod export;
mod face;
mod lex;
mod materials;
mod mtl;
mod mtl_write;
mod number;
mod reader;
mod split;
mod vec64;

pub use diag::MAX_WARNINGS;
pub use materials::DEFAULT_MATERIAL;
pub use mtl::DEFAULT_REFLECTANCE;
pub use split::MAX_CLIPPED_CORNERS;

use crate::scene::Scene;
use std::fmt;
use std::io::{self, Write};
use std::path::Path;

/// An import error located in the OBJ file or in one of its MTL files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjError {
    /// The file the fault is in: empty for the OBJ itself, else the MTL file name as written
    /// in `mtllib`.
    pub file: String,
    /// 1-based line.
    pub line: u32,
    /// 1-based column, in characters.
    pub column: u32,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ObjError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.file.is_empty() {
            write!(f, "{}:{}: {}", self.line, self.column, self.message)
        } else {
            write!(
                f,
                "{}:{}:{}: {}",
                self.file, self.line, self.column, self.message
            )
        }
    }
}

impl std::error::Error for ObjError {}

/// A successful import and what it had to change or ignore.
#[derive(Clone, Debug)]
pub struct ObjImport {
    /// The scene.
    pub scene: Scene,
    /// Human-readable notes ("12:1: degenerate face skipped"), in file order; at most
    /// [`MAX_WARNINGS`] and a last line counting the others.
    pub warnings: Vec<String>,
    /// Every warning made, shown in `warnings` or not.
    pub warnings_total: u64,
    /// Per polygon in global-id order, the number of the `f` statement it came from (1-based,
    /// counting every face of the file, skipped ones included, as modelling programs number
    /// them); the pieces of a split face share it.
    pub faces: Vec<u64>,
    /// What the file held.
    pub counts: ObjCounts,
}

/// Element counts of an imported OBJ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ObjCounts {
    /// `v` statements.
    pub vertices: u64,
    /// `vt` statements (not used).
    pub texture_coords: u64,
    /// `vn` statements (not used).
    pub normals: u64,
    /// `f` statements.
    pub faces: u64,
    /// Polygons of the scene (faces after splitting, without the skipped ones).
    pub polygons: u64,
    /// Faces skipped as degenerate.
    pub skipped_faces: u64,
}

/// Imports an OBJ. `load_mtl` returns the bytes of an MTL file named in `mtllib` (resolved
/// by the caller, relative to the OBJ), or a message if it cannot be read.
pub fn import(
    obj: &[u8],
    load_mtl: &mut dyn FnMut(&str) -> Result<Vec<u8>, String>,
) -> Result<ObjImport, ObjError> {
    reader::read(obj, load_mtl)
}

/// A `load_mtl` for [`import`] that reads MTL files from `dir` (the OBJ's folder). A name
/// that cannot be read there as written (an absolute path from another machine, say) is tried
/// once more by its last component, split at `/` or `\`. Only regular files are read, so an
/// OBJ naming `/dev/zero` or a pipe cannot make the import hang.
pub fn load_mtl_from(dir: &Path) -> impl FnMut(&str) -> Result<Vec<u8>, String> + '_ {
    move |name: &str| {
        let first = dir.join(name);
        match read_regular(&first) {
            Ok(bytes) => Ok(bytes),
            Err(e) => {
                let base = name.rsplit(['/', '\\']).next().unwrap_or(name);
                if base != name
                    && !base.is_empty()
                    && let Ok(bytes) = read_regular(&dir.join(base))
                {
                    return Ok(bytes);
                }
                Err(format!("{}: {e}", first.display()))
            }
        }
    }
}

/// Reads `path` if it is a regular file.
fn read_regular(path: &Path) -> io::Result<Vec<u8>> {
    let mut file = std::fs::File::open(path)?;
    if !file.metadata()?.is_file() {
        return Err(io::Error::other("not a regular file"));
    }
    let mut bytes = Vec::new();
    io::Read::read_to_end(&mut file, &mut bytes)?;
    Ok(bytes)
}

/// What an export wrote.
#[derive(Clone, Debug, Default)]
pub struct ObjExport {
    /// Faces written (one per polygon, in global-id order).
    pub faces: u64,
    /// Vertices written.
    pub vertices: u64,
    /// What could not be represented in OBJ/MTL (back reflectance, lights, extra bands...).
    pub warnings: Vec<String>,
}

/// Writes the expanded scene as OBJ (faces in global-id order) and its materials as MTL;
/// the OBJ names the MTL as `mtl_name` in its `mtllib` line. The scene's `up` axis becomes
/// +y, the OBJ convention (`Up::Y` writes the coordinates as they are). Buffers internally;
/// a scene that fails its check, or an `mtl_name` an OBJ line cannot hold, is `InvalidInput`.
pub fn export(
    scene: &Scene,
    up: crate::scene::Up,
    mtl_name: &str,
    obj: &mut dyn Write,
    mtl: &mut dyn Write,
) -> io::Result<ObjExport> {
    export::export(scene, up, mtl_name, obj, mtl)
}

#[cfg(test)]
mod tests;
