//! What a results row says about its polygon besides numbers: its material's name and its
//! group, the path of named clusters from the scene's root down to the cluster that holds it
//! (`scene/field/plant_3/leaves`; an unnamed cluster appears as `#index` among its
//! siblings; an instance's own name stands for the original it expands into), so that a
//! table can be filtered by organ or plant without flattening the scene and joining on face
//! order.
//!
//! The labels are read off the scene model as the rows go by, walking its expansion in
//! global-id order as `scene::expand` does: memory is the walk's depth, not the expanded
//! scene's polygons (a 10-million-polygon forest solved level by level held 40 MB of
//! material indices and a path per shoot before).

use crate::scene::{Cluster, Scene};
use std::sync::Arc;

/// Where a cluster of the model is: the scene's root tree or an original's, and the child
/// indices down to it.
#[derive(Clone, Debug, Default, PartialEq)]
struct At {
    original: Option<usize>,
    chain: Vec<usize>,
}

impl At {
    fn cluster<'s>(&self, scene: &'s Scene) -> Option<&'s Cluster> {
        let mut c = match self.original {
            None => &scene.root,
            Some(k) => &scene.originals.get(k)?.root,
        };
        for &i in &self.chain {
            c = c.children.get(i)?;
        }
        Some(c)
    }
}

/// A node of the walk whose children come next.
#[derive(Clone, Debug)]
struct Frame {
    at: At,
    next_child: usize,
}

/// Material and group of every polygon of an expanded scene, by global id, asked for in
/// increasing order (asking for an earlier id walks again from the start).
#[derive(Clone)]
pub struct RowLabels {
    scene: Arc<Scene>,
    /// Polygons of the expansion.
    total: u64,
    stack: Vec<Frame>,
    path: Vec<String>,
    /// The node whose polygons are `first..first + count`, and its group path.
    node: At,
    first: u64,
    count: u64,
    group: String,
    next_id: u64,
}

impl std::fmt::Debug for RowLabels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RowLabels")
            .field("polygons", &self.total)
            .field("at", &self.first)
            .finish_non_exhaustive()
    }
}

impl PartialEq for RowLabels {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.scene, &o.scene) || self.scene == o.scene
    }
}

impl RowLabels {
    /// The labels of `scene`'s expansion (a copy of the model is kept: see [`Self::shared`]).
    pub fn of(scene: &Scene) -> RowLabels {
        Self::shared(Arc::new(scene.clone()))
    }

    /// The labels of `scene`'s expansion, read off the model as rows are asked for.
    pub fn shared(scene: Arc<Scene>) -> RowLabels {
        let mut memo = vec![None; scene.originals.len()];
        let total = expanded(&scene, &scene.root, &mut memo);
        let mut r = RowLabels {
            scene,
            total,
            stack: Vec::new(),
            path: Vec::new(),
            node: At::default(),
            first: 0,
            count: 0,
            group: String::new(),
            next_id: 0,
        };
        r.restart();
        r
    }

    /// Polygons labelled.
    pub fn len(&self) -> usize {
        self.total as usize
    }

    /// True when no polygon is labelled.
    pub fn is_empty(&self) -> bool {
        self.total == 0
    }

    /// True when some polygon of the expansion has a material (by index) that satisfies
    /// `pred`.
    pub fn uses_material(&self, mut pred: impl FnMut(usize) -> bool) -> bool {
        let s = &*self.scene;
        let mut used = vec![false; s.materials.len()];
        let mut reached = vec![false; s.originals.len()];
        let mut todo: Vec<&Cluster> = vec![&s.root];
        while let Some(c) = todo.pop() {
            for p in &c.polygons {
                if let Some(u) = used.get_mut(p.material as usize) {
                    *u = true;
                }
            }
            if let Some(i) = &c.instance
                && i.exact
            {
                if let Some(false) = reached.get(i.original).copied() {
                    reached[i.original] = true;
                    todo.push(&s.originals[i.original].root);
                }
                continue;
            }
            todo.extend(c.children.iter());
        }
        used.iter().enumerate().any(|(m, &u)| u && pred(m))
    }

    /// The material name and group path of polygon `id` (`None` past the last polygon).
    pub fn label(&mut self, id: u64) -> Option<(&str, &str)> {
        if id >= self.total {
            return None;
        }
        if id < self.first {
            self.restart();
        }
        while id >= self.first + self.count {
            if !self.step() {
                return None;
            }
        }
        let s = &*self.scene;
        let p = self
            .node
            .cluster(s)?
            .polygons
            .get((id - self.first) as usize)?;
        let m = s
            .materials
            .get(p.material as usize)
            .map_or("", |m| m.name.as_str());
        Some((m, self.group.as_str()))
    }

    /// The material name of polygon `id`.
    pub fn material(&mut self, id: u64) -> Option<&str> {
        self.label(id).map(|(m, _)| m)
    }

    /// The group path of polygon `id`.
    pub fn group(&mut self, id: u64) -> Option<&str> {
        self.label(id).map(|(_, g)| g)
    }

    fn restart(&mut self) {
        self.stack.clear();
        self.path = vec!["scene".to_string()];
        self.next_id = 0;
        self.enter(At::default());
    }

    /// Enters the node at `at` (an exact instance: its original's root in its place).
    fn enter(&mut self, at: At) {
        let s = Arc::clone(&self.scene);
        let at = match at.cluster(&s).and_then(|c| c.instance.as_ref()) {
            Some(i) if i.exact && i.original < s.originals.len() => At {
                original: Some(i.original),
                chain: Vec::new(),
            },
            _ => at,
        };
        let count = at.cluster(&s).map_or(0, |c| c.polygons.len() as u64);
        self.first = self.next_id;
        self.count = count;
        self.next_id += count;
        if count > 0 {
            self.group = self.path.join("/");
        }
        self.node = at.clone();
        self.stack.push(Frame { at, next_child: 0 });
    }

    /// Moves to the next node of the expansion; false when there is none.
    fn step(&mut self) -> bool {
        let s = Arc::clone(&self.scene);
        while let Some(top) = self.stack.last_mut() {
            let Some(c) = top.at.cluster(&s) else {
                return false;
            };
            if let Some(child) = c.children.get(top.next_child) {
                let index = top.next_child;
                top.next_child += 1;
                let mut at = top.at.clone();
                at.chain.push(index);
                self.path
                    .push(child.name.clone().unwrap_or_else(|| format!("#{index}")));
                self.enter(at);
                return true;
            }
            self.stack.pop();
            self.path.pop();
        }
        false
    }
}

/// Polygons in the expansion of `c` (originals' counts kept in `memo`).
fn expanded(scene: &Scene, c: &Cluster, memo: &mut [Option<u64>]) -> u64 {
    if let Some(i) = &c.instance
        && i.exact
        && let Some(o) = scene.originals.get(i.original)
    {
        if let Some(n) = memo[i.original] {
            return n;
        }
        let n = expanded(scene, &o.root, memo);
        memo[i.original] = Some(n);
        return n;
    }
    c.polygons.len() as u64
        + c.children
            .iter()
            .map(|k| expanded(scene, k, memo))
            .sum::<u64>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{ExpandVisitor, ExpandedNode};

    /// Material and group of every polygon, from the expansion itself.
    fn expected(scene: &Scene) -> Vec<(String, String)> {
        struct Collect<'s>(&'s Scene, Vec<(String, String)>);
        impl ExpandVisitor for Collect<'_> {
            type Error = std::convert::Infallible;
            fn node(&mut self, n: &ExpandedNode<'_>) -> Result<(), Self::Error> {
                for p in &n.cluster.polygons {
                    let m = self.0.materials[p.material as usize].name.clone();
                    self.1.push((m, n.path.join("/")));
                }
                Ok(())
            }
        }
        let mut c = Collect(scene, Vec::new());
        let _ = crate::scene::expand(scene, &mut c);
        c.1
    }

    #[test]
    fn labels_follow_the_expansion_forwards_and_back() {
        // Approximate instances in approximate ones (the plant), exact ones (the room's
        // chairs, the maize plants, the leaves).
        for name in [
            "small_plant.hir",
            "chair_room.hir",
            "maize_2x2.hir",
            "leaves_cluster.hir",
            "cornell_box.hir",
        ] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../fixtures")
                .join(name);
            let scene = crate::files::load_scene(&path).unwrap().scene;
            let want = expected(&scene);
            let mut rows = RowLabels::of(&scene);
            assert_eq!(rows.len(), want.len(), "{name}");
            assert!(!rows.is_empty());
            let is = |rows: &mut RowLabels, id: usize| {
                let (m, g) = &want[id];
                assert_eq!(
                    rows.label(id as u64),
                    Some((m.as_str(), g.as_str())),
                    "{name} polygon {id}"
                );
            };
            for id in 0..want.len() {
                is(&mut rows, id);
            }
            assert_eq!(rows.label(want.len() as u64), None, "{name}");
            // Backwards (each a walk from the start) and by leaps.
            for id in (0..want.len()).rev().step_by(13) {
                is(&mut rows, id);
            }
            for id in (0..want.len()).step_by(29) {
                is(&mut rows, id);
            }
            // The materials used, as the expansion has them.
            for m in 0..scene.materials.len() {
                let used = want.iter().any(|(n, _)| *n == scene.materials[m].name);
                assert_eq!(rows.uses_material(|k| k == m), used, "{name} material {m}");
            }
        }
    }
}
