//! Export of the assembled operators for the Python cross-check (`cargo xtask crosscheck`):
//! the mesh as VTU, M, K, C on all 2N DOFs as Matrix Market files, and the load vector at
//! t = 0 (DOFs interleaved 2k + c, nothing eliminated).

use std::fmt::Write as _;
use std::path::Path;

use crate::error::{Error, Result};
use crate::fem::assemble::{Dofs, assemble_full};
use crate::linalg::{self, SpMat};
use crate::model::expr::VecExpr;
use crate::model::kinds;
use crate::problem::{Problem, build_loads};

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

/// Write mesh.vtu, M.mtx, K.mtx, C.mtx, f.txt and params.json into `dir`. The load vector is
/// the problem's own (f0, f2 and f3, assembled by `problem::build_loads`) on all 2N DOFs.
pub fn export_operators(p: &Problem, dir: &Path) -> Result<()> {
    let Some(mesh) = p.mesh.plane() else {
        return Err(Error::scene(
            "domain",
            "export-operators writes 2-D meshes only (the 3-D operators are cross-checked by tests/verification/crosscheck.rs)",
        ));
    };
    if p.material.thickness.is_some() {
        return Err(Error::scene(
            "material.viscosity",
            "export-operators writes M, K, C of a body whose stress they determine; in plane stress with a \
             viscosity not proportional to the elasticity ε_zz is an internal variable (Ps.1) beside them, so no \
             K and C alone describe it: use plane = \"strain\" or a proportional viscosity for the export",
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let n = mesh.nodes.len();
    let zero = vec![[0.0; 3]; n];
    let contact = vec![vtu::NodeContact::OFF; n];
    let frame =
        vtu::Snapshot { mesh: &p.mesh, material: &p.material, u: &zero, v: &zero, contact: &contact, eps_zz: &[] };
    write_atomic(&dir.join("mesh.vtu"), vtu::vtu(&frame).as_bytes())?;
    let model = &p.model;
    let (m, k, c) = assemble_full(mesh, &p.material, model.solver.mass)?;
    write_atomic(&dir.join("M.mtx"), matrix_market(&m).as_bytes())?;
    write_atomic(&dir.join("K.mtx"), matrix_market(&k).as_bytes())?;
    write_atomic(&dir.join("C.mtx"), matrix_market(&c).as_bytes())?;
    let all = Dofs::with_dim(n, &vec![false; n], 2);
    let f = build_loads(model, &p.mesh, &all)?.at(0.0);
    let mut ft = String::new();
    for v in f {
        let _ = writeln!(ft, "{v:e}");
    }
    write_atomic(&dir.join("f.txt"), ft.as_bytes())?;
    // every surface load the vector holds, as (side, expression source, edges)
    let surface = |side: &str, value: &VecExpr| {
        let edges = mesh.side(side).map(|s| s.facets.clone()).unwrap_or_default();
        serde_json::json!({"side": side, "value": value.sources(), "edges": edges})
    };
    let mut tractions: Vec<_> = model.loads.traction.iter().map(|tr| surface(&tr.side, &tr.value)).collect();
    if let Some(f3) = &model.loads.contact_surface {
        tractions.extend(model.contact_sides.iter().map(|side| surface(side, f3)));
    }
    let mat = &model.material;
    let params = serde_json::json!({
        "young": mat.young, "poisson": mat.poisson, "density": mat.density,
        "theta": mat.theta, "zeta": mat.zeta,
        "plane": kinds::name(&model.plane.unwrap_or_default()),
        "mass": kinds::name(&model.solver.mass),
        "body": model.loads.body.sources(), "tractions": tractions, "t": 0.0,
    });
    let text = serde_json::to_string_pretty(&params).map_err(|e| Error::Output(format!("params.json: {e}")))?;
    write_atomic(&dir.join("params.json"), text.as_bytes())
}
