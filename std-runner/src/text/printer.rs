//! Scene -> `.hir` text. Deterministic, 2-space indentation, floats in Rust's shortest
//! round-trip form, so that parsing the output gives back the same scene bit for bit.
//! Trees are walked with an explicit stack: any model prints without deep recursion.

use super::names::spell;
use crate::scene::{Camera, Cluster, LightData, Material, Scene};
use glam::Quat;
use std::fmt::Write;

/// Prints a whole scene.
pub(crate) fn print(scene: &Scene) -> String {
    let mut out = String::new();
    out.push_str("hirad 1\n");
    let bands = scene.bands as usize;
    if scene.band_names.is_empty() {
        let _ = writeln!(out, "bands {bands}");
    } else {
        out.push_str("bands");
        for n in &scene.band_names {
            let _ = write!(out, " {}", spell(n));
        }
        out.push('\n');
    }
    section(&mut out, &scene.materials, |o, m| material(o, m, bands));
    section(&mut out, &scene.suns, |o, l| light(o, "sun", l, bands));
    section(&mut out, &scene.sky, |o, l| light(o, "sky", l, bands));
    section(&mut out, &scene.cameras, camera);
    for o in &scene.originals {
        out.push('\n');
        let mut header = format!("original {}", spell(&o.name));
        if let Some(n) = &o.root.name {
            let _ = write!(header, " name {}", spell(n));
        }
        tree(&mut out, scene, &o.root, header);
    }
    out.push('\n');
    let mut header = "scene".to_string();
    if let Some(n) = &scene.root.name {
        let _ = write!(header, " {}", spell(n));
    }
    tree(&mut out, scene, &scene.root, header);
    out
}

/// A blank line, then one line per item (nothing for an empty list).
fn section<T>(out: &mut String, items: &[T], mut line: impl FnMut(&mut String, &T)) {
    if !items.is_empty() {
        out.push('\n');
    }
    for item in items {
        line(out, item);
        out.push('\n');
    }
}

/// ` v0 v1 ...` for the first `n` values.
fn values(out: &mut String, v: &[f32], n: usize) {
    for x in v.iter().take(n) {
        let _ = write!(out, " {x}");
    }
}

/// True if every used value is +0 (so the field may be left out without changing a bit).
fn all_zero(v: &[f32], n: usize) -> bool {
    v.iter().take(n).all(|x| x.to_bits() == 0)
}

fn material(out: &mut String, m: &Material, bands: usize) {
    let d = &m.data;
    let _ = write!(out, "material {} rho", spell(&m.name));
    values(out, &d.rho_front, bands);
    if !all_zero(&d.emit_front, bands) {
        out.push_str(" emit");
        values(out, &d.emit_front, bands);
    }
    if d.two_sided {
        out.push_str(" back_rho");
        values(out, &d.rho_back, bands);
        if !all_zero(&d.tau, bands) {
            out.push_str(" tau");
            values(out, &d.tau, bands);
        }
        if !all_zero(&d.emit_back, bands) {
            out.push_str(" back_emit");
            values(out, &d.emit_back, bands);
        }
    }
}

fn light(out: &mut String, kind: &str, l: &LightData, bands: usize) {
    let t = l.towards;
    let _ = write!(out, "{kind} from {} {} {} irradiance", t.x, t.y, t.z);
    values(out, &l.irradiance, bands);
}

fn camera(out: &mut String, c: &Camera) {
    out.push_str("camera");
    if let Some(n) = &c.name {
        let _ = write!(out, " {}", spell(n));
    }
    let (p, t, u) = (c.position, c.target, c.up);
    let _ = write!(
        out,
        " pos {} {} {} target {} {} {} up {} {} {} fovy {}",
        p.x, p.y, p.z, t.x, t.y, t.z, u.x, u.y, u.z, c.fovy_deg
    );
}

/// The attributes every node may carry (`axis`, `age`).
fn node_attributes(out: &mut String, c: &Cluster) {
    if let Some(a) = c.axis {
        let _ = write!(out, " axis {a}");
    }
    if let Some(a) = c.age {
        let _ = write!(out, " age {a}");
    }
}

/// The header line of a child node (without its body).
fn child_header(scene: &Scene, c: &Cluster) -> String {
    let mut h = String::new();
    match &c.instance {
        None => {
            h.push_str("cluster");
            if let Some(n) = &c.name {
                let _ = write!(h, " {}", spell(n));
            }
            node_attributes(&mut h, c);
        }
        Some(i) => {
            let original = match scene.originals.get(i.original) {
                Some(o) => spell(&o.name),
                None => spell(&format!("#{}", i.original)),
            };
            let mode = if i.exact { "exact" } else { "approx" };
            let _ = write!(h, "instance {original} {mode}");
            if let Some(n) = &c.name {
                let _ = write!(h, " name {}", spell(n));
            }
            node_attributes(&mut h, c);
            let t = &i.transform;
            let v = t.translation;
            if v.to_array().iter().any(|x| x.to_bits() != 0) {
                let _ = write!(h, " translate {} {} {}", v.x, v.y, v.z);
            }
            let q = t.rotation;
            let identity = Quat::IDENTITY;
            if q.to_array().map(f32::to_bits) != identity.to_array().map(f32::to_bits) {
                let _ = write!(h, " quat {} {} {} {}", q.w, q.x, q.y, q.z);
            }
            if t.scale.to_bits() != 1.0f32.to_bits() {
                let _ = write!(h, " scale {}", t.scale);
            }
        }
    }
    h
}

enum Step<'a> {
    Open(&'a Cluster, usize, String),
    Close(usize),
}

/// Indentation stops growing past this level: valid trees are at most 64 deep, and an
/// absurdly deep model must not make the output quadratic in size.
const MAX_INDENT: usize = 80;

fn indent(out: &mut String, level: usize) {
    for _ in 0..level.min(MAX_INDENT) {
        out.push_str("  ");
    }
}

/// Prints a tree whose root line is `header` (the root's `axis`/`age` are appended here).
fn tree(out: &mut String, scene: &Scene, root: &Cluster, mut header: String) {
    node_attributes(&mut header, root);
    let mut stack = vec![Step::Open(root, 0, header)];
    while let Some(step) = stack.pop() {
        let (c, level, header) = match step {
            Step::Close(level) => {
                indent(out, level);
                out.push_str("}\n");
                continue;
            }
            Step::Open(c, level, header) => (c, level, header),
        };
        indent(out, level);
        out.push_str(&header);
        let exact = c.instance.is_some_and(|i| i.exact);
        let empty = c.vertices.is_empty() && c.polygons.is_empty() && c.children.is_empty();
        if empty {
            out.push_str(if exact { "\n" } else { " {}\n" });
            continue;
        }
        out.push_str(" {\n");
        for v in &c.vertices {
            indent(out, level + 1);
            let _ = writeln!(out, "v {} {} {}", v.x, v.y, v.z);
        }
        for p in &c.polygons {
            indent(out, level + 1);
            let material = match scene.materials.get(p.material as usize) {
                Some(m) => spell(&m.name),
                None => spell(&format!("#{}", p.material)),
            };
            let n = p.corner_count();
            let _ = write!(out, "{} {material}", if n == 3 { "tri" } else { "quad" });
            for k in p.corners.iter().take(n) {
                let _ = write!(out, " {k}");
            }
            out.push('\n');
        }
        stack.push(Step::Close(level));
        for child in c.children.iter().rev() {
            stack.push(Step::Open(child, level + 1, child_header(scene, child)));
        }
    }
}
