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
}

impl Material {
    /// The plane-reduced material of the scene's constants.
    pub fn new(m: &MaterialParams, plane: Plane) -> Material {
        let (lambda, mu) = lame(m.young, m.poisson);
        let (theta, zeta) = (m.theta, m.zeta);
        // Plane stress: σ_zz = 0 eliminates ε_zz, giving λ* = 2λμ/(λ + 2μ) (and the same for
        // (θ, ζ), exact when A is proportional to B, which validation requires — decision 11).
        let reduce = |l: f64, m: f64| if l + 2.0 * m > 0.0 { 2.0 * l * m / (l + 2.0 * m) } else { 0.0 };
        let (lp, tp) = match plane {
            Plane::Strain => (lambda, theta),
            Plane::Stress => (reduce(lambda, mu), reduce(theta, zeta)),
        };
        Material { rho: m.density, lambda: lp, mu_lame: mu, theta: tp, zeta, lambda_3d: lambda, theta_3d: theta, plane }
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
    /// and σ_zz (zero in plane stress, λ tr ε + θ tr ε̇ in plane strain).
    pub fn stress(&self, eps_u: [f64; 3], eps_v: [f64; 3]) -> [f64; 4] {
        let b = self.elasticity();
        let a = self.viscosity();
        let eu = nalgebra::Vector3::from(eps_u);
        let ev = nalgebra::Vector3::from(eps_v);
        let s = b * eu + a * ev;
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
