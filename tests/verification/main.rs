//! The model checked equation by equation: closed forms (B.1–B.4), manufactured solutions with
//! and without contact in 2-D and 3-D (B.5), the energy balance (E.1), the variational
//! inequalities (V.1, V.2), property tests of the element matrices and laws, Coulomb friction,
//! chatter and its remedies, and the operators against scikit-fem's.
//! Each module is one of its files; `cargo xtask verify` ties a test to its file.

#[path = "../common/mod.rs"]
mod common;

mod analytic;
mod chatter;
mod coulomb;
mod crosscheck;
mod energy;
mod manufactured;
mod manufactured_contact;
mod manufactured_contact3d;
mod plane_stress;
mod properties;
mod solid;
mod solid_run;
mod variational;
