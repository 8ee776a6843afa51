//! The two ways laterals become instances, and the originals each way needs.
//!
//! - [`Approximate`] (the paper's trees): every axis grows its own geometry and is written as
//!   an *approximate* instance of the original of its class (kind and age class), carrying
//!   its geometry in the local frame of the original's size; the transform scales it to its
//!   own length and places it on its parent. Originals are representative axes of their
//!   class, grown the same way.
//! - [`Exact`] (forests): every axis is an *exact* instance of one of a few variants of its
//!   class, scaled to its length: the expanded tree is huge while the file holds only the
//!   variants.

use super::axis::{Laterals, TreeMaterials, grow_axis, grow_shoot};
use super::frame::{Placement, approximate};
use super::species::{SHOOT, Species};
use crate::generate::rng::Rng;
use crate::scene::{Cluster, InstanceOf, Original, Similarity};

/// Grows an axis or a shoot of `kind` and `age`, `length` metres long, in its canonical
/// frame.
pub fn grow(
    species: &Species,
    kind: u32,
    age: f32,
    length: f32,
    mats: TreeMaterials,
    rng: &Rng,
    laterals: &mut dyn Laterals,
) -> Cluster {
    if kind == SHOOT {
        grow_shoot(species, age, length, mats, rng)
    } else {
        grow_axis(species, kind, age, length, mats, rng, laterals)
    }
}

/// An original of the scene: its index in `Scene::originals` and its axis length (m).
#[derive(Clone, Copy, Debug)]
pub struct Built {
    /// Index in the scene's originals.
    pub original: usize,
    /// Length of the original's axis (m): instances scale by their length over this.
    pub length: f32,
}

/// Laterals as approximate instances of one original per class.
pub struct Approximate {
    /// Materials of the geometry.
    pub mats: TreeMaterials,
    /// Per class of the species: its original, once built.
    pub originals: Vec<Option<Built>>,
}

impl Laterals for Approximate {
    fn lateral(
        &mut self,
        species: &Species,
        kind: u32,
        age: f32,
        place: &Placement,
        rng: &mut Rng,
    ) -> Cluster {
        let length = species.length(kind, age) * rng.vary(1.0, 0.1);
        let grown = grow(species, kind, age, length, self.mats, &rng.fork(0), self);
        match species.class_of(kind, age).and_then(|c| self.originals[c]) {
            Some(b) => approximate(grown, length, b.original, b.length, place),
            // No original for this class (yet): the axis stays plain geometry of its parent.
            None => bake(grown, &place.similarity(1.0)),
        }
    }
}

/// Grows one original per class of `species`, bottom-up (each class only contains classes
/// built before it), appends them to `originals`, and returns the strategy that instances
/// them.
pub fn approximate_originals(
    species: &Species,
    mats: TreeMaterials,
    rng: &Rng,
    originals: &mut Vec<Original>,
) -> Approximate {
    let mut a = Approximate {
        mats,
        originals: vec![None; species.classes.len()],
    };
    for (i, class) in species.classes.iter().enumerate() {
        let length = species.length(class.kind, class.age);
        let root = grow(
            species,
            class.kind,
            class.age,
            length,
            mats,
            &rng.fork(i as u64),
            &mut a,
        );
        a.originals[i] = Some(Built {
            original: originals.len(),
            length,
        });
        originals.push(Original {
            name: class.name.to_string(),
            root,
        });
    }
    a
}

/// Laterals as exact instances of a few variants per class.
pub struct Exact {
    /// Materials of the geometry of classes without variants.
    pub mats: TreeMaterials,
    /// Per class of the species: its variants built so far.
    pub variants: Vec<Vec<Built>>,
}

impl Laterals for Exact {
    fn lateral(
        &mut self,
        species: &Species,
        kind: u32,
        age: f32,
        place: &Placement,
        rng: &mut Rng,
    ) -> Cluster {
        let length = species.length(kind, age) * rng.vary(1.0, 0.1);
        let class = species.class_of(kind, age);
        let variants = class.map(|c| self.variants[c].as_slice()).unwrap_or(&[]);
        if variants.is_empty() {
            let grown = grow(species, kind, age, length, self.mats, &rng.fork(0), self);
            return bake(grown, &place.similarity(1.0));
        }
        let v = variants[rng.int(0, variants.len() as u32 - 1) as usize];
        Cluster {
            axis: Some(kind),
            age: Some(age),
            instance: Some(InstanceOf {
                original: v.original,
                exact: true,
                transform: place.similarity(length / v.length),
            }),
            ..Cluster::default()
        }
    }
}

/// Grows `count` variants per class of `species` (ages spread from 0.8 to 1.2 times the
/// class's age), bottom-up, each made of exact instances of the variants before it; appends
/// them to `originals` (named `CLASS-K`) and returns the strategy that instances them.
pub fn exact_variants(
    species: &Species,
    mats: TreeMaterials,
    count: u32,
    rng: &Rng,
    originals: &mut Vec<Original>,
) -> Exact {
    let mut e = Exact {
        mats,
        variants: vec![Vec::new(); species.classes.len()],
    };
    for (i, class) in species.classes.iter().enumerate() {
        let mut built = Vec::new();
        for k in 0..count.max(1) {
            let spread = if count > 1 {
                k as f32 / (count - 1) as f32
            } else {
                0.5
            };
            let age = class.age * (0.8 + 0.4 * spread);
            let length = species.length(class.kind, age);
            let root = grow(
                species,
                class.kind,
                age,
                length,
                mats,
                &rng.fork(i as u64 * 64 + k as u64),
                &mut e,
            );
            built.push(Built {
                original: originals.len(),
                length,
            });
            originals.push(Original {
                name: format!("{}-{k}", class.name),
                root,
            });
        }
        e.variants[i] = built;
    }
    e
}

/// Writes a node's content in its parent's frame through `t` (used when a class has no
/// original): vertices are mapped, instances inside are composed with `t`.
pub fn bake(mut c: Cluster, t: &Similarity) -> Cluster {
    for v in &mut c.vertices {
        *v = t.point(*v);
    }
    c.children = c
        .children
        .into_iter()
        .map(|mut child| match &mut child.instance {
            Some(i) => {
                i.transform = t.compose(&i.transform);
                child
            }
            None => bake(child, t),
        })
        .collect();
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};

    #[test]
    fn bake_maps_vertices_and_composes_instances() {
        let mut c = Cluster::default();
        c.vertex(Vec3::X);
        c.children.push(Cluster {
            instance: Some(InstanceOf {
                original: 0,
                exact: true,
                transform: Similarity {
                    translation: Vec3::Z,
                    ..Similarity::IDENTITY
                },
            }),
            ..Cluster::default()
        });
        let t = Similarity {
            rotation: Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
            translation: Vec3::new(0.0, 0.0, 1.0),
            scale: 2.0,
        };
        let b = bake(c, &t);
        assert!((b.vertices[0] - Vec3::new(0.0, 2.0, 1.0)).length() < 1e-6);
        let inner = b.children[0].instance.unwrap().transform;
        assert!((inner.translation - Vec3::new(0.0, 0.0, 3.0)).length() < 1e-6);
        assert_eq!(inner.scale, 2.0);
    }
}
