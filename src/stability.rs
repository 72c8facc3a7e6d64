//! Stability map (`dyncontact study stability`, run by `cargo xtask stability`).
//! To be implemented.

use std::path::Path;

use crate::error::{Error, Result};

/// Options of the stability sweep.
#[derive(Debug, Clone, Default)]
pub struct StabilityOptions {
    /// a small sweep for smoke tests
    pub quick: bool,
}

/// Run the sweep and write its CSV and SVG files under `out`.
pub fn run(_out: &Path, _opts: &StabilityOptions) -> Result<String> {
    Err(Error::Output("the stability map is not implemented yet".into()))
}
