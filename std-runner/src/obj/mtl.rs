//! The MTL reader: `newmtl`, `Kd` (front reflectance), `Ke` (emitted exitance, W/m^2) and
//! `Tf` (diffuse transmittance; makes the material two-sided with back reflectance = `Kd`).
//!
//! Shading statements that radiosity cannot use (`Ka`, `Ks`, `Ns`, `d`, `illum`, textures,
//! PBR extensions, ...) are ignored silently; unknown statements with one warning each. Keys
//! are matched without regard to case. Physical limits are the core's
//! ([`MaterialData::check`]) and are reported at the statement that breaks them.

use super::ObjError;
use super::diag::{Warnings, error};
use super::lex::{Lexer, Line, Pos};
use super::number::parse_f32;
use super::reader::BARE_CR;
use hirad_core::limits::MAX_NAME_BYTES;
use hirad_core::material::{MaterialData, MaterialError};

/// Bands of an imported scene: R, G, B.
pub(crate) const OBJ_BANDS: u8 = 3;

/// Reflectance of a material without `Kd`, and of the built-in `default` material.
pub const DEFAULT_REFLECTANCE: f32 = 0.5;

/// A material read from an MTL file.
#[derive(Clone, Debug)]
pub(crate) struct MtlMaterial {
    /// Name as given by `newmtl` (words joined by one space).
    pub name: String,
    /// Where the name is.
    pub pos: Pos,
    /// Its data (3 bands), already checked.
    pub data: MaterialData,
}

/// A colour statement (`Kd`, `Ke`, `Tf`): three band values and where each was written.
#[derive(Clone, Copy, Debug)]
struct Colour {
    values: [f32; 3],
    at: [Pos; 3],
}

/// Statements of the material being read.
struct Pending {
    name: String,
    pos: Pos,
    kd: Option<Colour>,
    ke: Option<Colour>,
    tf: Option<Colour>,
}

/// Which statement a value came from, to report a broken limit where it was written.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Key {
    Kd,
    Ke,
    Tf,
}

/// Statements that describe shading radiosity has no use for.
const IGNORED: &[&str] = &[
    "ka",
    "ks",
    "ns",
    "ni",
    "d",
    "tr",
    "illum",
    "sharpness",
    "bump",
    "disp",
    "decal",
    "refl",
    "norm",
    "pr",
    "pm",
    "ps",
    "pc",
    "pcr",
    "aniso",
    "anisor",
];

/// Reads the MTL file `file` (its name as written in `mtllib`).
pub(crate) fn parse_mtl(
    src: &[u8],
    file: &str,
    warnings: &mut Warnings,
) -> Result<Vec<MtlMaterial>, ObjError> {
    let mut lexer = Lexer::new(src);
    let mut line = Line::default();
    let mut done = Vec::new();
    let mut current: Option<Pending> = None;
    while lexer.next_line(&mut line) {
        if let Some(at) = line.bare_cr {
            return Err(error(file, at, BARE_CR));
        }
        if line.invalid_utf8 {
            warnings.once(
                file,
                "utf8",
                line.pos(0),
                "not valid UTF-8: invalid bytes replaced by U+FFFD",
            );
        }
        let key = line.tok(0).to_ascii_lowercase();
        let which = match key.as_str() {
            "newmtl" => {
                if let Some(p) = current.take() {
                    done.push(finish(p, file, warnings));
                }
                if line.len() < 2 {
                    return Err(error(file, line.end(), "newmtl needs a material name"));
                }
                let name = line.joined(1);
                if name.len() > MAX_NAME_BYTES {
                    return Err(error(
                        file,
                        line.pos(1),
                        format!("material name is longer than {MAX_NAME_BYTES} bytes"),
                    ));
                }
                current = Some(Pending {
                    name,
                    pos: line.pos(1),
                    kd: None,
                    ke: None,
                    tf: None,
                });
                continue;
            }
            "kd" => Key::Kd,
            "ke" => Key::Ke,
            "tf" => Key::Tf,
            k if IGNORED.contains(&k) || k.starts_with("map_") => continue,
            _ => {
                warnings.once(
                    file,
                    &key,
                    line.pos(0),
                    format!("statement '{}' ignored", line.tok(0)),
                );
                continue;
            }
        };
        let Some(p) = current.as_mut() else {
            return Err(error(
                file,
                line.pos(0),
                format!("{} before any newmtl", line.tok(0)),
            ));
        };
        let colour = read_colour(&line, file, warnings)?;
        match which {
            Key::Kd => p.kd = Some(colour),
            Key::Ke => p.ke = Some(colour),
            Key::Tf => p.tf = Some(colour),
        }
        check(p, file, which)?;
    }
    if let Some(p) = current.take() {
        done.push(finish(p, file, warnings));
    }
    Ok(done)
}

/// Reads `KEY r [g b]`; `g` and `b` default to `r`.
fn read_colour(line: &Line, file: &str, warnings: &mut Warnings) -> Result<Colour, ObjError> {
    let key = line.tok(0);
    if line.len() > 1 {
        let form = line.tok(1).to_ascii_lowercase();
        if form == "spectral" || form == "xyz" {
            return Err(error(
                file,
                line.pos(1),
                format!("{key} {form} is not supported; give r g b values"),
            ));
        }
    }
    let given = line.len() - 1;
    if given != 1 && given < 3 {
        return Err(error(
            file,
            line.end(),
            format!("{key} needs 1 or 3 values (r, or r g b), found {given}"),
        ));
    }
    if given > 3 {
        warnings.once(
            file,
            &format!("{key} extra"),
            line.pos(4),
            format!("values after the third of {key} ignored"),
        );
    }
    let mut c = Colour {
        values: [0.0; 3],
        at: [line.pos(1); 3],
    };
    for b in 0..3 {
        let t = if given == 1 { 1 } else { 1 + b };
        c.values[b] = parse_f32(line.tok(t)).map_err(|m| error(file, line.pos(t), m))?;
        c.at[b] = line.pos(t);
    }
    Ok(c)
}

/// `Tf 1 1 1` is what Maya and 3ds Max write for every material, meaning "no transmission
/// filter" for an opaque surface. As a transmittance it would make the surface invisible (and
/// with any `Kd` create energy), so it is read as "no Tf".
fn is_filter_placeholder(p: &Pending) -> bool {
    p.tf.is_some_and(|tf| tf.values == [1.0; 3])
}

/// The material data of `p` as far as it is known.
fn data(p: &Pending) -> MaterialData {
    let mut m = MaterialData::black(OBJ_BANDS);
    let rho = p.kd.map_or([DEFAULT_REFLECTANCE; 3], |c| c.values);
    m.rho_front[..3].copy_from_slice(&rho);
    if let Some(ke) = p.ke {
        m.emit_front[..3].copy_from_slice(&ke.values);
    }
    if let Some(tf) = p.tf
        && !is_filter_placeholder(p)
    {
        m.two_sided = true;
        m.rho_back[..3].copy_from_slice(&rho);
        m.tau[..3].copy_from_slice(&tf.values);
    }
    m
}

/// Checks the material after statement `now`, blaming the statement that broke the limit.
fn check(p: &Pending, file: &str, now: Key) -> Result<(), ObjError> {
    let Err(e) = data(p).check() else {
        return Ok(());
    };
    let (key, band) = match e {
        MaterialError::Reflectance { band } => (Key::Kd, band),
        MaterialError::Transmittance { band } => (Key::Tf, band),
        MaterialError::Emission { band } => (Key::Ke, band),
        // Either statement can break conservation; the one just read did.
        MaterialError::EnergyNotConserved { band } => (now, band),
        MaterialError::NonFinite { band } => (now, band),
        // The importer never fills unused values; blame the statement just read.
        MaterialError::Unused | MaterialError::Bands => (now, 0),
    };
    let colour = match key {
        Key::Kd => p.kd,
        Key::Ke => p.ke,
        Key::Tf => p.tf,
    };
    let name = match key {
        Key::Kd => "Kd",
        Key::Ke => "Ke",
        Key::Tf => "Tf",
    };
    let pos = colour.map_or(p.pos, |c| c.at[usize::from(band).min(2)]);
    Err(error(
        file,
        pos,
        format!("material '{}': {name}: {e}", p.name),
    ))
}

fn finish(p: Pending, file: &str, warnings: &mut Warnings) -> MtlMaterial {
    if p.kd.is_none() {
        warnings.add(
            file,
            p.pos,
            format!(
                "material '{}' has no Kd: reflectance {DEFAULT_REFLECTANCE} assumed",
                p.name
            ),
        );
    }
    if let Some(tf) = p.tf
        && is_filter_placeholder(&p)
    {
        warnings.once(
            file,
            "Tf 1 1 1",
            tf.at[0],
            "Tf 1 1 1 (what Maya and 3ds Max write for opaque materials) ignored: the \
             materials that have it are opaque",
        );
    }
    MtlMaterial {
        data: data(&p),
        name: p.name,
        pos: p.pos,
    }
}
