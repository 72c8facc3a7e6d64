//! The Kelvin–Voigt material (P.1): elasticity B, viscosity A, density ρ, in plane strain or
//! plane stress, as 3×3 matrices in Voigt notation (ε_xx, ε_yy, γ_xy = 2ε_xy), and in three
//! dimensions as 6×6 matrices (ε_xx, ε_yy, ε_zz, γ_yz, γ_xz, γ_xy).

use nalgebra::{Matrix3, Matrix6};

use super::MaterialParams;
use super::kinds::Plane;

/// Lamé constants (λ, μ_L) from Young's modulus E and Poisson's ratio ν.
pub fn lame(young: f64, poisson: f64) -> (f64, f64) {
    let mu = young / (2.0 * (1.0 + poisson));
    let lambda = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
    (lambda, mu)
}

/// Density and the two isotropic operators of (P.1), reduced to the plane.
#[derive(Debug, Clone, Copy)]
pub struct Material {
    pub rho: f64,
    /// B ε = λ tr(ε) I + 2 μ_L ε (in-plane constants after the plane reduction)
    pub lambda: f64,
    pub mu_lame: f64,
    /// A ε = θ tr(ε) I + 2 ζ ε (in-plane constants after the plane reduction)
    pub theta: f64,
    pub zeta: f64,
    /// 3-D constants, kept for σ_zz in plane strain
    pub lambda_3d: f64,
    pub theta_3d: f64,
    pub plane: Plane,
    /// (Ps.1) plane stress with A not proportional to B: ε_zz is an internal variable, the
    /// in-plane constants above are the 3-D ones (the plane-strain forms), and this law adds
    /// the trace stress λ ε_zz + θ ε̇_zz. None otherwise (ε_zz eliminated algebraically).
    pub thickness: Option<ThicknessLaw>,
}

/// (Ps.1) The law of the out-of-plane strain s = ε_zz in plane stress: σ_zz = 0 reads
/// Λ s + Θ ṡ = −λ e − θ ė with e = ε_xx + ε_yy, Λ = λ + 2μ_L, Θ = θ + 2ζ (the scene's 3-D
/// constants), and s adds λ s + θ ṡ to σ_xx and σ_yy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThicknessLaw {
    pub lambda: f64,
    pub mu: f64,
    pub theta: f64,
    pub zeta: f64,
}

impl ThicknessLaw {
    /// Λ = λ + 2μ_L
    pub fn big_lambda(&self) -> f64 {
        self.lambda + 2.0 * self.mu
    }

    /// Θ = θ + 2ζ
    pub fn big_theta(&self) -> f64 {
        self.theta + 2.0 * self.zeta
    }

    /// (Ps.1) ṡ from σ_zz = 0 at one instant: ṡ = −(Λ s + λ e + θ ė)/Θ (Θ > 0 on this path).
    pub fn rate(&self, s: f64, e: f64, e_dot: f64) -> f64 {
        -(self.big_lambda() * s + self.lambda * e + self.theta * e_dot) / self.big_theta()
    }

    /// (Ps.1) The stress s adds to σ_xx and σ_yy: λ s + θ ṡ.
    pub fn trace_stress(&self, s: f64, e: f64, e_dot: f64) -> f64 {
        self.lambda * s + self.theta * self.rate(s, e, e_dot)
    }

    /// (Ps.1) s^0 = −(λ/Λ) e(u^0): the state of the elastic plane-stress reduction (s = 0 for an
    /// undeformed start), where the algebraic path would put it when A ∝ B.
    pub fn initial(&self, e0: f64) -> f64 {
        -self.lambda / self.big_lambda() * e0
    }
}

/// A = β B for some β ≥ 0 (θ μ_L = ζ λ to 1e-12): plane stress then eliminates ε_zz algebraically.
pub fn viscosity_proportional(lambda: f64, mu: f64, theta: f64, zeta: f64) -> bool {
    (theta * mu - zeta * lambda).abs() <= 1e-12 * (theta * mu).abs().max((zeta * lambda).abs())
}

impl Material {
    /// The plane-reduced material of the scene's constants.
    pub fn new(m: &MaterialParams, plane: Plane) -> Material {
        let (lambda, mu) = lame(m.young, m.poisson);
        let (theta, zeta) = (m.theta, m.zeta);
        let plane_strain = Material {
            rho: m.density,
            lambda,
            mu_lame: mu,
            theta,
            zeta,
            lambda_3d: lambda,
            theta_3d: theta,
            plane,
            thickness: None,
        };
        match plane {
            Plane::Strain => plane_strain,
            // decision 11: σ_zz = 0 eliminates ε_zz when A ∝ B, giving λ* = 2λμ/(λ + 2μ) and the
            // same for (θ, ζ); otherwise ε_zz is an internal variable (Ps.1)
            Plane::Stress if viscosity_proportional(lambda, mu, theta, zeta) => {
                let reduce = |l: f64, m: f64| if l + 2.0 * m > 0.0 { 2.0 * l * m / (l + 2.0 * m) } else { 0.0 };
                Material { lambda: reduce(lambda, mu), theta: reduce(theta, zeta), ..plane_strain }
            }
            Plane::Stress => plane_strain.with_thickness_variable(),
        }
    }

    /// (Ps.1) The same plane-stress material with ε_zz carried as an internal variable, the
    /// in-plane operators at the 3-D constants. `new` takes this path when A is not
    /// proportional to B; with A ∝ B it gives the algebraic reduction's answers to round-off
    /// (the tests compare the two). Without viscosity (Θ = 0) the material is returned as it is.
    pub fn with_thickness_variable(self) -> Material {
        if self.theta_3d + 2.0 * self.zeta <= 0.0 {
            // no viscosity: σ_zz = 0 is algebraic and ṡ undefined (Θ = 0): keep the reduction
            return self;
        }
        let law = ThicknessLaw { lambda: self.lambda_3d, mu: self.mu_lame, theta: self.theta_3d, zeta: self.zeta };
        Material { lambda: self.lambda_3d, theta: self.theta_3d, plane: Plane::Stress, thickness: Some(law), ..self }
    }

    /// Voigt matrix of B: [[λ+2μ, λ, 0], [λ, λ+2μ, 0], [0, 0, μ]].
    pub fn elasticity(&self) -> Matrix3<f64> {
        isotropic(self.lambda, self.mu_lame)
    }

    /// Voigt matrix of A: [[θ+2ζ, θ, 0], [θ, θ+2ζ, 0], [0, 0, ζ]].
    pub fn viscosity(&self) -> Matrix3<f64> {
        isotropic(self.theta, self.zeta)
    }

    /// Voigt matrix (ε_xx, ε_yy, ε_zz, γ_yz, γ_xz, γ_xy) of B in three dimensions: the scene's
    /// λ, μ_L without the plane reduction.
    pub fn elasticity_3d(&self) -> Matrix6<f64> {
        isotropic_3d(self.lambda_3d, self.mu_lame)
    }

    /// Voigt matrix of A in three dimensions (θ, ζ of the scene).
    pub fn viscosity_3d(&self) -> Matrix6<f64> {
        isotropic_3d(self.theta_3d, self.zeta)
    }

    pub fn has_viscosity(&self) -> bool {
        self.theta > 0.0 || self.zeta > 0.0
    }

    /// (P.1) Kelvin–Voigt stress σ = A ε(u̇) + B ε(u), in-plane components (σ_xx, σ_yy, σ_xy)
    /// and σ_zz (zero in plane stress, λ tr ε + θ tr ε̇ in plane strain); `eps_zz` is s = ε_zz
    /// where it is an internal variable (Ps.1: σ_xx, σ_yy gain λ s + θ ṡ), else unused.
    pub fn stress(&self, eps_u: [f64; 3], eps_v: [f64; 3], eps_zz: f64) -> [f64; 4] {
        let b = self.elasticity();
        let a = self.viscosity();
        let eu = nalgebra::Vector3::from(eps_u);
        let ev = nalgebra::Vector3::from(eps_v);
        let mut s = b * eu + a * ev;
        if let Some(law) = &self.thickness {
            let trace = law.trace_stress(eps_zz, eps_u[0] + eps_u[1], eps_v[0] + eps_v[1]);
            s[0] += trace;
            s[1] += trace;
        }
        let szz = match self.plane {
            Plane::Stress => 0.0,
            Plane::Strain => self.lambda_3d * (eps_u[0] + eps_u[1]) + self.theta_3d * (eps_v[0] + eps_v[1]),
        };
        [s[0], s[1], s[2], szz]
    }
}

/// λ tr(ε) I + 2μ ε on engineering Voigt strains: λ + 2μ / λ in the normal block, μ on the shears.
fn isotropic_3d(l: f64, m: f64) -> Matrix6<f64> {
    let mut d = Matrix6::zeros();
    for i in 0..3 {
        for j in 0..3 {
            d[(i, j)] = if i == j { l + 2.0 * m } else { l };
        }
        d[(3 + i, 3 + i)] = m;
    }
    d
}

fn isotropic(l: f64, m: f64) -> Matrix3<f64> {
    Matrix3::new(l + 2.0 * m, l, 0.0, l, l + 2.0 * m, 0.0, 0.0, 0.0, m)
}
