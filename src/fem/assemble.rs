//! Assembly of M, K, C on the P1 space (spec/model.md §4.1) and the elimination of the clamped
//! DOFs of Γ1 (P.3).

use crate::error::{Error, Result};
use crate::linalg::{self, SpMat};
use crate::mesh::solid::SolidMesh;
use crate::mesh::{Geometry, PlaneMesh};
use crate::model::kinds::MassKind;
use crate::model::material::Material;

use super::thickness::ThicknessStrain;
use super::{element, tet};

/// Numbering of the free DOFs: (node k, component c) → map[d k + c] = Some(free index), or
/// None on Γ̄1.
#[derive(Debug, Clone)]
pub struct Dofs {
    pub map: Vec<Option<usize>>,
    pub n_free: usize,
    pub n_nodes: usize,
    /// components per node (the space dimension d)
    pub dim: usize,
}

impl Dofs {
    /// (P.3) u = 0 on Γ1: all d components of every node on a clamped side are removed from
    /// the unknowns; the remaining DOFs are numbered in node order, (node k, component c) →
    /// map[d k + c].
    pub fn with_dim(n_nodes: usize, clamped: &[bool], dim: usize) -> Dofs {
        let mut map = vec![None; dim * n_nodes];
        let mut n_free = 0;
        for k in 0..n_nodes {
            if !clamped[k] {
                for c in 0..dim {
                    map[dim * k + c] = Some(n_free + c);
                }
                n_free += dim;
            }
        }
        Dofs { map, n_free, n_nodes, dim }
    }

    /// Free-DOF vector from nodal values with three components (the first d are read).
    pub fn gather_dim(&self, nodal: impl Fn(usize) -> [f64; 3]) -> Vec<f64> {
        let mut x = vec![0.0; self.n_free];
        for k in 0..self.n_nodes {
            let v = nodal(k);
            for c in 0..self.dim {
                if let Some(i) = self.map[self.dim * k + c] {
                    x[i] = v[c];
                }
            }
        }
        x
    }

    /// Nodal vectors with three components (z = 0 in 2-D) from a free-DOF vector (zero on Γ̄1).
    pub fn expand_dim(&self, x: &[f64]) -> Vec<[f64; 3]> {
        (0..self.n_nodes)
            .map(|k| {
                std::array::from_fn(|c| {
                    if c < self.dim { self.map[self.dim * k + c].map(|i| x[i]).unwrap_or(0.0) } else { 0.0 }
                })
            })
            .collect()
    }
}

/// The matrices of the semi-discrete momentum balance M ü + C u̇ + K u = f on the free DOFs.
pub struct Operators {
    pub m: SpMat,
    pub k: SpMat,
    pub c: SpMat,
    /// row-sum lumped nodal masses per free DOF (used by (C.k) whatever the mass choice)
    pub m_lumped: Vec<f64>,
    /// where each free DOF sits (its node's position; z = 0 in 2-D): the nested dissection of
    /// the step matrix's factor (`ordering`)
    pub positions: Vec<[f64; 3]>,
    /// (Ps.1) ε_zz per triangle in plane stress with A not proportional to B (K and C are then
    /// the plane-strain forms), None otherwise
    pub thickness: Option<ThicknessStrain>,
}

/// (P.2) Galerkin form of ρü = Div σ + f0 with σ from (P.1): assembles, on all 2N DOFs,
/// M_ij = ∫ρ φ_j·φ_i (consistent, or row-lumped), K_ij = ∫ Bε(φ_j):ε(φ_i) and
/// C_ij = ∫ Aε(φ_j):ε(φ_i). Returns (M, K, C).
pub fn assemble_full(mesh: &PlaneMesh, mat: &Material, mass: MassKind) -> Result<(SpMat, SpMat, SpMat)> {
    let n = 2 * mesh.nodes.len();
    let (db, da) = (mat.elasticity(), mat.viscosity());
    let cap = 36 * mesh.cells.len();
    let (mut tm, mut tk, mut tc) = (Vec::with_capacity(cap), Vec::with_capacity(cap), Vec::with_capacity(cap));
    for tri in &mesh.cells {
        let x = [mesh.nodes[tri[0]], mesh.nodes[tri[1]], mesh.nodes[tri[2]]];
        let area = element::gradients(x).1.abs();
        let ke = element::operator_matrix(x, &db);
        let ce = element::operator_matrix(x, &da);
        let me = match mass {
            MassKind::Consistent => element::consistent_mass(area, mat.rho),
            // the modified mass starts from the lumped one (see `modified_masses`)
            MassKind::Lumped | MassKind::Modified => element::lumped_mass(area, mat.rho),
        };
        let element = Element { nodes: tri, dim: 2, k: ke.as_slice(), c: ce.as_slice(), m: me.as_slice() };
        element.scatter(mat.has_viscosity(), (&mut tm, &mut tk, &mut tc));
    }
    Ok((linalg::from_triplets(n, n, &tm)?, linalg::from_triplets(n, n, &tk)?, linalg::from_triplets(n, n, &tc)?))
}

/// The element matrices of one simplex (column-major, N = d (d + 1) rows) and its vertices.
struct Element<'a> {
    nodes: &'a [usize],
    dim: usize,
    k: &'a [f64],
    c: &'a [f64],
    m: &'a [f64],
}

type Triplets = Vec<(usize, usize, f64)>;

impl Element<'_> {
    /// Add the entries to the triplet lists of (M, K, C): local DOF a = d·(vertex) + component
    /// goes to global d·node + component; C only with viscosity, M only where nonzero.
    fn scatter(&self, viscous: bool, (tm, tk, tc): (&mut Triplets, &mut Triplets, &mut Triplets)) {
        let (d, nl) = (self.dim, self.dim * self.nodes.len());
        let global = |a: usize| d * self.nodes[a / d] + a % d;
        for a in 0..nl {
            let ga = global(a);
            for b in 0..nl {
                let (gb, e) = (global(b), a + nl * b);
                tk.push((ga, gb, self.k[e]));
                if viscous {
                    tc.push((ga, gb, self.c[e]));
                }
                if self.m[e] != 0.0 {
                    tm.push((ga, gb, self.m[e]));
                }
            }
        }
    }
}

/// (P.2) in three dimensions: the Galerkin matrices of ρü = Div σ + f0 on all 3N DOFs of a
/// tetrahedral mesh, M (consistent or row-lumped), K and C from the 6×6 Voigt matrices of B and
/// A (no plane reduction). Returns (M, K, C).
pub fn assemble_solid(mesh: &SolidMesh, mat: &Material, mass: MassKind) -> Result<(SpMat, SpMat, SpMat)> {
    let n = 3 * mesh.nodes.len();
    let (db, da) = (mat.elasticity_3d(), mat.viscosity_3d());
    let cap = 144 * mesh.cells.len();
    let (mut tm, mut tk, mut tc) = (Vec::with_capacity(cap), Vec::with_capacity(cap), Vec::with_capacity(cap));
    for (t, tet) in mesh.cells.iter().enumerate() {
        let x = tet.map(|v| mesh.nodes[v]);
        let degenerate = || {
            Error::mesh(
                &mesh.source,
                format!("{} is degenerate", crate::mesh::cell_name(mesh.tags.as_ref(), "tetrahedron", t)),
            )
        };
        let volume = tet::gradients(x).ok_or_else(degenerate)?.1.abs();
        let ke = tet::operator_matrix(x, &db).ok_or_else(degenerate)?;
        let ce = tet::operator_matrix(x, &da).ok_or_else(degenerate)?;
        let me = match mass {
            MassKind::Consistent => tet::consistent_mass(volume, mat.rho),
            MassKind::Lumped | MassKind::Modified => {
                nalgebra::SMatrix::<f64, 12, 12>::from_diagonal_element(tet::vertex_mass(volume, mat.rho))
            }
        };
        let element = Element { nodes: tet, dim: 3, k: ke.as_slice(), c: ce.as_slice(), m: me.as_slice() };
        element.scatter(mat.has_viscosity(), (&mut tm, &mut tk, &mut tc));
    }
    Ok((linalg::from_triplets(n, n, &tm)?, linalg::from_triplets(n, n, &tk)?, linalg::from_triplets(n, n, &tc)?))
}

/// The submatrix on free DOFs.
pub fn restrict(a: &SpMat, dofs: &Dofs) -> Result<SpMat> {
    let trip: Vec<(usize, usize, f64)> =
        linalg::triplets(a).into_iter().filter_map(|(i, j, v)| Some((dofs.map[i]?, dofs.map[j]?, v))).collect();
    linalg::from_triplets(dofs.n_free, dofs.n_free, &trip)
}

impl Operators {
    /// The operators of a scene; `contact_nodes` are the mesh nodes of Γ̄3 \ Γ̄1 (used by the
    /// modified mass).
    pub fn new(
        mesh: &Geometry,
        mat: &Material,
        mass: MassKind,
        dofs: &Dofs,
        contact_nodes: &[usize],
    ) -> Result<Operators> {
        let kind = if mass == MassKind::Modified { MassKind::Lumped } else { mass };
        let (m, k, c) = match mesh {
            Geometry::Plane(mesh) => assemble_full(mesh, mat, kind)?,
            Geometry::Solid(mesh) => assemble_solid(mesh, mat, kind)?,
        };
        let m_lumped = nodal_masses(mesh, mat, mass, dofs, contact_nodes)?;
        let m = if mass == MassKind::Modified {
            let trip: Vec<(usize, usize, f64)> = (0..dofs.n_free).map(|i| (i, i, m_lumped[i])).collect();
            linalg::from_triplets(dofs.n_free, dofs.n_free, &trip)?
        } else {
            restrict(&m, dofs)?
        };
        let mut positions = vec![[0.0; 3]; dofs.n_free];
        for (g, free) in dofs.map.iter().enumerate() {
            if let Some(i) = free {
                positions[*i] = mesh.point(g / dofs.dim);
            }
        }
        let thickness = match (mesh, mat.thickness) {
            (Geometry::Plane(mesh), Some(law)) => Some(ThicknessStrain::new(mesh, law, dofs)),
            _ => None,
        };
        Ok(Operators { m, k: restrict(&k, dofs)?, c: restrict(&c, dofs)?, m_lumped, positions, thickness })
    }
}

/// The diagonal (lumped or modified) nodal mass per free DOF, the m_i of (C.k).
pub fn nodal_masses(
    mesh: &Geometry,
    mat: &Material,
    mass: MassKind,
    dofs: &Dofs,
    contact_nodes: &[usize],
) -> Result<Vec<f64>> {
    match (mesh, mass) {
        (_, MassKind::Modified) => Ok(per_dof(&modified_masses(mesh, mat, dofs, contact_nodes)?, dofs)),
        (Geometry::Plane(m), _) => Ok(per_dof(&vertex_masses(m, mat), dofs)),
        (Geometry::Solid(m), _) => Ok(per_dof(&solid_vertex_masses(m, mat), dofs)),
    }
}

/// Row-sum lumped mass per node of a tetrahedral mesh: Σ over adjacent tetrahedra of ρ|T|/4.
pub fn solid_vertex_masses(mesh: &SolidMesh, mat: &Material) -> Vec<f64> {
    let mut mass = vec![0.0; mesh.nodes.len()];
    for (t, tet) in mesh.cells.iter().enumerate() {
        let m = tet::vertex_mass(mesh.signed_measure(t).abs(), mat.rho);
        for &v in tet {
            mass[v] += m;
        }
    }
    mass
}

/// (R.1) Modified mass (the Khenous–Laborde–Renard family, as classified by Doyen–Ern–Piperno):
/// the lumped mass m_i of every contact node is set to zero and redistributed to the candidate
/// nodes near it that are not on Γ3 and not clamped — in 2-D (triangles) the nodes within two
/// edges of it; in 3-D (tetrahedra) the nodes within three edges of it that are at most twice
/// its longest edge away (a cloud a structured tetrahedral mesh keeps symmetric) — with weights
/// w_j of least Σ w_j²/m_j such that Σ w_j = 1 and Σ w_j x_j = x_i (3 conditions in 2-D, 4 in
/// 3-D): the total mass and the centre of mass are kept exactly. The boundary node lies outside
/// its neighbours' hull, so some weights are negative (mass is moved in by extrapolation, e.g.
/// +2 m_i to the first layer, −m_i from the second on a structured 2-D mesh). A candidate the
/// weights would leave with less than [`MODIFIED_MASS_FLOOR`](crate::defaults::MODIFIED_MASS_FLOOR)
/// of its own lumped mass is left out and the weights solved again, while more than d + 1
/// candidates remain; it is an error when the weights cannot be found that way (too few
/// candidates, a nearly singular system) or when a resulting mass is not positive.
pub fn modified_masses(mesh: &Geometry, mat: &Material, dofs: &Dofs, contact_nodes: &[usize]) -> Result<Vec<f64>> {
    let dim = mesh.dim();
    let n = mesh.n_nodes();
    let (mut mass, cells): (Vec<f64>, Vec<Vec<usize>>) = match mesh {
        Geometry::Plane(m) => (vertex_masses(m, mat), m.cells.iter().map(|t| t.to_vec()).collect()),
        Geometry::Solid(m) => (solid_vertex_masses(m, mat), m.cells.iter().map(|t| t.to_vec()).collect()),
    };
    let original = mass.clone();
    let mut adj = vec![Vec::new(); n];
    for cell in &cells {
        for &a in cell {
            for &b in cell {
                if a != b && !adj[a].contains(&b) {
                    adj[a].push(b);
                }
            }
        }
    }
    let mut is_contact = vec![false; n];
    contact_nodes.iter().for_each(|&i| is_contact[i] = true);
    let free = |j: usize| dofs.map[dim * j].is_some();
    let at = |i: usize| {
        let x = mesh.point(i);
        if dim == 3 { format!("({}, {}, {})", x[0], x[1], x[2]) } else { format!("({}, {})", x[0], x[1]) }
    };
    let distance = |a: usize, b: usize| {
        let (x, y) = (mesh.point(a), mesh.point(b));
        ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt()
    };
    for &i in contact_nodes {
        let mut cand: Vec<usize> = Vec::new();
        if dim == 2 {
            // the nodes within two edges
            for &j in &adj[i] {
                for &l in std::iter::once(&j).chain(adj[j].iter()) {
                    if !is_contact[l] && free(l) && !cand.contains(&l) {
                        cand.push(l);
                    }
                }
            }
        } else {
            // the nodes within three edges and twice the longest edge at i: a cloud that a
            // structured tetrahedral mesh (whose edges run along one diagonal) keeps symmetric,
            // so the tangential conditions need no extrapolation
            let reach = 2.0 * adj[i].iter().map(|&j| distance(i, j)).fold(0.0, f64::max);
            let mut seen = vec![i];
            let mut front = vec![i];
            for _ in 0..3 {
                let mut next = Vec::new();
                for &a in &front {
                    for &b in &adj[a] {
                        if !seen.contains(&b) {
                            seen.push(b);
                            next.push(b);
                        }
                    }
                }
                front = next;
            }
            cand.extend(
                seen.into_iter()
                    .filter(|&l| l != i && !is_contact[l] && free(l) && distance(i, l) <= reach * (1.0 + 1e-12)),
            );
        }
        let xi = mesh.point(i);
        // least Σ w²/m subject to A w = b: w = D Aᵀ (A D Aᵀ)⁻¹ b, A = [1; x − x_i; y − y_i (; z − z_i)];
        // a candidate whose mass this would take below MODIFIED_MASS_FLOOR of its own is left
        // out and the weights solved again (a corner node of a 3-D contact face extrapolates in
        // three directions, which can ask more of a light neighbour than it has)
        loop {
            let rows: Vec<[f64; 4]> = cand
                .iter()
                .map(|&j| {
                    let x = mesh.point(j);
                    [1.0, x[0] - xi[0], x[1] - xi[1], x[2] - xi[2]]
                })
                .collect();
            let lam = least_weights(dim, &rows, &cand, &original).ok_or_else(|| {
                Error::scene(
                    "solver.mass",
                    format!(
                        "\"modified\": contact {} at {} has too few free neighbours within two edges to move its mass \
                         while keeping the centre of mass; refine the mesh near the contact side or use mass = \"lumped\"",
                        mesh.node_name(i),
                        at(i)
                    ),
                )
            })?;
            let change: Vec<f64> = rows
                .iter()
                .zip(&cand)
                .map(|(r, &j)| original[i] * original[j] * (0..=dim).map(|k| r[k] * lam[k]).sum::<f64>())
                .collect();
            let worst = (0..cand.len())
                .map(|q| ((mass[cand[q]] + change[q]) / original[cand[q]], q))
                .filter(|(ratio, _)| *ratio < crate::defaults::MODIFIED_MASS_FLOOR)
                .min_by(|a, b| a.0.total_cmp(&b.0));
            // the weights must meet the conditions (a nearly singular system does not)
            let weights: Vec<f64> = change.iter().map(|c| c / original[i]).collect();
            let reach = rows.iter().map(|r| r[1].abs().max(r[2].abs()).max(r[3].abs())).fold(0.0, f64::max);
            let defect = (0..=dim)
                .map(|k| {
                    (rows.iter().zip(&weights).map(|(r, w)| r[k] * w).sum::<f64>() - if k == 0 { 1.0 } else { 0.0 })
                        .abs()
                        / if k == 0 { 1.0 } else { reach }
                })
                .fold(0.0, f64::max);
            match worst {
                Some((_, q)) if cand.len() > dim + 1 => {
                    cand.remove(q);
                }
                None if defect <= 1e-10 => {
                    for (q, &j) in cand.iter().enumerate() {
                        mass[j] += change[q];
                    }
                    break;
                }
                _ => {
                    return Err(Error::scene(
                        "solver.mass",
                        format!(
                            "\"modified\": the mass of contact {} at {} cannot be moved to its free neighbours within two edges \
                             keeping the centre of mass and every mass positive; refine the mesh near the contact side or use mass = \"lumped\"",
                            mesh.node_name(i),
                            at(i)
                        ),
                    ));
                }
            }
        }
        mass[i] = 0.0;
    }
    if let Some(j) = (0..n).find(|&j| !is_contact[j] && free(j) && mass[j] <= 0.0) {
        return Err(Error::scene(
            "solver.mass",
            format!(
                "\"modified\": redistributing the contact nodes' mass leaves {} at {} with mass {:.3e} <= 0; \
                 refine the mesh near the contact side or use mass = \"lumped\"",
                mesh.node_name(j),
                at(j),
                mass[j]
            ),
        ));
    }
    Ok(mass)
}

/// The multipliers λ of (R.1)'s least-squares weights w_j = m_j a_jᵀ λ, from
/// (Σ_j m_j a_j a_jᵀ) λ = e_1 with a_j = [1, x_j − x_i, …] (`dim` + 1 entries of each row used);
/// None when that matrix is singular.
fn least_weights(dim: usize, rows: &[[f64; 4]], cand: &[usize], m: &[f64]) -> Option<[f64; 4]> {
    if dim == 2 {
        let mut g = nalgebra::Matrix3::<f64>::zeros();
        for (r, &j) in rows.iter().zip(cand) {
            let a = nalgebra::Vector3::new(r[0], r[1], r[2]);
            g += m[j] * a * a.transpose();
        }
        g.try_inverse().map(|gi| {
            let l = gi * nalgebra::Vector3::new(1.0, 0.0, 0.0);
            [l[0], l[1], l[2], 0.0]
        })
    } else {
        let mut g = nalgebra::Matrix4::<f64>::zeros();
        for (r, &j) in rows.iter().zip(cand) {
            let a = nalgebra::Vector4::from(*r);
            g += m[j] * a * a.transpose();
        }
        g.try_inverse().map(|gi| {
            let l = gi * nalgebra::Vector4::new(1.0, 0.0, 0.0, 0.0);
            [l[0], l[1], l[2], l[3]]
        })
    }
}

/// Row-sum lumped mass per mesh node: Σ over adjacent triangles of ρ|T|/3.
pub fn vertex_masses(mesh: &PlaneMesh, mat: &Material) -> Vec<f64> {
    let mut mass = vec![0.0; mesh.nodes.len()];
    for tri in &mesh.cells {
        let x = [mesh.nodes[tri[0]], mesh.nodes[tri[1]], mesh.nodes[tri[2]]];
        let area = element::gradients(x).1.abs();
        for &v in tri {
            mass[v] += element::vertex_mass(area, mat.rho);
        }
    }
    mass
}

/// A nodal quantity on the free DOFs (every component of a node gets the node's value).
fn per_dof(per_node: &[f64], dofs: &Dofs) -> Vec<f64> {
    let mut d = vec![0.0; dofs.n_free];
    for (k, m) in per_node.iter().enumerate() {
        for c in 0..dofs.dim {
            if let Some(i) = dofs.map[dofs.dim * k + c] {
                d[i] = *m;
            }
        }
    }
    d
}
