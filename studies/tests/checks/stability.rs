//! The stability map (`cargo xtask stability`, studies/src/stability.rs): the quick
//! sweep's outputs, the classification rules, and one test per behaviour the full map found.
//! Every number pinned here was measured first (release, this machine; the values are
//! in each test's doc and message) on the base scene of the map (the academic scene on 16 × 8
//! cells, k = 5e-4; its (C.k) limit is 6.94e-4) or on fixtures/scenes/impact_friction.toml.
//! Horizons are shortened (T = 0.2–0.3 s) so the file stays well under 30 s in the dev profile.

use dyncontact::error::{Error, SolverFailure};
use dyncontact::scene::{EnforcementKind as Enforcement, NumOrStr, Scene};
use studies::stability::*;

fn var(name: &str) -> Variant {
    variant(name).unwrap_or_else(|| panic!("no variant {name}"))
}

/// The base scene with horizon `end`, step `k` and a variant applied.
fn base(end: f64, k: f64, v: &Variant) -> Scene {
    let mut s = base_scene(end);
    s.time.step = k;
    v.apply(&mut s);
    s
}

fn run(s: &Scene, v: &Variant) -> Measured {
    let m = run_scene(s, v.energy_conserving());
    println!(
        "{:<26} k = {:.3e}: {:<18} {}/{} steps, fp mean {:.2} max {} caps {}, newton {}, max E.1 {:.2e}, drift {:.3e}, gain {:.3e} {}",
        v.name,
        m.k,
        m.class.label(),
        m.steps_completed,
        m.steps_planned,
        m.fp_mean,
        m.fp_max,
        m.fp_capped_steps,
        m.newton_total,
        m.max_defect,
        m.drift,
        m.max_gain,
        m.note
    );
    m
}

/// The fraction of the external work the scheme destroyed numerically: −Σ(E.1 defect) / W.
fn lost_fraction(m: &Measured) -> f64 {
    -m.drift * m.scale / m.final_energy.external_work
}

/// The quick sweep (`--quick`) writes stability.csv with the header and one row per run, each
/// with a known class label, and stability.svg with every sweep's title and the legend; no run
/// of it produces a non-finite value.
#[test]
fn quick_sweep_writes_csv_and_svg_with_a_row_per_run() {
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("stability_quick");
    let _ = std::fs::remove_dir_all(&out);
    // each point's numerics sequential, as `dyncontact`'s main sets them (the sweep runner sets no global state)
    faer::set_global_parallelism(faer::Par::Seq);
    let report = studies::stability::run(&out, &StabilityOptions { quick: true, jobs: 2 }).expect("quick sweep");
    println!("{report}");
    let n = cases(true).len();
    assert!(n >= 7 * variants().len(), "the quick sweep has every sweep × every variant, got {n} cases");
    let csv = std::fs::read_to_string(out.join("stability.csv")).expect("stability.csv");
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(CSV_HEADER));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), n, "one CSV row per run");
    let labels: Vec<&str> = RunClass::ALL.iter().map(|c| c.label()).collect();
    let class_col = CSV_HEADER.split(',').position(|h| h == "class").expect("class column");
    for r in &rows {
        let class = r.split(',').nth(class_col).unwrap_or("");
        assert!(labels.contains(&class), "unknown class {class:?} in row {r}");
        assert_ne!(class, RunClass::NonFinite.label(), "a non-finite value appeared: {r}");
    }
    let svg = std::fs::read_to_string(out.join("stability.svg")).expect("stability.svg");
    assert!(svg.starts_with("<svg") || svg.contains("<svg"), "not an SVG document");
    for c in RunClass::ALL {
        assert!(svg.contains(c.label()), "the legend lacks {:?}", c.label());
    }
    for s in Sweep::ALL {
        assert!(svg.contains(s.parameter()), "the chart lacks the sweep over {}", s.parameter());
    }
    assert!(report.contains("stability map"), "the report starts with its title");
}

/// The classification follows the documented precedence: non-finite, then a stop (Solver →
/// newton failed, other errors → clear error), then energy growth above GAIN_TOLERANCE, then a
/// capped fixed point, then the (E.1) defect (energy-conserving variants only), else converged.
#[test]
fn classification_follows_the_documented_precedence() {
    use dyncontact::failure::{ContactFailure, InnerFailure, NewtonFailure, NewtonStatus, StepFailureCause};
    let solver = |cause: StepFailureCause| Error::Solver(Box::new(SolverFailure { step: 3, time: 0.1, cause }));
    let newton_failed = || {
        let inner =
            InnerFailure::Newton(NewtonFailure { status: NewtonStatus::MaxIterations, iterations: 50, residual: 1e-3 });
        StepFailureCause::Contact(ContactFailure { fixed_point_iteration: 1, inner })
    };
    let mut m = Measured::empty(10, 1e-3);
    m.steps_completed = 10;
    assert_eq!(classify(None, false, &m, true), RunClass::Converged);
    assert_eq!(classify(None, true, &m, true), RunClass::NonFinite);
    assert_eq!(classify(Some(solver(newton_failed()).kind()), false, &m, true), RunClass::NewtonFailed);
    assert_eq!(
        classify(Some(solver(StepFailureCause::NonFinite { entry: 3 }).kind()), false, &m, true),
        RunClass::NonFinite
    );
    assert_eq!(
        classify(Some(Error::scene("contact.penalty", "must be > 0").kind()), false, &m, true),
        RunClass::ClearError
    );
    m.max_defect = 2.0 * DEFECT_TOLERANCE;
    assert_eq!(classify(None, false, &m, true), RunClass::EnergyDefect, "a midpoint defect above 1e-9");
    assert_eq!(
        classify(None, false, &m, false),
        RunClass::Converged,
        "defects of non-conserving schemes are not judged"
    );
    m.fp_capped_steps = 1;
    assert_eq!(classify(None, false, &m, true), RunClass::FixedPointCapped);
    m.max_gain = 2.0 * GAIN_TOLERANCE;
    assert_eq!(classify(None, false, &m, true), RunClass::EnergyGrew);
    assert_eq!(
        classify(Some(solver(newton_failed()).kind()), false, &m, true),
        RunClass::NewtonFailed,
        "a stop beats a gain"
    );
}

/// ε = 0 (the limit ε → 0 is Problem P, not a penalty) is refused before any step with a clear
/// error naming `contact.penalty`, for every variant.
#[test]
fn zero_penalty_is_refused_with_a_clear_error() {
    for v in variants() {
        let r = run_case(&MapRun { sweep: Sweep::Penalty, value: 0.0, variant: v }, true);
        assert_eq!(r.m.class, RunClass::ClearError, "{}: {}", v.name, r.m.note);
        assert_eq!(r.m.steps_completed, 0);
        assert!(r.m.note.contains("contact.penalty"), "the error names the key: {}", r.m.note);
    }
}

/// Backward Euler loses energy at a rate ∝ k: with g = inf (compliance and velocity-weakening
/// friction, no constraint) the fraction of the external work it destroys doubles when k
/// doubles: ratio 2 ± 0.05 (measured 1.988 for k = 2.5e-4 → 5e-4, 1.970–2.003 over
/// k ∈ [6.25e-5, 1e-3]; a k^0.9 or k^1.1 loss would give 1.87 or 2.14).
#[test]
fn backward_euler_loses_energy_at_a_rate_proportional_to_k() {
    let be = var("backward-euler");
    let lost: Vec<f64> = [2.5e-4, 5e-4]
        .iter()
        .map(|&k| {
            let mut s = base(0.2, k, &be);
            s.contact.as_mut().expect("contact").penetration_bound = NumOrStr::Str("inf".into());
            let m = run(&s, &be);
            assert!(
                matches!(m.class, RunClass::Converged),
                "the run completes with converged fixed points: {}",
                m.note
            );
            lost_fraction(&m)
        })
        .collect();
    println!("lost fractions {lost:?}, ratio {}", lost[1] / lost[0]);
    assert!(lost[0] > 0.0 && lost[1] > 0.0, "backward Euler loses energy: {lost:?}");
    assert!((lost[1] / lost[0] - 2.0).abs() <= 0.05, "ratio {} is not 2 ± 0.05", lost[1] / lost[0]);
}

/// With the exact constraint (g = 0.02, the base scene) backward Euler's loss is sublinear in
/// k: the ratio for k = 2.5e-4 → 5e-4 is in (1.3, 1.85) (measured 1.72; 1.54–1.76 over
/// k ∈ [6.25e-5, 1e-3]); the constraint adds a loss that does not vanish like k.
#[test]
fn backward_euler_loss_with_the_exact_constraint_is_sublinear_in_k() {
    let be = var("backward-euler");
    let lost: Vec<f64> = [2.5e-4, 5e-4].iter().map(|&k| lost_fraction(&run(&base(0.2, k, &be), &be))).collect();
    let ratio = lost[1] / lost[0];
    println!("lost fractions {lost:?}, ratio {ratio}");
    assert!(ratio > 1.3 && ratio < 1.85, "ratio {ratio} outside (1.3, 1.85): an O(k) loss would give 2");
}

/// (E.1) Midpoint with exact enforcement never gains energy at any k: over k = 1.25e-4 … 4e-3
/// (to 5.8 × the (C.k) limit) on the base scene and on the impact scene at 1 and 16 × v0, the
/// stored energy never exceeds E^0 + W by more than 1e-12 of the energy scale (measured
/// ≤ 3.1e-17: rounding; the per-step (E.1) defect is ≤ 4e-16, so ≤ 2400 steps cannot reach
/// 1e-12), and the cumulative (E.1) drift stays below 1e-12 of the scale.
#[test]
fn midpoint_with_exact_enforcement_never_gains_energy_at_any_k() {
    let mid = var("midpoint");
    let mut scenes: Vec<Scene> =
        [1.25e-4, 2.5e-4, 5e-4, 1e-3, 2e-3, 4e-3].iter().map(|&k| base(0.3, k, &mid)).collect();
    for f in [1.0, 16.0] {
        scenes.push(MapRun { sweep: Sweep::Impact, value: f, variant: mid }.scene(IMPACT_END).expect("impact scene"));
    }
    for s in &scenes {
        let m = run(s, &mid);
        assert_eq!(m.steps_completed, m.steps_planned, "the run completes: {}", m.note);
        assert!(m.max_gain <= 1e-12, "k = {}: energy gain {:.3e} of the scale > 1e-12", m.k, m.max_gain);
        assert!(m.drift.abs() <= 1e-12, "k = {}: (E.1) drift {:.3e} of the scale > 1e-12", m.k, m.drift);
    }
}

/// (F.1) The fixed point needs more iterations as k grows and first hits the cap of 50 beyond
/// (C.k) (6.94e-4): midpoint mean iterations rise 5.2 → 6.7 → 9.5 for k = 2.5e-4, 5e-4, 1e-3
/// (T = 0.3), no step is capped inside the limit, one step is capped at k = 1e-3; with a cap of
/// 500 that step converges (in 71 iterations): beyond (C.k) F.1 is slow, it does not diverge.
#[test]
fn fixed_point_iterations_rise_with_k_and_the_cap_is_first_hit_beyond_ck() {
    let mid = var("midpoint");
    let runs: Vec<Measured> = [2.5e-4, 5e-4, 1e-3].iter().map(|&k| run(&base(0.3, k, &mid), &mid)).collect();
    let ck = runs[0].ck_limit.expect("a (C.k) limit");
    assert!(runs[1].k < ck && runs[2].k > ck, "k = 5e-4 inside and 1e-3 beyond the limit {ck}");
    assert!(
        runs[0].fp_mean < runs[1].fp_mean && runs[1].fp_mean < runs[2].fp_mean,
        "mean iterations do not rise with k"
    );
    assert_eq!(runs[0].fp_capped_steps + runs[1].fp_capped_steps, 0, "no capped step inside (C.k)");
    assert!(runs[2].fp_capped_steps >= 1, "k = 1e-3 (beyond C.k) caps at least one step (measured 1)");
    let mut s = base(0.3, 1e-3, &mid);
    s.solver.max_fixed_point_iterations = 500;
    let m = run(&s, &mid);
    assert_eq!(m.fp_capped_steps, 0, "with 500 iterations every step converges");
    assert!(m.fp_max > 50, "the capped step needed more than 50 iterations (measured 71), got {}", m.fp_max);
}

/// (F.1) Relaxation θ < 1 does not cure the capped fixed point beyond (C.k), it makes it worse:
/// at k = 1e-3 (T = 0.3, cap 50) the capped steps are 1, 4, 39 and the mean iterations 9.5,
/// 14.7, 24.6 for θ = 1, 0.7, 0.4 — the F.1 map contracts monotonically here, so damping only
/// slows it. Pinned: capped steps and mean iterations non-decreasing as θ falls, strictly more
/// capped steps at θ = 0.4 than at θ = 1.
#[test]
fn relaxation_below_one_does_not_cure_the_cap_beyond_ck() {
    let mid = var("midpoint");
    let runs: Vec<Measured> = [1.0, 0.7, 0.4]
        .iter()
        .map(|&th| {
            let mut s = base(0.3, 1e-3, &mid);
            s.solver.relaxation = th;
            run(&s, &mid)
        })
        .collect();
    for w in runs.windows(2) {
        assert!(w[1].fp_capped_steps >= w[0].fp_capped_steps, "fewer capped steps with smaller θ");
        assert!(w[1].fp_mean >= w[0].fp_mean, "fewer iterations with smaller θ");
    }
    assert!(runs[2].fp_capped_steps > runs[0].fp_capped_steps, "θ = 0.4 caps more steps than θ = 1");
}

/// (C.k) Backward Euler's friction sees v^{n+1} (twice the midpoint's weight on the unknown), so
/// its (C.k) limit is half the midpoint's (3.47e-4 against 6.94e-4 here), as ModelInfo reports:
/// at k = 5e-4 (inside the midpoint limit) it caps F.1 (3 steps, T = 0.3) where midpoint caps
/// none; at k = 2.5e-4 (inside both) it caps none.
#[test]
fn backward_euler_caps_the_fixed_point_inside_the_midpoint_ck_limit() {
    let (mid, be) = (var("midpoint"), var("backward-euler"));
    let be_big = run(&base(0.3, 5e-4, &be), &be);
    let mid_big = run(&base(0.3, 5e-4, &mid), &mid);
    let be_small = run(&base(0.3, 2.5e-4, &be), &be);
    let ck = mid_big.ck_limit.expect("limit");
    assert_eq!(be_big.ck_limit, Some(0.5 * ck), "backward Euler's limit is half the midpoint's");
    assert!(be_big.k > 0.5 * ck && be_big.k < ck, "k = 5e-4 lies between the two limits");
    assert!(be_big.fp_capped_steps >= 1, "backward Euler caps at k = 5e-4 (measured 3)");
    assert_eq!(mid_big.fp_capped_steps, 0, "midpoint does not cap at k = 5e-4");
    assert_eq!(be_small.fp_capped_steps, 0, "backward Euler does not cap at k = 2.5e-4");
}

/// (R.1) With the modified mass the contact nodes are massless, so (C.k) gives no admissible
/// step (limit 0): F.1 caps on many steps even at k = 2.5e-4 (444 of 1200, T = 0.3), where the
/// lumped midpoint converges everywhere; more iterations do not cure it (27 steps still capped
/// at 500 iterations for k = 1.25e-4, measured by the full map's exploration, not pinned here).
#[test]
fn modified_mass_has_no_ck_range_and_caps_the_fixed_point() {
    let (mid, modm) = (var("midpoint"), var("midpoint+modified-mass"));
    let m = run(&base(0.3, 2.5e-4, &modm), &modm);
    assert_eq!(m.ck_limit, Some(0.0), "massless contact nodes give a zero (C.k) limit");
    assert_eq!(m.steps_completed, m.steps_planned, "the run completes: {}", m.note);
    assert!(m.fp_capped_steps >= 100, "many capped steps (measured 444 of 1200), got {}", m.fp_capped_steps);
    assert!(m.max_gain <= 1e-12, "capping does not break (E.1): gain {:.3e}", m.max_gain);
    let l = run(&base(0.3, 2.5e-4, &mid), &mid);
    assert_eq!(l.fp_capped_steps, 0, "the lumped midpoint converges at the same k");
}

/// (N.4) The unfrozen Newton needs no fixed point where F.1 caps: at k = 1e-3 (beyond C.k,
/// T = 0.3) it converges on every step without a fallback while the frozen midpoint caps.
#[test]
fn newton_unfrozen_converges_where_the_fixed_point_caps() {
    let (mid, unf) = (var("midpoint"), var("midpoint+newton-unfrozen"));
    let m = run(&base(0.3, 1e-3, &unf), &unf);
    assert_eq!(m.class, RunClass::Converged, "{}", m.note);
    assert_eq!(m.fallbacks, 0, "no step fell back to F.1");
    assert!(run(&base(0.3, 1e-3, &mid), &mid).fp_capped_steps >= 1, "the frozen midpoint caps at this k");
}

/// (Pe.5) The penalty at ε = 1e-12 stops with a clear solver error, never a NaN: the Newton
/// fails at step 212 (t = 0.106), after u_ν first reaches g at step 195 (the penalty branch,
/// slope c + 1/ε = 1e12, is then active); the error names the step, the time, the residual and
/// a suggestion. It is not a tolerance floor: with newton_tolerance = 1e-6 it still fails (step
/// 248, residual 0.15). At ε = 1e-9 the midpoint completes with converged fixed points.
#[test]
fn penalty_at_1e_12_stops_with_a_clear_solver_error() {
    let mid = var("midpoint");
    let pen = |eps: f64, tol: f64| {
        let mut s = base(0.3, 5e-4, &mid);
        let c = s.contact.as_mut().expect("contact");
        c.enforcement = Enforcement::Penalty;
        c.penalty = Some(eps);
        s.solver.newton_tolerance = tol;
        run(&s, &mid)
    };
    let m = pen(1e-12, 1e-10);
    assert_eq!(m.class, RunClass::NewtonFailed, "{}", m.note);
    assert!((195..600).contains(&m.steps_completed), "fails after u_ν reaches g (step 195), got {}", m.steps_completed);
    for part in ["step", "newton solver failed", "relative residual", "Suggestion"] {
        assert!(m.note.contains(part), "the error lacks {part:?}: {}", m.note);
    }
    assert_eq!(pen(1e-12, 1e-6).class, RunClass::NewtonFailed, "a looser tolerance does not cure it");
    assert_eq!(pen(1e-9, 1e-10).class, RunClass::Converged, "ε = 1e-9 converges");
}

/// The trapezoid's averaged normal force ½(p(d^n) + p(d^{n+1})) is not the discrete gradient of
/// the penalty energy: at a stiff-penalty impact with no viscosity (ε = 1e-7) it creates energy
/// — E exceeds E^0 + W by 0.68 of the energy scale (the map's only "energy grew") — while the
/// midpoint, on the same run, gains ≤ 1e-12 (rounding, measured 7e-17) and at ε = 1e-3 the
/// trapezoid gains nothing beyond 1e-12 either.
#[test]
fn trapezoid_creates_energy_at_a_stiff_penalty_impact() {
    let (mid, tr) = (var("midpoint"), var("trapezoid"));
    let case = |eps: f64, v: Variant| MapRun { sweep: Sweep::ElasticImpactPenalty, value: eps, variant: v };
    let stiff = run(&case(1e-7, tr).scene(IMPACT_END).expect("scene"), &tr);
    assert_eq!(stiff.class, RunClass::EnergyGrew, "{}", stiff.note);
    assert!(stiff.max_gain > 0.1, "gain {:.3e} is not of order the energy scale (measured 0.68)", stiff.max_gain);
    let m = run(&case(1e-7, mid).scene(IMPACT_END).expect("scene"), &mid);
    assert!(m.max_gain <= 1e-12, "midpoint gains {:.3e}", m.max_gain);
    let soft = run(&case(1e-3, tr).scene(IMPACT_END).expect("scene"), &tr);
    assert!(soft.max_gain <= 1e-12, "trapezoid at ε = 1e-3 gains {:.3e}", soft.max_gain);
}

/// The Newton-failed mode shown by the iteration cap: with max_newton_iterations = 1 the midpoint
/// stops with newton failed at step 6 (5 steps completed), the cap named in the error; with 4
/// it completes (T = 0.3; every convex solve of this run takes at most 2 Newton iterations).
#[test]
fn newton_iteration_cap_of_one_stops_with_newton_failed() {
    let mid = var("midpoint");
    let cap = |n: i64| {
        let mut s = base(0.3, 5e-4, &mid);
        s.solver.max_newton_iterations = n;
        run(&s, &mid)
    };
    let m = cap(1);
    assert_eq!(m.class, RunClass::NewtonFailed, "{}", m.note);
    assert!(
        m.steps_completed <= 10,
        "fails within the first 10 steps (measured 5 completed), got {}",
        m.steps_completed
    );
    assert!(m.note.contains("no convergence in 1 iterations"), "{}", m.note);
    assert_eq!(cap(4).class, RunClass::Converged);
}

/// The map runs its cases as sweeps (fixtures/sweeps/stability_*.toml, each point a `run` into
/// its folder, read back from history.csv and summary.json): on the quick map every measured
/// quantity of every run — class, steps, k, (C.k) limit, fixed-point and Newton counts,
/// fallbacks, (E.1) defect, drift, energy gain, final energies, note — equals the in-process
/// run of the same case (`run_case`), exactly (the files hold every f64 to the last bit; only
/// the wall time differs).
#[test]
fn sweep_path_gives_the_in_process_numbers() {
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("stability_sweep_path");
    let _ = std::fs::remove_dir_all(&out);
    // each point's numerics sequential, as `dyncontact`'s main sets them (the sweep runner sets no global state)
    faer::set_global_parallelism(faer::Par::Seq);
    let rows = map_runs(&out, &StabilityOptions { quick: true, jobs: 2 }).expect("the quick map");
    assert_eq!(rows.len(), cases(true).len());
    for r in &rows {
        let mut a = run_case(&r.case, true).m;
        let mut b = r.m.clone();
        (a.wall_time_s, b.wall_time_s) = (0.0, 0.0);
        assert_eq!(
            format!("{a:?}"),
            format!("{b:?}"),
            "{} = {} / {}",
            r.case.sweep.key(),
            r.case.value,
            r.case.variant.name
        );
    }
    println!("{} runs: the sweep path and the in-process runs agree in every field", rows.len());
}
