//! dyncontact — a reference solver for the dynamic contact of a Kelvin–Voigt body with a
//! foundation: normal compliance with a penetration bound (finite penetration) and a
//! nonmonotone slip-rate-dependent friction law (Barboteu–Bartosz–Kalita, NARWA 22, 2015).
//! The model, its equation IDs and the project's decisions are in spec/model.md.
//!
//! Module map (data flows one way: scene → model → problem → operators → time loop → outputs):
//! - [`scene`]: the TOML scene (the README's contract); `Scene::validate` gives the typed [`model::Model`];
//!   [`overrides`]: `--set KEY=VALUE` on the scene's table before it is read
//! - [`model`]: the typed model, material (P.1), contact laws (P.5, P.6, P.8, Pe.5), expressions
//! - [`mesh`]: rectangle generator, Gmsh reader, Γ1/Γ2/Γ3, normals and weights ω_i (§4.1)
//! - [`fem`]: P1 assembly of M, K, C and f(t) (P.2–P.4)
//! - [`problem`]: model → discrete problem, initial data (S.0)
//! - [`scheme`]: midpoint / trapezoid / backward Euler step operator (S.1, S.2)
//! - [`step`]: the per-step contact problem: Delassus operator, Newton (N.1–N.4), conic twin, F.1
//! - [`energy`]: the discrete energy balance (E.1)
//! - [`simulation`]: the time loop (`Simulation::steps`, the one loop every caller drives)
//! - [`failure`]: why a solver or a run stopped (enums), and their messages; [`defaults`]: every tuning constant
//! - [`output`]: history.csv, contact.csv, summary.json, VTU frames, SVG charts; [`files`]: whole-file and
//!   whole-row writes (below both the outputs and the checkpoints)
//! - [`run`], [`checkpoint`]: a run with its outputs, checkpoints and resume; [`resources`]: memory and cost estimates;
//!   [`fingerprint`]: of the inputs a run reads (the scene and its mesh file)
//! - [`sweep`]: many runs of one scene (axes, `[set]`), in parallel here or as Snakemake jobs; sweep.csv
//! - [`study`]: the user's studies (`dyncontact study penalty`: the ε → 0 study), on the public API only;
//!   the developers' studies (benchmarks, stability map) are the `dyncontact-studies` crate (studies/)
//! - [`cli`]: the command line (the `dyncontact` executable and `python -m dyncontact` run it)
//! - [`linalg`]: thin wrappers over faer; [`ordering`]: the factors' fill-reducing orders; [`reference`]: closed forms; [`variational`]: V.1/V.2 checks

// Two lints this crate does not follow, on purpose:
// - `!(x > t)` is how the code says "fails unless x is a number above t": NaN fails it, which the
//   `partial_cmp` form the lint suggests would hide;
// - index loops read like the formulas they implement (i over nodes, c over components, several
//   arrays at once), where an iterator chain would not.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod checkpoint;
pub mod cli;
pub mod defaults;
pub mod energy;
pub mod error;
pub mod failure;
pub mod fem;
pub mod files;
pub mod fingerprint;
pub mod linalg;
pub mod mesh;
pub mod model;
pub mod ordering;
pub mod output;
pub mod overrides;
pub mod problem;
pub mod reference;
pub mod resources;
pub mod run;
pub mod scene;
pub mod scheme;
pub mod simulation;
pub mod step;
pub mod study;
pub mod sweep;
pub mod variational;

pub use error::{Error, Result};
