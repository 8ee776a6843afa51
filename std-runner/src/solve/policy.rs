//! Which originals `--method hi` closes and which it expands in place (`--instancing`, the
//! paper's section 4 "Instantiation policy"): a bit set over originals for the core
//! ([`hr::Inline`]) and, for each original, what was chosen and why.
//!
//! An original expanded in place puts its contents into the level of its parent (its own
//! instances closed or expanded by the same rule): a level skipped, as in the paper's
//! figure 4. `every:N` closes the instances at instancing depths 1, N + 1, 2N + 1, ...;
//! `auto` closes every original except those whose tables could not stand for them: an
//! original that emits light (tables carry no emission), one too small to be worth a level
//! of its own (fewer than [`AUTO_LEVEL_POLYGONS`] polygons expanded: exact and cheaper in
//! its parent's level, the paper's skipped levels), and one the scene has no tables for
//! whose bake would take long (more than [`AUTO_BAKE_POLYGONS`] polygons expanded).

use anyhow::{Result, anyhow, bail};
use hirad_core::hr::Inline;
use hirad_core::image::{SceneSource, SceneView};
use hirad_core::{MaterialId, NodeId, OriginalId, PolyId};
use std::str::FromStr;

/// Originals with more polygons than this once expanded, and no tables in the scene, are
/// expanded in place by `auto`: one hr solve of an original of 11,611 polygons takes about
/// 22 s at the tables' epsilon, and its bake needs 80 to 1,000 of them.
pub const AUTO_BAKE_POLYGONS: u64 = 8_000;

/// What a policy that closes an original without tables in the scene adds to its reason
/// when the bake before the solve will take long (more than [`AUTO_BAKE_POLYGONS`]).
fn long_bake(closed: bool, has_tables: bool, polygons: u64) -> String {
    if closed && !has_tables && polygons > AUTO_BAKE_POLYGONS {
        format!(
            "; no tables in the scene: baking {polygons} polygons before the solve takes long (hours at the defaults; `hirad tables --max-side N` bakes coarser ones)"
        )
    } else {
        String::new()
    }
}

/// Originals with fewer polygons than this once expanded are expanded in place by `auto`,
/// tables or not: a level of its own costs a load, a census, links copied, a solve and a
/// gather for a handful of polygons, and as a closed leaf in its parent it costs about as
/// much as its polygons there (the paper poplar's shoot, 27 polygons, has 286,735
/// instances in the paper stand: that many levels, against about 15,000 without them).
pub const AUTO_LEVEL_POLYGONS: u64 = 64;

/// Polygon area of its siblings inside a closed instance's box, over its own (mean over an
/// original's instances, see `overlap`), above which the printout says so.
pub const OVERLAP_NOTED: f32 = 1.0;

/// `--instancing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Policy {
    /// Every instance closed through its original's tables at its parent's level, and
    /// opened in turn (the paper's figure 2).
    All,
    /// Every instance expanded: hierarchical radiosity over the whole scene (`--method hr`).
    None,
    /// The instances at instancing depths 1, N + 1, 2N + 1, ... closed, the others expanded
    /// in place (the paper's "every other level" for N = 2).
    Every(u32),
    /// Closed unless tables cannot stand for the original (see the module documentation).
    Auto,
}

impl FromStr for Policy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "all" => Ok(Policy::All),
            "none" => Ok(Policy::None),
            "auto" => Ok(Policy::Auto),
            _ => match s.strip_prefix("every:").map(str::parse::<u32>) {
                Some(Ok(n)) if (1..=64).contains(&n) => Ok(Policy::Every(n)),
                _ => Err(format!(
                    "'{s}' is not an instancing policy: all, none, auto or every:N (N from 1 to 64)"
                )),
            },
        }
    }
}

impl std::fmt::Display for Policy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Policy::All => write!(f, "all"),
            Policy::None => write!(f, "none"),
            Policy::Every(n) => write!(f, "every:{n}"),
            Policy::Auto => write!(f, "auto"),
        }
    }
}

/// Polygons (expanded) of one original's instances above which a scene without its tables
/// is still solved with hi by default: hr holds about a kilobyte per polygon (the paper
/// stand's 1.21 million took 1.18 GB).
pub const HI_DEFAULT_POLYGONS: u64 = 1_000_000;

/// What the policy chose for one original.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    /// The original's name.
    pub name: String,
    /// Its instances in the expanded scene (each instance of an original that holds it
    /// counts its own).
    pub instances: u64,
    /// Its polygons once expanded.
    pub polygons: u64,
    /// The fewest instances between the scene's root and one of its instances, itself
    /// included (1: instanced in the scene's own tree); 0 when it is not instanced.
    pub depth: u32,
    /// True when its polygons (expanded) include emitting ones.
    pub emits: bool,
    /// True when the scene carries its tables.
    pub has_tables: bool,
    /// Closed (true) or expanded in place.
    pub closed: bool,
    /// Where closed: its siblings' polygon area inside its instances' boxes over its own
    /// (mean over its instances, see `overlap`).
    pub overlap: Option<f32>,
    /// Why, in a few words.
    pub why: String,
}

/// The policy applied to a scene.
#[derive(Clone, Debug)]
pub struct Decision {
    /// The policy.
    pub policy: Policy,
    /// One bit per original, set when it is expanded in place (see [`hr::Inline`]).
    pub inline: Vec<u8>,
    /// Per original, in order.
    pub originals: Vec<Choice>,
}

impl Decision {
    /// The bit set for the core.
    pub fn inline(&self) -> Inline<'_> {
        Inline::new(&self.inline)
    }

    /// The originals closed somewhere in the scene (instanced, not expanded in place).
    pub fn closed(&self) -> impl Iterator<Item = usize> + '_ {
        self.originals
            .iter()
            .enumerate()
            .filter(|(_, c)| c.closed && c.instances > 0)
            .map(|(k, _)| k)
    }

    /// Whether `hirad solve` without `--method` solves with hi: the policy closes an
    /// original whose tables the scene carries, or one whose instances hold more than
    /// [`HI_DEFAULT_POLYGONS`] polygons once expanded (more than hr holds in a sensible
    /// memory). Otherwise hi would first make tables that hr does not need (minutes per
    /// original), so the default is hr.
    pub fn hi_by_default(&self) -> bool {
        self.originals.iter().any(|c| {
            c.closed
                && c.instances > 0
                && (c.has_tables || c.instances.saturating_mul(c.polygons) > HI_DEFAULT_POLYGONS)
        })
    }

    /// The first original the policy closes although it emits light: its tables carry
    /// none, so its light would be lost.
    pub fn closed_emitter(&self) -> Option<&Choice> {
        self.originals
            .iter()
            .find(|c| c.closed && c.emits && c.instances > 0)
    }

    /// One line per instanced original: what was chosen and why.
    pub fn describe(&self) -> String {
        let mut s = format!("instancing {}:", self.policy);
        for c in self.originals.iter().filter(|c| c.instances > 0) {
            s.push_str(&format!(
                "\n  {}: {} ({} instances, {} polygons expanded, depth {}): {}",
                c.name,
                if c.closed {
                    "closed"
                } else {
                    "expanded in place"
                },
                c.instances,
                c.polygons,
                c.depth,
                c.why
            ));
        }
        s
    }
}

/// What the scene says of each original: instances, depth, emission (see [`Choice`]).
struct Facts {
    instances: Vec<u64>,
    depth: Vec<u32>,
    emits: Vec<bool>,
}

/// An instance found in a holder's tree: its original, its depth below the holder (1 plus
/// the approximate instances around it, whose own nodes lie in the tree) and whether it is
/// exact (its original's tree is what it expands to).
type Found = (u32, u32, bool);

/// Walks node `root`'s subtree by index: every instance node in it (see [`Found`]), and
/// whether any of the subtree's own polygons emits.
fn scan<S: SceneSource>(
    view: &SceneView<S>,
    root: u32,
    emitting: &[bool],
    found: &mut Vec<Found>,
) -> Result<bool> {
    let err = |e| anyhow!("{e}");
    let end = view.node(NodeId(root)).map_err(err)?.subtree_end;
    // Ends of the approximate instances' subtrees the walk is inside.
    let mut inside: Vec<u32> = Vec::new();
    let mut emits = false;
    let mut i = root;
    while i < end {
        while inside.last().is_some_and(|&e| e <= i) {
            inside.pop();
        }
        let rec = view.node(NodeId(i)).map_err(err)?;
        let mut polys = vec![hirad_core::image::PolygonRecord::default(); rec.poly_count as usize];
        view.polygons(PolyId(rec.poly_first), &mut polys)
            .map_err(err)?;
        emits |= polys
            .iter()
            .any(|p| emitting.get(p.material as usize).copied().unwrap_or(false));
        if let Some(id) = rec.instance()
            && i != root
        {
            let inst = view.instance(id).map_err(err)?;
            found.push((inst.original, inside.len() as u32 + 1, inst.is_exact()));
            if !inst.is_exact() {
                inside.push(rec.subtree_end);
            }
        }
        i += 1;
    }
    Ok(emits)
}

fn facts<S: SceneSource>(view: &SceneView<S>) -> Result<Facts> {
    let info = *view.info();
    let n = info.originals as usize;
    let err = |e| anyhow!("{e}");
    let emitting: Vec<bool> = (0..info.materials)
        .map(|m| {
            view.material(MaterialId(m)).map(|d| {
                (0..d.bands as usize).any(|b| d.emit_front[b] > 0.0 || d.emit_back[b] > 0.0)
            })
        })
        .collect::<Result<_, _>>()
        .map_err(err)?;
    // Per holder (the scene, then each original): what it instances, at which depth below it.
    let mut held: Vec<Vec<Found>> = Vec::with_capacity(n + 1);
    let mut own_emits = Vec::with_capacity(n);
    let mut found = Vec::new();
    scan(view, info.scene_root.0, &emitting, &mut found)?;
    held.push(std::mem::take(&mut found));
    for k in 0..n {
        let root = view.original(OriginalId(k as u32)).map_err(err)?.root;
        own_emits.push(scan(view, root, &emitting, &mut found)?);
        if let Some(&(j, _, _)) = found.iter().find(|&&(j, _, _)| j as usize >= k) {
            bail!("original {k} holds original {j}, which does not come before it");
        }
        held.push(std::mem::take(&mut found));
    }
    // Emission, inner originals first (an original holds only originals before it); an
    // approximate instance's own polygons were scanned with its holder.
    let mut emits = own_emits;
    for k in 0..n {
        if held[k + 1].iter().any(|&(j, _, e)| e && emits[j as usize]) {
            emits[k] = true;
        }
    }
    // Instances and depth, outer holders first: the scene, then the originals downwards.
    // An original's own tree is expanded once per exact instance (an approximate one
    // expands to its own nodes, which its holder's walk counted).
    let mut instances = vec![0u64; n];
    let mut exact = vec![0u64; n];
    let mut depth = vec![0u32; n];
    let visit = |count: u64,
                 base: u32,
                 list: &[Found],
                 instances: &mut [u64],
                 exact: &mut [u64],
                 depth: &mut [u32]| {
        for &(j, d, is_exact) in list {
            let j = j as usize;
            instances[j] = instances[j].saturating_add(count);
            if is_exact {
                exact[j] = exact[j].saturating_add(count);
            }
            let at = base + d;
            if depth[j] == 0 || at < depth[j] {
                depth[j] = at;
            }
        }
    };
    visit(1, 0, &held[0], &mut instances, &mut exact, &mut depth);
    for k in (0..n).rev() {
        let times = exact[k];
        if times > 0 {
            let base = depth[k];
            visit(
                times,
                base,
                &held[k + 1],
                &mut instances,
                &mut exact,
                &mut depth,
            );
        }
    }
    Ok(Facts {
        instances,
        depth,
        emits,
    })
}

/// Applies `policy` to the scene of `view` (for [`Policy::None`], every original expanded),
/// with the originals named in `expand` expanded in place whatever it says (an unknown
/// name is an error that lists the scene's originals).
pub fn decide<S: SceneSource>(
    view: &SceneView<S>,
    policy: Policy,
    expand: &[String],
) -> Result<Decision> {
    let info = *view.info();
    let n = info.originals as usize;
    let f = facts(view)?;
    let err = |e| anyhow!("{e}");
    let mut originals = Vec::with_capacity(n);
    let mut inline = vec![0u8; Inline::bytes(info.originals)];
    for k in 0..n {
        let rec = view.original(OriginalId(k as u32)).map_err(err)?;
        let mut buf = vec![
            0u8;
            view.string_len(hirad_core::StringId(rec.name))
                .map_err(err)?
        ];
        let name = view
            .string(hirad_core::StringId(rec.name), &mut buf)
            .map_err(err)?
            .to_string();
        let has_tables = view.table_of(OriginalId(k as u32)).map_err(err)?.is_some();
        let (polygons, depth, emits) = (rec.expanded_polygons, f.depth[k], f.emits[k]);
        let (closed, why) = match policy {
            Policy::All => (
                true,
                format!("all{}", long_bake(true, has_tables, polygons)),
            ),
            Policy::None => (false, "none".to_string()),
            Policy::Every(m) => {
                let closed = depth >= 1 && (depth - 1) % m == 0;
                (
                    closed,
                    format!(
                        "every:{m}: depth {depth} is {}a level of instances{}",
                        if closed { "" } else { "not " },
                        long_bake(closed, has_tables, polygons)
                    ),
                )
            }
            Policy::Auto if emits => (
                false,
                "it emits light, which tables do not carry".to_string(),
            ),
            Policy::Auto if polygons < AUTO_LEVEL_POLYGONS => (
                false,
                format!(
                    "{polygons} polygons (fewer than {AUTO_LEVEL_POLYGONS}) are cheaper in place than a level of their own"
                ),
            ),
            Policy::Auto if has_tables => (true, "the scene has its tables".to_string()),
            Policy::Auto if polygons > AUTO_BAKE_POLYGONS => (
                false,
                format!(
                    "no tables in the scene, and baking {polygons} polygons (more than {AUTO_BAKE_POLYGONS}) takes long"
                ),
            ),
            Policy::Auto => (
                true,
                format!("no tables in the scene yet; {polygons} polygons bake in minutes"),
            ),
        };
        originals.push(Choice {
            name,
            instances: f.instances[k],
            polygons,
            depth,
            emits,
            has_tables,
            closed,
            overlap: None,
            why,
        });
    }
    if let Some(name) = expand
        .iter()
        .find(|n| !originals.iter().any(|c| &c.name == *n))
    {
        let names: Vec<&str> = originals.iter().map(|c| c.name.as_str()).collect();
        bail!(
            "--expand {name}: the scene has no original of that name (it has: {})",
            if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            }
        );
    }
    for c in originals.iter_mut() {
        if c.closed && expand.contains(&c.name) {
            c.closed = false;
            c.why = "--expand names it".to_string();
        }
    }
    note_overlap(view, &mut originals)?;
    for (k, c) in originals.iter().enumerate() {
        if !c.closed {
            inline[k / 8] |= 1 << (k % 8);
        }
    }
    Ok(Decision {
        policy,
        inline,
        originals,
    })
}

/// Notes, for every closed original, how much of its instances' boxes their siblings'
/// polygons fill (see `overlap`): where they fill much, its tables (measured on it alone)
/// stand in for contents whose light mixes with its neighbours', and `--expand` may serve.
fn note_overlap<S: SceneSource>(view: &SceneView<S>, originals: &mut [Choice]) -> Result<()> {
    if !originals.iter().any(|c| c.closed && c.instances > 0) {
        return Ok(());
    }
    let closed: Vec<bool> = originals
        .iter()
        .map(|c| c.closed && c.instances > 0)
        .collect();
    let shares = super::overlap::overlaps(view, &closed)?;
    for (c, share) in originals.iter_mut().zip(shares) {
        if let (true, Some(share)) = (c.closed, share) {
            c.overlap = Some(share);
            if share > OVERLAP_NOTED {
                c.why.push_str(&format!(
                    "; its siblings' polygons inside its box hold {:.1} times its own area (their light mixes; --expand {} opens them together)",
                    share, c.name
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plant() -> Vec<u8> {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/small_plant.hir");
        let scene = crate::files::load_scene(&path).unwrap().scene;
        crate::scene::compile(&scene).unwrap()
    }

    #[test]
    fn hi_is_the_default_where_tables_are_carried_or_instances_too_many() {
        let choice = |instances: u64, polygons: u64, has_tables: bool, closed: bool| Choice {
            name: "o".into(),
            instances,
            polygons,
            depth: 1,
            emits: false,
            has_tables,
            closed,
            overlap: None,
            why: String::new(),
        };
        let decision = |originals: Vec<Choice>| Decision {
            policy: Policy::Auto,
            inline: Vec::new(),
            originals,
        };
        let many = HI_DEFAULT_POLYGONS / 1000 + 1;
        for (originals, hi) in [
            (vec![choice(10, 500, true, true)], true),
            (vec![choice(10, 500, false, true)], false),
            (vec![choice(many, 1000, false, true)], true),
            (vec![choice(many, 1000, false, false)], false),
            (vec![choice(10, 500, true, false)], false),
            (vec![choice(0, 500, true, true)], false),
            (
                vec![choice(10, 500, false, true), choice(3, 80, true, true)],
                true,
            ),
            (Vec::new(), false),
        ] {
            assert_eq!(
                decision(originals.clone()).hi_by_default(),
                hi,
                "{originals:?}"
            );
        }
    }

    #[test]
    fn a_policy_that_closes_a_large_original_without_tables_says_the_bake_is_long() {
        let big = AUTO_BAKE_POLYGONS + 1;
        assert!(long_bake(true, false, big).contains("takes long"));
        for (closed, has_tables, polygons) in [
            (false, false, big),
            (true, true, big),
            (true, false, AUTO_BAKE_POLYGONS),
        ] {
            assert_eq!(long_bake(closed, has_tables, polygons), "");
        }
    }

    #[test]
    fn policies_parse_and_print_back() {
        for p in [
            Policy::All,
            Policy::None,
            Policy::Auto,
            Policy::Every(1),
            Policy::Every(64),
        ] {
            assert_eq!(p.to_string().parse::<Policy>(), Ok(p));
        }
        for bad in [
            "every:0", "every:65", "every:", "every:x", "some", "ALL", "",
        ] {
            let e = bad.parse::<Policy>().unwrap_err();
            assert!(e.contains("all, none, auto or every:N"), "{bad}: {e}");
        }
    }

    #[test]
    fn the_plants_originals_by_depth() {
        // The plant: 5 approximate branches in the scene's tree, 4 twigs in each.
        let bytes = plant();
        let view = crate::scene::read_image(&bytes).unwrap();
        let closed = |p: Policy| -> Vec<(String, bool, u32, u64)> {
            decide(&view, p, &[])
                .unwrap()
                .originals
                .into_iter()
                .map(|c| (c.name, c.closed, c.depth, c.instances))
                .collect()
        };
        let both = |t: bool, b: bool| {
            vec![
                ("twig".to_string(), t, 2, 20),
                ("branch".to_string(), b, 1, 5),
            ]
        };
        assert_eq!(closed(Policy::All), both(true, true));
        // Closed, each has its siblings' share noted; expanded, none.
        let all = decide(&view, Policy::All, &[]).unwrap();
        for c in &all.originals {
            let f = c.overlap.expect("a closed original's share");
            assert!(f.is_finite() && f >= 0.0, "{c:?}");
        }
        let none = decide(&view, Policy::None, &[]).unwrap();
        assert!(none.originals.iter().all(|c| c.overlap.is_none()));
        assert_eq!(closed(Policy::Every(1)), both(true, true));
        assert_eq!(closed(Policy::Every(2)), both(false, true));
        assert_eq!(closed(Policy::None), both(false, false));
        // Both fewer than 64 polygons expanded: auto expands them in place.
        let auto = decide(&view, Policy::Auto, &[]).unwrap();
        assert!(
            auto.originals
                .iter()
                .all(|c| !c.closed && !c.emits && !c.has_tables && c.polygons < 64),
            "{:?}",
            auto.originals
        );
        assert!(auto.closed_emitter().is_none());
        assert_eq!(auto.closed().count(), 0);
        // The bits for the core: set where expanded in place.
        let every2 = decide(&view, Policy::Every(2), &[]).unwrap();
        assert!(every2.inline().expands(0) && !every2.inline().expands(1));
        assert_eq!(every2.closed().collect::<Vec<_>>(), vec![1]);
        let text = every2.describe();
        assert!(
            text.contains("twig: expanded in place (20 instances, 4 polygons expanded, depth 2)"),
            "{text}"
        );
    }
}
