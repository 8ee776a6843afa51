//! Output paths checked before any work starts: each must be writable where it is, none may
//! be a file the run reads, and no two may name the same file. A solve of an hour that could
//! not write its image, or that wrote its results over its own scene, lost the hour or the
//! scene.

use anyhow::{Result, bail};
use std::path::{Path, PathBuf};

/// One output: the option that names it (`--results`, `-o`, ...) and its path.
#[derive(Clone, Copy, Debug)]
pub struct Output<'a> {
    /// The option, for the message.
    pub option: &'a str,
    /// The path.
    pub path: &'a Path,
}

/// Checks `outputs` against each other and against `inputs` (the files the run reads).
/// An existing device or pipe (`/dev/null`, a FIFO) is written into, never replaced, and
/// may be named by several outputs.
/// Errors are usage errors (exit status 2, see [`crate::exit`]).
pub fn check_outputs(inputs: &[PathBuf], outputs: &[Output<'_>]) -> Result<()> {
    check(inputs, outputs).map_err(crate::exit::usage)
}

fn check(inputs: &[PathBuf], outputs: &[Output<'_>]) -> Result<()> {
    let mut seen: Vec<(PathBuf, Output<'_>)> = Vec::new();
    for out in outputs {
        let (option, path) = (out.option, out.path);
        let meta = std::fs::metadata(path).ok();
        if meta.as_ref().is_some_and(|m| m.is_dir()) {
            bail!("{option} {}: is a directory", path.display());
        }
        let written_into = meta.as_ref().is_some_and(|m| !m.is_file());
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !written_into {
            match std::fs::metadata(&dir) {
                Err(_) => bail!(
                    "{option} {}: the folder {} does not exist",
                    path.display(),
                    dir.display()
                ),
                Ok(m) if !m.is_dir() => bail!(
                    "{option} {}: {} is not a folder",
                    path.display(),
                    dir.display()
                ),
                Ok(_) => {}
            }
            // The output is written to a temporary file beside it, then renamed: that
            // file must be possible.
            let probe = crate::interrupt::uninterrupted(|| {
                tempfile::Builder::new()
                    .prefix(".hirad-check.")
                    .tempfile_in(&dir)
                    .map(drop)
            });
            if let Err(e) = probe {
                bail!(
                    "{option} {}: cannot write in {}: {e}",
                    path.display(),
                    dir.display()
                );
            }
        }
        for input in inputs {
            if same_file(input, path) {
                bail!(
                    "{option} {}: this is a file the run reads ({}); writing it would destroy it",
                    path.display(),
                    input.display()
                );
            }
        }
        let key = identity(path, &dir);
        if !written_into && let Some((_, first)) = seen.iter().find(|(k, _)| *k == key) {
            bail!(
                "{option} {} and {} {} name the same file: one would replace the other",
                path.display(),
                first.option,
                first.path.display()
            );
        }
        seen.push((key, *out));
    }
    Ok(())
}

/// A path's identity for comparing outputs: the canonical path of an existing file, else the
/// canonical folder joined with the name.
fn identity(path: &Path, dir: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    dir.join(path.file_name().unwrap_or_default())
}

/// True when `a` and `b` are the same existing file (a link to it included).
fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (ma, mb);
        matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
    }
}
