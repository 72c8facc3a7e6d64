//! The scene's schema: serde structs that mirror the TOML tables key for key (the names are the
//! public contract of the README and SCENES.md), the defaults of omitted keys, and the readers
//! of arrays whose length serde would not check.

use serde::{Deserialize, Deserializer};

use crate::defaults;
use crate::model::kinds::{
    BoundAt, ContactSolve, DomainKind, EnergyResidualAction, EnforcementKind, FixedPointAcceleration, FixedPointStart,
    FrictionBound, FrictionLaw, InnerSolver, MassKind, Plane, SchemeKind,
};

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    #[serde(default = "default_name")]
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub domain: Domain,
    #[serde(default)]
    pub boundary: Boundary,
    pub material: Material,
    #[serde(default)]
    pub loads: Loads,
    #[serde(default)]
    pub initial: Initial,
    pub contact: Option<Contact>,
    pub time: Time,
    #[serde(default)]
    pub solver: Solver,
    #[serde(default)]
    pub output: Output,
}

/// `name` when omitted.
fn default_name() -> String {
    "scene".into()
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    pub kind: DomainKind,
    /// [Lx, Ly] (rectangle) or [Lx, Ly, Lz] (box)
    #[serde(default, deserialize_with = "opt_components")]
    pub size: Option<Vec<f64>>,
    /// [nx, ny] (rectangle) or [nx, ny, nz] (box)
    #[serde(default, deserialize_with = "opt_components")]
    pub cells: Option<Vec<i64>>,
    pub file: Option<String>,
    /// a 2-D key (strain when absent); an error for a 3-D domain
    pub plane: Option<Plane>,
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Boundary {
    #[serde(default)]
    pub dirichlet: Vec<String>,
    #[serde(default)]
    pub contact: Vec<String>,
}

#[derive(Debug, Clone, Copy, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Viscosity {
    pub theta: f64,
    pub zeta: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub density: f64,
    pub young: f64,
    pub poisson: f64,
    #[serde(default)]
    pub viscosity: Viscosity,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Traction {
    pub side: String,
    #[serde(deserialize_with = "components")]
    pub value: Vec<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
#[derive(Default)]
pub struct Loads {
    /// d expressions in x, y (, z), t; absent: zero
    #[serde(default, deserialize_with = "opt_components")]
    pub body: Option<Vec<String>>,
    /// f3: a known surface load on Γ3 (all contact sides), on top of the contact forces —
    /// for manufactured solutions with contact (spec/model.md §7.5)
    #[serde(default, deserialize_with = "opt_components")]
    pub contact_surface: Option<Vec<String>>,
    #[serde(default)]
    pub traction: Vec<Traction>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
#[derive(Default)]
pub struct Initial {
    /// d expressions in x, y (, z); absent: zero
    #[serde(default, deserialize_with = "opt_components")]
    pub displacement: Option<Vec<String>>,
    #[serde(default, deserialize_with = "opt_components")]
    pub velocity: Option<Vec<String>>,
}

/// A number or a string (for `penetration_bound = "inf"` and `gap = 0.0`).
#[derive(Debug, Clone)]
pub enum NumOrStr {
    Num(f64),
    Str(String),
}

// Hand-written rather than `#[serde(untagged)]`, whose error ("data did not match any variant
// of untagged enum NumOrStr") names a Rust type instead of what the user should write.
impl<'de> Deserialize<'de> for NumOrStr {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = NumOrStr;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or a string")
            }
            fn visit_f64<E>(self, v: f64) -> std::result::Result<NumOrStr, E> {
                Ok(NumOrStr::Num(v))
            }
            fn visit_i64<E>(self, v: i64) -> std::result::Result<NumOrStr, E> {
                Ok(NumOrStr::Num(v as f64))
            }
            fn visit_u64<E>(self, v: u64) -> std::result::Result<NumOrStr, E> {
                Ok(NumOrStr::Num(v as f64))
            }
            fn visit_str<E>(self, v: &str) -> std::result::Result<NumOrStr, E> {
                Ok(NumOrStr::Str(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

/// A TOML array of exactly two entries. serde's `[T; 2]` reads the first two entries and
/// silently ignores the rest (`size = [2.0, 1.0, 3.0]` would be accepted), so pairs are read
/// as a sequence and their length is checked; element errors keep their `[i]` key path.
struct Pair<T>([T; 2]);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Pair<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let v = Vec::<T>::deserialize(d)?;
        let n = v.len();
        <[T; 2]>::try_from(v).map(Pair).map_err(|_| serde::de::Error::invalid_length(n, &"exactly 2 entries [a, b]"))
    }
}

/// A TOML array of 2 or 3 entries (a point or a vector field in the plane or in space; the
/// domain's dimension decides which is right, see `Scene::validate`).
struct Components<T>(Vec<T>);

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Components<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let v = Vec::<T>::deserialize(d)?;
        match v.len() {
            2 | 3 => Ok(Components(v)),
            n => Err(serde::de::Error::invalid_length(n, &"2 entries [a, b] (2-D) or 3 [a, b, c] (3-D)")),
        }
    }
}

fn components<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> std::result::Result<Vec<T>, D::Error> {
    Components::<T>::deserialize(d).map(|c| c.0)
}

fn opt_components<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> std::result::Result<Option<Vec<T>>, D::Error> {
    components(d).map(Some)
}

fn opt_pairs<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Option<Vec<[f64; 2]>>, D::Error> {
    Vec::<Pair<f64>>::deserialize(d).map(|v| Some(v.into_iter().map(|p| p.0).collect()))
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Contact {
    pub gap: Option<NumOrStr>,
    #[serde(default)]
    pub compliance: f64,
    pub penetration_bound: NumOrStr,
    #[serde(default)]
    pub enforcement: EnforcementKind,
    pub penalty: Option<f64>,
    #[serde(default)]
    pub friction_bound: FrictionBound,
    #[serde(default)]
    pub friction_bound_at: BoundAt,
    #[serde(default)]
    pub friction: Friction,
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Friction {
    #[serde(default)]
    pub law: FrictionLaw,
    #[serde(rename = "static")]
    pub static_: Option<f64>,
    pub kinetic: Option<f64>,
    pub decay: Option<f64>,
    pub coefficient: Option<f64>,
    #[serde(default, deserialize_with = "opt_pairs")]
    pub points: Option<Vec<[f64; 2]>>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Time {
    pub end: f64,
    pub step: f64,
    #[serde(default)]
    pub scheme: SchemeKind,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Solver {
    #[serde(default)]
    pub inner: InnerSolver,
    #[serde(default)]
    pub mass: MassKind,
    #[serde(default = "default_newton_tolerance")]
    pub newton_tolerance: f64,
    #[serde(default = "default_fixed_point_tolerance")]
    pub fixed_point_tolerance: f64,
    #[serde(default = "default_max_iterations")]
    pub max_newton_iterations: i64,
    #[serde(default = "default_max_iterations")]
    pub max_fixed_point_iterations: i64,
    #[serde(default = "default_relaxation")]
    pub relaxation: f64,
    /// (R.2) velocity-level persistency on nodes that stay on the constraint or in stick
    #[serde(default)]
    pub persistency: bool,
    /// "auto" | "dense" | "sparse": the form of the Delassus operator
    #[serde(default)]
    pub contact_solve: ContactSolve,
    /// "anderson" | "none": how (F.1) updates S
    #[serde(default)]
    pub fixed_point_acceleration: FixedPointAcceleration,
    /// "auto" | "predictor" | "unfrozen": where (F.1) starts each step
    #[serde(default)]
    pub fixed_point_start: FixedPointStart,
    /// the (E.1) guard of a midpoint run: a step whose residual exceeds this fraction of the
    /// energy scale ends the run ("fail") or is reported ("warn")
    #[serde(default = "default_energy_residual_limit")]
    pub energy_residual_limit: f64,
    #[serde(default)]
    pub energy_residual_action: EnergyResidualAction,
}

/// `solver.energy_residual_limit` when omitted: [`defaults::ENERGY_RESIDUAL_LIMIT`].
fn default_energy_residual_limit() -> f64 {
    defaults::ENERGY_RESIDUAL_LIMIT
}

/// `solver.newton_tolerance` when omitted: [`defaults::NEWTON_TOLERANCE`].
fn default_newton_tolerance() -> f64 {
    defaults::NEWTON_TOLERANCE
}

/// `solver.fixed_point_tolerance` when omitted: [`defaults::FIXED_POINT_TOLERANCE`].
fn default_fixed_point_tolerance() -> f64 {
    defaults::FIXED_POINT_TOLERANCE
}

/// `solver.max_newton_iterations` and `solver.max_fixed_point_iterations` when omitted:
/// [`defaults::MAX_ITERATIONS`].
fn default_max_iterations() -> i64 {
    defaults::MAX_ITERATIONS as i64
}

/// `solver.relaxation` when omitted: [`defaults::RELAXATION`] (no relaxation).
fn default_relaxation() -> f64 {
    defaults::RELAXATION
}

impl Default for Solver {
    fn default() -> Self {
        Solver {
            inner: InnerSolver::Newton,
            mass: MassKind::Lumped,
            newton_tolerance: default_newton_tolerance(),
            fixed_point_tolerance: default_fixed_point_tolerance(),
            max_newton_iterations: default_max_iterations(),
            max_fixed_point_iterations: default_max_iterations(),
            relaxation: default_relaxation(),
            persistency: false,
            contact_solve: ContactSolve::Auto,
            fixed_point_acceleration: FixedPointAcceleration::Anderson,
            fixed_point_start: FixedPointStart::Auto,
            energy_residual_limit: default_energy_residual_limit(),
            energy_residual_action: EnergyResidualAction::Fail,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    #[serde(default = "default_output_every")]
    pub every: i64,
    /// write trajectory.f64: u and v of every free DOF at every step (studies that compare
    /// whole trajectories read it)
    #[serde(default)]
    pub trajectory: bool,
}

/// `output.every` when omitted: [`defaults::OUTPUT_EVERY`].
fn default_output_every() -> i64 {
    defaults::OUTPUT_EVERY as i64
}

impl Default for Output {
    fn default() -> Self {
        Output { every: default_output_every(), trajectory: false }
    }
}
