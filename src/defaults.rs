//! Every default and tuning constant of the solvers, named, documented and set here only. The
//! scene's defaults (the README's contract) and the solvers' settings both read these.

/// `solver.newton_tolerance`: Newton stops when ‖F‖_∞ ≤ tolerance × the step's velocity scale.
pub const NEWTON_TOLERANCE: f64 = 1e-10;
/// `solver.fixed_point_tolerance`: (F.1) stops when S (or y) moves by less than this, relative.
pub const FIXED_POINT_TOLERANCE: f64 = 1e-8;
/// `solver.max_newton_iterations` and `solver.max_fixed_point_iterations`.
pub const MAX_ITERATIONS: usize = 50;
/// `solver.relaxation`: θ of (F.1) (1: no relaxation).
pub const RELAXATION: f64 = 1.0;
/// The most time steps a scene may ask for (time.end / time.step).
pub const MAX_STEPS: usize = 100_000_000;
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
