//! Checks of the model before it is compiled, with errors that name where in the scene tree
//! the fault is. Every physical and geometric rule is the core's own.

use super::{Cluster, Scene, too_small_message};
use hirad_core::geometry::{
    Aabb, ShapeError, Similarity, UNIT_TOLERANCE, camera_ok, polygon_shape,
};
use hirad_core::limits::{MAX_BANDS, MAX_INSTANCING_DEPTH, MAX_NAME_BYTES, MAX_NODE_DEPTH, NONE};
use std::fmt;

/// A fault in a scene model, located by its path in the tree.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    /// Where: e.g. `original 'chair' > cluster 'seat' > polygon 3`.
    pub path: String,
    /// What.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.path, self.message)
        }
    }
}

impl std::error::Error for SceneError {}

fn fail<T>(path: &str, message: impl Into<String>) -> Result<T, SceneError> {
    Err(SceneError {
        path: path.to_string(),
        message: message.into(),
    })
}

fn check_name(path: &str, what: &str, name: &str) -> Result<(), SceneError> {
    if name.len() > MAX_NAME_BYTES {
        return fail(
            path,
            format!("{what} name is longer than {MAX_NAME_BYTES} bytes"),
        );
    }
    Ok(())
}

/// Path label of a cluster: its name if it has one, else its child index.
pub(crate) fn cluster_label(c: &Cluster, index: usize) -> String {
    let kind = if c.instance.is_some() {
        "instance"
    } else {
        "cluster"
    };
    match &c.name {
        Some(n) => format!("{kind} '{n}'"),
        None => format!("{kind} #{index}"),
    }
}

/// What a checked tree stands for: the same derived values the image stores (see
/// `compile`), so that every scene `check` accepts compiles.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TreeSummary {
    pub expanded: u64,
    pub depth: u32,
    /// The box the image stores for this node (in its parent's frame).
    pub bbox: Aabb,
    /// False when the node's content is empty (its box then counts for nothing).
    pub contributes: bool,
}

impl Default for TreeSummary {
    fn default() -> Self {
        TreeSummary {
            expanded: 0,
            depth: 0,
            bbox: Aabb::EMPTY,
            contributes: false,
        }
    }
}

impl Scene {
    /// Checks every rule the binary image enforces, naming the faulty object.
    pub fn check(&self) -> Result<(), SceneError> {
        if self.bands == 0 || self.bands as usize > MAX_BANDS {
            return fail(
                "",
                format!("{} bands; 1 to {MAX_BANDS} are supported", self.bands),
            );
        }
        if !self.band_names.is_empty() && self.band_names.len() != self.bands as usize {
            return fail(
                "",
                format!(
                    "{} band names for {} bands",
                    self.band_names.len(),
                    self.bands
                ),
            );
        }
        for n in &self.band_names {
            check_name("bands", "band", n)?;
        }
        for (i, m) in self.materials.iter().enumerate() {
            let path = format!("material '{}'", m.name);
            check_name(&path, "material", &m.name)?;
            if m.data.bands != self.bands {
                return fail(
                    &path,
                    format!("has {} bands, the scene has {}", m.data.bands, self.bands),
                );
            }
            if let Err(e) = m.data.check() {
                return fail(&path, e.to_string());
            }
            if self.materials[..i].iter().any(|o| o.name == m.name) {
                return fail(&path, "defined twice");
            }
        }
        for (i, o) in self.originals.iter().enumerate() {
            check_name(&format!("original '{}'", o.name), "original", &o.name)?;
            if self.originals[..i].iter().any(|p| p.name == o.name) {
                return fail(&format!("original '{}'", o.name), "defined twice");
            }
        }
        let order = original_order(self)?;
        let mut summaries = vec![TreeSummary::default(); self.originals.len()];
        for &k in &order {
            let o = &self.originals[k];
            summaries[k] =
                self.check_tree(&format!("original '{}'", o.name), &o.root, &summaries)?;
        }
        self.check_tree("scene", &self.root, &summaries)?;
        for (kind, lights) in [("sun", &self.suns), ("sky direction", &self.sky)] {
            for (i, l) in lights.iter().enumerate() {
                let path = format!("{kind} {i}");
                if !l.towards.is_finite()
                    || (l.towards.length_squared() - 1.0).abs() > UNIT_TOLERANCE
                {
                    return fail(&path, "direction must be a unit vector");
                }
                let irr = &l.irradiance[..self.bands as usize];
                if irr.iter().any(|v| !v.is_finite() || *v < 0.0) {
                    return fail(&path, "irradiance must be finite and >= 0");
                }
                if l.irradiance[self.bands as usize..]
                    .iter()
                    .any(|v| v.to_bits() != 0)
                {
                    return fail(&path, "irradiance values past the band count must be 0");
                }
            }
        }
        for (i, c) in self.cameras.iter().enumerate() {
            let path = match &c.name {
                Some(n) => format!("camera '{n}'"),
                None => format!("camera {i}"),
            };
            if let Some(n) = &c.name {
                check_name(&path, "camera", n)?;
            }
            if !camera_ok(c.position, c.target, c.up, c.fovy_deg) {
                return fail(
                    &path,
                    "unusable: needs finite values, eye away from target, up not along the view, 0 < fovy < 180",
                );
            }
        }
        Ok(())
    }

    /// Checks one tree; `done` holds the summaries of originals checked before (in
    /// dependency order, so every original an instance refers to is already summarised).
    pub(crate) fn check_tree(
        &self,
        path: &str,
        root: &Cluster,
        done: &[TreeSummary],
    ) -> Result<TreeSummary, SceneError> {
        if root.instance.is_some() {
            return fail(path, "the root of a tree cannot be an instance");
        }
        self.check_node(path, root, 1, done)
    }

    fn check_node(
        &self,
        path: &str,
        c: &Cluster,
        depth: usize,
        done: &[TreeSummary],
    ) -> Result<TreeSummary, SceneError> {
        if depth > MAX_NODE_DEPTH {
            return fail(
                path,
                format!("clusters nested deeper than {MAX_NODE_DEPTH} levels"),
            );
        }
        if let Some(n) = &c.name {
            check_name(path, "cluster", n)?;
        }
        if let Some(age) = c.age
            && !(age.is_finite() && age >= 0.0)
        {
            return fail(path, "age must be finite and >= 0");
        }
        if c.axis == Some(NONE) {
            return fail(path, format!("axis kind {NONE} is reserved"));
        }
        if c.vertices.len() >= NONE as usize || c.polygons.len() >= NONE as usize {
            return fail(path, "too many vertices or polygons in one cluster");
        }
        for (i, v) in c.vertices.iter().enumerate() {
            if !v.is_finite() {
                return fail(
                    &format!("{path} > vertex {i}"),
                    "coordinate is not a finite number",
                );
            }
        }
        for (i, p) in c.polygons.iter().enumerate() {
            let ppath = format!("{path} > polygon {i}");
            let n = p.corner_count();
            let mut corners = [glam::Vec3::ZERO; 4];
            for (k, corner) in corners.iter_mut().enumerate().take(n) {
                match c.vertices.get(p.corners[k] as usize) {
                    Some(v) => *corner = *v,
                    None => {
                        return fail(
                            &ppath,
                            format!(
                                "corner {k} refers to vertex {}, which does not exist",
                                p.corners[k]
                            ),
                        );
                    }
                }
            }
            if p.material as usize >= self.materials.len() {
                return fail(&ppath, format!("material {} does not exist", p.material));
            }
            match polygon_shape(&corners[..n]) {
                Ok(_) => {}
                Err(ShapeError::TooSmall) => {
                    return fail(&ppath, too_small_message("the polygon", &corners[..n]));
                }
                Err(e) => return fail(&ppath, e.to_string()),
            }
        }
        let mut own = Aabb::EMPTY;
        for v in &c.vertices {
            own.include(*v);
        }
        let mut acc = TreeSummary {
            expanded: c.polygons.len() as u64,
            depth: 0,
            bbox: own,
            contributes: false,
        };
        for (i, child) in c.children.iter().enumerate() {
            let cpath = format!("{path} > {}", cluster_label(child, i));
            let s = self.check_node(&cpath, child, depth + 1, done)?;
            acc.expanded = match acc.expanded.checked_add(s.expanded) {
                Some(e) => e,
                None => return fail(path, "expands to more than 2^64 polygons"),
            };
            if s.contributes {
                acc.bbox = acc.bbox.union(s.bbox);
            }
            acc.depth = acc.depth.max(s.depth);
        }
        let computed = match &c.instance {
            None => acc,
            Some(inst) => {
                let Some(o) = self.originals.get(inst.original) else {
                    return fail(path, format!("original {} does not exist", inst.original));
                };
                let t = &inst.transform;
                if let Err(e) = Similarity::checked(t.rotation, t.translation, t.scale) {
                    return fail(path, e.to_string());
                }
                let target = done.get(inst.original).copied().unwrap_or_default();
                let root_box = if target.expanded == 0 {
                    Aabb::EMPTY
                } else {
                    t.aabb(&target.bbox)
                };
                if inst.exact {
                    if !c.polygons.is_empty() || !c.children.is_empty() || !c.vertices.is_empty() {
                        return fail(
                            path,
                            format!(
                                "an exact instance of '{}' cannot hold geometry of its own",
                                o.name
                            ),
                        );
                    }
                    TreeSummary {
                        expanded: target.expanded,
                        depth: target.depth + 1,
                        bbox: root_box,
                        contributes: false,
                    }
                } else {
                    TreeSummary {
                        expanded: acc.expanded,
                        depth: acc.depth + 1,
                        bbox: t.aabb(&acc.bbox).union(root_box),
                        contributes: false,
                    }
                }
            }
        };
        if computed.depth > MAX_INSTANCING_DEPTH {
            return fail(
                path,
                format!("instances nested deeper than {MAX_INSTANCING_DEPTH} levels"),
            );
        }
        if computed.bbox != Aabb::EMPTY && !computed.bbox.is_finite_nonempty() {
            return fail(
                path,
                "its placement puts geometry beyond the range of 32-bit floats",
            );
        }
        // The box the image stores: the content's, or a zero box for empty content.
        let contributes = computed.bbox != Aabb::EMPTY;
        let bbox = if contributes {
            computed.bbox
        } else {
            Aabb::new(glam::Vec3::ZERO, glam::Vec3::ZERO)
        };
        Ok(TreeSummary {
            bbox,
            contributes,
            ..computed
        })
    }
}

/// Every original referenced by an instance anywhere in `c`.
pub(crate) fn references(c: &Cluster, out: &mut Vec<usize>) {
    let mut stack = vec![c];
    while let Some(n) = stack.pop() {
        if let Some(i) = &n.instance {
            out.push(i.original);
        }
        stack.extend(n.children.iter().rev());
    }
}

/// Originals in dependency order (an original after every original it instances), stable
/// with respect to the model's order. Refuses cycles, naming them.
pub(crate) fn original_order(scene: &Scene) -> Result<Vec<usize>, SceneError> {
    let n = scene.originals.len();
    let mut deps: Vec<Vec<usize>> = Vec::with_capacity(n);
    for o in &scene.originals {
        let mut r = Vec::new();
        references(&o.root, &mut r);
        if let Some(bad) = r.iter().find(|&&k| k >= n) {
            return fail(
                &format!("original '{}'", o.name),
                format!("instance of original {bad}, which does not exist"),
            );
        }
        deps.push(r);
    }
    // 0 = unvisited, 1 = on the current path, 2 = done. Iterative DFS: no recursion depth
    // driven by input.
    let mut state = vec![0u8; n];
    let mut order = Vec::with_capacity(n);
    for start in 0..n {
        if state[start] != 0 {
            continue;
        }
        let mut path: Vec<(usize, usize)> = vec![(start, 0)];
        state[start] = 1;
        while let Some(&mut (node, ref mut next)) = path.last_mut() {
            if let Some(&dep) = deps[node].get(*next) {
                *next += 1;
                match state[dep] {
                    0 => {
                        state[dep] = 1;
                        path.push((dep, 0));
                    }
                    1 => {
                        let from = path.iter().position(|&(k, _)| k == dep).unwrap_or(0);
                        let mut names: Vec<&str> = path[from..]
                            .iter()
                            .map(|&(k, _)| scene.originals[k].name.as_str())
                            .collect();
                        names.push(&scene.originals[dep].name);
                        return fail(
                            &format!("original '{}'", scene.originals[dep].name),
                            format!("instances form a cycle: {}", names.join(" -> ")),
                        );
                    }
                    _ => {}
                }
            } else {
                state[node] = 2;
                order.push(node);
                path.pop();
            }
        }
    }
    Ok(order)
}
