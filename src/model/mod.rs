//! The model of model.md §1–§2: material (P.1), contact laws (P.5, P.6, P.8, Pe.5), the
//! contact model a scene switches on, and the expression strings of loads and data.

pub mod contact;
pub mod expr;
pub mod laws;
pub mod material;
