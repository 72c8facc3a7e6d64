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

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::mesh;
use crate::model::{Domain, Model};

/// Bytes of one stored sparse entry (f64 value and index).
const SPARSE_ENTRY: f64 = 16.0;
/// Entries per row of a P1 operator in 2-D (2 DOFs × 7 coupled nodes).
const ROW_ENTRIES: f64 = 14.0;
/// Sparse operators held at once: M, K, C, A_k and the right-hand-side matrix R.
const OPERATORS: f64 = 5.0;

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
}

impl Estimate {
    /// The estimated peak, in bytes.
    pub fn total(&self) -> f64 {
        self.mesh_bytes + self.operator_bytes + self.factor_bytes + self.contact_bytes
    }

    /// Floating-point work of one step: two triangular-solve pairs on the factor, and at most
    /// one dense Cholesky of the contact Newton matrix per Newton iteration (an upper bound: the
    /// factor is reused while the contact sets do not change, and the sparse form costs less).
    pub fn flops_per_step(&self) -> (f64, f64) {
        let factor_entries = self.factor_bytes / SPARSE_ENTRY;
        let m = (self.dim * self.contact_nodes) as f64;
        (2.0 * 2.0 * 2.0 * factor_entries, m * m * m / 3.0)
    }

    /// Human-readable lines for `dyncontact check`.
    pub fn lines(&self) -> Vec<String> {
        let (solve, lu) = self.flops_per_step();
        vec![
            format!(
                "memory (est.)  : {} in all — mesh {}, operators {}, factor of A_k {}, contact solve {}",
                gib(self.total()),
                gib(self.mesh_bytes),
                gib(self.operator_bytes),
                gib(self.factor_bytes),
                gib(self.contact_bytes)
            ),
            format!(
                "cost per step  : {:.2e} flop in the free and recovery solves; at most {:.2e} flop per Newton iteration of the contact solve (dense Cholesky on {} unknowns; reused while the contact sets hold, less with the sparse form)",
                solve,
                lu,
                self.dim * self.contact_nodes
            ),
        ]
    }
}

/// Bytes as GiB (or MiB below one GiB), for messages.
pub fn gib(bytes: f64) -> String {
    if bytes >= 1024.0 * 1024.0 * 1024.0 { format!("{:.1} GiB", bytes / 1024f64.powi(3)) } else { format!("{:.1} MiB", bytes / 1024f64.powi(2)) }
}

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
        Domain::Gmsh { file } => {
            let path: PathBuf = if Path::new(file).is_absolute() { file.into() } else { scene_dir.join(file) };
            if !path.exists() {
                return Err(Error::scene("domain.file", format!("mesh file {:?} does not exist", path.display().to_string())));
            }
            match mesh::gmsh::read_any(&path)? {
                mesh::Geometry::Plane(mesh) => {
                    let on_contact: usize = model.contact_sides.iter().filter_map(|s| mesh.side(s)).map(|s| s.edges.len() + 1).sum();
                    (mesh.nodes.len(), mesh.triangles.len(), on_contact)
                }
                mesh::Geometry::Solid(mesh) => {
                    // a surface's nodes: at most its faces' vertices (each face adds ≤ 1 node on a
                    // triangulated surface, plus the boundary)
                    let on_contact: usize = model
                        .contact_sides
                        .iter()
                        .filter_map(|s| mesh.side(s))
                        .map(|s| s.faces.iter().flatten().collect::<std::collections::HashSet<_>>().len())
                        .sum();
                    (mesh.nodes.len(), mesh.tets.len(), on_contact)
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
        // the dense W and one Newton matrix, W⁻¹ where the velocity form may keep it (from
        // GEMV_FROM unknowns), and the responses G = A_k⁻¹ Hᵀ where they are kept
        contact_bytes: (if m >= crate::defaults::GEMV_FROM as f64 { 3.0 } else { 2.0 }) * m * m * 8.0
            + Some(8.0 * n * m).filter(|g| *g <= crate::defaults::RESPONSES_BYTES).unwrap_or(0.0),
    })
}

/// The memory available now (MemAvailable of /proc/meminfo), when the system says.
pub fn available_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// Refuse a run whose estimate exceeds the memory available, naming both and what to change.
pub fn check_fits(e: &Estimate, available: Option<f64>) -> Result<()> {
    match available {
        Some(avail) if e.total() > avail => Err(Error::scene(
            "domain",
            format!(
                "the run would need about {} ({} nodes, {} unknowns: mesh {}, operators {}, factor of A_k {}, contact solve {}) \
                 but {} are available; use a coarser mesh (fewer domain.cells or a coarser Gmsh mesh)",
                gib(e.total()),
                e.nodes,
                e.unknowns,
                gib(e.mesh_bytes),
                gib(e.operator_bytes),
                gib(e.factor_bytes),
                gib(e.contact_bytes),
                gib(avail)
            ),
        )),
        _ => Ok(()),
    }
}
