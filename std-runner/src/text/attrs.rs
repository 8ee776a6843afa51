//! Attributes of nodes (`name`, `axis`, `age`) and the placement of instances (`translate`,
//! `rotate`, `quat`, `scale`), read in any order until a token that is not one of them.

use super::TextError;
use super::lexer::{Pos, Tok};
use super::parser::Parser;
use super::units::{normalised_direction, unit_quat};
use crate::scene::{Cluster, Similarity};
use glam::{Quat, Vec3};
use hirad_core::limits::NONE;

/// The placement written on an instance; absent parts are the identity.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Placement {
    translation: Option<Vec3>,
    rotation: Option<Quat>,
    rotations: u32,
    scale: Option<f32>,
}

impl Placement {
    /// The checked transform; errors point at the instance (`at`).
    pub fn similarity(&self, at: Pos) -> Result<Similarity, TextError> {
        let mut rotation = self.rotation.unwrap_or(Quat::IDENTITY);
        if self.rotations > 1 {
            // A product of unit quaternions drifts a little: renormalise only if it left
            // the tolerance.
            rotation = unit_quat(rotation).unwrap_or(rotation);
        }
        Similarity::checked(
            rotation,
            self.translation.unwrap_or(Vec3::ZERO),
            self.scale.unwrap_or(1.0),
        )
        .map_err(|e| at.error(format!("unusable placement: {e}")))
    }

    /// Applies `q` after the rotations already written.
    fn rotate(&mut self, q: Quat) {
        self.rotation = Some(match self.rotation {
            None => q,
            Some(before) => q * before,
        });
        self.rotations += 1;
    }
}

fn twice(at: Pos, kw: &str) -> TextError {
    at.error(format!("'{kw}' is given twice"))
}

impl Parser<'_> {
    /// Reads the `allowed` node attributes (no placement) into `node`.
    pub fn cluster_attributes(
        &mut self,
        node: &mut Cluster,
        allowed: &[&str],
    ) -> Result<(), TextError> {
        self.attributes(node, allowed).map(|_| ())
    }

    /// Reads the `allowed` attributes into `node`, returning the placement.
    pub fn attributes(
        &mut self,
        node: &mut Cluster,
        allowed: &[&str],
    ) -> Result<Placement, TextError> {
        let mut placement = Placement::default();
        loop {
            let t = self.cur.peek()?;
            let kw = match &t.tok {
                Tok::Word(w) if allowed.contains(&w.as_str()) => w.clone(),
                _ => return Ok(placement),
            };
            let at = self.cur.next()?.pos;
            match kw.as_str() {
                "name" => {
                    if node.name.is_some() {
                        return Err(twice(at, "name"));
                    }
                    node.name = Some(self.cur.name("name")?.0);
                }
                "axis" => {
                    if node.axis.is_some() {
                        return Err(twice(at, "axis"));
                    }
                    let (axis, p) = self.cur.integer("axis", "an axis kind")?;
                    if axis == NONE {
                        return Err(p.error(format!(
                            "axis kind {NONE} is reserved (use 0 to {})",
                            NONE - 1
                        )));
                    }
                    node.axis = Some(axis);
                }
                "age" => {
                    if node.age.is_some() {
                        return Err(twice(at, "age"));
                    }
                    let (age, p) = self.cur.number("age", at, "(the age, >= 0)")?;
                    if age < 0.0 {
                        return Err(p.error(format!("age must be >= 0, found {age}")));
                    }
                    node.age = Some(age);
                }
                "translate" => {
                    if placement.translation.is_some() {
                        return Err(twice(at, "translate"));
                    }
                    placement.translation = Some(self.vec3("translate", at, "(x y z)")?);
                }
                "rotate" => {
                    let v = self.vec4("rotate", at, "(axis x y z, then the angle in degrees)")?;
                    let Some(axis) = normalised_direction(v.truncate()) else {
                        return Err(at.error("the rotation axis must not be zero"));
                    };
                    placement.rotate(Quat::from_axis_angle(axis, v.w.to_radians()));
                }
                "quat" => {
                    let v = self.vec4("quat", at, "(w x y z)")?;
                    let Some(q) = unit_quat(Quat::from_xyzw(v.y, v.z, v.w, v.x)) else {
                        return Err(at.error("the quaternion must not be zero"));
                    };
                    placement.rotate(q);
                }
                "scale" => {
                    if placement.scale.is_some() {
                        return Err(twice(at, "scale"));
                    }
                    let (s, p) = self.cur.number("scale", at, "(the uniform scale factor)")?;
                    if !(s > 0.0 && s.is_normal()) {
                        return Err(
                            p.error(format!("the scale must be a positive number, found {s}"))
                        );
                    }
                    placement.scale = Some(s);
                }
                _ => return Ok(placement),
            }
        }
    }
}
