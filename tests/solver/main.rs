//! The contact solver and its runs: the contact step and its twins, the two forms of the contact
//! solve, Newton on the unfrozen bound (N.4), failure, interruption and resume, and every
//! fixture's outputs pinned (regression, snapshots).
//! Each module is one of its files; `cargo xtask verify` ties a test to its file.

#[path = "../common/mod.rs"]
mod common;

mod contact;
mod contact_solve;
mod regression;
mod robustness;
mod snapshots;
mod unfrozen;
