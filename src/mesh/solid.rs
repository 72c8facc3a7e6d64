//! Tetrahedral meshes (d = 3, spec/model.md §4.1): P1 tetrahedra with named boundary surfaces,
//! the structured `box` generator, and nodal boundary data on surfaces (outward normals ν_i and
//! weights ω_i = ∫ φ_i over a set of sides). The 2-D triangulations are in the parent module.

use std::collections::HashMap;

use crate::error::{Error, Result};

/// A named part of the boundary: triangles (node triples), oriented with the outward normal
/// (x1 − x0) × (x2 − x0).
#[derive(Debug, Clone)]
pub struct Surface {
    pub name: String,
    pub faces: Vec<[usize; 3]>,
}

/// A conforming P1 tetrahedral mesh with positively oriented tetrahedra and named surfaces.
#[derive(Debug, Clone)]
pub struct SolidMesh {
    pub nodes: Vec<[f64; 3]>,
    pub tets: Vec<[usize; 4]>,
    pub sides: Vec<Surface>,
    /// where the mesh came from, for messages
    pub source: String,
    /// the file's node and element tags (a Gmsh mesh): messages name nodes and cells by them
    pub tags: Option<super::Tags>,
}

/// Nodes of a set of surfaces with outward nodal normals and boundary weights.
#[derive(Debug, Clone, Default)]
pub struct SurfaceNodes {
    pub nodes: Vec<usize>,
    /// ω-weighted mean of the outward normals of the adjacent faces, normalized (decision 9)
    pub normals: Vec<[f64; 3]>,
    /// ω_i = ∫ φ_i over the sides (a third of each adjacent face's area; exact for P1)
    pub omega: Vec<f64>,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The face key: its sorted node triple.
fn key(f: [usize; 3]) -> [usize; 3] {
    let mut k = f;
    k.sort_unstable();
    k
}

impl SolidMesh {
    /// Structured box [0, lx] × [0, ly] × [0, lz] with nx × ny × nz cells, each cut into the six
    /// tetrahedra that share its main diagonal from (i, j, k) to (i+1, j+1, k+1) (the Kuhn
    /// subdivision: one tetrahedron per order in which the path along the diagonal steps in x,
    /// y and z; conforming across cells). Node n = (k (ny + 1) + j)(nx + 1) + i sits at
    /// (lx i/nx, ly j/ny, lz k/nz). Sides: "left" x = 0, "right" x = lx, "front" y = 0,
    /// "back" y = ly, "bottom" z = 0, "top" z = lz, two triangles per cell face.
    pub fn cuboid(l: [f64; 3], n: [usize; 3]) -> SolidMesh {
        let [nx, ny, nz] = n;
        let id = |i: usize, j: usize, k: usize| (k * (ny + 1) + j) * (nx + 1) + i;
        let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
        for k in 0..=nz {
            for j in 0..=ny {
                for i in 0..=nx {
                    nodes.push([l[0] * i as f64 / nx as f64, l[1] * j as f64 / ny as f64, l[2] * k as f64 / nz as f64]);
                }
            }
        }
        const ORDERS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
        let mut tets = Vec::with_capacity(6 * nx * ny * nz);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    for order in ORDERS {
                        let mut p = [i, j, k];
                        let mut t = [id(i, j, k), 0, 0, 0];
                        for (s, &axis) in order.iter().enumerate() {
                            p[axis] += 1;
                            t[s + 1] = id(p[0], p[1], p[2]);
                        }
                        tets.push(t);
                    }
                }
            }
        }
        let mut mesh = SolidMesh {
            nodes,
            tets,
            sides: Vec::new(),
            tags: None,
            source: format!("box {}x{}x{}, {nx}x{ny}x{nz} cells", l[0], l[1], l[2]),
        };
        mesh.orient();
        // boundary faces of the tetrahedra, sorted to the six sides by the coordinate they share
        let faces = mesh.boundary_faces();
        let names = ["left", "right", "front", "back", "bottom", "top"];
        let mut sides: Vec<Surface> = names.iter().map(|s| Surface { name: (*s).into(), faces: Vec::new() }).collect();
        for f in faces {
            let on = |axis: usize, v: f64| f.iter().all(|&q| mesh.nodes[q][axis] == v);
            if let Some(s) = (0..6).find(|&s| on(s / 2, if s % 2 == 0 { 0.0 } else { l[s / 2] })) {
                sides[s].faces.push(f);
            }
        }
        mesh.sides = sides;
        mesh
    }

    /// Swap two vertices of every negatively oriented tetrahedron.
    fn orient(&mut self) {
        for t in 0..self.tets.len() {
            if self.signed_volume(t) < 0.0 {
                self.tets[t].swap(2, 3);
            }
        }
    }

    /// Signed volume of tetrahedron `t`: ((x1 − x0) × (x2 − x0)) · (x3 − x0) / 6.
    pub fn signed_volume(&self, t: usize) -> f64 {
        let [a, b, c, d] = self.tets[t].map(|v| self.nodes[v]);
        dot(cross(sub(b, a), sub(c, a)), sub(d, a)) / 6.0
    }

    /// Total volume.
    pub fn volume(&self) -> f64 {
        (0..self.tets.len()).map(|t| self.signed_volume(t)).sum()
    }

    /// The faces of tetrahedron t, each oriented outward.
    fn tet_faces(&self, t: usize) -> [[usize; 3]; 4] {
        let [a, b, c, d] = self.tets[t];
        // for a positively oriented (a, b, c, d) these four have outward normals
        [[a, c, b], [a, b, d], [a, d, c], [b, c, d]]
    }

    /// Faces that belong to exactly one tetrahedron, outward.
    pub fn boundary_faces(&self) -> Vec<[usize; 3]> {
        let owners = self.face_owners();
        let mut out: Vec<[usize; 3]> = Vec::new();
        for t in 0..self.tets.len() {
            for f in self.tet_faces(t) {
                if owners.get(&key(f)).is_some_and(|o| o.len() == 1) {
                    out.push(f);
                }
            }
        }
        out
    }

    fn face_owners(&self) -> HashMap<[usize; 3], Vec<usize>> {
        let mut m: HashMap<[usize; 3], Vec<usize>> = HashMap::new();
        for t in 0..self.tets.len() {
            for f in self.tet_faces(t) {
                m.entry(key(f)).or_default().push(t);
            }
        }
        m
    }

    pub fn side(&self, name: &str) -> Option<&Surface> {
        self.sides.iter().find(|s| s.name == name)
    }

    fn side_list(&self) -> String {
        super::side_names(self.sides.iter().map(|s| s.name.as_str()))
    }

    fn named(&self, name: &str) -> Result<&Surface> {
        self.side(name).ok_or_else(|| {
            Error::mesh(&self.source, format!("no side named {name:?}; the mesh has {}", self.side_list()))
        })
    }

    /// For every face of a side, the outward unit normal and the area; errors if a face is not
    /// a boundary face of the mesh (interior, or no face of any tetrahedron) or is degenerate.
    pub fn face_geometry(&self, side: &Surface) -> Result<Vec<([f64; 3], f64)>> {
        let owners = self.face_owners();
        side.faces
            .iter()
            .map(|&f| {
                let tets = owners.get(&key(f)).map(|v| v.as_slice()).unwrap_or(&[]);
                if tets.len() != 1 {
                    return Err(Error::mesh(
                        &self.source,
                        format!(
                            "face {f:?} of side {:?} is {} — a side face must be on the boundary of exactly one tetrahedron",
                            side.name,
                            if tets.is_empty() { "not a face of any tetrahedron".to_string() } else { format!("shared by {} tetrahedra (interior)", tets.len()) }
                        ),
                    ));
                }
                let [p, q, r] = f.map(|v| self.nodes[v]);
                let nrm = cross(sub(q, p), sub(r, p));
                let twice_area = dot(nrm, nrm).sqrt();
                if !(twice_area > 0.0) {
                    return Err(Error::mesh(&self.source, format!("face {f:?} of side {:?} has zero area", side.name)));
                }
                let mut n = nrm.map(|c| c / twice_area);
                // orient outward: away from the fourth vertex of the owning tetrahedron
                let t = self.tets[tets[0]];
                let o = t.iter().copied().find(|v| !f.contains(v)).unwrap_or(f[0]);
                if dot(n, sub(self.nodes[o], p)) > 0.0 {
                    n = n.map(|c| -c);
                }
                Ok((n, 0.5 * twice_area))
            })
            .collect()
    }

    /// Nodes of the named sides, sorted, with outward nodal normals (the ω-weighted mean of the
    /// adjacent face normals, decision 9) and weights ω_i = Σ |F|/3 over adjacent faces. Nodes
    /// in `exclude` are left out (Γ̄1 nodes from Γ3). Errors if an edge of these sides is shared
    /// by more than two of their faces (a non-manifold surface) or a nodal normal vanishes.
    pub fn side_nodes(&self, names: &[String], exclude: &[bool]) -> Result<SurfaceNodes> {
        let mut acc: HashMap<usize, ([f64; 3], f64)> = HashMap::new();
        let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
        for name in names {
            let side = self.named(name)?;
            for (&f, (n, area)) in side.faces.iter().zip(self.face_geometry(side)?) {
                for k in 0..3 {
                    let e = acc.entry(f[k]).or_insert(([0.0; 3], 0.0));
                    for c in 0..3 {
                        e.0[c] += area / 3.0 * n[c];
                    }
                    e.1 += area / 3.0;
                    let (a, b) = (f[k], f[(k + 1) % 3]);
                    *edges.entry((a.min(b), a.max(b))).or_default() += 1;
                }
            }
        }
        if let Some((&(a, b), &count)) = edges.iter().filter(|e| *e.1 > 2).min_by_key(|e| *e.0) {
            return Err(Error::mesh(
                &self.source,
                format!(
                    "the edge between {} and {} of the sides {names:?} belongs to {count} of their faces: the contact surface is not a manifold",
                    super::node_name(self.tags.as_ref(), a),
                    super::node_name(self.tags.as_ref(), b)
                ),
            ));
        }
        let mut nodes: Vec<usize> =
            acc.keys().copied().filter(|&v| !exclude.get(v).copied().unwrap_or(false)).collect();
        nodes.sort_unstable();
        let mut out = SurfaceNodes::default();
        for v in nodes {
            let (n, w) = acc[&v];
            let norm = dot(n, n).sqrt();
            if !(norm > 1e-12 * w) {
                return Err(Error::mesh(
                    &self.source,
                    format!(
                        "{} sits where adjacent side faces have opposite normals; its nodal normal is undefined",
                        super::node_name(self.tags.as_ref(), v)
                    ),
                ));
            }
            out.nodes.push(v);
            out.normals.push(n.map(|c| c / norm));
            out.omega.push(w);
        }
        Ok(out)
    }

    /// Per-node flag: the node lies on one of the named sides.
    pub fn nodes_on(&self, names: &[String]) -> Result<Vec<bool>> {
        let mut on = vec![false; self.nodes.len()];
        for name in names {
            for f in &self.named(name)?.faces {
                f.iter().for_each(|&v| on[v] = true);
            }
        }
        Ok(on)
    }

    /// Structural checks: indices in range, every tetrahedron positively oriented with a volume
    /// above round-off, every node used, side faces on the boundary.
    pub fn check(&self) -> Result<()> {
        let names =
            super::CellNames { one: "tetrahedron", many: "tetrahedra", measure: "volume", zero: "zero (degenerate)" };
        super::check_cells(
            &self.source,
            self.nodes.len(),
            &self.tets,
            |t| self.signed_volume(t),
            self.bbox_diameter().powi(3),
            &names,
            self.tags.as_ref(),
        )?;
        for s in &self.sides {
            self.face_geometry(s)?;
        }
        Ok(())
    }

    pub fn bbox_diameter(&self) -> f64 {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &self.nodes {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        dot(sub(hi, lo), sub(hi, lo)).sqrt()
    }
}
