//! Closed-form reference solutions of spec/model.md §7, used by the tests and the benchmarks.

/// (B.1) Elastic bar (0, L) hitting a rigid wall with speed v0 at t = 0 (Signorini, g = 0,
/// p ≡ 0): the contact force per unit area is ρ c v0 on [0, 2L/c] and 0 afterwards,
/// c = sqrt(E/ρ); the bar leaves with speed v0 and energy is conserved.
pub fn bar_impact_force(rho: f64, young: f64, length: f64, v0: f64, t: f64) -> f64 {
    let c = (young / rho).sqrt();
    if (0.0..=2.0 * length / c).contains(&t) { rho * c * v0 } else { 0.0 }
}

/// Closed form of the bar hitting a compliant layer of stiffness k_n and depth g (spec/model.md §7.2),
/// valid before the reflected wave returns (t < 2L/c).
#[derive(Debug, Clone, Copy)]
pub struct CompliantLayer {
    pub rho: f64,
    pub young: f64,
    pub v0: f64,
    pub k_n: f64,
    pub g: f64,
}

impl CompliantLayer {
    /// Impedance ρc.
    pub fn impedance(&self) -> f64 {
        (self.rho * self.young).sqrt()
    }
    /// τ = ρc/k_n.
    pub fn tau(&self) -> f64 {
        self.impedance() / self.k_n
    }
    /// Time t* at which the penetration reaches g, if it does (v0 τ > g).
    pub fn t_star(&self) -> Option<f64> {
        let (tau, v0) = (self.tau(), self.v0);
        (v0 * tau > self.g).then(|| -tau * (1.0 - self.g / (v0 * tau)).ln())
    }
    /// (B.2) Penetration δ(t) of Problem P: v0 τ (1 − e^{−t/τ}) in the compliance phase,
    /// then g; the reaction beyond p(g) is λ = ρ c v0 − k_n g.
    pub fn penetration_exact(&self, t: f64) -> f64 {
        let d = self.v0 * self.tau() * (1.0 - (-t / self.tau()).exp());
        d.min(self.g)
    }
    /// (B.2) The limit of the penalty overshoot δ − g of Problem P_ε:
    /// e_∞ = ε (ρ c v0 − k_n g)/(1 + ε k_n) = O(ε).
    pub fn penalty_overshoot_limit(&self, eps: f64) -> f64 {
        (eps * (self.impedance() * self.v0 - self.k_n * self.g) / (1.0 + eps * self.k_n)).max(0.0)
    }
    /// Penetration of Problem P_ε: after t*, δ − g = e_∞ (1 − e^{−(t − t*)/τ_ε}),
    /// τ_ε = ρc/(k_n + 1/ε).
    pub fn penetration_penalty(&self, eps: f64, t: f64) -> f64 {
        match self.t_star() {
            Some(ts) if t > ts => {
                let tau_e = self.impedance() / (self.k_n + 1.0 / eps);
                self.g + self.penalty_overshoot_limit(eps) * (1.0 - (-(t - ts) / tau_e).exp())
            }
            _ => self.penetration_exact(t),
        }
    }
}

/// (B.3) Block of mass m pressed with force N and pulled with F_t under
/// μ(v) = b + (a − b) e^{−αv}, from rest: v ≡ 0 if F_t ≤ N a, otherwise
/// v(t) = (1/α) ln[(c2 + (c1 − c2) e^{α c1 t/m})/c1] with c1 = F_t − N b, c2 = N(a − b).
pub fn sliding_block_velocity(m: f64, normal: f64, pull: f64, a: f64, b: f64, alpha: f64, t: f64) -> f64 {
    if pull <= normal * a {
        return 0.0;
    }
    let c1 = pull - normal * b;
    let c2 = normal * (a - b);
    if alpha == 0.0 {
        return (pull - normal * a) * t / m;
    }
    // log-sum form, stable for large α c1 t/m
    let e = alpha * c1 * t / m;
    let val = if e > 30.0 {
        e + ((c1 - c2) + c2 * (-e).exp()).ln() - c1.ln()
    } else {
        ((c2 + (c1 - c2) * e.exp()) / c1).ln()
    };
    val / alpha
}

/// A manufactured solution of (P.1)–(P.4) without contact on a rectangle clamped at x = 0:
/// u(x, y, t) = T(t) U(x, y), U = (sin(a x) cos(b y), sin(a x) sin(b y)), T = 1 + sin(ω t).
/// With L = λT + θT', G = μT + ζT' (plane strain), σ = L div U I + 2G ε(U) and
/// Div σ = (L + G) ∇ div U + G ΔU, ΔU = −(a² + b²) U, so
/// f0 = ρ T'' U − (L + G) ∇ div U + G (a² + b²) U and f2 = σ ν on the other sides.
#[derive(Debug, Clone, Copy)]
pub struct ManufacturedKV {
    pub a: f64,
    pub b: f64,
    pub omega: f64,
    pub rho: f64,
    /// in-plane Lamé constants of B and A
    pub lambda: f64,
    pub mu: f64,
    pub theta: f64,
    pub zeta: f64,
}

impl ManufacturedKV {
    fn t_expr(&self) -> String {
        format!("(1 + sin({w}*t))", w = self.omega)
    }
    fn dt_expr(&self) -> String {
        format!("({w}*cos({w}*t))", w = self.omega)
    }
    fn ddt_expr(&self) -> String {
        format!("(-{w2}*sin({w}*t))", w = self.omega, w2 = self.omega * self.omega)
    }
    fn l_expr(&self) -> String {
        format!("({l}*{t} + {th}*{dt})", l = self.lambda, th = self.theta, t = self.t_expr(), dt = self.dt_expr())
    }
    fn g_expr(&self) -> String {
        format!("({m}*{t} + {z}*{dt})", m = self.mu, z = self.zeta, t = self.t_expr(), dt = self.dt_expr())
    }
    /// (B.5) Manufactured body force f0 = ρ T'' U − (L + G) ∇ div U + G (a² + b²) U, as two
    /// expression strings in x, y, t.
    pub fn body_force(&self) -> [String; 2] {
        let (a, b) = (self.a, self.b);
        let (l, g, ddt) = (self.l_expr(), self.g_expr(), self.ddt_expr());
        let k2 = a * a + b * b;
        let ux = format!("sin({a}*x)*cos({b}*y)");
        let uy = format!("sin({a}*x)*sin({b}*y)");
        // ∇ div U
        let gx = format!("(-{a2}*sin({a}*x)*cos({b}*y) + {ab}*cos({a}*x)*cos({b}*y))", a2 = a * a, ab = a * b);
        let gy = format!("(-{ab}*cos({a}*x)*sin({b}*y) - {b2}*sin({a}*x)*sin({b}*y))", ab = a * b, b2 = b * b);
        [
            format!("{rho}*{ddt}*{ux} - ({l} + {g})*{gx} + {g}*{k2}*{ux}", rho = self.rho),
            format!("{rho}*{ddt}*{uy} - ({l} + {g})*{gy} + {g}*{k2}*{uy}", rho = self.rho),
        ]
    }
    /// σ_xx, σ_yy, σ_xy as expression strings.
    fn stress_exprs(&self) -> [String; 3] {
        let (a, b) = (self.a, self.b);
        let (l, g) = (self.l_expr(), self.g_expr());
        let div = format!("({a}*cos({a}*x)*cos({b}*y) + {b}*sin({a}*x)*cos({b}*y))");
        let exx = format!("({a}*cos({a}*x)*cos({b}*y))");
        let eyy = format!("({b}*sin({a}*x)*cos({b}*y))");
        let gxy = format!("(-{b}*sin({a}*x)*sin({b}*y) + {a}*cos({a}*x)*sin({b}*y))");
        [format!("{l}*{div} + 2*{g}*{exx}"), format!("{l}*{div} + 2*{g}*{eyy}"), format!("{g}*{gxy}")]
    }
    /// f2 = σ ν on a side with outward normal `normal` (one of the axes).
    pub fn traction(&self, normal: [f64; 2]) -> [String; 2] {
        let [sxx, syy, sxy] = self.stress_exprs();
        let (nx, ny) = (normal[0], normal[1]);
        [format!("{nx}*({sxx}) + {ny}*({sxy})"), format!("{nx}*({sxy}) + {ny}*({syy})")]
    }
    /// Exact displacement.
    pub fn u(&self, x: f64, y: f64, t: f64) -> [f64; 2] {
        let tt = 1.0 + (self.omega * t).sin();
        [tt * (self.a * x).sin() * (self.b * y).cos(), tt * (self.a * x).sin() * (self.b * y).sin()]
    }
    /// Exact displacement gradient [[∂x ux, ∂y ux], [∂x uy, ∂y uy]].
    pub fn grad_u(&self, x: f64, y: f64, t: f64) -> [[f64; 2]; 2] {
        let tt = 1.0 + (self.omega * t).sin();
        let (a, b) = (self.a, self.b);
        [
            [tt * a * (a * x).cos() * (b * y).cos(), -tt * b * (a * x).sin() * (b * y).sin()],
            [tt * a * (a * x).cos() * (b * y).sin(), tt * b * (a * x).sin() * (b * y).cos()],
        ]
    }
    /// u0 and v0 as expression strings in x, y.
    pub fn initial(&self) -> ([String; 2], [String; 2]) {
        let (a, b, w) = (self.a, self.b, self.omega);
        (
            [format!("sin({a}*x)*cos({b}*y)"), format!("sin({a}*x)*sin({b}*y)")],
            [format!("{w}*sin({a}*x)*cos({b}*y)"), format!("{w}*sin({a}*x)*sin({b}*y)")],
        )
    }
}

/// (B.4) Hertz contact of a rigid cylinder of radius R pressed with P per unit length on an
/// elastic half-space in plane strain (E* = E/(1 − ν²)): half-width a = sqrt(4PR/(π E*)) and
/// pressure p(s) = p0 sqrt(1 − s²/a²), p0 = 2P/(π a), at distance s from the centre.
/// Returns (a, p(s)).
pub fn hertz_pressure(load: f64, radius: f64, young: f64, poisson: f64, s: f64) -> (f64, f64) {
    let e_star = young / (1.0 - poisson * poisson);
    let a = (4.0 * load * radius / (std::f64::consts::PI * e_star)).sqrt();
    let p0 = 2.0 * load / (std::f64::consts::PI * a);
    (a, p0 * (1.0 - (s / a).powi(2)).max(0.0).sqrt())
}
