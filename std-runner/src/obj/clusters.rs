//! Builds the cluster tree of an import from `o` and `g` statements.
//!
//! Faces before any `o`/`g` go to the (unnamed) root. `o` starts a child of the root, `g` a
//! child of the current `o` cluster (or of the root). Every statement starts a new cluster,
//! so the depth-first order of the tree is the order of the faces in the file. A cluster's
//! vertices are the OBJ vertices its polygons use, in first-use order. Clusters left without
//! polygons are dropped as soon as the next one starts, so memory follows the faces.

use crate::scene::{Cluster, Polygon};
use glam::Vec3;
use hirad_core::limits::NONE;
use std::collections::HashMap;

/// Where the next polygons go.
#[derive(Clone, Copy, Debug)]
enum Target {
    Root,
    /// `root.children[i]`.
    Child(usize),
    /// `root.children[i].children[j]`.
    Grandchild(usize, usize),
}

/// The tree under construction.
#[derive(Debug)]
pub(crate) struct Clusters {
    root: Cluster,
    /// Index in `root.children` of the current `o` cluster.
    object: Option<usize>,
    target: Target,
    /// OBJ vertex index -> index in the target's vertices.
    local: HashMap<usize, u32>,
}

/// The target cluster cannot take more vertices or polygons (`u32` indices).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ClusterFull;

impl Clusters {
    /// A tree with only the root.
    pub fn new() -> Self {
        Clusters {
            root: Cluster::default(),
            object: None,
            target: Target::Root,
            local: HashMap::new(),
        }
    }

    fn target_mut(&mut self) -> &mut Cluster {
        match self.target {
            Target::Root => &mut self.root,
            Target::Child(i) => &mut self.root.children[i],
            Target::Grandchild(i, j) => &mut self.root.children[i].children[j],
        }
    }

    /// Drops the current target if it ended up empty (it is always the last child of its
    /// parent); with `with_object`, also closes the current `o` cluster, dropping it if empty.
    fn prune(&mut self, with_object: bool) {
        let empty = |c: &Cluster| c.polygons.is_empty() && c.children.is_empty();
        match self.target {
            Target::Root => {}
            // The `o` cluster itself is only dropped with `with_object` (a `g` inside it
            // leaves it in place).
            Target::Child(i) => {
                if self.object != Some(i) && empty(&self.root.children[i]) {
                    self.root.children.truncate(i);
                }
            }
            Target::Grandchild(i, j) => {
                if empty(&self.root.children[i].children[j]) {
                    self.root.children[i].children.truncate(j);
                }
            }
        }
        if with_object
            && let Some(i) = self.object.take()
            && empty(&self.root.children[i])
        {
            self.root.children.truncate(i);
        }
        self.target = Target::Root;
        self.local.clear();
    }

    /// `o NAME`: a new child of the root.
    pub fn start_object(&mut self, name: Option<String>) {
        self.prune(true);
        self.root.children.push(Cluster {
            name,
            ..Cluster::default()
        });
        let i = self.root.children.len() - 1;
        self.object = Some(i);
        self.target = Target::Child(i);
    }

    /// `g NAME`: a new child of the current `o` cluster, or of the root.
    pub fn start_group(&mut self, name: Option<String>) {
        self.prune(false);
        let cluster = Cluster {
            name,
            ..Cluster::default()
        };
        match self.object {
            Some(i) => {
                let parent = &mut self.root.children[i];
                parent.children.push(cluster);
                self.target = Target::Grandchild(i, parent.children.len() - 1);
            }
            None => {
                self.root.children.push(cluster);
                self.target = Target::Child(self.root.children.len() - 1);
            }
        }
    }

    /// Adds a polygon whose corners are OBJ vertex indices into `positions` (3 or 4 of them).
    pub fn add(
        &mut self,
        positions: &[Vec3],
        corners: &[usize],
        material: u32,
    ) -> Result<(), ClusterFull> {
        let limit = NONE as usize - 1;
        let mut local = [NONE; 4];
        let mut map = std::mem::take(&mut self.local);
        let cluster = self.target_mut();
        if cluster.polygons.len() >= limit {
            self.local = map;
            return Err(ClusterFull);
        }
        let mut result = Ok(());
        for (slot, &g) in local.iter_mut().zip(corners) {
            if let Some(&l) = map.get(&g) {
                *slot = l;
                continue;
            }
            if cluster.vertices.len() >= limit {
                result = Err(ClusterFull);
                break;
            }
            let l = cluster.vertices.len() as u32;
            cluster.vertices.push(positions[g]);
            map.insert(g, l);
            *slot = l;
        }
        if result.is_ok() {
            cluster.polygons.push(Polygon {
                corners: local,
                material,
            });
        }
        self.local = map;
        result
    }

    /// The finished tree, empty clusters dropped.
    pub fn finish(mut self) -> Cluster {
        self.prune(true);
        self.root
    }
}
