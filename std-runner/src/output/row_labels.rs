//! What a results row says about its polygon besides numbers: its material's name and its
//! group, the path of named clusters from the scene's root down to the cluster that holds it
//! (`scene/field/plant_3/leaves`; an unnamed cluster appears as `#index` among its
//! siblings; an instance's own name stands for the original it expands into), so that a
//! table can be filtered by organ or plant without flattening the scene and joining on face
//! order.

use crate::scene::{self, ExpandVisitor, ExpandedNode, Scene};

/// Material and group of every polygon of an expanded scene, by global id.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RowLabels {
    /// Material names (the scene's, by index).
    materials: Vec<String>,
    /// Per global id, the index of its material.
    material: Vec<u32>,
    /// Group paths, one per expanded cluster that holds polygons, in global-id order.
    groups: Vec<String>,
    /// Per entry of `groups`, the global id of its first polygon (increasing).
    first: Vec<u64>,
}

impl RowLabels {
    /// The labels of every polygon of `scene`'s expansion (4 bytes per polygon, and one path
    /// per cluster that holds polygons).
    pub fn of(scene: &Scene) -> RowLabels {
        struct Collect(RowLabels);
        impl ExpandVisitor for Collect {
            type Error = std::convert::Infallible;
            fn node(&mut self, n: &ExpandedNode<'_>) -> Result<(), Self::Error> {
                if n.cluster.polygons.is_empty() {
                    return Ok(());
                }
                self.0.first.push(n.first_id);
                self.0.groups.push(n.path.join("/"));
                self.0
                    .material
                    .extend(n.cluster.polygons.iter().map(|p| p.material));
                Ok(())
            }
        }
        let mut c = Collect(RowLabels {
            materials: scene.materials.iter().map(|m| m.name.clone()).collect(),
            ..RowLabels::default()
        });
        let _ = scene::expand(scene, &mut c);
        c.0
    }

    /// Polygons labelled.
    pub fn len(&self) -> usize {
        self.material.len()
    }

    /// True when no polygon is labelled.
    pub fn is_empty(&self) -> bool {
        self.material.is_empty()
    }

    /// True when some polygon's material (by index) satisfies `pred`.
    pub fn uses_material(&self, mut pred: impl FnMut(usize) -> bool) -> bool {
        let mut used = vec![false; self.materials.len()];
        for &m in &self.material {
            if let Some(u) = used.get_mut(m as usize) {
                *u = true;
            }
        }
        used.iter().enumerate().any(|(m, &u)| u && pred(m))
    }

    /// The material name of polygon `id` (`None` past the last polygon).
    pub fn material(&self, id: u64) -> Option<&str> {
        let m = *self.material.get(usize::try_from(id).ok()?)?;
        Some(self.materials.get(m as usize).map_or("", String::as_str))
    }

    /// The group path of polygon `id` (`None` past the last polygon).
    pub fn group(&self, id: u64) -> Option<&str> {
        if id >= self.material.len() as u64 {
            return None;
        }
        let k = self.first.partition_point(|&f| f <= id).checked_sub(1)?;
        self.groups.get(k).map(String::as_str)
    }
}
