//! The scene file (the README's scene contract): TOML schema, defaults, and validation with
//! key-path messages.
//!
//! Two stages: [`Scene::from_toml`] reads the schema with serde (`deny_unknown_fields` and
//! `serde_path_to_error`, so an unknown key or a wrong type names its path) into a plain,
//! editable [`Scene`]; [`Scene::validate`] checks the ranges physics requires and the
//! combinations that make sense and returns the typed [`Model`](crate::model::Model) (parsed
//! expressions, laws, enforcement, scheme) — the only thing `Problem::new` accepts. Nothing here
//! touches the mesh; side names are checked against the mesh in `crate::problem`.
//!
//! - [`schema`]: the serde structs that mirror the TOML (their key names are the contract) and
//!   the defaults of omitted keys;
//! - [`parse`]: text (with `--set` overrides) → [`Scene`], errors with their key path;
//! - [`validate`]: [`Scene`] → the typed model, and the checks of names and free text.

pub mod parse;
pub mod schema;
pub mod validate;

pub use crate::model::kinds::{
    Bound, BoundAt, ContactSolve, DomainKind, EnergyResidualAction, EnforcementKind, FixedPointAcceleration,
    FixedPointStart, FrictionBound, FrictionLaw, InnerSolver, MassKind, Plane, SchemeKind,
};
pub use parse::{one_paragraph, overridden_text};
pub use schema::{
    Boundary, Contact, Domain, Friction, Initial, Loads, Material, NumOrStr, Output, Scene, Solver, Time, Traction,
    Viscosity,
};
pub use validate::{check_name, check_text};

/// The embedded default scene (`dyncontact run` with no SCENE).
pub const DEFAULT_SCENE: &str = include_str!("../../fixtures/scenes/academic.toml");
