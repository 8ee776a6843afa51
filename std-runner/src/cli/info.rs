//! `hirad info SCENE`.

use crate::files::{self, Format};
use anyhow::Result;
use hirad_core::MaterialId;
use hirad_core::image::{SceneSource, SceneView};
use hirad_core::limits::MAX_NAME_BYTES;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `hirad info`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  hirad info fixtures/chair_room.hir\n  hirad info poplar.hirb --json > poplar.json\n  hirad info model.obj          # what an OBJ import makes of the file"
)]
pub struct Args {
    /// Scene file (.hir, .hirb or .obj).
    pub scene: PathBuf,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Do not print loader warnings.
    #[arg(long, short)]
    pub quiet: bool,
}

/// What `info` reports.
struct Report {
    format: Format,
    bands: u32,
    band_names: Vec<String>,
    materials: u32,
    two_sided: u32,
    emitting: u32,
    info: hirad_core::image::SceneInfo,
    /// The up axis `solve` and `flatten` take, and what says so.
    up: (crate::scene::Up, &'static str),
    /// One per table.
    tables: Vec<TableLine>,
}

/// What `info` says of one original's tables.
struct TableLine {
    name: String,
    tau: u32,
    incoming: u32,
    outgoing: u32,
    /// Polygons whose first scattering is kept apart, and the side of their grid.
    scatterers: u32,
    single_side: u32,
    bytes: u64,
    met: bool,
}

fn report<S: SceneSource>(format: Format, v: &SceneView<S>) -> Result<Report> {
    let info = *v.info();
    let mut r = Report {
        format,
        bands: info.bands,
        band_names: Vec::new(),
        materials: info.materials,
        two_sided: 0,
        emitting: 0,
        info,
        up: (crate::scene::Up::Y, "the OBJ convention"),
        tables: Vec::new(),
    };
    if format != Format::Obj {
        let camera = if info.cameras > 0 {
            Some(v.camera(hirad_core::CameraId(0))?.up)
        } else {
            None
        };
        let sky = (0..info.sky)
            .map(|i| v.sky(hirad_core::LightId(i)))
            .collect::<Result<Vec<_>, _>>()?;
        r.up = crate::scene::Up::of_parts(camera, &sky, info.bands as usize);
    }
    let mut buf = [0u8; MAX_NAME_BYTES];
    for b in 0..info.bands {
        if let Some(id) = v.band_name(b)? {
            r.band_names.push(v.string(id, &mut buf)?.to_string());
        }
    }
    for t in 0..info.tables {
        let rec = v.table(t)?;
        let o = v.original(hirad_core::OriginalId(rec.original))?;
        let name = v
            .string(hirad_core::StringId(o.name), &mut buf)?
            .to_string();
        r.tables.push(TableLine {
            name,
            tau: rec.tau_side,
            incoming: rec.incoming_side,
            outgoing: rec.outgoing_side,
            scatterers: rec.scatterers,
            single_side: rec.single_side,
            bytes: 4 * rec.values() + rec.visible_bytes(),
            met: rec.flags & hirad_core::image::TABLE_MET != 0,
        });
    }
    for m in 0..info.materials {
        let d = v.material(MaterialId(m))?;
        let n = d.bands as usize;
        r.two_sided += d.two_sided as u32;
        r.emitting += (d.emit_front[..n]
            .iter()
            .chain(&d.emit_back[..n])
            .any(|&e| e > 0.0)) as u32;
    }
    Ok(r)
}

/// Runs `hirad info`.
pub fn run(a: Args) -> Result<()> {
    let format = Format::of(&a.scene).map_err(crate::exit::input)?;
    let r = if format == Format::Binary {
        report(format, &files::open_image(&a.scene)?).map_err(crate::exit::input)?
    } else {
        let loaded = files::load_scene(&a.scene)?;
        super::warn_all(&loaded.warnings, loaded.warnings_total, a.quiet);
        let bytes = files::compile(&a.scene, &loaded.scene)?;
        let view = crate::scene::read_image(&bytes)
            .map_err(|e| crate::exit::input(anyhow::anyhow!("{}: {e}", a.scene.display())))?;
        report(format, &view)?
    };
    let text = if a.json {
        json(&a.scene, &r)
    } else {
        table(&a.scene, &r)
    };
    super::print_out(&text)
}

fn table(path: &std::path::Path, r: &Report) -> String {
    let i = &r.info;
    let mut s = String::new();
    let names = if r.band_names.is_empty() {
        String::new()
    } else {
        format!(" ({})", r.band_names.join(" "))
    };
    let _ = writeln!(s, "scene             {}", path.display());
    let _ = writeln!(s, "format            {}", r.format.name());
    let _ = writeln!(s, "bands             {}{names}", r.bands);
    let _ = writeln!(
        s,
        "materials         {} ({} two-sided, {} emitting)",
        r.materials, r.two_sided, r.emitting
    );
    let _ = writeln!(
        s,
        "polygons          {} (every instance expanded: what solve lights)",
        i.expanded_polygons
    );
    let _ = writeln!(
        s,
        "stored polygons   {} (in the file: each original once, plus the approximate instances' own), {} vertices",
        i.polygons, i.vertices
    );
    let _ = writeln!(s, "clusters          {}", i.clusters);
    let _ = writeln!(s, "originals         {}", i.originals);
    let _ = writeln!(
        s,
        "instances         {} ({} exact, {} approximate)",
        i.exact_instances + i.approximate_instances,
        i.exact_instances,
        i.approximate_instances
    );
    let _ = writeln!(s, "instancing depth  {}", i.instancing_depth);
    let _ = writeln!(
        s,
        "tables            {} of {} originals ({} bytes)",
        i.tables,
        i.originals,
        r.tables.iter().map(|t| t.bytes).sum::<u64>()
    );
    for t in &r.tables {
        let single = if t.scatterers > 0 {
            format!(
                ", first scattering of {} polygons on grid {}",
                t.scatterers, t.single_side
            )
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "  {}: tau grid {}, phase {} x {}{single}, {} bytes{}",
            t.name,
            t.tau,
            t.incoming,
            t.outgoing,
            t.bytes,
            if t.met { "" } else { ", error targets not met" }
        );
    }
    let _ = writeln!(s, "cluster depth     {}", i.max_node_depth);
    let _ = writeln!(
        s,
        "lights            {}, {}",
        plural(i.suns as u64, "sun", "suns"),
        plural(i.sky as u64, "sky direction", "sky directions")
    );
    let _ = writeln!(s, "cameras           {}", i.cameras);
    let _ = writeln!(
        s,
        "up axis           {} ({}; --up changes it)",
        r.up.0.name(),
        r.up.1
    );
    let _ = writeln!(s, "binary image      {} bytes", i.image_bytes);
    s
}

fn json(path: &std::path::Path, r: &Report) -> String {
    let i = &r.info;
    let names: Vec<String> = r.band_names.iter().map(|n| json_str(n)).collect();
    format!(
        concat!(
            "{{\"scene\":{},\"format\":{},\"bands\":{},\"band_names\":[{}],\"materials\":{},",
            "\"two_sided_materials\":{},\"emitting_materials\":{},\"polygons\":{},\"stored_polygons\":{},",
            "\"vertices\":{},\"clusters\":{},\"originals\":{},\"exact_instances\":{},",
            "\"approximate_instances\":{},\"instancing_depth\":{},\"cluster_depth\":{},\"suns\":{},",
            "\"sky_directions\":{},\"cameras\":{},\"up_axis\":{},\"image_bytes\":{},\"tables\":[{}]}}\n"
        ),
        json_str(&path.display().to_string()),
        json_str(r.format.name()),
        r.bands,
        names.join(","),
        r.materials,
        r.two_sided,
        r.emitting,
        i.expanded_polygons,
        i.polygons,
        i.vertices,
        i.clusters,
        i.originals,
        i.exact_instances,
        i.approximate_instances,
        i.instancing_depth,
        i.max_node_depth,
        i.suns,
        i.sky,
        i.cameras,
        json_str(r.up.0.name()),
        i.image_bytes,
        r.tables
            .iter()
            .map(|t| format!(
                "{{\"original\":{},\"tau_side\":{},\"incoming_side\":{},\"outgoing_side\":{},\"scatterers\":{},\"single_side\":{},\"bytes\":{},\"met\":{}}}",
                json_str(&t.name),
                t.tau,
                t.incoming,
                t.outgoing,
                t.scatterers,
                t.single_side,
                t.bytes,
                t.met
            ))
            .collect::<Vec<_>>()
            .join(",")
    )
}

/// A JSON string literal.
pub(crate) fn json_str(s: &str) -> String {
    let mut o = String::with_capacity(s.len() + 2);
    o.push('"');
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(o, "\\u{:04x}", c as u32);
            }
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// `1 sun`, `2 suns`, `0 suns`.
pub(crate) fn plural(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}
