//! Which axis of a scene is up, and the exact rotations between that frame, hirad's z-up
//! frame and OBJ's y-up frame.
//!
//! hirad's own scenes (the generators, the format's examples) are z up; OBJ files are y up by
//! convention (Blender, Maya and hirad's own import read them so). A scene says its up axis
//! through its first camera's `up`, else through its sky (the mean of its directions, the
//! zenith for any real sky), else it is z up. The rotations are signed permutations of the
//! coordinates, so applying them never rounds (and writes no negative zeros).

use super::Scene;
use glam::{DVec3, Vec3};

/// A signed coordinate axis: the direction a scene treats as up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Up {
    /// 0, 1 or 2 for x, y, z.
    axis: u8,
    /// Up is the negative direction of `axis`.
    negative: bool,
}

impl Up {
    /// +z: hirad's own scenes.
    pub const Z: Up = Up {
        axis: 2,
        negative: false,
    };
    /// +y: the OBJ convention.
    pub const Y: Up = Up {
        axis: 1,
        negative: false,
    };

    /// The signed axis nearest to `v` (None for a zero or non-finite vector).
    pub fn nearest(v: Vec3) -> Option<Up> {
        if !v.is_finite() || v == Vec3::ZERO {
            return None;
        }
        let a = v.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        Some(Up {
            axis,
            negative: v[axis as usize] < 0.0,
        })
    }

    /// The up axis of a hirad scene (see the module): its first camera's, else its sky's,
    /// else +z.
    pub fn of_scene(scene: &Scene) -> Up {
        Up::of_parts(
            scene.cameras.first().map(|c| c.up),
            &scene.sky,
            scene.bands as usize,
        )
        .0
    }

    /// [`Up::of_scene`] from the first camera's up vector and the sky of `bands` bands,
    /// with what decided it: `"its first camera"`, `"its sky"` or `"hirad's default"`.
    pub fn of_parts(
        camera_up: Option<Vec3>,
        sky: &[super::LightData],
        bands: usize,
    ) -> (Up, &'static str) {
        if let Some(up) = camera_up {
            return (Up::nearest(up).unwrap_or(Up::Z), "its first camera");
        }
        let sum: Vec3 = sky
            .iter()
            .map(|s| s.towards * s.irradiance.iter().take(bands).sum::<f32>())
            .sum();
        match Up::nearest(sum) {
            Some(up) => (up, "its sky"),
            None => (Up::Z, "hirad's default"),
        }
    }

    /// Parses `x`, `y`, `z`, `-x`, `-y`, `-z` (also `+x`..., any case).
    pub fn parse(s: &str) -> Option<Up> {
        let t = s.trim().to_ascii_lowercase();
        let (negative, name) = match t.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, t.strip_prefix('+').unwrap_or(&t)),
        };
        let axis = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return None,
        };
        Some(Up { axis, negative })
    }

    /// The unit vector.
    pub fn vector(self) -> DVec3 {
        let mut v = DVec3::ZERO;
        v[self.axis as usize] = if self.negative { -1.0 } else { 1.0 };
        v
    }

    /// A direction given in a z-up frame, in this scene's frame (a rotation taking +z to this
    /// axis).
    pub fn from_z_up(self, v: DVec3) -> DVec3 {
        let (x, y, z) = (v.x, v.y, v.z);
        match (self.axis, self.negative) {
            (2, false) => v,
            (2, true) => DVec3::new(x, 0.0 - y, 0.0 - z),
            (1, false) => DVec3::new(x, z, 0.0 - y),
            (1, true) => DVec3::new(x, 0.0 - z, y),
            (0, false) => DVec3::new(z, y, 0.0 - x),
            _ => DVec3::new(0.0 - z, y, x),
        }
    }

    /// A point of this scene's frame in the z-up frame (the inverse of [`Up::from_z_up`]).
    pub fn to_z_up(self, v: Vec3) -> Vec3 {
        let (x, y, z) = (v.x, v.y, v.z);
        match (self.axis, self.negative) {
            (2, false) => v,
            (2, true) => Vec3::new(x, 0.0 - y, 0.0 - z),
            (1, false) => Vec3::new(x, 0.0 - z, y),
            (1, true) => Vec3::new(x, z, 0.0 - y),
            (0, false) => Vec3::new(0.0 - z, y, x),
            _ => Vec3::new(z, y, 0.0 - x),
        }
    }

    /// A point of this scene's frame in OBJ's y-up frame.
    pub fn to_y_up(self, v: Vec3) -> Vec3 {
        let z = self.to_z_up(v);
        Vec3::new(z.x, z.z, 0.0 - z.y)
    }

    /// Turns a whole scene from this frame into the z-up frame: vertices of the scene's own
    /// tree, the placements of its instances (their originals keep their local frames),
    /// cameras, suns and sky. Vertices move exactly; instance rotations are composed.
    pub fn rotate_scene_to_z_up(self, scene: &mut Scene) {
        if self == Up::Z {
            return;
        }
        let columns = [DVec3::X, DVec3::Y, DVec3::Z].map(|e| self.to_z_up(e.as_vec3()).as_dvec3());
        let q = glam::DQuat::from_mat3(&glam::DMat3::from_cols(columns[0], columns[1], columns[2]))
            .as_quat();
        fn walk(c: &mut super::Cluster, up: Up, q: glam::Quat) {
            if let Some(inst) = &mut c.instance {
                let t = &mut inst.transform;
                t.rotation = (q * t.rotation).normalize();
                t.translation = up.to_z_up(t.translation);
                return;
            }
            c.vertices.iter_mut().for_each(|v| *v = up.to_z_up(*v));
            c.children.iter_mut().for_each(|k| walk(k, up, q));
        }
        walk(&mut scene.root, self, q);
        for c in &mut scene.cameras {
            c.position = self.to_z_up(c.position);
            c.target = self.to_z_up(c.target);
            c.up = self.to_z_up(c.up);
        }
        for l in scene.suns.iter_mut().chain(scene.sky.iter_mut()) {
            l.towards = self.to_z_up(l.towards);
        }
    }

    /// `+x`, `-z`, ...
    pub fn name(self) -> &'static str {
        ["+x", "-x", "+y", "-y", "+z", "-z"][self.axis as usize * 2 + self.negative as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all() -> Vec<Up> {
        ["x", "-x", "y", "-y", "z", "-z"]
            .iter()
            .map(|s| Up::parse(s).unwrap())
            .collect()
    }

    #[test]
    fn rotations_are_proper_and_inverse() {
        let probe = Vec3::new(0.25, -1.5, 3.0);
        for up in all() {
            // +z goes to up, and back.
            assert_eq!(up.from_z_up(DVec3::Z), up.vector(), "{}", up.name());
            assert_eq!(up.to_z_up(up.vector().as_vec3()), Vec3::Z, "{}", up.name());
            assert_eq!(up.to_y_up(up.vector().as_vec3()), Vec3::Y, "{}", up.name());
            // Inverse of each other, exactly.
            let back = up.from_z_up(up.to_z_up(probe).as_dvec3()).as_vec3();
            assert_eq!(back, probe, "{}", up.name());
            // A rotation, not a reflection: the images of x and y still cross to that of z.
            let (ex, ey) = (up.from_z_up(DVec3::X), up.from_z_up(DVec3::Y));
            assert_eq!(ex.cross(ey), up.vector(), "{}", up.name());
            // Lengths kept.
            assert_eq!(up.to_y_up(probe).length(), probe.length());
        }
        assert_eq!(
            Up::Z.to_y_up(Vec3::new(1.0, 2.0, 3.0)),
            Vec3::new(1.0, 3.0, -2.0)
        );
    }

    #[test]
    fn a_turned_scene_is_the_same_scene_z_up() {
        use crate::scene::{Cluster, InstanceOf, Original, Similarity};
        let tri = |c: &mut Cluster| {
            c.vertices = vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 2.0, 1.0),
            ];
            c.polygons = vec![crate::scene::triangle(0, 1, 2, 0)];
        };
        let mut scene = Scene::new(1);
        tri(&mut scene.root);
        let mut leaf = Cluster::default();
        tri(&mut leaf);
        scene.originals.push(Original {
            name: "leaf".into(),
            root: leaf,
        });
        scene.root.children.push(Cluster {
            instance: Some(InstanceOf {
                original: 0,
                exact: true,
                transform: Similarity {
                    rotation: glam::Quat::from_rotation_x(0.3),
                    translation: Vec3::new(4.0, 5.0, 6.0),
                    scale: 2.0,
                },
            }),
            ..Cluster::default()
        });
        let before = world(&scene);
        for up in all() {
            let mut turned = scene.clone();
            up.rotate_scene_to_z_up(&mut turned);
            for (a, b) in world(&turned).iter().zip(&before) {
                assert!((*a - up.to_z_up(*b)).length() < 1e-5, "{}", up.name());
            }
        }
    }

    /// World corners of every polygon, in expansion order.
    fn world(scene: &Scene) -> Vec<Vec3> {
        struct W(Vec<Vec3>);
        impl crate::scene::ExpandVisitor for W {
            type Error = ();
            fn node(&mut self, n: &crate::scene::ExpandedNode<'_>) -> Result<(), ()> {
                let c = n.cluster;
                for v in &c.vertices {
                    self.0.push(n.to_world.point(*v));
                }
                Ok(())
            }
        }
        let mut w = W(Vec::new());
        crate::scene::expand(scene, &mut w).unwrap();
        w.0
    }

    #[test]
    fn parse_and_nearest() {
        assert_eq!(Up::parse("+Z"), Some(Up::Z));
        assert_eq!(Up::parse(" y "), Some(Up::Y));
        assert_eq!(Up::parse("-y").map(Up::name), Some("-y"));
        assert_eq!(Up::parse("w"), None);
        assert_eq!(Up::parse("--y"), None);
        assert_eq!(
            Up::nearest(Vec3::new(0.1, -0.9, 0.3)).map(Up::name),
            Some("-y")
        );
        assert_eq!(Up::nearest(Vec3::ZERO), None);
        assert_eq!(Up::nearest(Vec3::NAN), None);
    }

    #[test]
    fn a_scene_says_its_up_by_camera_then_sky() {
        let mut scene = Scene::new(1);
        assert_eq!(Up::of_scene(&scene), Up::Z);
        let mut irradiance = [0.0; hirad_core::limits::MAX_BANDS];
        irradiance[0] = 3.0;
        scene.sky.push(crate::scene::LightData {
            towards: Vec3::new(0.2, 0.9, 0.1).normalize(),
            irradiance,
        });
        assert_eq!(Up::of_scene(&scene), Up::Y);
        scene.cameras.push(crate::scene::Camera {
            name: None,
            position: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::new(-1.0, 0.0, 0.0),
            fovy_deg: 45.0,
        });
        assert_eq!(Up::of_scene(&scene).name(), "-x");
    }
}
