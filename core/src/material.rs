//! Materials: per-band diffuse reflectance, diffuse transmittance and emitted exitance.
//!
//! A one-sided material reflects and emits on its front only; its back absorbs everything.
//! A two-sided material (a leaf) has its own back reflectance and emission and a diffuse
//! transmittance shared by both sides (paper, section 5.2).

use crate::limits::MAX_BANDS;

/// Flag bit: the material has a back side and transmits light.
pub const TWO_SIDED: u32 = 1;

/// Radiometric data of one material, `bands` entries used in each array.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialData {
    /// Number of bands in use (1..=8).
    pub bands: u8,
    /// True for a leaf-like material with a back side and transmission.
    pub two_sided: bool,
    /// Front reflectance per band (dimensionless, 0..=1).
    pub rho_front: [f32; MAX_BANDS],
    /// Front emitted exitance per band (W/m^2).
    pub emit_front: [f32; MAX_BANDS],
    /// Back reflectance per band (two-sided only, else 0).
    pub rho_back: [f32; MAX_BANDS],
    /// Diffuse transmittance per band (two-sided only, else 0).
    pub tau: [f32; MAX_BANDS],
    /// Back emitted exitance per band (two-sided only, else 0) (W/m^2).
    pub emit_back: [f32; MAX_BANDS],
}

/// Why material data is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialError {
    /// A value is NaN or infinite.
    NonFinite {
        /// Band index.
        band: u8,
    },
    /// A reflectance outside 0..=1.
    Reflectance {
        /// Band index.
        band: u8,
    },
    /// A transmittance outside 0..=1.
    Transmittance {
        /// Band index.
        band: u8,
    },
    /// Reflectance plus transmittance above 1 on one side: energy would be created.
    EnergyNotConserved {
        /// Band index.
        band: u8,
    },
    /// A negative emitted exitance.
    Emission {
        /// Band index.
        band: u8,
    },
    /// A value the material does not use is not zero: a band past `bands`, or a back-side
    /// value of a one-sided material. (Zeros keep one material one value.)
    Unused,
    /// The band count is outside 1..=8.
    Bands,
}

impl core::fmt::Display for MaterialError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            MaterialError::NonFinite { band } => {
                write!(f, "band {band}: value is not a finite number")
            }
            MaterialError::Reflectance { band } => {
                write!(f, "band {band}: reflectance must lie in 0..=1")
            }
            MaterialError::Transmittance { band } => {
                write!(f, "band {band}: transmittance must lie in 0..=1")
            }
            MaterialError::EnergyNotConserved { band } => {
                write!(
                    f,
                    "band {band}: reflectance + transmittance exceeds 1 (energy would be created)"
                )
            }
            MaterialError::Emission { band } => {
                write!(f, "band {band}: emitted exitance must be >= 0")
            }
            MaterialError::Unused => f.write_str(
                "values past the band count, or back-side values of a one-sided material, must be 0",
            ),
            MaterialError::Bands => write!(f, "band count must lie in 1..={MAX_BANDS}"),
        }
    }
}

/// Slack allowed on reflectance + transmittance <= 1 for decimal values that round up in f32.
const CONSERVATION_SLACK: f32 = 1e-6;

impl MaterialData {
    /// A material with every value zero (black, one-sided).
    pub const fn black(bands: u8) -> Self {
        MaterialData {
            bands,
            two_sided: false,
            rho_front: [0.0; MAX_BANDS],
            emit_front: [0.0; MAX_BANDS],
            rho_back: [0.0; MAX_BANDS],
            tau: [0.0; MAX_BANDS],
            emit_back: [0.0; MAX_BANDS],
        }
    }

    /// Number of f32 values this material occupies in the image's value pool.
    pub const fn value_count(bands: u32, two_sided: bool) -> u32 {
        if two_sided { 5 * bands } else { 2 * bands }
    }

    /// Checks the physical ranges of every used band.
    pub fn check(&self) -> Result<(), MaterialError> {
        let n = self.bands as usize;
        if n == 0 || n > MAX_BANDS {
            return Err(MaterialError::Bands);
        }
        let unused_front = self.rho_front[n..].iter().chain(&self.emit_front[n..]);
        let unused_back = if self.two_sided {
            [&self.rho_back[n..], &self.tau[n..], &self.emit_back[n..]]
        } else {
            [&self.rho_back[..], &self.tau[..], &self.emit_back[..]]
        };
        if unused_front
            .chain(unused_back.into_iter().flatten())
            .any(|v| v.to_bits() != 0)
        {
            return Err(MaterialError::Unused);
        }
        for b in 0..n {
            let band = b as u8;
            let vals = [
                self.rho_front[b],
                self.emit_front[b],
                self.rho_back[b],
                self.tau[b],
                self.emit_back[b],
            ];
            if vals.iter().any(|v| !v.is_finite()) {
                return Err(MaterialError::NonFinite { band });
            }
            if !(0.0..=1.0).contains(&self.rho_front[b]) || !(0.0..=1.0).contains(&self.rho_back[b])
            {
                return Err(MaterialError::Reflectance { band });
            }
            if !(0.0..=1.0).contains(&self.tau[b]) {
                return Err(MaterialError::Transmittance { band });
            }
            if self.rho_front[b] + self.tau[b] > 1.0 + CONSERVATION_SLACK
                || self.rho_back[b] + self.tau[b] > 1.0 + CONSERVATION_SLACK
            {
                return Err(MaterialError::EnergyNotConserved { band });
            }
            if self.emit_front[b] < 0.0 || self.emit_back[b] < 0.0 {
                return Err(MaterialError::Emission { band });
            }
        }
        Ok(())
    }

    /// Fills from the image's value layout: front reflectance, front emission, and for
    /// two-sided materials back reflectance, transmittance, back emission; `bands` values each.
    pub fn from_values(bands: u8, two_sided: bool, values: &[f32]) -> Self {
        let n = bands as usize;
        let mut m = MaterialData::black(bands);
        m.two_sided = two_sided;
        let mut fields: [&mut [f32; MAX_BANDS]; 5] = [
            &mut m.rho_front,
            &mut m.emit_front,
            &mut m.rho_back,
            &mut m.tau,
            &mut m.emit_back,
        ];
        let used = if two_sided { 5 } else { 2 };
        for (k, field) in fields.iter_mut().enumerate().take(used) {
            for b in 0..n {
                field[b] = values.get(k * n + b).copied().unwrap_or(0.0);
            }
        }
        m
    }

    /// Writes the image's value layout (see [`MaterialData::from_values`]) into `out`,
    /// returning the number of values written, or `None` if `out` is too short.
    pub fn to_values(&self, out: &mut [f32]) -> Option<usize> {
        let n = self.bands as usize;
        let fields = [
            &self.rho_front,
            &self.emit_front,
            &self.rho_back,
            &self.tau,
            &self.emit_back,
        ];
        let used = if self.two_sided { 5 } else { 2 };
        let total = used * n;
        let out = out.get_mut(..total)?;
        for (k, field) in fields.iter().enumerate().take(used) {
            out[k * n..(k + 1) * n].copy_from_slice(&field[..n]);
        }
        Some(total)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_round_trip_and_checks() {
        let mut m = MaterialData::black(2);
        m.two_sided = true;
        m.rho_front[..2].copy_from_slice(&[0.1, 0.4]);
        m.rho_back[..2].copy_from_slice(&[0.1, 0.35]);
        m.tau[..2].copy_from_slice(&[0.05, 0.5]);
        let mut buf = [0.0; 40];
        let n = m.to_values(&mut buf).unwrap();
        assert_eq!(n, 10);
        assert_eq!(MaterialData::from_values(2, true, &buf[..n]), m);
        assert!(m.check().is_ok());
        m.tau[1] = 0.7;
        assert_eq!(
            m.check(),
            Err(MaterialError::EnergyNotConserved { band: 1 })
        );
        m.tau[1] = f32::NAN;
        assert_eq!(m.check(), Err(MaterialError::NonFinite { band: 1 }));
        m.tau[1] = 0.0;
        m.emit_front[0] = -1.0;
        assert_eq!(m.check(), Err(MaterialError::Emission { band: 0 }));
        m.emit_front[0] = 0.0;
        m.tau[2] = 0.5;
        assert_eq!(m.check(), Err(MaterialError::Unused));
        m.tau[2] = 0.0;
        m.two_sided = false;
        assert_eq!(m.check(), Err(MaterialError::Unused));
        m.rho_back = [0.0; MAX_BANDS];
        m.tau = [0.0; MAX_BANDS];
        assert_eq!(m.check(), Ok(()));
        m.rho_back[0] = -0.0;
        assert_eq!(m.check(), Err(MaterialError::Unused));
    }
}
