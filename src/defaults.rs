//! Every default and tuning constant of the solvers, named, documented and set here only. The
//! scene's defaults (the README's contract) and the solvers' settings both read these.

/// `solver.newton_tolerance`: Newton stops when ‖F‖_∞ ≤ tolerance × the step's velocity scale.
pub const NEWTON_TOLERANCE: f64 = 1e-10;
/// A velocity-form solve with loose directions has landed, whatever its last direction, once its
/// Newton residual is within this of the velocity scale: where an exact direction lands (its
/// conjugate gradients stop at PCG_TOLERANCE of the scale), so complementarity holds to
/// round-off. A loose direction divides the residual by ≳ 1e3 on fixed sets, so it takes one
/// from Newton's tolerance: measured on academic3d 48×24×16, 40 pressing steps, 166 → 135
/// Newton iterations and 212 → 36 products with the exact W⁻¹, the same convex solves.
pub const NEWTON_LANDING: f64 = 1e-13;
/// `solver.fixed_point_tolerance`: (F.1) stops when S (or y) moves by less than this, relative.
pub const FIXED_POINT_TOLERANCE: f64 = 1e-8;
/// `solver.max_newton_iterations` and `solver.max_fixed_point_iterations`.
pub const MAX_ITERATIONS: usize = 50;
/// `solver.relaxation`: θ of (F.1) (1: no relaxation).
pub const RELAXATION: f64 = 1.0;
/// The most time steps a scene may ask for (time.end / time.step).
pub const MAX_STEPS: usize = 100_000_000;
/// `solver.energy_residual_limit`: a midpoint step whose (E.1) residual exceeds this fraction of
/// the energy scale ends the run (or, with `energy_residual_action = "warn"`, is reported). The
/// identity holds to the solver tolerances: measured ≤ 5e-13 on every fixture (conic twin: the
/// same order), so 1e-6 is 10⁶ above round-off and far below a broken step (a friction coefficient
/// of 1e20 gave 0.2, of 1e300 gave 1.0).
pub const ENERGY_RESIDUAL_LIMIT: f64 = 1e-6;
/// The largest friction coefficient a scene may give: no pair of materials comes near it (rubber
/// on clean glass: ~4), and a coefficient of 1e20 turns the step into round-off.
pub const MAX_FRICTION_COEFFICIENT: f64 = 100.0;
/// The most load evaluations `check` spends on the time-dependent loads at every load time of
/// the run (one per quadrature point and time): 2e7 take ~0.5 s here (the expressions are a
/// stack program of ~20 ns an evaluation); a larger scan is skipped and `check` says so.
pub const CHECK_LOAD_EVALUATIONS: usize = 20_000_000;
/// `output.every`: a frame every this many steps.
pub const OUTPUT_EVERY: usize = 10;

/// Newton's backtracking line search on ½‖F‖²: at most this many halvings of the step length …
pub const LINE_SEARCH_HALVINGS: usize = 30;
/// … accepting the first step length α with ½‖F(x + α d)‖² ≤ (1 − ARMIJO α) ½‖F(x)‖².
pub const ARMIJO: f64 = 1e-4;

/// The conic twin's gap and feasibility tolerance (Clarabel's tol_gap_abs, tol_gap_rel,
/// tol_feas) is the Newton tolerance, but never below this (Clarabel's own floor of accuracy).
pub const CONIC_TOLERANCE_FLOOR: f64 = 1e-12;
/// Clarabel's tolerance on the KKT ratio and its iteration cap per program.
pub const CLARABEL_TOL_KTRATIO: f64 = 1e-8;
pub const CLARABEL_MAX_ITER: u32 = 400;

/// Clarabel's static regularization of its KKT systems (its default is 1e-8). On the 3-D programs
/// with a second-order cone per node the default stopped the interior point at a duality gap of
/// ~4e-5 (AlmostSolved) and the friction forces 1e-5 off the law; 1e-12 lets it reach the gap
/// tolerance (measured: the 3-D twins agree to 1e-7 instead of 1e-5).
pub const CLARABEL_STATIC_REGULARIZATION: f64 = 1e-12;
/// Majorization–minimization rounds of the conic twin's logarithmic branches.
pub const CONIC_MAX_ROUNDS: usize = 100;
/// Constraints and pieces inactive by more than this many velocity scales are left out of the
/// conic program (a huge right-hand side stalls the interior point) and put back when reached.
pub const CONIC_FAR: f64 = 1e3;
/// Node status from an interior-point solution: separated below this fraction of the largest
/// contact force, in stick below this fraction of the velocity scale (times a_v).
pub const CONIC_SEPARATION_FLOOR: f64 = 1e-8;
pub const CONIC_STICK_FLOOR: f64 = 1e-7;

/// `contact_solve = "auto"` considers the sparse Delassus operator from this many contact
/// unknowns (d n_c) on: below, the dense operator is cheap whatever its decay.
pub const SPARSE_FROM: usize = 256;

/// `contact_solve = "auto"` takes the sparse Delassus operator when the probed radius keeps at
/// most this share of the contact nodes per column (measured: a strip with 256 contact nodes,
/// share 0.13, runs 1.3× faster sparse; 256×128 cells, share 0.69, 2.4× slower).
pub const SPARSE_DENSITY: f64 = 0.25;

/// With the dense Delassus operator the time loop keeps the responses G = A_k⁻¹ Hᵀ (n × d n_c,
/// from the same solves) when they take at most this many bytes, and recovers v^{n+1} − v_free
/// = −G r by columns when that reads fewer numbers than a solve pair on the factor of A_k.
pub const RESPONSES_BYTES: f64 = 32.0 * 1024.0 * 1024.0;

/// The recovery reads G's columns when they hold at most this many times the entries of a solve
/// pair: a column update streams memory, a sparse triangular solve walks it (measured on the
/// academic scene: 64 columns of 1,088 entries in ~5 µs against ~37 µs for a solve pair on a
/// factor of 28,048 entries, ~10× per entry read).
pub const RESPONSES_ADVANTAGE: f64 = 4.0;

/// The sparse Delassus operator drops entries below this fraction of the diagonal.
pub const DELASSUS_TRUNCATION: f64 = 1e-12;

/// Cells along one side of a rectangle at most: long strips (8,192 cells along Γ3 in the
/// scaling benchmark) are fine; the total size is guarded by the memory estimate of `run`
/// (src/resources.rs), not by this bound.
pub const MAX_CELLS_PER_SIDE: i64 = 65_536;

/// The Newton matrices W'_UU + D of a nearby iteration (same unknowns, other D or slip frames)
/// are solved by conjugate gradients preconditioned with the kept Cholesky factor to this
/// relative residual (far below the Newton tolerance, so the direction is exact to round-off for
/// Newton's purposes) …
pub const PCG_TOLERANCE: f64 = 1e-13;
/// An exact direction's conjugate gradients (velocity form, near field) never stop tighter than
/// this relative residual, near the round-off of their recurrence.
pub const LANDING_FLOOR: f64 = 1e-15;
/// … within this many iterations, else the matrix is factored anew.
pub const PCG_MAX_ITERATIONS: usize = 12;
/// The kept factor preconditions a Newton matrix whose unknowns U differ from its own when at
/// most this share of U is new to it (the rest is factored anew).
pub const PCG_NEW_SHARE: f64 = 0.1;

/// (F.1) inexact inner solves: a convex problem of the fixed point is solved by Newton to this
/// fraction of the relative change of S in the previous iteration (the accepted one to the full
/// Newton tolerance) …
pub const INNER_FORCING: f64 = 1e-2;
/// … taking the first iteration's change as this (so its tolerance is INNER_FORCING × this).
pub const INNER_FORCING_START: f64 = 1e-4;
/// (F.1) Anderson's extrapolation of S combines the newest iterate with up to this many earlier
/// ones (academic3d 24×12×8 shaken from 0.2 to 0.3 s, Newton started at the last solve: 2,235
/// convex solves with 1, 1,930 with 3, 1,753 with 5).
pub const ANDERSON_DEPTH: usize = 5;
/// Newton's directions from conjugate gradients stop at the relative residual
/// min(PCG_FORCING_MAX, PCG_FORCING ‖F‖/scale) (Eisenstat–Walker forcing: the linear error stays
/// below the quadratic one, so convergence stays quadratic), never below PCG_TOLERANCE
/// (measured on academic3d at 12×6×4 cells: factors 0, 0.01, 0.1, 1 gave contact solves of
/// 1.64, 1.28, 1.23, 1.32 s).
pub const PCG_FORCING: f64 = 0.1;
pub const PCG_FORCING_MAX: f64 = 1e-3;

/// `fixed_point_start = "auto"` starts (F.1) at the unfrozen Newton's root (where (C.k) or (Ck.1)
/// shows the step problem convex) from
/// this many contact unknowns (d n_c) on, where the velocity form's Newton iterations are what a
/// step costs: academic3d 24×12×8 (936), 40 shaken steps, 26.0 → 9.6 ms per contact solve (the
/// thick bench's medians).
/// Below, a convex solve costs little, and small scenes keep the predictor's start and their
/// outputs.
pub const ROOT_START_FROM: usize = 256;

/// A dense Delassus operator with at least this many components is applied by faer's
/// matrix–vector product (runtime-dispatched SIMD: 0.087 ms against 0.145 ms for the column loop
/// at 936 components); below, the column loop that skips separated nodes.
pub const GEMV_FROM: usize = 256;
/// Conjugate gradients on the kept factor replace a new factorization for Newton matrices of
/// at least this many unknowns (also when U itself changed, if little of it is new), and for
/// smaller ones only when U is unchanged and slip frames are present (3-D slip, where D and the
/// frames move every iteration). Small 2-D matrices change only with the contact sets and are
/// refactored exactly, so the cache never changes their answer (a Cholesky of ~130 unknowns
/// costs less than the extra iterations inexact directions bring: measured on the 2-D academic
/// scene, 23,707 Newton iterations with conjugate gradients against 13,494 with factorizations).
pub const PCG_FROM: usize = 300;

/// The velocity form of the Newton directions (W⁻¹ kept, conjugate gradients on the free
/// components) is taken when a trial solve with W⁻¹ alone reaches 1e-10 within this many
/// iterations at setup (a well-conditioned W: 16 on academic3d at 24×12×8 cells) …
pub const VELOCITY_FORM_TRIAL: usize = 40;
/// The near field of W⁻¹ that preconditions the velocity form: the node pairs (i, j) with
/// max_ab |W⁻¹_ab| / √(W⁻¹_aa W⁻¹_bb) ≥ this over their d × d block. W⁻¹ (the Schur complement
/// of A_k on the contact unknowns, a discrete Dirichlet-to-Neumann map) is local: on academic3d
/// at 32×16×12 cells 1e-3 keeps 1.2% of its entries (the 8 neighbours of a node), and conjugate
/// gradients to 1e-10 take 4 iterations with their sparse Cholesky factor against 19 with node
/// blocks (1e-4 keeps 2.5% and takes 3). The finer the mesh against W⁻¹'s decay length, the more
/// neighbours a tolerance keeps and the dearer the factor (refactored ~2 times per pressing step):
/// at 64×32×24 3e-3 keeps 0.41% (1e-3: 0.77%) for 5% more CG iterations, and the median contact
/// solve per pressing step is 108–110 ms against 137 ms (1e-2: 112 ms); from 24×12×8 to
/// 48×24×16 the two are within the machine's spread.
pub const NEAR_FIELD_TOLERANCE: f64 = 3e-3;
/// The near field preconditions the velocity form from this many contact unknowns on (below,
/// node blocks): with each direction solved to round-off it costs more iterations' worth of
/// factorizations than it saves on small W. Measured (cargo xtask bench --thick-only, median
/// contact solve per step, pressing phase): 936 unknowns (academic3d 24×12×8) 5.9 ms against 4.8
/// with node blocks; 1,632 (32×16×12) 45.9 against 50.7; 3,600 (48×24×16) 252 against 385.
/// Re-measured with the loose directions and the hierarchical forms (academic3d's whole run,
/// 2,000 steps, contact solve in s, node blocks → near field): 432 unknowns (16×8×4) 4.63 → 4.47,
/// 660 (20×10×6) 12.0 → 11.4, 936 (24×12×8) 25.6 → 24.1 — within 6%, so not taken lower.
pub const NEAR_FIELD_FROM: usize = 1200;
/// The velocity form keeps its near-field factor as CG's preconditioner for the next solves
/// while the free set holds (Newton's iterations and the steps after), until a solve with it
/// takes more than this many times the iterations it took when new. Measured (this 2-core
/// machine, contact solve): hertz3d (1,875 components, 302 directions) 6.2–6.6 s → 4.8–5.1 s,
/// outputs bit for bit, CG 3,322 iterations either way; academic3d at 32×16×12 over 0.3 s
/// (pressing, then shaking) 67.6 → 61.0 s (CG 46,665 → 59,389, Newton 9,808 both); at 48×24×16,
/// 40 pressing steps, 91 → 99 ms per step (CG 775 → 1,109: there the factorizations saved do
/// not pay for the iterations added).
pub const NEAR_FIELD_KEPT_SLOWDOWN: usize = 2;
/// A dense W (whose responses A_k⁻¹ Hᵀ are not kept) comes from the Schur complement of A_k on
/// the contact unknowns from this many components on, instead of d n_c solve pairs with the
/// factor of A_k (`delassus::delassus_pair`). Measured on academic3d (W and W⁻¹ together, one
/// process, this 2-core machine): 252 components 0.006 s against 0.017 s; 936 (24×12×8) 0.15
/// against 0.69; 1,632 (32×16×12) 0.70 against 3.34; 3,600 (48×24×16) 5.5 against 25.2; 6,336
/// (64×32×24) 51 against 218. It wins at every size; below this bound the solves stay (they
/// cost well under a second there), so the small scenes keep their bits (of the pinned
/// fixtures only hertz3d, 1,875 components, takes the Schur route: CHANGELOG, pin 11).
pub const SCHUR_FROM: usize = 512;
/// … and a direction falls back to the force form when its solve needs more than this many.
pub const VELOCITY_FORM_MAX_ITERATIONS: usize = 60;
/// The products with W⁻¹ and W in the velocity form go through their hierarchical forms
/// (`delassus::HMatrix`), with W⁻¹'s certified loose form for the directions taken while the
/// sets move (`DirectionForm`), from this many contact unknowns on. Measured on academic3d's
/// whole run (2,000 steps, pressing then shaking, this 2-core machine, node blocks below
/// NEAR_FIELD_FROM, contact solve in s, dense products → hierarchical forms): 324 components
/// (12×8×4) 3.04 → 3.14 (the dense form stays below), 432 (16×8×4) 5.87 → 4.63, 660 (20×10×6)
/// 22.1 → 12.0, 936 (24×12×8, the fixture) 56.9 → 25.6 (the whole run 72.9 → 37 s); pressing
/// only (`cargo xtask bench --thick-only`, median per step, near field from 1,632 on) 936 7.9 →
/// 4.3 ms, 1,632 (32×16×12) 43.7 → 12.6, 3,600 (48×24×16) 320.7 → 41.9, 6,336 (64×32×24)
/// 1,583.6 → 105.1. (It was 1,200, measured before the loose directions.) Of the pinned fixtures
/// only hertz3d (1,875 components) takes it (CHANGELOG, pin 12); academic3d is pinned at 8×4×4
/// (108 components).
pub const HMATRIX_FROM: usize = 400;
/// … W⁻¹ compressed to every entry within this fraction of max|W⁻¹| for the exact directions
/// (those Newton lands with: see `DirectionForm`) …
pub const HMATRIX_TOLERANCE: f64 = 1e-12;
/// … and, for the loose directions, to the loosest of these fractions whose compression is
/// certified (HMATRIX_CERTIFICATE); none certified, no loose form. Its storage on academic3d's
/// thick boxes (3,600 → 6,336 components) grows like m^1.0 at 1e-6, m^1.3 at 1e-8 and m^1.6 at
/// 1e-12 (docs/performance.md); 1e-6 is certified on every academic3d box measured (1,173 to
/// 6,336 components).
pub const HMATRIX_LOOSE_TOLERANCES: [f64; 3] = [1e-6, 1e-8, 1e-10];
/// A compression of W⁻¹ is certified when ‖H − W⁻¹‖_F ≤ this fraction of 1/‖W‖_∞, a lower bound
/// of λ_min(W⁻¹) (W is symmetric positive definite, λ_max(W) ≤ ‖W‖_∞): then every principal
/// submatrix of H keeps at least 90% of W⁻¹'s least eigenvalue (Weyl), so the conjugate gradients'
/// operator (W⁻¹)_FF + ω Ĝ_F stays positive definite, and each Newton direction solves a system
/// within this relative distance of the exact one (an inexact Newton step with forcing ≤ 0.11).
pub const HMATRIX_CERTIFICATE: f64 = 0.1;
/// … and W, for the momentum residual (N.1), to every entry within this fraction of max|W|.
pub const HMATRIX_TOLERANCE_W: f64 = 1e-14;

/// (R.1) A contact node's mass is not moved onto a neighbour in a way that leaves the neighbour
/// with less than this share of its own lumped mass: that neighbour is left out of the
/// redistribution and the weights are solved again.
pub const MODIFIED_MASS_FLOOR: f64 = 0.01;

/// A sparse Cholesky factor is ordered by nested dissection (`ordering`) when that factor holds
/// at most this share of the entries of faer's approximate minimum degree: a solve pair costs
/// about in proportion to the entries (a factorization falls faster: 28.0 → 10.5 s for 0.56 of
/// them at academic3d 64×32×24), so above this share the gain is within the machine's spread
/// and faer's default stays (academic3d's fixture, 24×12×8: 0.80, taken; 8×4×4: 0.94, not).
pub const NESTED_DISSECTION_ADVANTAGE: f64 = 0.85;
