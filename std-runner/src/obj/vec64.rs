//! Minimal `f64` vectors for polygon splitting (glam's `f64` types are not enabled in this
//! workspace). Double precision keeps projections and orientation tests of `f32` input exact
//! enough that only genuinely degenerate corners look degenerate.

use glam::Vec3;
use std::ops::{Add, Div, Sub};

/// A 3D vector of `f64`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct D3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// A 2D vector of `f64`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct D2 {
    pub x: f64,
    pub y: f64,
}

impl D3 {
    /// Widens an `f32` vector.
    pub fn from_vec3(v: Vec3) -> Self {
        D3 {
            x: f64::from(v.x),
            y: f64::from(v.y),
            z: f64::from(v.z),
        }
    }

    /// Dot product.
    pub fn dot(self, o: D3) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product.
    pub fn cross(self, o: D3) -> D3 {
        D3 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }

    /// Squared length.
    pub fn length_squared(self) -> f64 {
        self.dot(self)
    }

    /// Length.
    pub fn length(self) -> f64 {
        self.length_squared().sqrt()
    }

    /// Component-wise minimum.
    pub fn min(self, o: D3) -> D3 {
        D3 {
            x: self.x.min(o.x),
            y: self.y.min(o.y),
            z: self.z.min(o.z),
        }
    }

    /// Component-wise maximum.
    pub fn max(self, o: D3) -> D3 {
        D3 {
            x: self.x.max(o.x),
            y: self.y.max(o.y),
            z: self.z.max(o.z),
        }
    }

    /// A unit vector perpendicular to this unit vector.
    pub fn any_orthonormal(self) -> D3 {
        // Cross with the axis least aligned with `self`.
        let (ax, ay, az) = (self.x.abs(), self.y.abs(), self.z.abs());
        let axis = if ax <= ay && ax <= az {
            D3 {
                x: 1.0,
                y: 0.0,
                z: 0.0,
            }
        } else if ay <= az {
            D3 {
                x: 0.0,
                y: 1.0,
                z: 0.0,
            }
        } else {
            D3 {
                x: 0.0,
                y: 0.0,
                z: 1.0,
            }
        };
        let u = self.cross(axis);
        u / u.length()
    }

    /// Mean of a non-empty list of points.
    pub fn mean(pts: &[D3]) -> D3 {
        let mut s = D3::default();
        for p in pts {
            s = s + *p;
        }
        s / pts.len() as f64
    }
}

impl Add for D3 {
    type Output = D3;
    fn add(self, o: D3) -> D3 {
        D3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl Sub for D3 {
    type Output = D3;
    fn sub(self, o: D3) -> D3 {
        D3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl Div<f64> for D3 {
    type Output = D3;
    fn div(self, k: f64) -> D3 {
        D3 {
            x: self.x / k,
            y: self.y / k,
            z: self.z / k,
        }
    }
}

impl D2 {
    /// 2D cross product (z of the 3D one).
    pub fn perp_dot(self, o: D2) -> f64 {
        self.x * o.y - self.y * o.x
    }

    /// Dot product.
    pub fn dot(self, o: D2) -> f64 {
        self.x * o.x + self.y * o.y
    }

    /// Squared length.
    pub fn length_squared(self) -> f64 {
        self.dot(self)
    }
}

impl Sub for D2 {
    type Output = D2;
    fn sub(self, o: D2) -> D2 {
        D2 {
            x: self.x - o.x,
            y: self.y - o.y,
        }
    }
}
