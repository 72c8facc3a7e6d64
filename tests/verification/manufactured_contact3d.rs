//! (B.5) Dynamic manufactured solutions *with contact* in three dimensions (spec/model.md §7.5
//! recipe), on the unit cube clamped at the top (z = 1), contact on the bottom (ν = (0, 0, −1),
//! tangent plane x–y), the four other faces loaded by f2 = σν:
//!
//!   u = (1 − z) (A(t) + c x², B(t) + c y², −D(x, y, t)),
//!   A = (V/ω) sin ωt,  B = (V/ω)(1 − cos ωt),  D = δ0 + e x + f y + η sin 2t,
//!
//! so on Γ3 the penetration is d = D − gap and the slip rate is u̇_τ = V (cos ωt, sin ωt): a
//! constant speed in a direction that turns in the tangent plane (by ωT = 1.5 rad over the run).
//! By hand (φ = 1 − z, tr ε = 2c(x + y)φ + D, tr ε̇ = Ḋ):
//!   σ_xx = λ tr ε + 4μ c x φ + θ Ḋ,  σ_yy = λ tr ε + 4μ c y φ + θ Ḋ,  σ_zz = λ tr ε + 2μ D + (θ + 2ζ) Ḋ,
//!   σ_xy = 0,  σ_xz = −μ (A + c x² + φ e) − ζ A′,  σ_yz = −μ (B + c y² + φ f) − ζ B′,
//!   Div σ = (λ(2cφ + e) + 4μcφ + μe, λ(2cφ + f) + 4μcφ + μf, −2c(λ + μ)(x + y)),
//! f0 = ρü − Div σ, and the known load f3 on Γ3 closes σν = f3 − (p + λ)ν − t in the chosen regime:
//! - separation: gap = 0.2 > D, no contact force: f3 = σν;
//! - compliance with friction in slip: gap = 0, g = inf: f3 = σν + p(D)ν + μ(V) p(D) (cos ωt, sin ωt, 0);
//! - the constraint active: e = f = η = 0, δ0 = g, a prescribed λ = 5(1 + x + y + ½ sin 2t) ≥ 0:
//!   f3 = σν + (p(g) + λ)ν + μ(V) p(g) (cos ωt, sin ωt, 0) (capped bound).
//!
//! Friction is velocity strengthening, μ(r) = 0.6 − 0.3 e^{−5r}, as in 2-D (tests/verification/manufactured_contact.rs:
//! under weakening the uniform slip is dynamically unstable on these meshes).
//! Expected: energy-norm order ≈ 1 in h (P1); midpoint order ≈ 2 in k while the solution stays in
//! one regime (it does by construction). Asserted within ±0.2 (h) and ±0.3 (k: the friction bound
//! uses p_τ at the predictor and the slip rate at the midpoint, both O(k²) consistent, with larger
//! constants), as in 2-D; measured values are printed and recorded.

use crate::common;

use common::Regime;

use dyncontact::fem::norms::error_norms_3d;
use dyncontact::model::material::lame;
use dyncontact::scene::Scene;

const END: f64 = 0.5;
const RHO: f64 = 1.0;
const YOUNG: f64 = 10.0;
const POISSON: f64 = 0.3;
const THETA: f64 = 0.01;
const ZETA: f64 = 0.01;
const CQ: f64 = 0.02; // c
const C_NU: f64 = 50.0;
const SPEED: f64 = 0.05; // V
const OMEGA: f64 = 3.0; // ω

struct Mms {
    regime: Regime,
    delta0: f64,
    e: f64,
    f: f64,
    eta: f64,
}

impl Mms {
    fn new(regime: Regime) -> Mms {
        match regime {
            Regime::Constraint => Mms { regime, delta0: 0.02, e: 0.0, f: 0.0, eta: 0.0 },
            _ => Mms { regime, delta0: 0.02, e: 0.01, f: 0.005, eta: 0.005 },
        }
    }
    fn a(t: f64) -> f64 {
        SPEED / OMEGA * (OMEGA * t).sin()
    }
    fn b(t: f64) -> f64 {
        SPEED / OMEGA * (1.0 - (OMEGA * t).cos())
    }
    fn d(&self, x: f64, y: f64, t: f64) -> f64 {
        self.delta0 + self.e * x + self.f * y + self.eta * (2.0 * t).sin()
    }
    fn u(&self, [x, y, z]: [f64; 3], t: f64) -> [f64; 3] {
        let phi = 1.0 - z;
        [phi * (Self::a(t) + CQ * x * x), phi * (Self::b(t) + CQ * y * y), -phi * self.d(x, y, t)]
    }
    /// ∂_j u_i at [i][j]
    fn grad(&self, [x, y, z]: [f64; 3], t: f64) -> [[f64; 3]; 3] {
        let phi = 1.0 - z;
        [
            [2.0 * CQ * x * phi, 0.0, -(Self::a(t) + CQ * x * x)],
            [0.0, 2.0 * CQ * y * phi, -(Self::b(t) + CQ * y * y)],
            [-phi * self.e, -phi * self.f, self.d(x, y, t)],
        ]
    }
    // expression strings
    fn s_a(&self) -> String {
        format!("({}*sin({OMEGA}*t))", SPEED / OMEGA)
    }
    fn s_b(&self) -> String {
        format!("({}*(1 - cos({OMEGA}*t)))", SPEED / OMEGA)
    }
    fn s_ad(&self) -> String {
        format!("({SPEED}*cos({OMEGA}*t))")
    }
    fn s_bd(&self) -> String {
        format!("({SPEED}*sin({OMEGA}*t))")
    }
    fn s_d(&self) -> String {
        format!("({} + {}*x + {}*y + {}*sin(2*t))", self.delta0, self.e, self.f, self.eta)
    }
    fn s_dd(&self) -> String {
        format!("({}*cos(2*t))", 2.0 * self.eta)
    }
    /// σ_xx, σ_yy, σ_zz, σ_xz, σ_yz (σ_xy = 0) as strings in x, y, z, t.
    fn stress(&self) -> [String; 5] {
        let (l, m) = lame(YOUNG, POISSON);
        let tr = format!("(2*{CQ}*(x + y)*(1 - z) + {})", self.s_d());
        let dd = self.s_dd();
        [
            format!("{l}*{tr} + {}*x*(1 - z) + {THETA}*{dd}", 4.0 * m * CQ),
            format!("{l}*{tr} + {}*y*(1 - z) + {THETA}*{dd}", 4.0 * m * CQ),
            format!("{l}*{tr} + {}*{} + {}*{dd}", 2.0 * m, self.s_d(), THETA + 2.0 * ZETA),
            format!("-{m}*({} + {CQ}*x^2 + (1 - z)*{}) - {ZETA}*{}", self.s_a(), self.e, self.s_ad()),
            format!("-{m}*({} + {CQ}*y^2 + (1 - z)*{}) - {ZETA}*{}", self.s_b(), self.f, self.s_bd()),
        ]
    }
    /// f0 = ρü − Div σ.
    fn body(&self) -> [String; 3] {
        let (l, m) = lame(YOUNG, POISSON);
        let (add, bdd) =
            (format!("({}*sin({OMEGA}*t))", -SPEED * OMEGA), format!("({}*cos({OMEGA}*t))", SPEED * OMEGA));
        [
            format!(
                "{RHO}*(1 - z)*{add} - ({l}*(2*{CQ}*(1 - z) + {e}) + {}*(1 - z) + {}*{e})",
                4.0 * m * CQ,
                m,
                e = self.e
            ),
            format!(
                "{RHO}*(1 - z)*{bdd} - ({l}*(2*{CQ}*(1 - z) + {f}) + {}*(1 - z) + {}*{f})",
                4.0 * m * CQ,
                m,
                f = self.f
            ),
            format!("{RHO}*(1 - z)*({}*sin(2*t)) + {}*(x + y)", 4.0 * self.eta, 2.0 * CQ * (l + m)),
        ]
    }
    /// f2 = σν on the side with outward normal ±e_axis (axis 0: x, 1: y).
    fn traction(&self, axis: usize, sign: f64) -> [String; 3] {
        let [sxx, syy, _, sxz, syz] = self.stress();
        let row = if axis == 0 { [sxx, "0".into(), sxz] } else { ["0".into(), syy, syz] };
        row.map(|v| format!("{sign}*({v})"))
    }
    /// f3 on Γ3 (z = 0): σν + contact terms of the regime.
    fn f3(&self) -> [String; 3] {
        let [_, _, szz, sxz, syz] = self.stress();
        let mu = format!("((0.3 - 0.6)*exp(-5*{SPEED}) + 0.6)");
        let (c, s) = (format!("cos({OMEGA}*t)"), format!("sin({OMEGA}*t)"));
        match self.regime {
            Regime::Separation => [format!("-({sxz})"), format!("-({syz})"), format!("-({szz})")],
            Regime::Slip => {
                let p = format!("({C_NU}*{})", self.s_d());
                [format!("-({sxz}) + {mu}*{p}*{c}"), format!("-({syz}) + {mu}*{p}*{s}"), format!("-({szz}) - {p}")]
            }
            Regime::Constraint => {
                let pg = C_NU * self.delta0;
                [
                    format!("-({sxz}) + {mu}*{pg}*{c}"),
                    format!("-({syz}) + {mu}*{pg}*{s}"),
                    format!("-({szz}) - ({pg} + 5*(1 + x + y + 0.5*sin(2*t)))"),
                ]
            }
        }
    }
    fn scene(&self, cells: usize, k: f64) -> Scene {
        let (gap, bound) = match self.regime {
            Regime::Separation => ("0.2", "\"inf\"".to_string()),
            Regime::Slip => ("0", "\"inf\"".to_string()),
            Regime::Constraint => ("0", format!("{}", self.delta0)),
        };
        let vec3 = |v: &[String; 3]| format!("[\"{}\", \"{}\", \"{}\"]", v[0], v[1], v[2]);
        let side =
            |name: &str, v: [String; 3]| format!("[[loads.traction]]\nside = \"{name}\"\nvalue = {}\n", vec3(&v));
        let tractions = [
            side("left", self.traction(0, -1.0)),
            side("right", self.traction(0, 1.0)),
            side("front", self.traction(1, -1.0)),
            side("back", self.traction(1, 1.0)),
        ]
        .concat();
        let d0 = format!("({} + {}*x + {}*y)", self.delta0, self.e, self.f);
        let text = format!(
            r#"
name = "mms_contact3d"
[domain]
kind = "box"
size = [1.0, 1.0, 1.0]
cells = [{cells}, {cells}, {cells}]
[boundary]
dirichlet = ["top"]
contact = ["bottom"]
[material]
density = {RHO}
young = {YOUNG}
poisson = {POISSON}
viscosity = {{ theta = {THETA}, zeta = {ZETA} }}
[loads]
body = {}
contact_surface = {}
{tractions}
[initial]
displacement = ["(1 - z)*{CQ}*x^2", "(1 - z)*{CQ}*y^2", "-(1 - z)*{d0}"]
velocity = ["(1 - z)*{SPEED}", "0", "-(1 - z)*{}"]
[contact]
gap = "{gap}"
compliance = {C_NU}
penetration_bound = {bound}
[contact.friction]
law = "exponential"
static = 0.3
kinetic = 0.6
decay = 5.0
[time]
end = {END}
step = {k}
[solver]
newton_tolerance = 1e-12
fixed_point_tolerance = 1e-12
max_fixed_point_iterations = 200
"#,
            vec3(&self.body()),
            vec3(&self.f3()),
            2.0 * self.eta,
        );
        Scene::from_toml(&text, "mms_contact3d").unwrap_or_else(|e| panic!("{e}"))
    }
}

fn check(regime: Regime) {
    let m = Mms::new(regime);
    // space: k = 1/256 keeps the O(k²) time error well below the finest energy error
    let mut en = Vec::new();
    for cells in [4, 8, 16] {
        let (p, u, seen) = common::run_regimes(m.scene(cells, 1.0 / 256.0));
        let (_, e1) = error_norms_3d(
            p.mesh.solid().expect("a 3-D mesh"),
            &p.material,
            &p.dofs.expand_dim(&u),
            |x| m.u(x, END),
            |x| m.grad(x, END),
        );
        en.push(e1);
        if cells == 16 {
            regime.assert_seen(seen);
        }
    }
    // time: self-convergence on 4×4×4 cells
    let ks = [END / 8.0, END / 16.0, END / 32.0, END / 64.0, END / 128.0];
    let ek = common::self_convergence_in_k(&ks, |k| m.scene(4, k));
    common::assert_contact_orders("manufactured_contact3d", &format!("3-D {regime:?}"), &en, &ek);
}

/// (B.5) in 3-D, separation: energy order ≈ 1 in h, midpoint order ≈ 2 in k; no contact force acts.
#[test]
fn b5_mms_contact3d_separation() {
    check(Regime::Separation);
}

/// (B.5) (P.5) (P.6) (S.5) in 3-D, compliance with friction on the disk, slipping at a constant
/// speed in a direction that turns in the tangent plane: orders ≈ 1 (h), ≈ 2 (k).
#[test]
fn b5_mms_contact3d_slip_turning() {
    check(Regime::Slip);
}

/// (B.5) (S.4) in 3-D, the constraint active (u_ν ≡ g) with a prescribed λ ≥ 0 and capped
/// friction slipping along a turning direction: orders ≈ 1 (h), ≈ 2 (k).
#[test]
fn b5_mms_contact3d_constraint_active() {
    check(Regime::Constraint);
}
