//! The tables as CSV, for plotting and for canopy models that take a crown's reflectance
//! and transmittance by sun direction.

use super::OriginalTables;
use std::io::{self, Write};

/// Header of the per-direction file.
pub const HEADER: &str = "original,band,cell,x,y,z,solid_angle_sr,tau,area_m2,shadow_m2,albedo,scattered_m2,absorbed_fraction,energy_residual";

/// Header of the bidirectional file.
pub const BIDIRECTIONAL_HEADER: &str = "original,band,in_cell,out_cell,out_x,out_y,out_z,response_front_per_m2_sr,response_back_per_m2_sr,first_scattering_m2_sr,intensity_m2_sr";

/// One row per original, band and incoming cell: the direction towards the sun (the
/// original's frame), the cell's solid angle, `tau` and the areas there, the albedo, the
/// scattered power per W/m^2 of sun, and what the bake measured (absorbed fraction of the
/// power crossing the box, energy residual).
pub fn write_directions(
    out: &mut dyn Write,
    tables: &[OriginalTables],
    names: &[String],
) -> io::Result<()> {
    writeln!(out, "{HEADER}")?;
    for t in tables {
        let view = t.view();
        for c in 0..t.incoming.cells() {
            let d = t.incoming.direction(c);
            for b in 0..t.bands {
                let i = c as usize * t.bands + b;
                writeln!(
                    out,
                    "{},{},{c},{},{},{},{},{},{},{},{},{},{},{}",
                    csv_name(&t.name),
                    band_label(names, b),
                    d.x,
                    d.y,
                    d.z,
                    t.incoming.solid_angle(),
                    view.tau(d),
                    view.area(d),
                    view.shadow(d),
                    view.albedo(d, b),
                    view.scattered(d, b),
                    t.absorbed[i],
                    t.residual[i]
                )?;
            }
        }
    }
    Ok(())
}

/// One row per original, band, incoming and outgoing cell: the responses to light falling
/// on the fronts and on the backs (of the light scattered more than once where the first
/// scattering is kept apart), the first scattering (0 where it is not kept apart) and the
/// whole intensity towards the outgoing cell's centre, for a sun of 1 W/m^2 at the incoming
/// cell's centre.
pub fn write_bidirectional(
    out: &mut dyn Write,
    tables: &[OriginalTables],
    names: &[String],
) -> io::Result<()> {
    writeln!(out, "{BIDIRECTIONAL_HEADER}")?;
    for t in tables {
        let view = t.view();
        let phase = view.phase();
        for ci in 0..t.incoming.cells() {
            let source = t.incoming.direction(ci);
            for co in 0..t.outgoing.cells() {
                let o = t.outgoing.direction(co);
                for b in 0..t.bands {
                    writeln!(
                        out,
                        "{},{},{ci},{co},{},{},{},{},{},{},{}",
                        csv_name(&t.name),
                        band_label(names, b),
                        o.x,
                        o.y,
                        o.z,
                        phase.response_at(ci, co, 0, b),
                        phase.response_at(ci, co, 1, b),
                        view.single().map_or(0.0, |x| x.intensity(source, o, b)),
                        view.intensity(source, o, b)
                    )?;
                }
            }
        }
    }
    Ok(())
}

/// A band's name, or its index when the scene names none.
fn band_label(names: &[String], b: usize) -> String {
    names.get(b).cloned().unwrap_or_else(|| b.to_string())
}

/// A name as a CSV field (quoted when it holds a comma or a quote).
fn csv_name(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
