//! The depth-first expansion of a scene: every instance replaced by its geometry, in global-id
//! order (a node's own polygons, then its children in order). Streams: one node at a time is
//! handed to the visitor, the expanded scene is never held.

use super::{Cluster, Scene};
use hirad_core::geometry::Similarity;

/// A node of the expanded scene, as handed to an [`ExpandVisitor`].
pub struct ExpandedNode<'a> {
    /// The stored cluster whose own polygons and vertices this is.
    pub cluster: &'a Cluster,
    /// Maps the cluster's vertices to scene (world) coordinates.
    pub to_world: Similarity,
    /// Global id of the cluster's first own polygon; the others follow in order.
    pub first_id: u64,
    /// Nesting depth in the expanded hierarchy (scene root = 0).
    pub depth: usize,
    /// Names along the path from the scene root (unnamed nodes appear as `#index`); the
    /// name of an exact instance stands for the original's root it expands into.
    pub path: &'a [String],
}

/// Receives the expanded scene one node at a time, in global-id order.
pub trait ExpandVisitor {
    /// The error that stops the walk.
    type Error;
    /// Called for every node of the expansion, parents before children.
    fn node(&mut self, node: &ExpandedNode<'_>) -> Result<(), Self::Error>;
}

struct Level<'a> {
    cluster: &'a Cluster,
    to_world: Similarity,
    next_child: usize,
}

/// Walks the expansion of `scene` in global-id order.
pub fn expand<V: ExpandVisitor>(scene: &Scene, visitor: &mut V) -> Result<u64, V::Error> {
    let mut next_id = 0u64;
    let mut path: Vec<String> = vec!["scene".to_string()];
    let mut stack: Vec<Level<'_>> = Vec::new();
    enter(
        scene,
        &scene.root,
        Similarity::IDENTITY,
        &mut stack,
        &mut path,
        &mut next_id,
        visitor,
    )?;
    while let Some(top) = stack.last_mut() {
        if let Some(child) = top.cluster.children.get(top.next_child) {
            let index = top.next_child;
            top.next_child += 1;
            let to_world = top.to_world;
            path.push(label(child, index));
            enter(
                scene,
                child,
                to_world,
                &mut stack,
                &mut path,
                &mut next_id,
                visitor,
            )?;
        } else {
            stack.pop();
            path.pop();
        }
    }
    Ok(next_id)
}

fn label(c: &Cluster, index: usize) -> String {
    c.name.clone().unwrap_or_else(|| format!("#{index}"))
}

/// Visits `c` (placed by `parent_to_world`) and pushes the level whose children come next.
/// An exact instance enters its original's root in its place.
fn enter<'a, V: ExpandVisitor>(
    scene: &'a Scene,
    c: &'a Cluster,
    parent_to_world: Similarity,
    stack: &mut Vec<Level<'a>>,
    path: &mut [String],
    next_id: &mut u64,
    visitor: &mut V,
) -> Result<(), V::Error> {
    let (node, to_world) = match &c.instance {
        None => (c, parent_to_world),
        Some(i) => {
            let to_world = parent_to_world.compose(&i.transform);
            match (i.exact, scene.originals.get(i.original)) {
                (true, Some(o)) => (&o.root, to_world),
                _ => (c, to_world),
            }
        }
    };
    visitor.node(&ExpandedNode {
        cluster: node,
        to_world,
        first_id: *next_id,
        depth: stack.len(),
        path,
    })?;
    *next_id += node.polygons.len() as u64;
    stack.push(Level {
        cluster: node,
        to_world,
        next_child: 0,
    });
    Ok(())
}
