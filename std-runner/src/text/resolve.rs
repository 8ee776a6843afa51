//! After parsing: names to indices, cycles of originals, instancing depth and expanded
//! polygon counts, each refused at the `instance` that causes it. Every walk is iterative.

use super::TextError;
use super::lexer::Pos;
use super::parser::{Parser, TreeInfo};
use crate::scene::{Cluster, Scene};
use hirad_core::limits::{MAX_INSTANCING_DEPTH, NONE};

/// Turns a parsed document into a checked scene.
pub(crate) fn finish(p: Parser<'_>) -> Result<Scene, TextError> {
    let Parser {
        mut scene,
        materials,
        originals,
        mut original_trees,
        mut scene_tree,
        ..
    } = p;
    let (material_of, original_of) = match (materials.resolve(), originals.resolve()) {
        (Ok(m), Ok(o)) => (m, o),
        (Err(a), Err(b)) => {
            return Err(if (a.line, a.column) <= (b.line, b.column) {
                a
            } else {
                b
            });
        }
        (Err(e), _) | (_, Err(e)) => return Err(e),
    };
    let trees = scene
        .originals
        .iter_mut()
        .map(|o| &mut o.root)
        .chain(std::iter::once(&mut scene.root));
    for root in trees {
        remap(root, &material_of, &original_of);
    }
    for tree in original_trees
        .iter_mut()
        .chain(std::iter::once(&mut scene_tree))
    {
        for e in &mut tree.entries {
            e.target = original_of.get(e.target).copied().unwrap_or(usize::MAX);
        }
    }
    let order = dependency_order(&scene, &original_trees)?;
    let mut summaries = vec![Summary::default(); original_trees.len()];
    for &k in &order {
        if let Some(tree) = original_trees.get(k) {
            let s = summarise(tree, &summaries)?;
            if let Some(slot) = summaries.get_mut(k) {
                *slot = s;
            }
        }
    }
    summarise(&scene_tree, &summaries)?;
    // Every rule was checked above with a position; this is a safety net.
    scene
        .check()
        .map_err(|e| Pos::START.error(format!("internal check failed: {e}")))?;
    Ok(scene)
}

/// Replaces provisional material and original ids by indices, in every node of a tree.
fn remap(root: &mut Cluster, material_of: &[usize], original_of: &[usize]) {
    let mut stack = vec![root];
    while let Some(node) = stack.pop() {
        for p in &mut node.polygons {
            p.material = material_of
                .get(p.material as usize)
                .and_then(|&m| u32::try_from(m).ok())
                .unwrap_or(NONE);
        }
        if let Some(i) = &mut node.instance {
            i.original = original_of.get(i.original).copied().unwrap_or(usize::MAX);
        }
        stack.extend(node.children.iter_mut());
    }
}

/// Originals in an order where each comes after every original it instances; refuses a
/// cycle at the instance that closes it (the first met in document order).
fn dependency_order(scene: &Scene, trees: &[TreeInfo]) -> Result<Vec<usize>, TextError> {
    let name = |k: usize| scene.originals.get(k).map_or("?", |o| o.name.as_str());
    // 0 = not visited, 1 = on the current path, 2 = done.
    let mut state = vec![0u8; trees.len()];
    let mut order = Vec::with_capacity(trees.len());
    for start in 0..trees.len() {
        if state.get(start) != Some(&0) {
            continue;
        }
        let mut path: Vec<(usize, usize)> = vec![(start, 0)];
        if let Some(s) = state.get_mut(start) {
            *s = 1;
        }
        while let Some(&mut (node, ref mut next)) = path.last_mut() {
            let entry = trees.get(node).and_then(|t| t.entries.get(*next)).copied();
            let Some(entry) = entry else {
                if let Some(s) = state.get_mut(node) {
                    *s = 2;
                }
                order.push(node);
                path.pop();
                continue;
            };
            *next += 1;
            match state.get(entry.target) {
                Some(0) => {
                    if let Some(s) = state.get_mut(entry.target) {
                        *s = 1;
                    }
                    path.push((entry.target, 0));
                }
                Some(1) => {
                    let from = path
                        .iter()
                        .position(|&(k, _)| k == entry.target)
                        .unwrap_or(0);
                    let mut names: Vec<&str> =
                        path.iter().skip(from).map(|&(k, _)| name(k)).collect();
                    names.push(name(entry.target));
                    return Err(entry.pos.error(format!(
                        "this instance closes a cycle of originals: {} (an original cannot contain itself)",
                        names.join(" -> ")
                    )));
                }
                _ => {}
            }
        }
    }
    Ok(order)
}

/// What an original stands for once expanded.
#[derive(Clone, Copy, Debug, Default)]
struct Summary {
    depth: u32,
    expanded: u64,
}

/// Instancing depth and expanded polygons of one tree, given the summaries of the originals
/// it instances; refuses too deep instancing and counts beyond `u64` at the guilty instance.
fn summarise(tree: &TreeInfo, done: &[Summary]) -> Result<Summary, TextError> {
    let n = tree.entries.len();
    // Deepest instancing below each entry (from its approximate body); parents come before
    // their children, so a reverse pass sees children first.
    let mut below = vec![0u32; n];
    let mut depth = vec![0u32; n];
    for i in (0..n).rev() {
        let Some(e) = tree.entries.get(i) else {
            continue;
        };
        let inner = if e.exact {
            done.get(e.target).map_or(0, |s| s.depth)
        } else {
            below.get(i).copied().unwrap_or(0)
        };
        let d = inner.saturating_add(1);
        if let Some(slot) = depth.get_mut(i) {
            *slot = d;
        }
        if let Some(b) = e.parent.and_then(|p| below.get_mut(p)) {
            *b = (*b).max(d);
        }
    }
    let mut total = Summary {
        depth: 0,
        expanded: tree.polygons,
    };
    for (e, &d) in tree.entries.iter().zip(&depth) {
        if d == MAX_INSTANCING_DEPTH + 1 {
            return Err(e.pos.error(format!(
                "instances are nested deeper than {MAX_INSTANCING_DEPTH} levels through this one"
            )));
        }
        if e.parent.is_none() {
            total.depth = total.depth.max(d);
        }
        if e.exact {
            let add = done.get(e.target).map_or(0, |s| s.expanded);
            total.expanded = total.expanded.checked_add(add).ok_or_else(|| {
                e.pos
                    .error("with this instance the tree expands to more than 2^64 polygons")
            })?;
        }
    }
    Ok(total)
}
