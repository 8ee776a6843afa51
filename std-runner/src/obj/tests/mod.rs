//! Unit tests of the OBJ/MTL reader and writer, one file per part: lexing and numbers, face
//! splitting, statements and errors, the writer. Shared helpers live here.

mod export;
mod lexing;
mod reading;
mod split;

use super::lex::{Lexer, Line, Pos};
use super::number::{parse_f32, resolve_index};
use super::split::{Piece, split};
use super::*;
use crate::scene::{Cluster, InstanceOf, Material, MaterialData, Similarity, Up, quad, triangle};
use glam::{Quat, Vec3};
use hirad_core::geometry::polygon_shape;
use proptest::prelude::*;

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// Imports `obj` with the MTL files `mtls` (name, text).
fn import_with(obj: &str, mtls: &[(&str, &str)]) -> Result<ObjImport, ObjError> {
    let mut load = |name: &str| -> Result<Vec<u8>, String> {
        mtls.iter()
            .find(|(n, _)| *n == name)
            .map(|(_, t)| t.as_bytes().to_vec())
            .ok_or_else(|| "no such file".to_string())
    };
    import(obj.as_bytes(), &mut load)
}

fn import_str(obj: &str) -> Result<ObjImport, ObjError> {
    import_with(obj, &[])
}

/// The error of an import that must fail, as `(file, line, column)`, and its message.
fn fails(obj: &str, mtls: &[(&str, &str)]) -> ((String, u32, u32), String) {
    match import_with(obj, mtls) {
        Ok(_) => panic!("import of {obj:?} should fail"),
        Err(e) => ((e.file, e.line, e.column), e.message),
    }
}

fn lines(src: &str) -> Vec<Vec<(String, u32, u32)>> {
    let mut lexer = Lexer::new(src.as_bytes());
    let mut line = Line::default();
    let mut out = Vec::new();
    while lexer.next_line(&mut line) {
        out.push(
            (0..line.len())
                .map(|i| {
                    let Pos { line: l, col } = line.pos(i);
                    (line.tok(i).to_string(), l, col)
                })
                .collect(),
        );
    }
    out
}

fn t(s: &str, line: u32, col: u32) -> (String, u32, u32) {
    (s.to_string(), line, col)
}
