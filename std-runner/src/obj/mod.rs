//! Wavefront OBJ + MTL: import into the scene model, and export of the expanded scene.

use crate::scene::Scene;
use std::fmt;
use std::io::{self, Write};

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
    /// Human-readable notes ("12:1: degenerate face skipped"), in file order.
    pub warnings: Vec<String>,
}

/// Imports an OBJ. `load_mtl` returns the bytes of an MTL file named in `mtllib` (resolved
/// by the caller, relative to the OBJ), or a message if it cannot be read.
pub fn import(
    obj: &[u8],
    load_mtl: &mut dyn FnMut(&str) -> Result<Vec<u8>, String>,
) -> Result<ObjImport, ObjError> {
    let _ = (obj, load_mtl);
    Err(ObjError {
        file: String::new(),
        line: 1,
        column: 1,
        message: "the OBJ importer is not written yet".into(),
    })
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
/// the OBJ names the MTL as `mtl_name` in its `mtllib` line.
pub fn export(
    scene: &Scene,
    mtl_name: &str,
    obj: &mut dyn Write,
    mtl: &mut dyn Write,
) -> io::Result<ObjExport> {
    let _ = (scene, mtl_name, obj, mtl);
    Err(io::Error::other("the OBJ exporter is not written yet"))
}
