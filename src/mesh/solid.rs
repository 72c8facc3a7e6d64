//! Tetrahedral meshes (d = 3, spec/model.md §4.1): the [`Tetrahedron`] cell (signed volume,
//! faces and their outward normals, the manifold check of a contact surface) and the
//! structured `box` generator. What every dimension shares is [`Mesh`] in the parent module.

use std::collections::HashMap;

use super::{Cell, CellNames, Mesh, Side, key, node_name};
use crate::error::{Error, Result};

/// The P1 tetrahedron: positively oriented ((x1 − x0) × (x2 − x0)) · (x3 − x0) > 0, facets are
/// triangular faces.
#[derive(Debug, Clone, Copy)]
pub struct Tetrahedron;

/// A conforming P1 tetrahedral mesh with positively oriented tetrahedra and named surfaces.
pub type SolidMesh = Mesh<Tetrahedron>;

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Cell for Tetrahedron {
    const D: usize = 3;
    const NAMES: CellNames = CellNames {
        one: "tetrahedron",
        many: "tetrahedra",
        measure: "volume",
        zero: "zero (degenerate)",
        facet: "face",
    };
    type Point = [f64; 3];
    type Vertices = [usize; 4];
    type Facet = [usize; 3];

    /// The faces of a tetrahedron, each oriented outward when it is positively oriented.
    fn facets([a, b, c, d]: [usize; 4]) -> impl Iterator<Item = [usize; 3]> {
        [[a, c, b], [a, b, d], [a, d, c], [b, c, d]].into_iter()
    }

    /// Signed volume of tetrahedron `t`: ((x1 − x0) × (x2 − x0)) · (x3 − x0) / 6.
    fn signed_measure(mesh: &SolidMesh, t: usize) -> f64 {
        let [a, b, c, d] = mesh.cells[t].map(|v| mesh.nodes[v]);
        dot(cross(sub(b, a), sub(c, a)), sub(d, a)) / 6.0
    }

    /// For every face of a side, the outward unit normal and the area; errors if a face is not
    /// a boundary face of the mesh (interior, or no face of any tetrahedron) or is degenerate.
    fn facet_geometry(mesh: &SolidMesh, side: &Side<Tetrahedron>) -> Result<Vec<([f64; 3], f64)>> {
        let owners = mesh.facet_owners();
        side.facets
            .iter()
            .map(|&f| {
                let tets = owners.get(&key(f)).map(|v| v.as_slice()).unwrap_or(&[]);
                if tets.len() != 1 {
                    return Err(Error::mesh(
                        &mesh.source,
                        format!(
                            "face {f:?} of side {:?} is {} — a side face must be on the boundary of exactly one tetrahedron",
                            side.name,
                            if tets.is_empty() { "not a face of any tetrahedron".to_string() } else { format!("shared by {} tetrahedra (interior)", tets.len()) }
                        ),
                    ));
                }
                let [p, q, r] = f.map(|v| mesh.nodes[v]);
                let nrm = cross(sub(q, p), sub(r, p));
                let twice_area = dot(nrm, nrm).sqrt();
                if !(twice_area > 0.0) {
                    return Err(Error::mesh(&mesh.source, format!("face {f:?} of side {:?} has zero area", side.name)));
                }
                let mut n = nrm.map(|c| c / twice_area);
                // orient outward: away from the fourth vertex of the owning tetrahedron
                let t = mesh.cells[tets[0]];
                let o = t.iter().copied().find(|v| !f.contains(v)).unwrap_or(f[0]);
                if dot(n, sub(mesh.nodes[o], p)) > 0.0 {
                    n = n.map(|c| -c);
                }
                Ok((n, 0.5 * twice_area))
            })
            .collect()
    }

    /// The faces of the sides `names` make a manifold surface: no edge belongs to more than two
    /// of them.
    fn check_sides(mesh: &SolidMesh, names: &[String], faces: &[[usize; 3]]) -> Result<()> {
        let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
        for f in faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        if let Some((&(a, b), &count)) = edges.iter().filter(|e| *e.1 > 2).min_by_key(|e| *e.0) {
            return Err(Error::mesh(
                &mesh.source,
                format!(
                    "the edge between {} and {} of the sides {names:?} belongs to {count} of their faces: the contact surface is not a manifold",
                    node_name(mesh.tags.as_ref(), a),
                    node_name(mesh.tags.as_ref(), b)
                ),
            ));
        }
        Ok(())
    }
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
        let mut cells = Vec::with_capacity(6 * nx * ny * nz);
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
                        cells.push(t);
                    }
                }
            }
        }
        let mut mesh = Mesh {
            nodes,
            cells,
            sides: Vec::new(),
            tags: None,
            source: format!("box {}x{}x{}, {nx}x{ny}x{nz} cells", l[0], l[1], l[2]),
        };
        mesh.orient();
        // boundary faces of the tetrahedra, sorted to the six sides by the coordinate they share
        let faces = mesh.boundary_faces();
        let names = ["left", "right", "front", "back", "bottom", "top"];
        let mut sides: Vec<Side<Tetrahedron>> =
            names.iter().map(|s| Side { name: (*s).into(), facets: Vec::new() }).collect();
        for f in faces {
            let on = |axis: usize, v: f64| f.iter().all(|&q| mesh.nodes[q][axis] == v);
            if let Some(s) = (0..6).find(|&s| on(s / 2, if s % 2 == 0 { 0.0 } else { l[s / 2] })) {
                sides[s].facets.push(f);
            }
        }
        mesh.sides = sides;
        mesh
    }

    /// Swap two vertices of every negatively oriented tetrahedron.
    fn orient(&mut self) {
        for t in 0..self.cells.len() {
            if self.signed_measure(t) < 0.0 {
                self.cells[t].swap(2, 3);
            }
        }
    }

    /// Faces that belong to exactly one tetrahedron, outward.
    pub fn boundary_faces(&self) -> Vec<[usize; 3]> {
        let owners = self.facet_owners();
        let mut out: Vec<[usize; 3]> = Vec::new();
        for &c in &self.cells {
            for f in Tetrahedron::facets(c) {
                if owners.get(&key(f)).is_some_and(|o| o.len() == 1) {
                    out.push(f);
                }
            }
        }
        out
    }
}
