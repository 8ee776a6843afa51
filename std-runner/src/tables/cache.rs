//! Tables kept on disk between runs, keyed by a hash of what they depend on: the original's
//! expanded geometry in its own frame, each polygon's material values, the bands and the
//! table settings. An entry carries its key and a checksum of its contents; one that does
//! not read back whole, does not match, or holds values out of range is recomputed and
//! written again, never used.
//!
//! Where: `--cache DIR`, else `$HIRAD_CACHE`, else `$XDG_CACHE_HOME/hirad/tables`, else
//! `$HOME/.cache/hirad/tables`.

use super::OriginalTables;
use super::bake::TableSettings;
use super::original::Alone;
use crate::scene::Scene;
use anyhow::{Context, Result};
use hirad_core::image::TableRecord;
use std::path::{Path, PathBuf};

/// First bytes of an entry.
const MAGIC: &[u8; 8] = b"HIRADTBL";

/// Changes whenever what a bake computes changes, so that older entries miss.
const BAKE_VERSION: u32 = 5;

/// A folder of cached tables.
#[derive(Clone, Debug)]
pub struct Cache {
    dir: PathBuf,
}

/// An entry's key.
pub type Key = [u8; 32];

impl Cache {
    /// The cache folder: `over`, else the environment's (see the module documentation);
    /// `None` when no folder can be named.
    pub fn locate(over: Option<&Path>) -> Option<Cache> {
        let env = |k: &str| {
            std::env::var_os(k)
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
        };
        let dir = over
            .map(Path::to_path_buf)
            .or_else(|| env("HIRAD_CACHE"))
            .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("hirad").join("tables")))
            .or_else(|| env("HOME").map(|d| d.join(".cache").join("hirad").join("tables")))?;
        Some(Cache { dir })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The key of original `alone` of `scene` baked with `settings`.
    pub fn key(scene: &Scene, alone: &Alone, settings: &TableSettings) -> Key {
        let mut h = blake3::Hasher::new();
        h.update(MAGIC);
        h.update(&BAKE_VERSION.to_le_bytes());
        h.update(&[scene.bands]);
        // A bake's hr solves expand the original: a setting only closed instances read
        // is left out, so that adding one keeps every entry made before it (they are the
        // same tables).
        let text = format!("{settings:?}").replace(
            &format!(", own_polygons: {}", settings.solve.own_polygons),
            "",
        );
        h.update(text.as_bytes());
        h.update(&(alone.polygons.len() as u64).to_le_bytes());
        for (p, &m) in alone.polygons.iter().zip(&alone.materials) {
            h.update(&[p.len() as u8]);
            for c in p {
                for x in c.to_array() {
                    h.update(&x.to_bits().to_le_bytes());
                }
            }
            let mut values = [0.0f32; 40];
            let n = scene.materials[m as usize]
                .data
                .to_values(&mut values)
                .unwrap_or(0);
            h.update(&[scene.materials[m as usize].data.two_sided as u8]);
            for v in &values[..n] {
                h.update(&v.to_bits().to_le_bytes());
            }
        }
        *h.finalize().as_bytes()
    }

    fn path(&self, key: &Key) -> PathBuf {
        self.dir.join(format!(
            "{}.tables",
            blake3::Hash::from_bytes(*key).to_hex()
        ))
    }

    /// The tables of `key`, if an entry holds them whole and sound (named `name`, original
    /// `index`); `Ok(None)` on a miss, and on an entry that is not sound (which the next
    /// store replaces).
    pub fn load(&self, key: &Key, name: &str, index: usize) -> Option<OriginalTables> {
        let bytes = std::fs::read(self.path(key)).ok()?;
        decode(&bytes, key, name, index)
    }

    /// Writes the tables under `key` (through a temporary file, renamed into place).
    pub fn store(&self, key: &Key, t: &OriginalTables) -> Result<()> {
        std::fs::create_dir_all(&self.dir)
            .with_context(|| format!("cannot create the table cache {}", self.dir.display()))?;
        let path = self.path(key);
        crate::files::write_atomic(&path, |w| Ok(w.write_all(&encode(key, t))?))
    }
}

/// An entry: magic, version, key, the table record, polygons, then the values, absorbed
/// fractions and residuals as f32, the scatterers' visible fractions as bytes, and a
/// checksum of all before it.
fn encode(key: &Key, t: &OriginalTables) -> Vec<u8> {
    let rec = t.to_scene();
    let mut b = Vec::new();
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&BAKE_VERSION.to_le_bytes());
    b.extend_from_slice(key);
    b.extend_from_slice(bytemuck::bytes_of(&rec.record));
    b.extend_from_slice(&(t.polygons as u64).to_le_bytes());
    for v in rec.values.iter().chain(&t.absorbed).chain(&t.residual) {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&rec.visible);
    let sum = blake3::hash(&b);
    b.extend_from_slice(sum.as_bytes());
    b
}

fn decode(b: &[u8], key: &Key, name: &str, index: usize) -> Option<OriginalTables> {
    let head = 8 + 4 + 32;
    let rec_size = std::mem::size_of::<TableRecord>();
    if b.len() < head + rec_size + 8 + 32 {
        return None;
    }
    let (body, sum) = b.split_at(b.len() - 32);
    if blake3::hash(body).as_bytes() != sum
        || &body[..8] != MAGIC
        || body[8..12] != BAKE_VERSION.to_le_bytes()
        || &body[12..44] != key
    {
        return None;
    }
    let record: TableRecord = bytemuck::pod_read_unaligned(&body[head..head + rec_size]);
    let polygons = u64::from_le_bytes(body[head + rec_size..head + rec_size + 8].try_into().ok()?);
    let values = record.values() as usize;
    let per_cell = (record.incoming_side as usize).pow(2) * record.bands as usize;
    let visible = record.visible_bytes() as usize;
    let rest = &body[head + rec_size + 8..];
    if rest.len() != 4 * (values + 2 * per_cell) + visible {
        return None;
    }
    let (floats, visible) = rest.split_at(rest.len() - visible);
    let floats: Vec<f32> = floats
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let mut t = OriginalTables::from_record(
        name,
        index,
        polygons as usize,
        &record,
        &floats[..values],
        visible,
    )?;
    t.absorbed = floats[values..values + per_cell].to_vec();
    t.residual = floats[values + per_cell..].to_vec();
    // The values must make sound tables (ranges, lengths, box), as the image's would.
    t.try_view().ok()?;
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A setting that only closed instances read leaves every key as it was (the bake's hr
    /// solves expand the original), so that the entries made before it stay valid; a
    /// setting the bake reads changes it.
    #[test]
    fn keys_ignore_what_only_closed_instances_read() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/small_plant.hir");
        let scene = crate::text::parse(&std::fs::read(path).unwrap()).unwrap();
        let alone = crate::tables::Alone::new(&scene, 0).unwrap();
        let settings = TableSettings::default();
        let key = Cache::key(&scene, &alone, &settings);
        for own_polygons in [0, 1, u32::MAX] {
            let mut other = settings;
            other.solve.own_polygons = own_polygons;
            assert_eq!(Cache::key(&scene, &alone, &other), key, "{own_polygons}");
        }
        let mut finer = settings;
        finer.solve.epsilon *= 0.5;
        assert_ne!(Cache::key(&scene, &alone, &finer), key);
        let other = crate::tables::Alone::new(&scene, 1).unwrap();
        assert_ne!(Cache::key(&scene, &other, &settings), key);
    }
}
