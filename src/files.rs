//! File writes that leave no half-written file behind: a whole file is written under a
//! temporary name and renamed (a reader, or a run stopped mid-write, never sees a half-written
//! summary, PVD, chart or checkpoint, and a failed write removes its temporary); a CSV file grows
//! by whole rows ([`AppendFile`]: a row that could not be written whole is cut off again).

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Write `bytes` to `path` through a temporary file and a rename; on failure the temporary is
/// removed and `path` is as it was.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("{}.tmp", path.extension().and_then(|e| e.to_str()).unwrap_or("")));
    let written = std::fs::write(&tmp, bytes)
        .map_err(|e| Error::io(&tmp, e))
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e)));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// Write several files into `dir` (created), each atomically (a study's tables and charts).
pub fn write_files(dir: &Path, files: &[(&str, &[u8])]) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for (name, bytes) in files {
        write_atomic(&dir.join(name), bytes)?;
    }
    Ok(())
}

/// A file written by appending whole records (rows of a CSV file): each [`AppendFile::append`]
/// writes its bytes or, when the write fails part-way (a full disk), cuts the file back to the
/// last whole record before returning the error.
#[derive(Debug)]
pub struct AppendFile {
    file: File,
    path: PathBuf,
    /// the length of the file's whole records
    len: u64,
}

impl AppendFile {
    /// A new file (an existing one is truncated).
    pub fn create(path: &Path) -> Result<AppendFile> {
        let file = File::create(path).map_err(|e| Error::io(path, e))?;
        Ok(AppendFile { file, path: path.to_path_buf(), len: 0 })
    }

    /// An existing file, appended to after its last byte.
    pub fn open(path: &Path) -> Result<AppendFile> {
        let file = std::fs::OpenOptions::new().append(true).open(path).map_err(|e| Error::io(path, e))?;
        let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
        Ok(AppendFile { file, path: path.to_path_buf(), len })
    }

    /// Append one whole record.
    pub fn append(&mut self, bytes: &[u8]) -> Result<()> {
        match self.file.write_all(bytes) {
            Ok(()) => {
                self.len += bytes.len() as u64;
                Ok(())
            }
            Err(e) => {
                // whatever part of the record reached the file goes again
                let _ = self.file.set_len(self.len);
                Err(Error::io(&self.path, e))
            }
        }
    }
}
