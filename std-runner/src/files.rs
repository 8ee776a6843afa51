//! Scene files on disk: format detection, loading with located errors, a file-backed image
//! source, and writing outputs atomically (temporary name, then rename).

use crate::scene::{self, Scene};
use crate::{obj, text};
use anyhow::{Context, Result, anyhow, bail};
use hirad_core::image::{SceneSource, SceneView, SourceError};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The scene formats hirad reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.hir`: the text format.
    Text,
    /// `.hirb`: the binary image.
    Binary,
    /// `.obj` (+ `.mtl`): Wavefront OBJ.
    Obj,
}

impl Format {
    /// The format named by a path's extension.
    pub fn of(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("hir") => Ok(Format::Text),
            Some("hirb") => Ok(Format::Binary),
            Some("obj") => Ok(Format::Obj),
            _ => bail!(
                "{}: unknown scene format; expected a .hir, .hirb or .obj file",
                path.display()
            ),
        }
    }

    /// Short name for messages.
    pub fn name(self) -> &'static str {
        match self {
            Format::Text => "hir (text)",
            Format::Binary => "hirb (binary image)",
            Format::Obj => "obj (Wavefront)",
        }
    }
}

/// A scene image read from a file with positioned reads: validation and level loading read
/// it piece by piece, so the file never has to fit in memory.
#[derive(Debug)]
pub struct FileSource {
    file: File,
    len: u64,
}

impl FileSource {
    /// Opens a `.hirb` file.
    pub fn open(path: &Path) -> Result<Self> {
        not_a_directory(path)?;
        let file = File::open(path).with_context(|| format!("{}: cannot open", path.display()))?;
        let len = file
            .metadata()
            .with_context(|| format!("{}: cannot stat", path.display()))?
            .len();
        Ok(FileSource { file, len })
    }
}

impl SceneSource for FileSource {
    fn len(&self) -> u64 {
        self.len
    }

    fn read_at(&self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
        let end = offset
            .checked_add(buf.len() as u64)
            .ok_or(SourceError::OutOfRange)?;
        if end > self.len {
            return Err(SourceError::OutOfRange);
        }
        read_exact_at(&self.file, offset, buf)
            .map_err(|e| SourceError::Io(e.raw_os_error().unwrap_or(-1)))
    }
}

#[cfg(unix)]
fn read_exact_at(f: &File, offset: u64, buf: &mut [u8]) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(f, buf, offset)
}

#[cfg(windows)]
fn read_exact_at(f: &File, mut offset: u64, mut buf: &mut [u8]) -> std::io::Result<()> {
    use std::os::windows::fs::FileExt;
    while !buf.is_empty() {
        match f.seek_read(buf, offset)? {
            0 => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            n => {
                buf = &mut buf[n..];
                offset += n as u64;
            }
        }
    }
    Ok(())
}

/// Opens and validates a `.hirb` file without reading it whole; errors are input errors.
pub fn open_image(path: &Path) -> Result<SceneView<FileSource>> {
    let src = FileSource::open(path).map_err(crate::exit::input)?;
    SceneView::open(src).map_err(|e| crate::exit::input(anyhow!("{}: {e}", path.display())))
}

/// A loaded scene and the notes the loader made.
pub struct Loaded {
    /// The scene model.
    pub scene: Scene,
    /// The format it came from.
    pub format: Format,
    /// Loader warnings, already prefixed with the file (at most `obj::MAX_WARNINGS` and a
    /// line counting the others).
    pub warnings: Vec<String>,
    /// Every warning the loader made, shown or not.
    pub warnings_total: u64,
    /// Faces the loader skipped (degenerate or too small for single precision; OBJ only).
    pub skipped_faces: u64,
    /// The files read: the scene, and an OBJ's material libraries.
    pub inputs: Vec<PathBuf>,
    /// For an OBJ, the face number (1-based) each polygon came from, in global-id order
    /// (see `obj::ObjImport::faces`); `None` for other formats.
    pub faces: Option<Vec<u64>>,
    /// The scene's up axis: +y for an OBJ (the convention), else `scene::Up::of_scene`.
    pub up: scene::Up,
}

fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))
}

/// Loads a scene from `.hir`, `.hirb` or `.obj`; every error names the file and the line and
/// column (text) or byte offset (binary) of the fault.
/// Errors are input errors (exit status 3, see [`crate::exit`]).
pub fn load_scene(path: &Path) -> Result<Loaded> {
    load(path, true).map_err(crate::exit::input)
}

/// [`load_scene`] keeping of a binary image's tables only their records (see
/// `scene::decompile_records`): for a solve that reads the image itself.
pub fn load_scene_records(path: &Path) -> Result<Loaded> {
    load(path, false).map_err(crate::exit::input)
}

fn load(path: &Path, tables: bool) -> Result<Loaded> {
    let format = Format::of(path)?;
    not_a_directory(path)?;
    let mut warnings = Vec::new();
    let (mut warnings_total, mut skipped_faces) = (0, 0);
    let mut inputs = vec![path.to_path_buf()];
    let mut faces = None;
    let scene = match format {
        Format::Text => {
            let bytes = read(path)?;
            text::parse(&bytes).map_err(|e| anyhow!("{}:{e}", path.display()))?
        }
        Format::Binary => {
            let view = open_image(path)?;
            let scene = if tables {
                scene::decompile(&view)
            } else {
                scene::decompile_records(&view)
            };
            scene.map_err(|e| anyhow!("{}: {e}", path.display()))?
        }
        Format::Obj => {
            let bytes = read(path)?;
            let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
            let mut inner = obj::load_mtl_from(&dir);
            // Remember the material libraries read, by either name `load_mtl_from` tries.
            let mut load_mtl = |name: &str| {
                let r = inner(name);
                if r.is_ok() {
                    let base = name.rsplit(['/', '\\']).next().unwrap_or(name);
                    for p in [dir.join(name), dir.join(base)] {
                        if p.is_file() && !inputs.contains(&p) {
                            inputs.push(p);
                        }
                    }
                }
                r
            };
            let imported = obj::import(&bytes, &mut load_mtl).map_err(|e| {
                if e.file.is_empty() {
                    anyhow!("{}:{e}", path.display())
                } else {
                    anyhow!("{}", relocate(&dir, &e))
                }
            })?;
            for w in imported.warnings {
                warnings.push(format!("{}:{w}", path.display()));
            }
            warnings_total = imported.warnings_total;
            skipped_faces = imported.counts.skipped_faces;
            faces = Some(imported.faces);
            imported.scene
        }
    };
    let up = match format {
        Format::Obj => scene::Up::Y,
        _ => scene::Up::of_scene(&scene),
    };
    Ok(Loaded {
        up,
        scene,
        format,
        warnings,
        warnings_total,
        skipped_faces,
        inputs,
        faces,
    })
}

/// Refuses a directory given as a scene file (reading it failed with an OS error code).
fn not_a_directory(path: &Path) -> Result<()> {
    if std::fs::metadata(path).is_ok_and(|m| m.is_dir()) {
        bail!("{}: is a directory, not a scene file", path.display());
    }
    Ok(())
}

fn relocate(dir: &Path, e: &obj::ObjError) -> String {
    format!(
        "{}:{}:{}: {}",
        dir.join(&e.file).display(),
        e.line,
        e.column,
        e.message
    )
}

/// Compiles a loaded scene into its binary image, with the file named in errors.
/// Errors are input errors (the scene is invalid).
pub fn compile(path: &Path, scene: &Scene) -> Result<Vec<u8>> {
    scene::compile(scene).map_err(|e| crate::exit::input(anyhow!("{}: {e}", path.display())))
}

/// Writes `path` through a temporary file in the same directory, renamed into place only
/// when `write` succeeded: a failed run never leaves a half-written output.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let tmp = temp_beside(path)?;
    let mut w = BufWriter::new(tmp);
    write(&mut w)?;
    let tmp = w
        .into_inner()
        .map_err(|e| anyhow!("{}: cannot write: {}", path.display(), e.error()))?;
    persist(tmp, path)
}

/// A temporary file in the directory of `path`.
pub fn temp_beside(path: &Path) -> Result<tempfile::NamedTempFile> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let stem = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    let prefix = format!(".{stem}.");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    // An output is an ordinary file: read-write for everyone the umask allows, not the
    // owner-only mode of a temporary file.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    // Removed on SIGINT or SIGTERM (see `interrupt`).
    crate::interrupt::temporary(|| builder.tempfile_in(&dir)).with_context(|| {
        format!(
            "{}: cannot create a temporary file in {}",
            path.display(),
            dir.display()
        )
    })
}

/// Flushes a finished temporary file to disk and renames it to `path`. When `path` is a
/// device or a pipe (`/dev/null`, a FIFO a reader waits on), the finished bytes are written
/// into it instead: renaming over it would replace it with a file (as root, `/dev/null` for
/// every program on the machine).
pub fn persist(tmp: tempfile::NamedTempFile, path: &Path) -> Result<()> {
    let temp = tmp.path().to_path_buf();
    // No interruption between the output coming into place and the registry knowing it.
    crate::interrupt::in_place(&temp, path, || persist_now(tmp, path))
}

fn persist_now(tmp: tempfile::NamedTempFile, path: &Path) -> Result<()> {
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
        let mut from = tmp
            .reopen()
            .with_context(|| format!("{}: cannot read the finished output back", path.display()))?;
        let mut to = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .with_context(|| format!("{}: cannot open for writing", path.display()))?;
        std::io::copy(&mut from, &mut to)
            .with_context(|| format!("{}: cannot write", path.display()))?;
        return Ok(());
    }
    tmp.as_file()
        .sync_all()
        .with_context(|| format!("{}: cannot write", path.display()))?;
    tmp.persist(path).map_err(|e| {
        anyhow!(
            "{}: cannot rename the finished file into place: {}",
            path.display(),
            e.error
        )
    })?;
    Ok(())
}
