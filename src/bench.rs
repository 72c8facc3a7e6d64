//! Work–precision benchmark (`dyncontact study bench`, run by `cargo xtask bench`).
//! To be implemented.

use std::path::Path;

use crate::error::{Error, Result};

/// Options of the benchmark.
#[derive(Debug, Clone, Default)]
pub struct BenchOptions {
    /// a small configuration for smoke tests
    pub quick: bool,
}

/// Run the benchmark and write its CSV and SVG files under `out`.
pub fn run(_out: &Path, _opts: &BenchOptions) -> Result<String> {
    Err(Error::Output("the benchmark is not implemented yet".into()))
}
