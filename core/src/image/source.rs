//! Where image bytes come from: memory, flash, or a file read piece by piece.

/// Why a source could not deliver bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceError {
    /// The requested range lies past the end of the source.
    OutOfRange,
    /// The device or file failed; the code is source-specific (an OS error number for files).
    Io(i32),
}

impl core::fmt::Display for SourceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SourceError::OutOfRange => f.write_str("read past the end of the scene"),
            SourceError::Io(code) => write!(f, "read failed (error code {code})"),
        }
    }
}

/// Random-access bytes of a scene image. Reads take `&self` so that several workers can read
/// one source at once (a file source uses positioned reads).
pub trait SceneSource {
    /// Total length in bytes.
    fn len(&self) -> u64;

    /// True if the source holds no bytes.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Fills `buf` with the bytes at `offset..offset + buf.len()`.
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError>;
}

/// An image held in memory.
#[derive(Clone, Copy, Debug)]
pub struct SliceSource<'a>(pub &'a [u8]);

impl SceneSource for SliceSource<'_> {
    fn len(&self) -> u64 {
        self.0.len() as u64
    }

    fn read_at(&self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
        let start = usize::try_from(offset).map_err(|_| SourceError::OutOfRange)?;
        let end = start
            .checked_add(buf.len())
            .ok_or(SourceError::OutOfRange)?;
        let bytes = self.0.get(start..end).ok_or(SourceError::OutOfRange)?;
        buf.copy_from_slice(bytes);
        Ok(())
    }
}

impl<S: SceneSource + ?Sized> SceneSource for &S {
    fn len(&self) -> u64 {
        (**self).len()
    }

    fn read_at(&self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
        (**self).read_at(offset, buf)
    }
}
