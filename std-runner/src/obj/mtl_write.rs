//! The MTL side of an export: material names OBJ can hold, and one `newmtl` block per
//! material with `Kd`, `Ke` (when emitting) and `Tf` (two-sided materials).

use crate::scene::{MaterialData, Scene};
use hirad_core::limits::MAX_BANDS;
use std::collections::BTreeSet;
use std::io::{self, Write};

/// `text` with every character OBJ/MTL cannot hold in a name replaced by `_`: `#` (starts a
/// comment), control characters (end lines), a trailing `\` (continues the line), and, when
/// `spaces` is false, whitespace.
pub(crate) fn sanitize(text: &str, spaces: bool) -> String {
    let mut s: String = text
        .chars()
        .map(|c| {
            if c == '#' || c.is_control() || (!spaces && c.is_whitespace()) {
                '_'
            } else {
                c
            }
        })
        .collect();
    if s.ends_with('\\') {
        s.pop();
        s.push('_');
    }
    s
}

/// Names for the materials of `scene` that `usemtl`/`newmtl` can hold and that are unique,
/// with a warning for each name that had to change. Names that need no change keep it; the
/// others are sanitised and, if that makes them collide, numbered.
pub(crate) fn material_names(scene: &Scene, warnings: &mut Vec<String>) -> Vec<String> {
    let fits = |n: &str| !n.is_empty() && sanitize(n, false) == n;
    let mut taken: BTreeSet<String> = scene
        .materials
        .iter()
        .filter(|m| fits(&m.name))
        .map(|m| m.name.clone())
        .collect();
    let mut names = Vec::with_capacity(scene.materials.len());
    for m in &scene.materials {
        if fits(&m.name) {
            names.push(m.name.clone());
            continue;
        }
        let mut name = sanitize(&m.name, false);
        if name.is_empty() {
            name = "unnamed".to_string();
        }
        if taken.contains(&name) {
            let mut k = 2u64;
            while taken.contains(&format!("{name}_{k}")) {
                k += 1;
            }
            name = format!("{name}_{k}");
        }
        warnings.push(format!(
            "material '{}' written as '{name}' (MTL names cannot hold spaces, '#' or \
             control characters, and must be unique)",
            m.name
        ));
        taken.insert(name.clone());
        names.push(name);
    }
    names
}

/// Three colour values from the `bands` used values of `v`: one band repeated, three as they
/// are, other counts the first three padded with the last.
fn rgb(v: &[f32; MAX_BANDS], bands: u8) -> [f32; 3] {
    let n = usize::from(bands).clamp(1, MAX_BANDS);
    [v[0], v[1.min(n - 1)], v[2.min(n - 1)]]
}

/// The warning for scenes whose band count is neither 1 nor 3.
fn band_warning(scene: &Scene) -> Option<String> {
    let n = usize::from(scene.bands);
    let label = |b: usize| match scene.band_names.get(b) {
        Some(name) => format!("{} ('{name}')", b + 1),
        None => format!("{}", b + 1),
    };
    match n {
        1 | 3 => None,
        2 => Some(format!(
            "the scene has 2 bands and MTL colours are r g b: written as bands {}, {}, {}",
            label(0),
            label(1),
            label(1)
        )),
        _ => Some(format!(
            "the scene has {n} bands and MTL colours are r g b: bands {} are lost",
            (3..n).map(label).collect::<Vec<_>>().join(", ")
        )),
    }
}

fn write_colour(out: &mut dyn Write, key: &str, c: [f32; 3]) -> io::Result<()> {
    writeln!(out, "{key} {} {} {}", c[0], c[1], c[2])
}

fn any_nonzero(v: &[f32; MAX_BANDS], bands: u8) -> bool {
    v[..usize::from(bands).min(MAX_BANDS)]
        .iter()
        .any(|&x| x != 0.0)
}

/// Writes the MTL file for `scene` with the material names `names`.
pub(crate) fn write_mtl(
    scene: &Scene,
    names: &[String],
    out: &mut dyn Write,
    warnings: &mut Vec<String>,
) -> io::Result<()> {
    warnings.extend(band_warning(scene));
    writeln!(
        out,
        "# hirad materials: Kd = front reflectance, Ke = emitted exitance"
    )?;
    writeln!(
        out,
        "# (W/m^2), Tf = diffuse transmittance of a two-sided material (back = Kd)."
    )?;
    writeln!(out, "# Materials: {}", scene.materials.len())?;
    for (m, name) in scene.materials.iter().zip(names) {
        let d: &MaterialData = &m.data;
        writeln!(out)?;
        writeln!(out, "newmtl {name}")?;
        write_colour(out, "Kd", rgb(&d.rho_front, scene.bands))?;
        if any_nonzero(&d.emit_front, scene.bands) {
            write_colour(out, "Ke", rgb(&d.emit_front, scene.bands))?;
        }
        if d.two_sided {
            let tau = rgb(&d.tau, scene.bands);
            write_colour(out, "Tf", tau)?;
            if tau == [1.0; 3] {
                warnings.push(format!(
                    "material '{}': Tf 1 1 1 is read back (by hirad too) as the 'no filter' \
                     value Maya and 3ds Max write for opaque materials",
                    m.name
                ));
            }
            let n = usize::from(scene.bands).min(MAX_BANDS);
            if d.rho_back[..n] != d.rho_front[..n] {
                warnings.push(format!(
                    "material '{}': its back reflectance differs from the front; MTL keeps \
                     only Kd (front), which a reader uses for both sides",
                    m.name
                ));
            }
            if any_nonzero(&d.emit_back, scene.bands) {
                warnings.push(format!(
                    "material '{}': back emission cannot be written to MTL and is lost",
                    m.name
                ));
            }
        }
    }
    Ok(())
}
