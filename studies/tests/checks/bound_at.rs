//! The friction_bound_at study (Co.2): where the friction bound is evaluated, the predictor
//! against u_ν^{n+½} of the iterate, converging in k on the soft pulled block.

use dyncontact::model::kinds::BoundAt;
use studies::bound_at::{BoundAtOptions, csv, rows};

/// (Co.2) The friction_bound_at study (quick: c_ν = 1e3 and 1e7, two steps) gives a row per case,
/// compliance, point and step, every error finite and positive, and on the soft block (c_ν = 1e3,
/// resolved by k) the error falls with k at both points (second order: the halving divides it by
/// ≥ 2.8, i.e. an observed order ≥ 1.5 — measured ratio 4.5).
#[test]
fn co2_bound_at_study_runs_and_converges_on_the_soft_block() {
    let rows = rows(&BoundAtOptions { quick: true }).expect("study");
    assert_eq!(rows.len(), 2 * 2 * 2 * 2);
    assert!(rows.iter().all(|r| r.error_tangential.is_finite() && r.error_tangential > 0.0));
    assert!(csv(&rows).starts_with("case,compliance,bound_at,k,error_tangential_impulse,wall_time_s\n"));
    for at in [BoundAt::Predictor, BoundAt::Midpoint] {
        let e: Vec<f64> = rows
            .iter()
            .filter(|r| r.case == "block" && r.compliance == 1e3 && r.at == at)
            .map(|r| r.error_tangential)
            .collect();
        println!("block, c = 1e3, {at:?}: {e:?}");
        assert!(e[0] / e[1] >= 2.8, "{at:?}: {e:?}");
    }
}
