//! Botanical parameters of a columnar poplar (Lombardy-like *Populus nigra*): how long, thick
//! and branched an axis of each order is at a given age, and how its leafy shoots look.
//!
//! Units: metres, years, degrees. Every axis is described in its own canonical frame: its
//! base at the origin, growing along +z and bending towards +x (which the placement turns
//! towards its parent's direction, so that branches become erect: the columnar crown).

/// Axis kind of the trunk (botanical order 0).
pub const TRUNK: u32 = 0;
/// The highest branch order; the laterals of such axes are all leafy shoots.
pub const MAX_BRANCH_ORDER: u32 = 3;
/// Axis kind of a leafy shoot: the short, leaf-bearing growth that ends every axis and
/// carries the foliage of order-3 axes (its botanical order follows its parent's; the kind
/// marks it as the leaf-bearing class).
pub const SHOOT: u32 = 4;

/// The parameters of one branching order (kinds 0 to 3).
#[derive(Clone, Debug)]
pub struct AxisParams {
    /// Length reached with age (m): `max_length * (1 - exp(-age / growth_years))`.
    pub max_length: f32,
    /// Time constant of the length growth (years).
    pub growth_years: f32,
    /// Base radius over length (dimensionless).
    pub radius_ratio: f32,
    /// Tip radius over base radius.
    pub tip_ratio: f32,
    /// Sides of the internode cylinders (3 to 5: low polygon).
    pub sides: u32,
    /// Mean number of internode cylinders; each axis draws this +-1.
    pub segments: u32,
    /// Angle between an axis of this order and its parent at insertion (degrees).
    pub insertion_deg: f32,
    /// Total bend of the axis towards its parent's direction, base to tip (degrees).
    pub bend_deg: f32,
    /// Laterals per metre of the lateral zone.
    pub lateral_density: f32,
    /// The lateral zone: fractions of the length where laterals are inserted.
    pub zone: [f32; 2],
    /// Relative spread of the lateral count between axes of the same length (the trunk,
    /// one per tree, has none: it sets the size of the whole tree).
    pub count_spread: f32,
}

/// The parameters of a leafy shoot (kind [`SHOOT`]).
#[derive(Clone, Debug)]
pub struct ShootParams {
    /// Stem length (m).
    pub length: f32,
    /// Stem base radius (m); the tip is half.
    pub radius: f32,
    /// Sides of the stem cylinders.
    pub sides: u32,
    /// Stem cylinders.
    pub segments: u32,
    /// Mean leaves per shoot; each shoot draws this +-`leaf_spread`.
    pub leaves: u32,
    /// Spread of the leaf count.
    pub leaf_spread: u32,
    /// Leaf blade length (m) in the middle of the shoot.
    pub leaf_length: f32,
    /// Blade width over blade length (poplar leaves are deltoid: nearly as wide as long).
    pub leaf_width: f32,
    /// Angle between a leaf and the stem (degrees).
    pub leaf_angle_deg: f32,
    /// Petiole: distance from the stem to the blade base, over the blade length.
    pub petiole: f32,
    /// Angle between a shoot and its parent axis (degrees).
    pub insertion_deg: f32,
}

/// A class of axes that share an original: one kind, ages from `min_age` up to the next
/// class of the same kind. Older axes reuse the original of the oldest class, built at a
/// medium age (the paper's section 5.2: the reflectance of an axis tends to a limit with age).
#[derive(Clone, Debug)]
pub struct Class {
    /// Name of the original.
    pub name: &'static str,
    /// Axis kind (1 to 3, or [`SHOOT`]).
    pub kind: u32,
    /// Youngest age of the class (years).
    pub min_age: f32,
    /// Age at which the class's representative axis (its original) is grown (years).
    pub age: f32,
}

/// A species: orders, shoots, phyllotaxy and the instancing classes.
#[derive(Clone, Debug)]
pub struct Species {
    /// Kinds 0 (trunk) to [`MAX_BRANCH_ORDER`].
    pub axes: [AxisParams; 4],
    /// Leafy shoots.
    pub shoot: ShootParams,
    /// Angle between successive laterals around their parent (degrees): spiral phyllotaxy.
    pub divergence_deg: f32,
    /// Laterals younger than this (years) are leafy shoots whatever their order.
    pub shoot_age: f32,
    /// Instancing classes, ordered so that a class only contains axes of classes before it
    /// (shoots first, then orders from the highest down).
    pub classes: Vec<Class>,
}

impl Species {
    /// A columnar poplar: a 30-year-old tree is about 26 m tall with a crown about 6 m wide,
    /// and, as the paper's tree, about 119,000 polygons in 4 instancing levels.
    pub fn poplar() -> Self {
        let axis = |max_length, growth_years, radius_ratio, sides, segments| AxisParams {
            max_length,
            growth_years,
            radius_ratio,
            tip_ratio: 0.2,
            sides,
            segments,
            insertion_deg: 0.0,
            bend_deg: 0.0,
            lateral_density: 0.0,
            zone: [0.0, 0.0],
            count_spread: 0.1,
        };
        let trunk = AxisParams {
            tip_ratio: 0.08,
            lateral_density: 0.4,
            zone: [0.12, 0.97],
            count_spread: 0.0,
            ..axis(32.0, 18.0, 0.012, 5, 5)
        };
        let order1 = AxisParams {
            insertion_deg: 28.0,
            bend_deg: 22.0,
            lateral_density: 1.65,
            zone: [0.2, 0.95],
            ..axis(8.0, 5.0, 0.02, 4, 5)
        };
        let order2 = AxisParams {
            insertion_deg: 45.0,
            bend_deg: 20.0,
            lateral_density: 5.9,
            zone: [0.15, 0.95],
            ..axis(2.5, 3.0, 0.018, 3, 5)
        };
        let order3 = AxisParams {
            insertion_deg: 55.0,
            bend_deg: 12.0,
            lateral_density: 11.9,
            zone: [0.1, 0.95],
            ..axis(1.2, 2.0, 0.015, 3, 5)
        };
        Species {
            axes: [trunk, order1, order2, order3],
            shoot: ShootParams {
                length: 0.4,
                radius: 0.003,
                sides: 3,
                segments: 2,
                leaves: 20,
                leaf_spread: 3,
                leaf_length: 0.11,
                leaf_width: 0.8,
                leaf_angle_deg: 60.0,
                petiole: 0.4,
                insertion_deg: 60.0,
            },
            divergence_deg: 137.5,
            shoot_age: 1.5,
            classes: vec![
                class("shoot", SHOOT, 0.0, 1.0),
                class("branch3", 3, 0.0, 2.5),
                class("branch2", 2, 0.0, 4.0),
                class("branch1-young", 1, 0.0, 4.0),
                class("branch1-medium", 1, 8.0, 12.0),
            ],
        }
    }

    /// Natural length of an axis of `kind` at `age` (m).
    pub fn length(&self, kind: u32, age: f32) -> f32 {
        if kind == SHOOT {
            return self.shoot.length;
        }
        let p = &self.axes[kind.min(MAX_BRANCH_ORDER) as usize];
        p.max_length * (1.0 - (-age / p.growth_years).exp())
    }

    /// Trunk height of a tree of `age` (m).
    pub fn height(&self, age: f32) -> f32 {
        self.length(TRUNK, age)
    }

    /// Index in [`Species::classes`] of the class of an axis of `kind` and `age`: the class
    /// of that kind with the largest `min_age` not above `age`.
    pub fn class_of(&self, kind: u32, age: f32) -> Option<usize> {
        let mut best: Option<usize> = None;
        for (i, c) in self.classes.iter().enumerate() {
            if c.kind == kind
                && c.min_age <= age
                && best.is_none_or(|b| self.classes[b].min_age <= c.min_age)
            {
                best = Some(i);
            }
        }
        best.or_else(|| self.classes.iter().position(|c| c.kind == kind))
    }

    /// Multiplies every lateral density (more detail, same size).
    pub fn densify(&mut self, factor: f32) {
        for a in &mut self.axes {
            a.lateral_density *= factor;
        }
    }
}

fn class(name: &'static str, kind: u32, min_age: f32, age: f32) -> Class {
    Class {
        name,
        kind,
        min_age,
        age,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_and_classes() {
        let s = Species::poplar();
        let h = s.height(30.0);
        assert!((24.0..28.0).contains(&h), "{h}");
        assert!(s.length(1, 25.0) > s.length(1, 5.0));
        let name = |k, a| s.classes[s.class_of(k, a).unwrap()].name;
        assert_eq!(name(1, 3.0), "branch1-young");
        assert_eq!(name(1, 8.0), "branch1-medium");
        assert_eq!(name(1, 25.0), "branch1-medium");
        assert_eq!(name(2, 9.0), "branch2");
        assert_eq!(name(SHOOT, 0.5), "shoot");
        // A class only contains axes of higher kinds, which come before it.
        for (i, c) in s.classes.iter().enumerate() {
            assert!(s.classes[i..].iter().all(|d| d.kind <= c.kind));
        }
    }
}
