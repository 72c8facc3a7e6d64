//! Export of the assembled operators for the Python cross-check (`cargo xtask crosscheck`):
//! the mesh as VTU, M, K, C on all 2N DOFs as Matrix Market files, and the load vector at
//! t = 0 (DOFs interleaved 2k + c, nothing eliminated).

use std::fmt::Write as _;
use std::path::Path;

use crate::error::{Error, Result};
use crate::fem::assemble::{assemble_full, Dofs};
use crate::fem::LoadVector;
use crate::linalg::{self, SpMat};
use crate::model::expr::VecExpr;
use crate::problem::Problem;

use super::{vtu, write_atomic};

fn matrix_market(a: &SpMat) -> String {
    let t = linalg::triplets(a);
    let mut s = String::with_capacity(40 * t.len());
    s.push_str("%%MatrixMarket matrix coordinate real general\n");
    let _ = writeln!(s, "{} {} {}", a.nrows(), a.ncols(), t.len());
    for (i, j, v) in t {
        let _ = writeln!(s, "{} {} {v:e}", i + 1, j + 1);
    }
    s
}

/// Write mesh.vtu, M.mtx, K.mtx, C.mtx, f.txt and params.json into `dir`.
pub fn export_operators(p: &Problem, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let n = p.mesh.nodes.len();
    let zero = vec![[0.0; 2]; n];
    let contact = vec![(0.0, 0.0, 0.0, 0.0, -1); n];
    let frame = vtu::Frame { mesh: &p.mesh, material: &p.material, u: &zero, v: &zero, contact: &contact };
    write_atomic(&dir.join("mesh.vtu"), vtu::vtu(&frame).as_bytes())?;
    let (m, k, c) = assemble_full(&p.mesh, &p.material, p.scene.solver.mass)?;
    write_atomic(&dir.join("M.mtx"), matrix_market(&m).as_bytes())?;
    write_atomic(&dir.join("K.mtx"), matrix_market(&k).as_bytes())?;
    write_atomic(&dir.join("C.mtx"), matrix_market(&c).as_bytes())?;
    let all = Dofs::new(n, &vec![false; n]);
    let body = VecExpr::parse(&p.scene.loads.body, &["x", "y", "t"], "loads.body")?;
    let mut surface = Vec::new();
    let mut tractions = Vec::new();
    for (i, tr) in p.scene.loads.traction.iter().enumerate() {
        let path = format!("loads.traction[{i}].value");
        let edges = p.mesh.side(&tr.side).map(|s| s.edges.clone()).unwrap_or_default();
        tractions.push(serde_json::json!({"side": tr.side, "value": tr.value, "edges": edges}));
        surface.push((edges, VecExpr::parse(&tr.value, &["x", "y", "t"], &path)?, path));
    }
    let f = LoadVector::new(&p.mesh, &all, &body, &surface).at(0.0);
    let mut ft = String::new();
    for v in f {
        let _ = writeln!(ft, "{v:e}");
    }
    write_atomic(&dir.join("f.txt"), ft.as_bytes())?;
    let mat = &p.scene.material;
    let params = serde_json::json!({
        "young": mat.young, "poisson": mat.poisson, "density": mat.density,
        "theta": mat.viscosity.theta, "zeta": mat.viscosity.zeta,
        "plane": format!("{:?}", p.scene.domain.plane).to_lowercase(),
        "mass": format!("{:?}", p.scene.solver.mass).to_lowercase(),
        "body": p.scene.loads.body, "tractions": tractions, "t": 0.0,
    });
    let text = serde_json::to_string_pretty(&params).map_err(|e| Error::Output(format!("params.json: {e}")))?;
    write_atomic(&dir.join("params.json"), text.as_bytes())
}
