//! The OBJ side of an export: the expanded scene streamed node by node, world-space vertices,
//! faces in global-id order, `g` with the node's path, `usemtl` when the material changes.

use super::ObjExport;
use super::mtl_write::{material_names, sanitize, write_mtl};
use crate::scene::{ExpandVisitor, ExpandedNode, Scene, Up, expand};
use std::io::{self, BufWriter, Write};

/// Counts what the expansion will write, so that the header can say it up front.
#[derive(Default)]
struct Count {
    polygons: u64,
    vertices: u64,
}

impl ExpandVisitor for Count {
    type Error = std::convert::Infallible;
    fn node(&mut self, node: &ExpandedNode<'_>) -> Result<(), Self::Error> {
        if !node.cluster.polygons.is_empty() {
            self.polygons += node.cluster.polygons.len() as u64;
            self.vertices += node.cluster.vertices.len() as u64;
        }
        Ok(())
    }
}

/// Writes the nodes of the expansion as they come.
struct Writer<'a, W: Write> {
    out: W,
    names: &'a [String],
    /// The scene's up axis, written as +y.
    up: Up,
    /// OBJ vertices written so far (the next one is `vertices + 1`).
    vertices: u64,
    faces: u64,
    material: Option<u32>,
    /// A cluster name had to change to fit a `g` line.
    renamed_group: bool,
}

impl<W: Write> ExpandVisitor for Writer<'_, W> {
    type Error = io::Error;
    fn node(&mut self, node: &ExpandedNode<'_>) -> io::Result<()> {
        let c = node.cluster;
        if c.polygons.is_empty() {
            return Ok(());
        }
        self.group(node.path)?;
        for v in &c.vertices {
            let w = self.up.to_y_up(node.to_world.point(*v));
            writeln!(self.out, "v {} {} {}", w.x, w.y, w.z)?;
        }
        for p in &c.polygons {
            if self.material != Some(p.material) {
                let name = self.names.get(p.material as usize).ok_or_else(|| {
                    io::Error::new(io::ErrorKind::InvalidInput, "polygon without a material")
                })?;
                writeln!(self.out, "usemtl {name}")?;
                self.material = Some(p.material);
            }
            self.out.write_all(b"f")?;
            for &k in &p.corners[..p.corner_count()] {
                write!(self.out, " {}", self.vertices + u64::from(k) + 1)?;
            }
            self.out.write_all(b"\n")?;
            self.faces += 1;
        }
        self.vertices += c.vertices.len() as u64;
        Ok(())
    }
}

impl<W: Write> Writer<'_, W> {
    /// `g` with the node's path joined by `/`; unnamed nodes (`#3`) are written `_3`.
    fn group(&mut self, path: &[String]) -> io::Result<()> {
        self.out.write_all(b"g ")?;
        for (i, label) in path.iter().enumerate() {
            if i > 0 {
                self.out.write_all(b"/")?;
            }
            let clean = sanitize(label, true);
            let generated = label
                .strip_prefix('#')
                .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()));
            if clean != *label && !generated {
                self.renamed_group = true;
            }
            self.out.write_all(clean.as_bytes())?;
        }
        self.out.write_all(b"\n")
    }
}

/// What OBJ/MTL cannot hold about the scene as a whole.
fn scene_warnings(scene: &Scene, out: &mut Vec<String>) {
    let mut lost = |n: usize, what: &str| {
        if n > 0 {
            out.push(format!("{n} {what} cannot be written to OBJ and are lost"));
        }
    };
    lost(scene.suns.len(), "sun(s)");
    lost(scene.sky.len(), "sky direction(s)");
    lost(scene.cameras.len(), "camera(s)");
    if !scene.band_names.is_empty() {
        out.push(format!(
            "band names ({}) cannot be written to OBJ/MTL and are lost",
            scene.band_names.join(", ")
        ));
    }
}

/// See [`super::export`].
pub(crate) fn export(
    scene: &Scene,
    up: Up,
    mtl_name: &str,
    obj: &mut dyn Write,
    mtl: &mut dyn Write,
) -> io::Result<ObjExport> {
    if let Err(e) = scene.check() {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, e));
    }
    if mtl_name.is_empty() || sanitize(mtl_name, true) != mtl_name {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("'{mtl_name}' cannot be named in an OBJ mtllib line"),
        ));
    }
    let mut warnings = Vec::new();
    scene_warnings(scene, &mut warnings);
    let names = material_names(scene, &mut warnings);
    let mut mtl = BufWriter::new(mtl);
    write_mtl(scene, &names, &mut mtl, &mut warnings)?;
    mtl.flush()?;

    let mut count = Count::default();
    let Ok(_) = expand(scene, &mut count);
    let mut w = Writer {
        out: BufWriter::new(obj),
        names: &names,
        up,
        vertices: 0,
        faces: 0,
        material: None,
        renamed_group: false,
    };
    writeln!(
        w.out,
        "# hirad flatten: {} polygons, {} vertices, {} materials",
        count.polygons,
        count.vertices,
        scene.materials.len()
    )?;
    writeln!(
        w.out,
        "# Face k (1-based, in file order) is the polygon with global id k-1."
    )?;
    if up != Up::Y {
        writeln!(
            w.out,
            "# The scene's {} axis is written as +y, the OBJ convention (a rotation).",
            up.name()
        )?;
    }
    writeln!(w.out, "mtllib {mtl_name}")?;
    expand(scene, &mut w)?;
    w.out.flush()?;
    if w.renamed_group {
        warnings.push(
            "cluster names with '#', control characters or a trailing '\\' were written \
             with '_' in their place"
                .to_string(),
        );
    }
    Ok(ObjExport {
        faces: w.faces,
        vertices: w.vertices,
        warnings,
    })
}
