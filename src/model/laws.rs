//! Contact laws of spec/model.md §1–§2 and their discrete forms of §4.2:
//! the normal compliance p and its energy P (P.5), the penalty p_ε (Pe.5), the discrete
//! gradient DP (S.3), the friction-bound normal part p_τ and the coefficient μ (P.6), and the
//! friction potential ψ (P.8).
//!
//! Every normal law here is a sum of "hinges" P(r) = Σ_j (c_j/2)(r − s_j)_+², which covers
//! linear compliance p(r) = c_ν r_+ (one hinge at 0) and its penalty (a second hinge at g
//! with stiffness 1/ε). Keeping that structure lets DP and its derivative be evaluated in
//! closed form without cancellation, and lets the conic solver write each hinge as a cone.

/// One hinge (c/2)(r − s)_+² of the normal energy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hinge {
    pub c: f64,
    pub s: f64,
}

/// A normal response p(r) = Σ_j c_j (r − s_j)_+ with energy P(r) = Σ_j (c_j/2)(r − s_j)_+².
#[derive(Debug, Clone, PartialEq)]
pub struct NormalLaw {
    pub hinges: Vec<Hinge>,
}

impl NormalLaw {
    /// (P.5) Linear normal compliance p(r) = c_ν r_+ (zero for r ≤ 0, nondecreasing).
    pub fn compliance(c_nu: f64) -> NormalLaw {
        let hinges = if c_nu > 0.0 { vec![Hinge { c: c_nu, s: 0.0 }] } else { vec![] };
        NormalLaw { hinges }
    }

    /// (Pe.5) Regularized response p_ε(r) = p(r) + (r − g)_+/ε of Problem P_ε.
    pub fn penalized(c_nu: f64, g: f64, eps: f64) -> NormalLaw {
        let mut law = NormalLaw::compliance(c_nu);
        law.hinges.push(Hinge { c: 1.0 / eps, s: g });
        law
    }

    pub fn is_zero(&self) -> bool {
        self.hinges.is_empty()
    }

    /// p(r) = Σ c_j (r − s_j)_+.
    pub fn p(&self, r: f64) -> f64 {
        self.hinges.iter().map(|h| h.c * (r - h.s).max(0.0)).sum()
    }

    /// p'(r) (right derivative at the kinks).
    pub fn dp(&self, r: f64) -> f64 {
        self.hinges.iter().map(|h| if r >= h.s { h.c } else { 0.0 }).sum()
    }

    /// The energy P(r) = ∫_0^r p = Σ (c_j/2)(r − s_j)_+² (all s_j ≥ 0).
    pub fn energy(&self, r: f64) -> f64 {
        self.hinges.iter().map(|h| 0.5 * h.c * (r - h.s).max(0.0).powi(2)).sum()
    }

    /// (S.3) Discrete gradient DP(a, b) = (P(b) − P(a))/(b − a), DP(a, a) = p(a), evaluated
    /// hinge by hinge in closed form: c(A + B)/2 when both A = a − s, B = b − s are ≥ 0,
    /// c B²/(2(B − A)) when A < 0 < B, c A²/(2(A − B)) when B < 0 < A, and 0 when both ≤ 0.
    pub fn discrete_gradient(&self, a: f64, b: f64) -> f64 {
        self.hinges.iter().map(|h| hinge_dp(h.c, a - h.s, b - h.s)).sum()
    }

    /// ∂DP(a, b)/∂b, the Newton derivative of (S.3) in its second argument.
    pub fn discrete_gradient_db(&self, a: f64, b: f64) -> f64 {
        self.hinges.iter().map(|h| hinge_dp_db(h.c, a - h.s, b - h.s)).sum()
    }
}

fn hinge_dp(c: f64, a: f64, b: f64) -> f64 {
    if a >= 0.0 && b >= 0.0 {
        0.5 * c * (a + b)
    } else if a <= 0.0 && b <= 0.0 {
        0.0
    } else if a < 0.0 {
        0.5 * c * b * b / (b - a)
    } else {
        0.5 * c * a * a / (a - b)
    }
}

fn hinge_dp_db(c: f64, a: f64, b: f64) -> f64 {
    if a >= 0.0 && b >= 0.0 {
        0.5 * c
    } else if a <= 0.0 && b <= 0.0 {
        0.0
    } else if a < 0.0 {
        0.5 * c * b * (b - 2.0 * a) / ((b - a) * (b - a))
    } else {
        0.5 * c * a * a / ((a - b) * (a - b))
    }
}

/// How a time scheme turns the normal law into the force of one step (decision 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NormalForceRule {
    /// midpoint: q = DP(d^n, d^{n+1}) (S.3)
    DiscreteGradient,
    /// trapezoid: q = (p(d^n) + p(d^{n+1}))/2
    Average,
    /// backward Euler: q = p(d^{n+1})
    EndPoint,
}

impl NormalForceRule {
    /// The force q of a step from d^n = a to d^{n+1} = b.
    pub fn force(self, law: &NormalLaw, a: f64, b: f64) -> f64 {
        match self {
            NormalForceRule::DiscreteGradient => law.discrete_gradient(a, b),
            NormalForceRule::Average => 0.5 * (law.p(a) + law.p(b)),
            NormalForceRule::EndPoint => law.p(b),
        }
    }
    /// ∂q/∂b.
    pub fn force_db(self, law: &NormalLaw, a: f64, b: f64) -> f64 {
        match self {
            NormalForceRule::DiscreteGradient => law.discrete_gradient_db(a, b),
            NormalForceRule::Average => 0.5 * law.dp(b),
            NormalForceRule::EndPoint => law.dp(b),
        }
    }
}

/// (P.6) Normal part of the friction bound, p_τ(r) = p(min(r_+, g)) ("capped", decision 1)
/// or p(r) ("uncapped"), where p is the compliance law alone (never the penalty).
#[derive(Debug, Clone, PartialEq)]
pub struct FrictionBoundLaw {
    pub compliance: NormalLaw,
    /// Some(g) caps the argument at g.
    pub cap: Option<f64>,
}

impl FrictionBoundLaw {
    /// (P.6) p_τ(r).
    pub fn p_tau(&self, r: f64) -> f64 {
        match self.cap {
            Some(g) => self.compliance.p(r.max(0.0).min(g)),
            None => self.compliance.p(r),
        }
    }
    /// sup p_τ (= p(g) capped; infinite uncapped unless the law is zero).
    pub fn sup(&self) -> f64 {
        if self.compliance.is_zero() {
            return 0.0;
        }
        match self.cap {
            Some(g) => self.compliance.p(g),
            None => f64::INFINITY,
        }
    }
}

/// (P.6) The slip-rate-dependent friction coefficient μ(r), r = ‖u̇_τ‖ ≥ 0.
#[derive(Debug, Clone, PartialEq)]
pub enum FrictionCoefficient {
    /// μ(r) = (a − b) e^{−α r} + b
    Exponential {
        a: f64,
        b: f64,
        alpha: f64,
    },
    Constant(f64),
    /// piecewise linear through (r_k, μ_k), constant beyond the last point
    Table(Vec<[f64; 2]>),
}

impl FrictionCoefficient {
    /// (P.6) μ(r): static value μ(0), Lipschitz, bounded.
    pub fn mu(&self, r: f64) -> f64 {
        let r = r.abs();
        match self {
            FrictionCoefficient::Exponential { a, b, alpha } => (a - b) * (-alpha * r).exp() + b,
            FrictionCoefficient::Constant(c) => *c,
            FrictionCoefficient::Table(pts) => {
                let last = pts[pts.len() - 1];
                if r >= last[0] {
                    return last[1];
                }
                for w in pts.windows(2) {
                    let ([r0, m0], [r1, m1]) = (w[0], w[1]);
                    if r <= r1 {
                        return m0 + (m1 - m0) * (r - r0) / (r1 - r0);
                    }
                }
                last[1]
            }
        }
    }

    /// μ'(r) (right derivative at table kinks).
    pub fn dmu(&self, r: f64) -> f64 {
        let r = r.abs();
        match self {
            FrictionCoefficient::Exponential { a, b, alpha } => -alpha * (a - b) * (-alpha * r).exp(),
            FrictionCoefficient::Constant(_) => 0.0,
            FrictionCoefficient::Table(pts) => {
                for w in pts.windows(2) {
                    let ([r0, m0], [r1, m1]) = (w[0], w[1]);
                    if r < r1 {
                        return (m1 - m0) / (r1 - r0);
                    }
                }
                0.0
            }
        }
    }

    /// L_μ = sup |μ'| of (C.k).
    pub fn lipschitz(&self) -> f64 {
        match self {
            FrictionCoefficient::Exponential { a, b, alpha } => alpha * (a - b).abs(),
            FrictionCoefficient::Constant(_) => 0.0,
            FrictionCoefficient::Table(pts) => {
                pts.windows(2).map(|w| ((w[1][1] - w[0][1]) / (w[1][0] - w[0][0])).abs()).fold(0.0, f64::max)
            }
        }
    }

    /// True when μ does not depend on the slip rate (with S's normal part at the predictor, one
    /// convex solve per step suffices; the total bound and the midpoint still iterate F.1).
    pub fn is_constant(&self) -> bool {
        match self {
            FrictionCoefficient::Constant(_) => true,
            FrictionCoefficient::Exponential { a, b, alpha } => a == b || *alpha == 0.0,
            FrictionCoefficient::Table(pts) => pts.iter().all(|p| p[1] == pts[0][1]),
        }
    }

    /// (P.8) Friction potential ψ(ξ) = ∫_0^{‖ξ‖} μ(s) ds (here for scalar ξ in 2-D).
    pub fn psi(&self, xi: f64) -> f64 {
        let r = xi.abs();
        match self {
            FrictionCoefficient::Exponential { a, b, alpha } => {
                if *alpha == 0.0 {
                    a * r
                } else {
                    // 1 − e^{−αr} = −expm1(−αr): no cancellation when αr is tiny
                    b * r + (a - b) * (-(-alpha * r).exp_m1()) / alpha
                }
            }
            FrictionCoefficient::Constant(c) => c * r,
            FrictionCoefficient::Table(pts) => {
                let mut acc = 0.0;
                for w in pts.windows(2) {
                    let ([r0, m0], [r1, m1]) = (w[0], w[1]);
                    if r <= r0 {
                        return acc;
                    }
                    let hi = r.min(r1);
                    let m_hi = m0 + (m1 - m0) * (hi - r0) / (r1 - r0);
                    acc += 0.5 * (m0 + m_hi) * (hi - r0);
                    if r <= r1 {
                        return acc;
                    }
                }
                let last = pts[pts.len() - 1];
                acc + last[1] * (r - last[0]).max(0.0)
            }
        }
    }
}
