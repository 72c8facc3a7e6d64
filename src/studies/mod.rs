//! Studies that run many scenes through the solver's public API (the one time loop,
//! `Simulation::steps`, and `run::run`): the ε → 0 study of Problem P_ε, the stability map,
//! convergence under refinement, where the friction bound is evaluated (bound_at), and the
//! work–precision benchmark. `harness` holds what they share: CSV tables, fitted
//! slopes and charts.

pub mod bench;
pub mod bookkeeping;
pub mod bound_at;
pub mod convergence;
pub mod harness;
pub mod penalty;
pub mod scaling;
pub mod stability;
