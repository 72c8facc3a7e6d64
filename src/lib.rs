//! dyncontact — a reference solver for the dynamic contact of a Kelvin–Voigt body with a
//! foundation: normal compliance with a penetration bound (finite penetration) and a
//! nonmonotone slip-rate-dependent friction law (Barboteu–Bartosz–Kalita, NARWA 22, 2015).
//!
//! Module map (data flows one way: scene → problem → operators → time loop → outputs):
//! - [`scene`]: the TOML scene (SCENES.md), validation with key paths
//! - [`mesh`]: rectangle generator, Gmsh reader, Γ1/Γ2/Γ3, normals and weights ω_i (model.md §4.1)
//! - [`model`]: material (P.1), contact laws (P.5, P.6, P.8, Pe.5), expressions
//! - [`fem`]: P1 assembly of M, K, C and f(t) (P.2–P.4)
//! - [`problem`]: scene → discrete problem, initial data (S.0)
//! - [`scheme`]: midpoint / trapezoid / backward Euler step operator (S.1, S.2)
//! - [`step`]: the per-step contact problem: Delassus operator, Newton (N.1–N.3), conic twin, F.1
//! - [`energy`]: the discrete energy balance (E.1)
//! - [`simulation`]: the time loop
//! - [`output`]: history.csv, contact.csv, summary.json, VTU frames, SVG plots
//! - [`linalg`]: thin wrappers over faer

pub mod bench;
pub mod checkpoint;
pub mod energy;
pub mod error;
pub mod fem;
pub mod linalg;
pub mod mesh;
pub mod model;
pub mod output;
pub mod problem;
pub mod reference;
pub mod run;
pub mod scene;
pub mod scheme;
pub mod simulation;
pub mod stability;
pub mod step;
pub mod variational;
pub mod study;

pub use error::{Error, Result};
