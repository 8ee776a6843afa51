//! Bodies `{ ... }` of the scene, originals, clusters and approximate instances: vertices,
//! polygons (checked when the body closes, so that indices may refer forward) and nested
//! clusters and instances. Recursion is bounded by `MAX_NODE_DEPTH`, checked before descending.

use super::TextError;
use super::cursor::to_u32;
use super::lexer::{Pos, Tok};
use super::parser::{Entry, Parser};
use crate::scene::{Cluster, InstanceOf, Polygon, too_small_message};
use glam::Vec3;
use hirad_core::geometry::{ShapeError, polygon_shape};
use hirad_core::limits::{MAX_NODE_DEPTH, NONE};

/// A polygon whose indices and shape are checked when its body closes.
struct Pending {
    /// Index in the node's polygons.
    index: usize,
    /// The `tri` / `quad` keyword.
    at: Pos,
    /// Where each corner was written.
    corner_at: [Pos; 4],
}

impl Parser<'_> {
    /// Reads the items of a body whose `{` (at `open`) was just consumed, into `node` at
    /// nesting level `depth`; `parent` is the nearest enclosing instance of this tree.
    pub fn body(
        &mut self,
        node: &mut Cluster,
        open: Pos,
        depth: usize,
        parent: Option<usize>,
    ) -> Result<(), TextError> {
        let mut pending = Vec::new();
        loop {
            let t = self.cur.next()?;
            let word = match &t.tok {
                Tok::Close => break,
                Tok::End => {
                    return Err(open.error(
                        "this '{' is never closed: expected '}' before the end of the input",
                    ));
                }
                Tok::Word(w) => w.as_str(),
                _ => "",
            };
            match word {
                "v" => {
                    let p = self.vec3("v", t.pos, "(x y z)")?;
                    node.vertices.push(p);
                }
                "tri" => pending.push(self.polygon(node, t.pos, 3)?),
                "quad" => pending.push(self.polygon(node, t.pos, 4)?),
                "cluster" => self.cluster(node, t.pos, depth, parent)?,
                "instance" => self.instance(node, t.pos, depth, parent)?,
                _ => {
                    return Err(t.pos.error(format!(
                        "expected v, tri, quad, cluster, instance or '}}' (to close the '{{' at line {}, column {}), found {}",
                        open.line,
                        open.column,
                        t.describe()
                    )));
                }
            }
        }
        check_polygons(node, &pending)?;
        self.tree.polygons = self
            .tree
            .polygons
            .saturating_add(node.polygons.len() as u64);
        Ok(())
    }

    /// `tri MAT I J K`, `tri MAT` + 9 numbers, `quad MAT I J K L`, `quad MAT` + 12 numbers.
    fn polygon(&mut self, node: &mut Cluster, at: Pos, n: usize) -> Result<Pending, TextError> {
        let kw = if n == 3 { "tri" } else { "quad" };
        let (material, mat_at) = self.cur.name("material name")?;
        let id = self.materials.use_name(&material, mat_at);
        let raw = self.cur.raw_numbers()?;
        let mut corners = [NONE; 4];
        let mut corner_at = [at; 4];
        if raw.len() == n {
            for (k, (text, p)) in raw.iter().enumerate().take(4) {
                corners[k] = to_u32(text, *p, "a vertex index")?;
                corner_at[k] = *p;
            }
        } else if raw.len() == 3 * n {
            let mut coords = Vec::with_capacity(3 * n);
            for (text, p) in &raw {
                coords.push(super::cursor::to_f32(text, *p)?);
            }
            for (k, xyz) in coords.chunks_exact(3).enumerate().take(4) {
                corners[k] = u32::try_from(node.vertices.len()).unwrap_or(NONE);
                corner_at[k] = raw.get(3 * k).map_or(at, |r| r.1);
                node.vertices.push(Vec3::from_slice(xyz));
            }
        } else {
            return Err(at.error(format!(
                "expected {n} vertex indices or {} corner coordinates after '{kw} {}', found {} number{}",
                3 * n,
                super::names::spell(&material),
                raw.len(),
                if raw.len() == 1 { "" } else { "s" }
            )));
        }
        node.polygons.push(Polygon {
            corners,
            material: u32::try_from(id).unwrap_or(NONE),
        });
        Ok(Pending {
            index: node.polygons.len() - 1,
            at,
            corner_at,
        })
    }

    /// Refuses a child at `at` below a node at level `depth` if it would be too deep.
    fn nesting(at: Pos, depth: usize) -> Result<(), TextError> {
        if depth >= MAX_NODE_DEPTH {
            return Err(at.error(format!(
                "clusters and instances are nested deeper than {MAX_NODE_DEPTH} levels here (the body of the scene or of an original is level 1)"
            )));
        }
        Ok(())
    }

    /// `cluster [NAME] [axis N] [age A] { BODY }`.
    fn cluster(
        &mut self,
        parent_node: &mut Cluster,
        at: Pos,
        depth: usize,
        parent: Option<usize>,
    ) -> Result<(), TextError> {
        Self::nesting(at, depth)?;
        let mut c = Cluster::default();
        if self.cur.at_name()? {
            c.name = Some(self.cur.name("cluster name")?.0);
        }
        self.cluster_attributes(&mut c, &["axis", "age"])?;
        let open = self.cur.open("to open the body of the cluster")?;
        self.body(&mut c, open, depth + 1, parent)?;
        parent_node.children.push(c);
        Ok(())
    }

    /// `instance ORIGINAL exact [ATTR...]` or `instance ORIGINAL approx [ATTR...] { BODY }`.
    fn instance(
        &mut self,
        parent_node: &mut Cluster,
        at: Pos,
        depth: usize,
        parent: Option<usize>,
    ) -> Result<(), TextError> {
        Self::nesting(at, depth)?;
        let (original, orig_at) = self.cur.name("original name")?;
        let target = self.originals.use_name(&original, orig_at);
        let spelled = super::names::spell(&original);
        let t = self.cur.next()?;
        let exact = if t.is_word("exact") {
            true
        } else if t.is_word("approx") {
            false
        } else {
            return Err(t.pos.error(format!(
                "expected 'exact' or 'approx' after 'instance {spelled}', found {}",
                t.describe()
            )));
        };
        let mut c = Cluster::default();
        let placement = self.attributes(
            &mut c,
            &[
                "name",
                "axis",
                "age",
                "translate",
                "rotate",
                "quat",
                "scale",
            ],
        )?;
        let transform = placement.similarity(at)?;
        let entry = self.tree.entries.len();
        self.tree.entries.push(Entry {
            pos: at,
            target,
            exact,
            parent,
        });
        if exact {
            let next = self.cur.peek()?;
            if next.tok == Tok::Open {
                return Err(next.pos.error(format!(
                    "an exact instance uses the geometry of original '{original}' and cannot have a body; write 'approx' to give it geometry of its own"
                )));
            }
        } else {
            let open = self.cur.open(&format!(
                "to open the body of the approximate instance of '{original}' (its own geometry; write 'exact' to use the original's)"
            ))?;
            self.body(&mut c, open, depth + 1, Some(entry))?;
        }
        c.instance = Some(InstanceOf {
            original: target,
            exact,
            transform,
        });
        parent_node.children.push(c);
        Ok(())
    }
}

/// Checks the indices and shapes of the polygons read in one body.
fn check_polygons(node: &Cluster, pending: &[Pending]) -> Result<(), TextError> {
    for p in pending {
        let Some(poly) = node.polygons.get(p.index) else {
            continue;
        };
        let n = poly.corner_count();
        let mut pts = [Vec3::ZERO; 4];
        for ((pt, &i), at) in pts.iter_mut().zip(&poly.corners).zip(&p.corner_at).take(n) {
            match node.vertices.get(i as usize) {
                Some(v) => *pt = *v,
                None => {
                    let count = node.vertices.len();
                    let range = match count {
                        0 => "this body has no vertices".to_string(),
                        1 => "this body has 1 vertex, index 0".to_string(),
                        _ => format!("this body has {count} vertices, 0 to {}", count - 1),
                    };
                    return Err(at.error(format!(
                        "vertex index {i} is out of range: {range} (indices count the 'v' lines and inline corners of the same body)"
                    )));
                }
            }
        }
        if let Err(e) = polygon_shape(&pts[..n]) {
            let what = if n == 3 { "triangle" } else { "quad" };
            let message = match e {
                ShapeError::Degenerate => {
                    format!("this {what} has no area (repeated or collinear corners)")
                }
                ShapeError::TooSmall => too_small_message(&format!("this {what}"), &pts[..n]),
                ShapeError::NonPlanar => {
                    "this quad is not planar; split it into two triangles".to_string()
                }
                ShapeError::NonConvex => {
                    "this quad is not strictly convex (a dart, a bow-tie or a straight corner); split it into two triangles".to_string()
                }
                ShapeError::NonFinite | ShapeError::TooLarge => format!(
                    "this {what} is too large: computing its area overflows 32-bit floats"
                ),
            };
            return Err(p.at.error(message));
        }
    }
    Ok(())
}
