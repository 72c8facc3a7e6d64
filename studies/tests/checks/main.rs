//! The developer studies end to end: the benchmark, the stability map, convergence tables and
//! where the friction bound is evaluated.
//! Each module is one of its files; `cargo xtask verify` ties a test to its file.

#[path = "../../../tests/common/mod.rs"]
mod common;

mod bench_smoke;
mod bound_at;
mod charts;
mod convergence;
mod stability;
