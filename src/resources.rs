//! Memory and cost known before they are spent: an estimate from the model alone (the mesh's
//! sizes from the domain description, without building it for a rectangle), which `check`
//! prints and `run` compares with the memory available before it assembles anything.
//!
//! The estimate is an upper-end model, not a measurement: P1 in 2-D couples a node with at
//! most ~7 nodes, so a sparse operator has ≤ 14 entries per row (16 bytes each: value and
//! index); the sparse Cholesky factor of a 2-D mesh under a fill-reducing ordering holds about
//! 4 n log₂ n entries (nested dissection on a grid gives 31/8 n log₂ n); the contact solve holds
//! the dense Delassus operator and the Newton matrix, (2 n_c)² entries each (an upper bound:
//! `contact_solve = "auto"` may take the sparse form, which the estimate cannot size before
//! probing W's decay).
//!
//! In 3-D (the Kuhn box: a node couples with ≤ 15 nodes, so ≤ 45 entries per row) the factor
//! of a nested-dissection ordering grows like n^{4/3}; the estimate takes 12 n^{4/3} entries
//! (a box of 24×12×8 cells: 9,375 unknowns, measured by faer's AMD ordering below that), and
//! (3 n_c)² for each contact matrix.
//!
//! The peak is the larger of two phases, over the process's own baseline ([`BASELINE`]): the
//! assembly, which holds the triplet lists of M, K and C at once (24 bytes per entry of every
//! element matrix) while faer converts them, and the solve, which holds the operators, the
//! factor and the contact matrices. Calibrated against the peak resident memory (VmHWM) of
//! eleven runs, 2-D and 3-D, 12 MB to 1 GB: estimate ÷ measured peak 0.91–1.17 (the assembly
//! phase was the larger in all of them; `tests/contract/resources.rs` checks three scenes within ±30%).

use std::path::Path;

use crate::error::{Error, Result};
use crate::mesh;
use crate::model::{Domain, Model};

/// Bytes of one stored sparse entry (f64 value and index).
const SPARSE_ENTRY: f64 = 16.0;
/// Entries per row of a P1 operator in 2-D (2 DOFs × 7 coupled nodes).
const ROW_ENTRIES: f64 = 14.0;
/// Sparse operators held at once: M, K, C, A_k and the right-hand-side matrix R.
const OPERATORS: f64 = 5.0;
/// The process before it holds a problem: the program, its libraries, the allocator, the
/// output buffers (measured: a run of 1,088 unknowns peaks at 12.6 MB).
pub const BASELINE: f64 = 8e6;
/// The second factor of the Schur complement's route to W (A_k with the contact unknowns ordered
/// last), in units of the estimated factor of A_k: a fitted constant, not a ratio of factors.
/// The bodies that take this route are thick, where both factors are ordered by nested
/// dissection (`ordering`); fitted to the measured peaks of the thick bench: 4,301–4,569 MB at
/// 64×32×24 (two runs; estimate 4.5 GiB, ~4.8 GB) and 1,464–1,482 MB at 48×24×16 (estimate
/// 1.4 GiB, the assembly's phase there); 2.3 fitted the peaks under AMD (7,428 MB at 64×32×24). Where the order keeps AMD,
/// its factor holds less than 1/NESTED_DISSECTION_ADVANTAGE (1.18) of the dissection's, so
/// this term is then at most ~18% low. `run` sizes the second factor exactly before computing it
/// (`schur::contact_block_of_factor`'s budget); a sweep's memory request and how many of its
/// points run at once read this estimate.
const SCHUR_FACTOR: f64 = 0.8;
/// Bytes per entry of an element matrix during assembly: a (row, column, value) triplet of 24
/// bytes for each of M, K and C, held at once, and faer's conversion of one of them (fitted to
/// the measured peaks: 4 × 24).
const ASSEMBLY_ENTRY: f64 = 96.0;

/// What a run of a model will hold in memory, in bytes, and its sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    pub nodes: usize,
    pub triangles: usize,
    /// velocity unknowns (d per node, before the clamped ones are removed)
    pub unknowns: usize,
    /// contact nodes (at most)
    pub contact_nodes: usize,
    /// the space dimension d (unknowns per node and per contact node)
    pub dim: usize,
    pub mesh_bytes: f64,
    pub operator_bytes: f64,
    pub factor_bytes: f64,
    pub contact_bytes: f64,
    /// the assembly's triplet lists (M, K, C at once) and faer's conversion
    pub assembly_bytes: f64,
    /// the setup of a dense W by the Schur complement of A_k (0 when W comes from the
    /// solves): the second factorization, with the contact unknowns last, and three m × m
    /// matrices, held beside the factor of A_k
    pub schur_bytes: f64,
    /// what the run writes to disk ([`Outputs`])
    pub outputs: Outputs,
}

/// The bytes a run writes, estimated from the sizes (measured: a VTU frame takes ~190 bytes
/// per node and ~65 (2-D) or ~115 (3-D) per cell, a history.csv row ~420 bytes, a contact.csv
/// row ~220 bytes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outputs {
    pub frames: usize,
    pub frame_bytes: f64,
    pub history_bytes: f64,
    pub contact_bytes: f64,
    pub trajectory_bytes: f64,
    /// checkpoint.json (every run writes one at its end)
    pub checkpoint_bytes: f64,
}

impl Outputs {
    pub fn total(&self) -> f64 {
        self.frames as f64 * self.frame_bytes
            + self.history_bytes
            + self.contact_bytes
            + self.trajectory_bytes
            + self.checkpoint_bytes
    }
}

impl Estimate {
    /// What the solve holds: the mesh and state, the operators, the factor, the contact matrices.
    pub fn solve_bytes(&self) -> f64 {
        self.mesh_bytes + self.operator_bytes + self.factor_bytes + self.contact_bytes
    }

    /// What the setup of W by the Schur complement holds at its peak: the solve's mesh,
    /// operators and factor, the second factor and three dense m × m matrices (0 without it).
    pub fn schur_setup_bytes(&self) -> f64 {
        if self.schur_bytes > 0.0 {
            self.mesh_bytes + self.operator_bytes + self.factor_bytes + self.schur_bytes
        } else {
            0.0
        }
    }

    /// The estimated peak resident memory, in bytes: the baseline and the largest of the
    /// assembly, the setup of W by the Schur complement and the solve.
    pub fn total(&self) -> f64 {
        self.required().max(BASELINE + self.schur_setup_bytes())
    }

    /// The least the run needs, in bytes: the baseline and the larger of the assembly and the
    /// solve. The Schur complement's setup is taken only when its second factor fits in the
    /// memory available at that moment (else W comes from the solves, with no second factor), so
    /// the resource guard refuses by this figure.
    pub fn required(&self) -> f64 {
        BASELINE + (self.mesh_bytes + self.assembly_bytes).max(self.solve_bytes())
    }

    /// Floating-point work of one step: two triangular-solve pairs on the factor (a bound: where
    /// the step splits its pair, `Simulation::step`, two of the four passes read only the part of
    /// the factor the contact unknowns reach, 0.68–0.77 of it on academic3d's thick boxes), and per
    /// Newton iteration of the contact solve at most one dense Cholesky of the Newton matrix
    /// (m³/3: an upper bound, the factor is reused while the contact sets do not change, and the
    /// sparse form costs less) or, in the velocity form (3-D, from GEMV_FROM unknowns), about
    /// [`VELOCITY_PRODUCTS`] products with the dense W or W⁻¹ (2m² each).
    pub fn flops_per_step(&self) -> (f64, f64) {
        let factor_entries = self.factor_bytes / SPARSE_ENTRY;
        let m = (self.dim * self.contact_nodes) as f64;
        let newton = if self.velocity_form() { VELOCITY_PRODUCTS * 2.0 * m * m } else { m * m * m / 3.0 };
        (2.0 * 2.0 * 2.0 * factor_entries, newton)
    }

    /// Whether the contact solve may run in the velocity form (3-D, a dense W of at least
    /// GEMV_FROM unknowns).
    fn velocity_form(&self) -> bool {
        self.dim == 3 && self.dim * self.contact_nodes >= crate::defaults::GEMV_FROM
    }

    /// Human-readable lines for `dyncontact check`.
    pub fn lines(&self) -> Vec<String> {
        let (solve, lu) = self.flops_per_step();
        vec![
            format!(
                "memory (est.)  : {} at the peak — the solve holds {} (mesh {}, operators {}, factor of A_k {}, contact solve {}), the assembly {}{}",
                gib(self.total()),
                gib(self.solve_bytes()),
                gib(self.mesh_bytes),
                gib(self.operator_bytes),
                gib(self.factor_bytes),
                gib(self.contact_bytes),
                gib(self.mesh_bytes + self.assembly_bytes),
                if self.schur_bytes > 0.0 {
                    format!(
                        ", the setup of W by the Schur complement {} (a second factor with the contact unknowns last and three m × m matrices: {}; taken only if it fits then, else W comes from the solves and the peak is {})",
                        gib(self.schur_setup_bytes()),
                        gib(self.schur_bytes),
                        gib(self.required())
                    )
                } else {
                    String::new()
                }
            ),
            format!(
                "outputs (est.) : {} — {} frames of {} each, history.csv {}, contact.csv {}, checkpoint.json {}{}",
                gib(self.outputs.total()),
                self.outputs.frames,
                gib(self.outputs.frame_bytes),
                gib(self.outputs.history_bytes),
                gib(self.outputs.contact_bytes),
                gib(self.outputs.checkpoint_bytes),
                if self.outputs.trajectory_bytes > 0.0 {
                    format!(", trajectory.f64 {}", gib(self.outputs.trajectory_bytes))
                } else {
                    String::new()
                }
            ),
            format!(
                "contact setup  : {}",
                if self.schur_bytes > 0.0 {
                    "a dense W and W⁻¹ from the Schur complement of A_k — one more sparse factorization (contact unknowns last) and ~m³ dense flop (`auto` may still probe W sparse first)"
                } else {
                    "W from d n_c solve pairs with the factor of A_k (or probed sparse: d × colours solves)"
                }
            ),
            {
                // the hierarchical forms from HMATRIX_FROM components: the dense products' flop are
                // then a bound
                let hierarchical =
                    self.velocity_form() && self.dim * self.contact_nodes >= crate::defaults::HMATRIX_FROM;
                format!(
                    "cost per step  : {:.2e} flop in the free and recovery solves; {} {:.2e} flop per Newton iteration of the contact solve ({} on {} unknowns)",
                    solve,
                    if self.velocity_form() && !hierarchical { "about" } else { "at most" },
                    lu,
                    if self.velocity_form() {
                        // the products' form (HMATRIX_FROM) and the preconditioner (NEAR_FIELD_FROM)
                        format!(
                            "velocity form: ~9 products with the {}, {}",
                            if hierarchical {
                                "hierarchical W or W⁻¹ (0.3–0.6 of the dense values, measured)"
                            } else {
                                "dense W or W⁻¹"
                            },
                            if self.dim * self.contact_nodes >= crate::defaults::NEAR_FIELD_FROM {
                                "a sparse near-field factor"
                            } else {
                                "node-block preconditioner"
                            }
                        )
                    } else {
                        "dense Cholesky; reused while the contact sets hold, less with the sparse form".to_string()
                    },
                    self.dim * self.contact_nodes
                )
            },
        ]
    }
}

/// Bytes as TiB, GiB or MiB, for messages.
pub fn gib(bytes: f64) -> String {
    let k = 1024f64;
    if bytes >= k.powi(4) {
        format!("{:.1} TiB", bytes / k.powi(4))
    } else if bytes >= k.powi(3) {
        format!("{:.1} GiB", bytes / k.powi(3))
    } else {
        format!("{:.1} MiB", bytes / k.powi(2))
    }
}

/// The dense products with W or W⁻¹ of one Newton iteration in velocity form: W⁻¹ on the right-hand
/// side, the conjugate gradients with the near-field preconditioner (6.0 per direction on
/// academic3d at 48×24×16, each to round-off), the prescribed rows, and W in the line search's
/// residual.
pub const VELOCITY_PRODUCTS: f64 = 9.0;

/// The estimate of a model; a Gmsh mesh is read (its size is the file's), a rectangle is not built.
pub fn estimate(model: &Model, scene_dir: &Path) -> Result<Estimate> {
    let (nodes, triangles, contact_nodes) = match &model.domain {
        Domain::Rectangle { cells: [nx, ny], .. } => {
            let side = |s: &str| match s {
                "bottom" | "top" => nx + 1,
                "left" | "right" => ny + 1,
                _ => 0,
            };
            ((nx + 1) * (ny + 1), 2 * nx * ny, model.contact_sides.iter().map(|s| side(s)).sum())
        }
        Domain::Box { cells: [nx, ny, nz], .. } => {
            let side = |s: &str| match s {
                "bottom" | "top" => (nx + 1) * (ny + 1),
                "front" | "back" => (nx + 1) * (nz + 1),
                "left" | "right" => (ny + 1) * (nz + 1),
                _ => 0,
            };
            ((nx + 1) * (ny + 1) * (nz + 1), 6 * nx * ny * nz, model.contact_sides.iter().map(|s| side(s)).sum())
        }
        Domain::Gmsh { .. } => {
            let path = model.domain.mesh_file(scene_dir)?.unwrap_or_default();
            match mesh::gmsh::read_any(&path)? {
                mesh::Geometry::Plane(mesh) => {
                    let on_contact: usize =
                        model.contact_sides.iter().filter_map(|s| mesh.side(s)).map(|s| s.facets.len() + 1).sum();
                    (mesh.nodes.len(), mesh.cells.len(), on_contact)
                }
                mesh::Geometry::Solid(mesh) => {
                    // a surface's nodes: at most its faces' vertices (each face adds ≤ 1 node on a
                    // triangulated surface, plus the boundary)
                    let on_contact: usize = model
                        .contact_sides
                        .iter()
                        .filter_map(|s| mesh.side(s))
                        .map(|s| s.facets.iter().flatten().collect::<std::collections::HashSet<_>>().len())
                        .sum();
                    (mesh.nodes.len(), mesh.cells.len(), on_contact)
                }
            }
        }
    };
    let d = model.dim as f64;
    let n = d * nodes as f64;
    let (row_entries, factor_entries) = if model.dim == 3 {
        (45.0, 12.0 * n.powf(4.0 / 3.0) + 45.0 * n)
    } else {
        (ROW_ENTRIES, 4.0 * n * n.max(2.0).log2() + ROW_ENTRIES * n)
    };
    let m = d * contact_nodes as f64;
    // the element matrix of a triangle is 6 × 6, of a tetrahedron 12 × 12
    let element_entries = ((model.dim + 1) * model.dim).pow(2) as f64;
    let steps = model.time.steps;
    // every `output.every`-th step, the first and the last
    let frames = steps.checked_div(model.output_every).map_or(0, |f| f + 2);
    let outputs = Outputs {
        frames,
        frame_bytes: 4096.0 + 190.0 * nodes as f64 + if model.dim == 3 { 115.0 } else { 65.0 } * triangles as f64,
        history_bytes: 420.0 * (steps + 2) as f64,
        contact_bytes: 220.0 * (contact_nodes * frames) as f64,
        trajectory_bytes: if model.output_trajectory { (steps + 1) as f64 * (16.0 * n + 16.0) } else { 0.0 },
        // u and v of every node and λ, t of every contact node as u64 decimal text (≤ 21 bytes
        // each); measured 4,489 bytes for 45 nodes of 2-D with 9 contact nodes
        checkpoint_bytes: 4096.0 + 21.0 * (model.dim * (2 * nodes + contact_nodes)) as f64,
    };
    Ok(Estimate {
        nodes,
        triangles,
        unknowns: model.dim * nodes,
        contact_nodes,
        dim: model.dim,
        // coordinates, triangles, and the state vectors (u, v, loads, work: ~8 per unknown)
        mesh_bytes: 16.0 * nodes as f64 + 24.0 * triangles as f64 + 8.0 * 8.0 * n,
        operator_bytes: OPERATORS * row_entries * n * SPARSE_ENTRY,
        factor_bytes: factor_entries * SPARSE_ENTRY,
        // the dense W and one Newton matrix ((Ck.1)'s test at setup holds W's tangent block,
        // ((d − 1)/d)² m² values, before any Newton matrix exists: it fits that one's place),
        // W⁻¹ where the velocity form may keep it (from
        // GEMV_FROM unknowns), and the responses G = A_k⁻¹ Hᵀ where they are kept
        // (the near field of W⁻¹ and its factor: a few node blocks per node, below 1% of these);
        // from HMATRIX_FROM unknowns the hierarchical W⁻¹ besides, at 1e-12 and at its loose ε
        // (each never more values than the dense one: a block whose factors would not be smaller
        // stays dense; 0.35 and 0.145 of them measured at 3,600 unknowns)
        contact_bytes: (if m >= crate::defaults::HMATRIX_FROM as f64 {
            5.0
        } else if m >= crate::defaults::GEMV_FROM as f64 {
            3.0
        } else {
            2.0
        }) * m
            * m
            * 8.0
            + Some(8.0 * n * m).filter(|g| *g <= crate::defaults::RESPONSES_BYTES).unwrap_or(0.0),
        assembly_bytes: ASSEMBLY_ENTRY * element_entries * triangles as f64,
        // a dense W from SCHUR_FROM components on whose responses are not kept (an upper
        // bound again: `auto` may probe it sparse)
        schur_bytes: if m >= crate::defaults::SCHUR_FROM as f64 && 8.0 * n * m > crate::defaults::RESPONSES_BYTES {
            SCHUR_FACTOR * factor_entries * SPARSE_ENTRY + 3.0 * m * m * 8.0
        } else {
            0.0
        },
        outputs,
    })
}

/// The memory available now (MemAvailable of /proc/meminfo), when the system says.
pub fn available_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// The bytes free for an unprivileged writer on the file system that holds `dir` (or its first
/// existing ancestor), when the system says (statvfs).
pub fn free_disk(dir: &Path) -> Option<f64> {
    let mut at = dir;
    while !at.exists() {
        at = at.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        if at == Path::new(".") {
            break;
        }
    }
    let c = std::ffi::CString::new(at.as_os_str().as_encoded_bytes()).ok()?;
    let mut st = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `c` is a NUL-terminated path and `st` a buffer of the type statvfs fills; it is
    // read only when the call succeeds.
    let st = unsafe {
        if libc::statvfs(c.as_ptr(), st.as_mut_ptr()) != 0 {
            return None;
        }
        st.assume_init()
    };
    Some(st.f_bavail as f64 * st.f_frsize as f64)
}

/// Refuse a run whose outputs would not fit on the file system of its folder, naming the
/// estimate, the frames and the key to change.
pub fn check_disk(e: &Estimate, out: &Path) -> Result<()> {
    let Some(free) = free_disk(out) else { return Ok(()) };
    let need = e.outputs.total();
    if need <= free {
        return Ok(());
    }
    Err(Error::scene(
        "output.every",
        format!(
            "the outputs would take about {} ({} frames of {} each, history.csv {}) but {} are free on the file system of {}; \
             write fewer frames (a larger output.every) or choose another --out",
            gib(need),
            e.outputs.frames,
            gib(e.outputs.frame_bytes),
            gib(e.outputs.history_bytes),
            gib(free),
            out.display()
        ),
    ))
}

/// This process's peak resident memory so far, in bytes (Linux: VmHWM of /proc/self/status;
/// None elsewhere).
pub fn peak_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: f64 =
        text.lines().find_map(|l| l.strip_prefix("VmHWM:"))?.trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kb * 1024.0)
}

/// Start [`peak_memory`] again from the memory resident now, for a bench that measures several
/// runs in one process: the allocator's free heap is handed back first (`malloc_trim`), then
/// VmHWM is reset to the current VmRSS (`5` into /proc/self/clear_refs, Linux ≥ 4.0). False
/// where either is not available (the peak then stays the process's).
pub fn reset_peak_memory() -> bool {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: malloc_trim only returns free memory of glibc's heap to the system.
        unsafe { libc::malloc_trim(0) };
        std::fs::write("/proc/self/clear_refs", "5").is_ok()
    }
    #[cfg(not(target_os = "linux"))]
    {
        false
    }
}

/// Refuse a run whose estimate exceeds the memory available, naming both and what to change.
pub fn check_fits(e: &Estimate, available: Option<f64>) -> Result<()> {
    match available {
        Some(avail) if e.required() > avail => Err(Error::scene(
            "domain",
            format!(
                "the run would need about {} ({} nodes, {} unknowns; the solve holds mesh {}, operators {}, factor of A_k {}, contact solve {}{}) \
                 but {} are available; use a coarser mesh (fewer domain.cells or a coarser Gmsh mesh)",
                gib(e.required()),
                e.nodes,
                e.unknowns,
                gib(e.mesh_bytes),
                gib(e.operator_bytes),
                gib(e.factor_bytes),
                gib(e.contact_bytes),
                if e.schur_bytes > 0.0 {
                    format!(
                        "; W from the solves, as the Schur complement's setup would hold {} more",
                        gib(e.schur_bytes)
                    )
                } else {
                    String::new()
                },
                gib(avail)
            ),
        )),
        _ => Ok(()),
    }
}
