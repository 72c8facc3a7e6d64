//! dyncontact's developer studies: they run many scenes through the solver's public API (the one
//! time loop, `Simulation::steps`, `run::run` and sweeps) and write tables and charts for the
//! README — the work–precision benchmark ([`bench`], with [`scaling`] and [`bookkeeping`]), the
//! stability map ([`stability`]), convergence under refinement ([`convergence`]) and where the
//! friction bound is evaluated ([`bound_at`]). They are not part of the solver: the library
//! (`dyncontact`) never imports them. `cargo xtask bench | stability | bound-at` runs them in
//! release mode through this crate's binary, `dyncontact-studies`.

#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod bench;
pub mod bookkeeping;
pub mod bound_at;
pub mod convergence;
pub mod scaling;
pub mod stability;
pub mod thick;
