//! The public contract from the outside: the command line, scenes and their errors, generated bad
//! input, hostile run folders, Gmsh meshes, sweeps and overrides, solution verification
//! (`refine`), the ε-study, the charts, the VTU frames, and memory known before it is spent.
//! Each module is one of its files; `cargo xtask verify` ties a test to its file.

#[path = "../common/mod.rs"]
mod common;

mod charts;
mod cli;
mod example;
mod fuzz_inputs;
mod gmsh;
mod hostile;
mod numbers;
mod readme;
mod refine;
mod resources;
mod scenes;
mod study;
mod sweep;
mod vtu;
