//! `trajectory.f64` (`[output] trajectory = true`): the displacement and velocity of every free
//! DOF at t = 0 and after every step, as exact little-endian f64 — what a study comparing whole
//! trajectories reads (the ε → 0 study's e_V and e_H are maxima over every step of norms of
//! differences of two runs' fields). Layout: the 8 bytes `DCTRAJ01`, the number n of free DOFs
//! (u64), then per record the step (u64), t (f64), u (n f64) and v (n f64).

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Read, Write};
use std::path::Path;

use crate::error::{Error, Result};

const MAGIC: &[u8; 8] = b"DCTRAJ01";

/// The writer of trajectory.f64.
pub struct TrajectoryWriter {
    file: BufWriter<File>,
    path: std::path::PathBuf,
}

impl TrajectoryWriter {
    /// A new file for `n` free DOFs.
    pub fn create(path: &Path, n: usize) -> Result<TrajectoryWriter> {
        let io = |e| Error::io(path, e);
        let mut file = BufWriter::new(File::create(path).map_err(io)?);
        file.write_all(MAGIC).map_err(io)?;
        file.write_all(&(n as u64).to_le_bytes()).map_err(io)?;
        Ok(TrajectoryWriter { file, path: path.to_path_buf() })
    }

    /// Reopen after checkpoint step `step`: records after it are cut off.
    pub fn reopen(path: &Path, n: usize, step: usize) -> Result<TrajectoryWriter> {
        let io = |e| Error::io(path, e);
        let keep = 16 + (step as u64 + 1) * record_bytes(n);
        let f = OpenOptions::new().write(true).open(path).map_err(io)?;
        f.set_len(keep).map_err(io)?;
        let f = OpenOptions::new().append(true).open(path).map_err(io)?;
        Ok(TrajectoryWriter { file: BufWriter::new(f), path: path.to_path_buf() })
    }

    /// Append the record of `step`.
    pub fn record(&mut self, step: usize, t: f64, u: &[f64], v: &[f64]) -> Result<()> {
        let io = |e| Error::io(&self.path, e);
        let mut buf = Vec::with_capacity(16 + 8 * (u.len() + v.len()));
        buf.extend_from_slice(&(step as u64).to_le_bytes());
        buf.extend_from_slice(&t.to_le_bytes());
        for x in u.iter().chain(v) {
            buf.extend_from_slice(&x.to_le_bytes());
        }
        self.file.write_all(&buf).map_err(io)?;
        self.file.flush().map_err(io)
    }
}

fn record_bytes(n: usize) -> u64 {
    16 + 16 * n as u64
}

/// One record of a trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryRecord {
    pub step: usize,
    pub t: f64,
    pub u: Vec<f64>,
    pub v: Vec<f64>,
}

/// Read every complete record of `path` (a half-written last record is dropped).
pub fn read(path: &Path) -> Result<Vec<TrajectoryRecord>> {
    let mut bytes = Vec::new();
    File::open(path).and_then(|mut f| f.read_to_end(&mut bytes)).map_err(|e| Error::read(path, e))?;
    let bad =
        || Error::read(path, std::io::Error::new(std::io::ErrorKind::InvalidData, "not a dyncontact trajectory file"));
    if bytes.len() < 16 || &bytes[..8] != MAGIC {
        return Err(bad());
    }
    let word = |at: usize| -> [u8; 8] { std::array::from_fn(|k| bytes[at + k]) };
    let n = u64::from_le_bytes(word(8)) as usize;
    let size = usize::try_from(record_bytes(n)).map_err(|_| bad())?;
    let mut out = Vec::new();
    let mut at = 16;
    while at + size <= bytes.len() {
        let f = |k: usize| f64::from_le_bytes(word(at + 16 + 8 * k));
        out.push(TrajectoryRecord {
            step: u64::from_le_bytes(word(at)) as usize,
            t: f64::from_le_bytes(word(at + 8)),
            u: (0..n).map(f).collect(),
            v: (n..2 * n).map(f).collect(),
        });
        at += size;
    }
    Ok(out)
}
