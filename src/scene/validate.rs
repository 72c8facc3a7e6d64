//! Validating a scene: the ranges physics requires and the combinations that make sense, each
//! error with its key path, and the typed [`Model`] built from the [`Scene`].

use super::schema::{Contact, Friction, NumOrStr, Scene};
use crate::defaults;
use crate::error::{Error, Result};
use crate::model::expr::{Expr, VecExpr};
use crate::model::kinds::{
    self, Bound, BoundAt, DomainKind, EnforcementKind, FrictionBound, FrictionLaw, InnerSolver, MassKind,
};
use crate::model::laws::FrictionCoefficient;
use crate::model::{self, ContactParams, Enforcement, MaterialParams, Model, SolverParams, TimeParams};

impl Scene {
    /// Check ranges and combinations and build the typed [`Model`]: every error names its key
    /// path, every expression is parsed here once, and nothing downstream re-checks a value.
    pub fn validate(&self) -> Result<Model> {
        check_name("name", &self.name)?;
        check_text("description", &self.description)?;
        let domain = self.validate_domain()?;
        self.validate_boundary()?;
        let material = self.validate_material()?;
        let loads = self.validate_loads()?;
        let initial = self.validate_initial()?;
        if !self.boundary.contact.is_empty() && self.contact.is_none() {
            return Err(Error::scene("contact", "missing section [contact]: boundary.contact names contact sides"));
        }
        let contact = match &self.contact {
            Some(c) => Some(self.validate_contact(c)?),
            None => None,
        };
        let time = self.validate_time()?;
        let solver = self.validate_solver()?;
        if self.output.every < 0 {
            return Err(Error::scene(
                "output.every",
                format!("must be >= 0 (0: no frames), got {}", self.output.every),
            ));
        }
        Ok(Model {
            name: self.name.clone(),
            description: self.description.clone(),
            domain,
            dim: self.dim(),
            plane: self.domain.plane,
            dirichlet: self.boundary.dirichlet.clone(),
            // a [contact] section without contact sides switches nothing on
            contact_sides: if contact.is_some() { self.boundary.contact.clone() } else { Vec::new() },
            material,
            loads,
            initial,
            contact: contact.filter(|_| !self.boundary.contact.is_empty()),
            time,
            solver,
            output_every: self.output.every as usize,
            output_trajectory: self.output.trajectory,
            warnings: self.warnings(),
        })
    }

    /// Where a valid scene asks for more than the model will switch on, or for a choice that has
    /// no effect: each is said, never silent.
    fn warnings(&self) -> Vec<String> {
        let mut w = self.unused_keys();
        let Some(c) = &self.contact else { return w };
        if self.boundary.contact.is_empty() {
            w.push("the [contact] section is not used: boundary.contact names no contact side".to_string());
            return w;
        }
        let f = &c.friction;
        if f.law == FrictionLaw::Constant && f.coefficient == Some(0.0) {
            w.push("contact.friction.coefficient = 0: the contact is frictionless".to_string());
        }
        if f.law == FrictionLaw::None
            && (c.friction_bound != FrictionBound::Capped || c.friction_bound_at != BoundAt::Predictor)
        {
            w.push(
                "contact.friction_bound and friction_bound_at have no effect: contact.friction.law = \"none\""
                    .to_string(),
            );
        }
        let infinite = matches!(&c.penetration_bound, NumOrStr::Str(s) if s.trim() == "inf")
            || matches!(&c.penetration_bound, NumOrStr::Num(g) if g.is_infinite());
        if f.law != FrictionLaw::None && c.friction_bound == FrictionBound::Capped && infinite {
            w.push("contact.friction_bound = \"capped\" has no cap with penetration_bound = \"inf\": the bound is μ p(r), uncapped".to_string());
        }
        if c.friction_bound == FrictionBound::Total && c.friction_bound_at != BoundAt::Predictor {
            w.push("contact.friction_bound_at has no effect with friction_bound = \"total\" (the bound is the contact force of the iterate)".to_string());
        }
        let at_iterate = c.friction_bound != FrictionBound::Total && c.friction_bound_at == BoundAt::Midpoint;
        if f.law != FrictionLaw::None && at_iterate && self.solver.inner == InnerSolver::NewtonUnfrozen {
            w.push(
                "solver.inner = \"newton-unfrozen\" solves the bound at the predictor (N.4) or the total bound (Co.3), not the \
                 bound at the iterate's midpoint: every step is solved by the fixed point (F.1) with the frozen Newton"
                    .to_string(),
            );
        }
        w
    }

    /// The keys the chosen options do not use, each said as ignored: `penalty` beside
    /// enforcement = "exact" (the contract's scene template gives both, its comment saying ε
    /// acts only with "penalty"), the coefficients of another friction law (`--set contact.friction.law=constant
    /// --set contact.friction.coefficient=0.3` on a scene with the exponential law keeps its
    /// static, kinetic and decay), a mesh file beside a rectangle or box, size and cells beside a
    /// Gmsh mesh. A key no option knows is still refused by the schema.
    fn unused_keys(&self) -> Vec<String> {
        let mut w = Vec::new();
        let d = &self.domain;
        let kind = format!("{:?}", d.kind).to_lowercase();
        match d.kind {
            DomainKind::Rectangle | DomainKind::Box if d.file.is_some() => w.push(format!(
                "domain.file is not used with kind = \"{kind}\" and is ignored (kind = \"gmsh\" reads it)"
            )),
            DomainKind::Gmsh => {
                for (key, present) in [("size", d.size.is_some()), ("cells", d.cells.is_some())] {
                    if present {
                        w.push(format!(
                            "domain.{key} is not used with kind = \"gmsh\" (the mesh file gives the geometry) and is ignored"
                        ));
                    }
                }
            }
            _ => {}
        }
        let Some(c) = &self.contact else { return w };
        if c.enforcement == EnforcementKind::Exact && c.penalty.is_some() {
            w.push(
                "contact.penalty is not used with enforcement = \"exact\" and is ignored (enforcement = \"penalty\" uses it)"
                    .to_string(),
            );
        }
        let f = &c.friction;
        let law = format!("{:?}", f.law).to_lowercase();
        let used: &[&str] = match f.law {
            FrictionLaw::None => &[],
            FrictionLaw::Constant => &["coefficient"],
            FrictionLaw::Exponential => &["static", "kinetic", "decay"],
            FrictionLaw::Table => &["points"],
        };
        let given = [
            ("static", f.static_.is_some()),
            ("kinetic", f.kinetic.is_some()),
            ("decay", f.decay.is_some()),
            ("coefficient", f.coefficient.is_some()),
            ("points", f.points.is_some()),
        ];
        for (key, present) in given {
            if present && !used.contains(&key) {
                w.push(format!("contact.friction.{key} is not used by law = \"{law}\" and is ignored"));
            }
        }
        w
    }

    /// The space dimension of the domain: 3 for a box, 2 for a rectangle; for a Gmsh mesh (whose
    /// dimension is the file's) the number of components of the vectors the scene gives, 2 when
    /// it gives none (`Problem::new` checks it against the mesh).
    pub fn dim(&self) -> usize {
        match self.domain.kind {
            DomainKind::Box => 3,
            DomainKind::Rectangle => 2,
            DomainKind::Gmsh => self.first_vector().map_or(2, |(_, d)| d),
        }
    }

    /// (Gmsh scenes) The first vector the scene gives, by key path, and its number of
    /// components: the dimension the scene's vectors have (the mesh's must match).
    fn first_vector(&self) -> Option<(String, usize)> {
        let (l, i) = (&self.loads, &self.initial);
        [
            ("loads.body", l.body.as_ref()),
            ("loads.contact_surface", l.contact_surface.as_ref()),
            ("initial.displacement", i.displacement.as_ref()),
            ("initial.velocity", i.velocity.as_ref()),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.map(|v| (k.to_string(), v.len())))
        .chain(l.traction.iter().enumerate().map(|(j, t)| (format!("loads.traction[{j}].value"), t.value.len())))
        .next()
    }

    /// The coordinates expressions may use: x, y (, z), and t when `with_t`.
    fn space_vars(&self, with_t: bool) -> &'static [&'static str] {
        match (self.dim(), with_t) {
            (3, true) => &["x", "y", "z", "t"],
            (3, false) => &["x", "y", "z"],
            (_, true) => &["x", "y", "t"],
            (_, false) => &["x", "y"],
        }
    }

    /// A vector field of the scene at `path`: d expressions (zero when absent); the number of
    /// components must be the domain's dimension.
    fn vector_field(&self, src: Option<&[String]>, with_t: bool, path: &str) -> Result<VecExpr> {
        let d = self.dim();
        match src {
            None => Ok(VecExpr::zero(d)),
            Some(v) if v.len() != d => Err(Error::scene(
                path,
                match (self.domain.kind, self.first_vector()) {
                    (DomainKind::Gmsh, Some((first, _))) => format!(
                        "has {} components, but {first} has {d}: every vector of a Gmsh scene has the mesh's \
                         dimension (2 or 3 components)",
                        v.len()
                    ),
                    _ => format!(
                        "has {} components; the {d}-D domain (kind = {:?}) needs {d}",
                        v.len(),
                        kinds::name(&self.domain.kind)
                    ),
                },
            )),
            Some(v) => VecExpr::parse(v, self.space_vars(with_t), path),
        }
    }

    /// (P.7) The initial conditions u(0) = u0, u̇(0) = v0 of the scene, as fields in x, y (, z).
    pub fn validate_initial(&self) -> Result<model::Initial> {
        Ok(model::Initial {
            displacement: self.vector_field(self.initial.displacement.as_deref(), false, "initial.displacement")?,
            velocity: self.vector_field(self.initial.velocity.as_deref(), false, "initial.velocity")?,
        })
    }

    /// `size` and `cells` of a structured domain with `n` entries each (checked ranges).
    fn structured<const N: usize>(&self, what: &str, names: &str) -> Result<([f64; N], [usize; N])> {
        let e = |p: &str, m: String| Err(Error::scene(p, m));
        let d = &self.domain;
        let Some(size) = &d.size else {
            return e("domain.size", format!("missing: a {what} needs size = [{names}]"));
        };
        let Ok(size) = <[f64; N]>::try_from(size.as_slice()) else {
            return e("domain.size", format!("a {what} needs {N} entries [{names}], got {}", size.len()));
        };
        for (i, s) in size.iter().enumerate() {
            if !(s.is_finite() && *s > 0.0) {
                return e(&format!("domain.size[{i}]"), format!("must be a finite number > 0, got {s}"));
            }
        }
        let Some(cells) = &d.cells else {
            return e(
                "domain.cells",
                format!("missing: a {what} needs cells = [{}]", if N == 3 { "nx, ny, nz" } else { "nx, ny" }),
            );
        };
        let Ok(cells) = <[i64; N]>::try_from(cells.as_slice()) else {
            return e("domain.cells", format!("a {what} needs {N} entries, got {}", cells.len()));
        };
        for (i, c) in cells.iter().enumerate() {
            if *c < 1 {
                return e(&format!("domain.cells[{i}]"), format!("must be >= 1, got {c}"));
            }
            if *c > defaults::MAX_CELLS_PER_SIDE {
                let max = defaults::MAX_CELLS_PER_SIDE;
                return e(&format!("domain.cells[{i}]"), format!("must be <= {max}, got {c}"));
            }
        }
        Ok((size, cells.map(|c| c as usize)))
    }

    fn validate_domain(&self) -> Result<model::Domain> {
        let e = |p: &str, m: String| Err(Error::scene(p, m));
        let d = &self.domain;
        match d.kind {
            DomainKind::Rectangle => {
                let (size, cells) = self.structured::<2>("rectangle", "Lx, Ly")?;
                Ok(model::Domain::Rectangle { size, cells })
            }
            DomainKind::Box => {
                if d.plane.is_some() {
                    return e(
                        "domain.plane",
                        "is a 2-D key (plane strain or stress); a box is three-dimensional: remove it".into(),
                    );
                }
                let (size, cells) = self.structured::<3>("box", "Lx, Ly, Lz")?;
                Ok(model::Domain::Box { size, cells })
            }
            DomainKind::Gmsh => {
                let file = match &d.file {
                    None => {
                        return e("domain.file", "missing: kind = \"gmsh\" needs file = \"path/to/mesh.msh\"".into());
                    }
                    Some(f) if f.trim().is_empty() => return e("domain.file", "is empty".into()),
                    Some(f) => f.clone(),
                };
                Ok(model::Domain::Gmsh { file })
            }
        }
    }

    fn validate_boundary(&self) -> Result<()> {
        for (i, s) in self.boundary.dirichlet.iter().enumerate() {
            if self.boundary.contact.contains(s) {
                return Err(Error::scene(
                    format!("boundary.dirichlet[{i}]"),
                    format!("side {s:?} is also a contact side; a side is either clamped (Γ1) or in contact (Γ3)"),
                ));
            }
        }
        for (name, list) in [("dirichlet", &self.boundary.dirichlet), ("contact", &self.boundary.contact)] {
            for (i, s) in list.iter().enumerate() {
                if list[..i].contains(s) {
                    return Err(Error::scene(format!("boundary.{name}[{i}]"), format!("side {s:?} is listed twice")));
                }
            }
        }
        Ok(())
    }

    fn validate_material(&self) -> Result<MaterialParams> {
        let e = |p: &str, m: String| Err(Error::scene(p, m));
        let m = &self.material;
        if !(m.density.is_finite() && m.density > 0.0) {
            return e("material.density", format!("must be a finite number > 0, got {}", m.density));
        }
        if !(m.young.is_finite() && m.young > 0.0) {
            return e("material.young", format!("must be a finite number > 0, got {}", m.young));
        }
        if !(m.poisson.is_finite() && m.poisson > -1.0 && m.poisson < 0.5) {
            return e("material.poisson", format!("must be in (-1, 0.5), got {}", m.poisson));
        }
        let v = m.viscosity;
        if !(v.theta.is_finite() && v.theta >= 0.0) {
            return e("material.viscosity.theta", format!("must be >= 0, got {}", v.theta));
        }
        if !(v.zeta.is_finite() && v.zeta >= 0.0) {
            return e("material.viscosity.zeta", format!("must be >= 0, got {}", v.zeta));
        }
        Ok(MaterialParams { density: m.density, young: m.young, poisson: m.poisson, theta: v.theta, zeta: v.zeta })
    }

    fn validate_loads(&self) -> Result<model::Loads> {
        let e = |p: &str, m: String| Err(Error::scene(p, m));
        let body = self.vector_field(self.loads.body.as_deref(), true, "loads.body")?;
        let f3 = self.vector_field(self.loads.contact_surface.as_deref(), true, "loads.contact_surface")?;
        if !f3.is_zero() && self.boundary.contact.is_empty() {
            return e("loads.contact_surface", "acts on Γ3 but boundary.contact is empty".into());
        }
        let mut traction = Vec::new();
        for (i, tr) in self.loads.traction.iter().enumerate() {
            let p = format!("loads.traction[{i}]");
            let path = format!("{p}.value");
            let value = self.vector_field(Some(&tr.value), true, &path)?;
            if self.boundary.dirichlet.contains(&tr.side) {
                return e(
                    &format!("{p}.side"),
                    format!("{:?} is a Dirichlet side (Γ1); tractions act on Γ2 only", tr.side),
                );
            }
            if self.boundary.contact.contains(&tr.side) {
                return e(
                    &format!("{p}.side"),
                    format!("{:?} is a contact side (Γ3); tractions act on Γ2 only", tr.side),
                );
            }
            if self.loads.traction[..i].iter().any(|o| o.side == tr.side) {
                return e(&format!("{p}.side"), format!("{:?} already has a traction; give one per side", tr.side));
            }
            traction.push(model::Traction { side: tr.side.clone(), value, path });
        }
        Ok(model::Loads { body, traction, contact_surface: (!f3.is_zero()).then_some(f3) })
    }

    fn validate_time(&self) -> Result<TimeParams> {
        let e = |p: &str, m: String| Err(Error::scene(p, m));
        let t = &self.time;
        if !(t.end.is_finite() && t.end > 0.0) {
            return e("time.end", format!("must be a finite number > 0, got {}", t.end));
        }
        if !(t.step.is_finite() && t.step > 0.0) {
            return e("time.step", format!("must be a finite number > 0, got {}", t.step));
        }
        if t.step > t.end * (1.0 + 1e-12) {
            return e("time.step", format!("must be <= time.end = {}, got {}", t.end, t.step));
        }
        let n = (t.end / t.step).round();
        if n > defaults::MAX_STEPS as f64 {
            let count = if n < 1e15 { format!("{n:.0}") } else { format!("{n:.3e}") };
            return e(
                "time.step",
                format!(
                    "too many steps ({count}), at most {}: choose time.step >= {:.3e}",
                    defaults::MAX_STEPS,
                    t.end / defaults::MAX_STEPS as f64
                ),
            );
        }
        if (n * t.step - t.end).abs() > 1e-6 * t.step {
            return e(
                "time.step",
                format!(
                    "time.end / time.step = {:.6} is not a whole number of steps; choose step = end / N (e.g. {:.6e})",
                    t.end / t.step,
                    t.end / n.max(1.0)
                ),
            );
        }
        Ok(TimeParams { end: t.end, step: t.step, steps: n as usize, scheme: t.scheme })
    }

    fn validate_solver(&self) -> Result<SolverParams> {
        let e = |p: &str, m: String| Err(Error::scene(p, m));
        let s = &self.solver;
        for (key, val) in [("newton_tolerance", s.newton_tolerance), ("fixed_point_tolerance", s.fixed_point_tolerance)]
        {
            if !(val.is_finite() && val > 0.0 && val < 1.0) {
                return e(&format!("solver.{key}"), format!("must be in (0, 1), got {val}"));
            }
        }
        for (key, val) in [
            ("max_newton_iterations", s.max_newton_iterations),
            ("max_fixed_point_iterations", s.max_fixed_point_iterations),
        ] {
            if !(1..=100_000).contains(&val) {
                return e(&format!("solver.{key}"), format!("must be in 1..=100000, got {val}"));
            }
        }
        if !(s.relaxation.is_finite() && s.relaxation > 0.0 && s.relaxation <= 1.0) {
            return e("solver.relaxation", format!("must be in (0, 1], got {}", s.relaxation));
        }
        if !(s.energy_residual_limit.is_finite() && s.energy_residual_limit > 0.0) {
            return e(
                "solver.energy_residual_limit",
                format!(
                    "must be a finite number > 0 (a fraction of the energy scale), got {}",
                    s.energy_residual_limit
                ),
            );
        }
        if s.persistency && s.mass == MassKind::Consistent {
            return e(
                "solver.persistency",
                "needs a diagonal mass (mass = \"lumped\" or \"modified\"): with the consistent mass, zeroing one node's \
                 velocity does not remove a nonnegative kinetic energy"
                    .into(),
            );
        }
        if s.mass == MassKind::Modified && self.boundary.contact.is_empty() {
            return e(
                "solver.mass",
                "\"modified\" moves the mass of the contact nodes and needs a contact side".into(),
            );
        }
        Ok(SolverParams {
            inner: s.inner,
            mass: s.mass,
            newton_tolerance: s.newton_tolerance,
            fixed_point_tolerance: s.fixed_point_tolerance,
            max_newton_iterations: s.max_newton_iterations as usize,
            max_fixed_point_iterations: s.max_fixed_point_iterations as usize,
            relaxation: s.relaxation,
            persistency: s.persistency,
            contact_solve: s.contact_solve,
            fixed_point_acceleration: s.fixed_point_acceleration,
            fixed_point_start: s.fixed_point_start,
            energy_residual_limit: s.energy_residual_limit,
            energy_residual_action: s.energy_residual_action,
        })
    }

    fn validate_contact(&self, c: &Contact) -> Result<ContactParams> {
        let e = |p: &str, m: String| Err(Error::scene(p, m));
        let gap = match &c.gap {
            None => Expr::constant(0.0),
            Some(NumOrStr::Str(g)) => Expr::parse(g, self.space_vars(false), "contact.gap")?,
            Some(NumOrStr::Num(g)) if !g.is_finite() => return e("contact.gap", format!("must be finite, got {g}")),
            Some(NumOrStr::Num(g)) => Expr::constant(*g),
        };
        if !(c.compliance.is_finite() && c.compliance >= 0.0) {
            return e("contact.compliance", format!("must be >= 0, got {}", c.compliance));
        }
        let bound = Self::bound_of(c)?;
        let enforcement = match (c.enforcement, c.penalty) {
            (EnforcementKind::Penalty, None) => {
                return e("contact.penalty", "missing: enforcement = \"penalty\" needs penalty = ε > 0".into());
            }
            (EnforcementKind::Penalty, Some(eps)) if !(eps.is_finite() && eps > 0.0) => {
                return e("contact.penalty", format!("must be a finite number > 0, got {eps}"));
            }
            (EnforcementKind::Penalty, Some(eps)) => Enforcement::Penalty { epsilon: eps },
            // a penalty beside enforcement = "exact" is ignored, and said (`Scene::warnings`)
            (EnforcementKind::Exact, _) => Enforcement::Exact,
        };
        if c.enforcement == EnforcementKind::Penalty && bound == Bound::Infinite {
            return e(
                "contact.enforcement",
                "\"penalty\" penalizes u_ν > g and needs a finite penetration_bound".into(),
            );
        }
        if bound == Bound::Infinite && c.compliance == 0.0 {
            return e(
                "contact.compliance",
                "is 0 and penetration_bound is \"inf\": the foundation exerts no force; give compliance > 0 or a finite bound".into(),
            );
        }
        let friction = validate_friction(&c.friction)?;
        let switched_on = friction.as_ref().is_some_and(|mu| !(mu.is_constant() && mu.mu(0.0) == 0.0));
        if switched_on && c.compliance == 0.0 && c.friction_bound != FrictionBound::Total {
            return e(
                "contact.friction_bound",
                format!(
                    "is \"{}\", the friction bound μ p_τ(u_ν) with p_τ from the compliance, which is identically 0 with \
                     compliance = 0: the friction law would be switched off. For Coulomb friction with the whole contact \
                     force (Signorini–Coulomb with g = 0) set friction_bound = \"total\"; or give compliance > 0",
                    kinds::name(&c.friction_bound)
                ),
            );
        }
        Ok(ContactParams {
            gap,
            compliance: c.compliance,
            bound,
            enforcement,
            friction_bound: c.friction_bound,
            friction_bound_at: c.friction_bound_at,
            friction,
        })
    }

    /// The penetration bound of a contact section.
    pub fn bound_of(c: &Contact) -> Result<Bound> {
        match &c.penetration_bound {
            NumOrStr::Num(g) if g.is_finite() && *g >= 0.0 => Ok(Bound::Finite(*g)),
            NumOrStr::Num(g) if *g == f64::INFINITY => Ok(Bound::Infinite),
            NumOrStr::Num(g) => {
                Err(Error::scene("contact.penetration_bound", format!("must be >= 0 or \"inf\", got {g}")))
            }
            NumOrStr::Str(s) if s.trim() == "inf" => Ok(Bound::Infinite),
            NumOrStr::Str(s) => Err(Error::scene(
                "contact.penetration_bound",
                format!("must be a number >= 0 or the string \"inf\", got {s:?}"),
            )),
        }
    }
}

/// The friction section: the keys each law needs, and the coefficient μ it defines (None for
/// `law = "none"`); another law's keys are ignored and said ([`Scene::unused_keys`]).
fn validate_friction(f: &Friction) -> Result<Option<FrictionCoefficient>> {
    let e = |p: &str, m: String| Err(Error::scene(p, m));
    let p = "contact.friction";
    let need = |key: &str, v: Option<f64>| -> Result<f64> {
        match v {
            None => Err(Error::scene(
                format!("{p}.{key}"),
                format!("missing: law = \"{}\" needs it", format!("{:?}", f.law).to_lowercase()),
            )),
            Some(x) if !(x.is_finite() && x >= 0.0) => {
                Err(Error::scene(format!("{p}.{key}"), format!("must be >= 0, got {x}")))
            }
            Some(x) if key != "decay" && x > defaults::MAX_FRICTION_COEFFICIENT => Err(Error::scene(
                format!("{p}.{key}"),
                format!("a friction coefficient must be at most {}, got {x}", defaults::MAX_FRICTION_COEFFICIENT),
            )),
            Some(x) => Ok(x),
        }
    };
    if f.law == FrictionLaw::Table {
        let Some(pts) = &f.points else {
            return e(
                &format!("{p}.points"),
                "missing: law = \"table\" needs points = [[r0, mu0], [r1, mu1], ...]".into(),
            );
        };
        validate_table(pts)?;
    }
    Ok(match f.law {
        FrictionLaw::None => None,
        FrictionLaw::Constant => Some(FrictionCoefficient::Constant(need("coefficient", f.coefficient)?)),
        FrictionLaw::Exponential => Some(FrictionCoefficient::Exponential {
            a: need("static", f.static_)?,
            b: need("kinetic", f.kinetic)?,
            alpha: need("decay", f.decay)?,
        }),
        FrictionLaw::Table => f.points.clone().map(FrictionCoefficient::Table),
    })
}

/// The points of `law = "table"`: μ(0) first, finite, μ ≥ 0, slip rates strictly increasing.
fn validate_table(pts: &[[f64; 2]]) -> Result<()> {
    let e = |p: &str, m: String| Err(Error::scene(p, m));
    let p = "contact.friction";
    if pts.is_empty() {
        return e(&format!("{p}.points"), "is empty; give at least one [slip rate, mu] pair".into());
    }
    if pts[0][0] != 0.0 {
        return e(
            &format!("{p}.points[0][0]"),
            format!("the first slip rate must be 0 (μ(0) is the static value), got {}", pts[0][0]),
        );
    }
    for (i, [r, mu]) in pts.iter().enumerate() {
        if !(r.is_finite() && mu.is_finite()) {
            return e(&format!("{p}.points[{i}]"), "must be finite numbers".into());
        }
        if *mu < 0.0 {
            return e(&format!("{p}.points[{i}][1]"), format!("μ must be >= 0, got {mu}"));
        }
        if *mu > defaults::MAX_FRICTION_COEFFICIENT {
            return e(
                &format!("{p}.points[{i}][1]"),
                format!("a friction coefficient must be at most {}, got {mu}", defaults::MAX_FRICTION_COEFFICIENT),
            );
        }
        if i > 0 && *r <= pts[i - 1][0] {
            return e(
                &format!("{p}.points[{i}][0]"),
                format!("slip rates must increase strictly, got {} after {}", r, pts[i - 1][0]),
            );
        }
    }
    Ok(())
}

/// A name that becomes a folder (`out/<name>`) and reaches generated files (the Snakefile, CSV,
/// SVG): 1 to 100 characters from letters, digits and `_ - . +`, not starting with `.` or `-`.
pub fn check_name(key: &str, name: &str) -> Result<()> {
    let ok_char = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '+');
    if name.is_empty() || name.len() > 100 || !name.chars().all(ok_char) || name.starts_with(['.', '-']) {
        return Err(Error::scene(
            key,
            format!(
                "must be 1 to 100 letters, digits or _ - . + (not starting with . or -): it names a folder and files; got {name:?}"
            ),
        ));
    }
    Ok(())
}

/// Free text (a description, a label): any character but control characters other than tab.
pub fn check_text(key: &str, text: &str) -> Result<()> {
    match text.chars().find(|c| c.is_control() && *c != '\t') {
        Some(c) => Err(Error::scene(key, format!("holds the control character {:?}: give plain text on one line", c))),
        None => Ok(()),
    }
}
