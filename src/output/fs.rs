//! Atomic file writes: a file is written under a temporary name and renamed, so a reader (or a
//! run stopped mid-write) never sees a half-written summary, PVD, chart or checkpoint.

use std::path::Path;

use crate::error::{Error, Result};

/// Write `bytes` to `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("{}.tmp", path.extension().and_then(|e| e.to_str()).unwrap_or("")));
    std::fs::write(&tmp, bytes).map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}
