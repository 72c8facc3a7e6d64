//! Convergence of the academic scene against a fine reference: h and k halved
//! together three times (8×4 / 2e-3 → 32×16 / 5e-4) against 64×32 / 2.5e-4, T = 0.3 s, for the
//! midpoint rule and backward Euler. No exact solution exists, so no order is asserted: the
//! errors must fall under refinement (they do), and the observed orders go into the report.
//! `cargo xtask bench` repeats this with one more level and every scheme, mass and solver.

use crate::common;

use dyncontact::scene::SchemeKind;
use studies::convergence::convergence;

fn orders(e: &[f64]) -> Vec<f64> {
    e.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// The academic scene converges under joint refinement of h and k: displacement and impulse
/// errors fall at every level for midpoint and backward Euler (orders reported).
#[test]
fn academic_scene_converges_under_refinement() {
    for scheme in [SchemeKind::Midpoint, SchemeKind::BackwardEuler] {
        let rows = convergence(scheme, 3, 0.3).expect("study");
        let col = |f: fn(&studies::convergence::ConvergenceRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
        let (force, imp, disp) = (col(|r| r.error_force), col(|r| r.error_impulse), col(|r| r.error_disp));
        println!("{scheme:?}: force {force:?} orders {:?}", orders(&force));
        println!("{scheme:?}: impulse {imp:?} orders {:?}", orders(&imp));
        println!("{scheme:?}: displacement {disp:?} orders {:?}", orders(&disp));
        for (q, e) in [("impulse", &imp), ("displacement", &disp), ("force per step", &force)] {
            let o = orders(e);
            common::measured(
                "convergence::academic_scene_converges_under_refinement",
                &format!("academic {scheme:?}: {q} order (16x8 → 32x16)"),
                o[o.len() - 1],
                "reported",
            );
        }
        assert!(imp.windows(2).all(|w| w[1] < w[0]), "{scheme:?}: impulse error does not fall: {imp:?}");
        assert!(disp.windows(2).all(|w| w[1] < w[0]), "{scheme:?}: displacement error does not fall: {disp:?}");
    }
}
