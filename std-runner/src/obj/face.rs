//! The corners of an `f` statement: `v`, `v/vt`, `v//vn` or `v/vt/vn`, each index positive
//! (from the first element) or negative (back from the last one defined so far). Texture and
//! normal indices are validated and dropped.

use super::ObjError;
use super::diag::error;
use super::lex::Line;
use super::number::resolve_index;

/// How many elements of each kind are defined so far.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Defined {
    /// `v` statements.
    pub vertices: usize,
    /// `vt` statements.
    pub texcoords: usize,
    /// `vn` statements.
    pub normals: usize,
}

/// Reads the corners of the face on `line` (tokens after the keyword) into `out` as 0-based
/// vertex indices.
pub(crate) fn read_corners(
    line: &Line,
    defined: Defined,
    out: &mut Vec<usize>,
) -> Result<(), ObjError> {
    out.clear();
    for t in 1..line.len() {
        let tok = line.tok(t);
        let parts = tok.split('/').count();
        let mut offset = 0usize;
        for (k, part) in tok.split('/').enumerate() {
            let at = line.pos_in(t, offset);
            let parts_after = parts - k - 1;
            match k {
                0 => {
                    let v = resolve_index(part, "vertex", defined.vertices)
                        .map_err(|m| error("", at, m))?;
                    out.push(v);
                }
                1 => {
                    // Empty only in the `v//vn` form.
                    if !part.is_empty() || parts_after == 0 {
                        resolve_index(part, "texture coordinate", defined.texcoords)
                            .map_err(|m| error("", at, m))?;
                    }
                }
                2 => {
                    resolve_index(part, "normal", defined.normals).map_err(|m| error("", at, m))?;
                }
                _ => {
                    return Err(error(
                        "",
                        line.pos_in(t, offset.saturating_sub(1)),
                        format!("'{tok}': a face corner is v, v/vt, v//vn or v/vt/vn"),
                    ));
                }
            }
            offset += part.chars().count() + 1;
        }
    }
    Ok(())
}
