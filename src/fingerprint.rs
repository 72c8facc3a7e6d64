//! Fingerprints (FNV-1a, 64 bits, as hex): of a text, and of everything a run reads.
//!
//! A checkpoint resumes only a run of the same inputs, and a sweep point counts as completed
//! only for the same inputs: the scene as validated (its parsed form, so comments and layout in
//! the file do not count) *and* the bytes of every file the scene reads (the Gmsh mesh). Moving
//! one node of the mesh changes the fingerprint. FNV-1a detects changes; it is not a defence
//! against a forger (nothing in a run folder is).

use std::path::Path;

use crate::error::{Error, Result};
use crate::model::Model;

/// FNV-1a 64 of some bytes, continuing from `h` (start with [`START`]).
fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

const START: u64 = 0xcbf2_9ce4_8422_2325;

/// The fingerprint of a text.
pub fn text(text: &str) -> String {
    format!("{:016x}", fnv1a(START, text.as_bytes()))
}

/// The fingerprint of a run's inputs: the validated model and the bytes of every file it reads
/// (`scene_dir` resolves a relative path as the problem does).
pub fn inputs(model: &Model, scene_dir: &Path) -> Result<String> {
    // the same problem, the same fingerprint: `plane` left out is plane strain
    let normalized = Model { plane: Some(model.plane.unwrap_or_default()), ..model.clone() };
    // what the solver makes of the model changed where the salt changes (2: t_n is the decimal
    // of n·k): a point run by an earlier version runs again
    let mut h = fnv1a(START, b"inputs 2;");
    h = fnv1a(h, format!("{normalized:?}").as_bytes());
    if let Some(path) = model.domain.mesh_file(scene_dir)? {
        let bytes = std::fs::read(&path).map_err(|e| Error::read(&path, e))?;
        h = fnv1a(h, path.display().to_string().as_bytes());
        h = fnv1a(h, &(bytes.len() as u64).to_le_bytes());
        h = fnv1a(h, &bytes);
    }
    Ok(format!("{h:016x}"))
}
