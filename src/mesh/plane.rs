//! Triangulations (d = 2, spec/model.md §4.1): the [`Triangle`] cell (signed area, edges and
//! their outward normals) and the structured `rectangle` generator. What every dimension shares
//! is [`Mesh`] in the parent module.

use super::{Cell, CellNames, Mesh, Side, node_list};
use crate::error::{Error, Result};

/// The P1 triangle: vertices counterclockwise, facets are edges.
#[derive(Debug, Clone, Copy)]
pub struct Triangle;

/// A conforming P1 triangulation with counterclockwise triangles and named sides.
pub type PlaneMesh = Mesh<Triangle>;

impl Cell for Triangle {
    const D: usize = 2;
    const NAMES: CellNames =
        CellNames { one: "triangle", many: "triangles", measure: "area", zero: "zero", facet: "edge" };
    type Point = [f64; 2];
    type Vertices = [usize; 3];
    type Facet = [usize; 2];

    fn facets(c: [usize; 3]) -> impl Iterator<Item = [usize; 2]> {
        (0..3).map(move |k| [c[k], c[(k + 1) % 3]])
    }

    /// Signed area of triangle `t` (positive when counterclockwise).
    fn signed_measure(mesh: &PlaneMesh, t: usize) -> f64 {
        let [a, b, c] = mesh.cells[t];
        let (p, q, r) = (mesh.nodes[a], mesh.nodes[b], mesh.nodes[c]);
        0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]))
    }

    /// For every side edge, the outward unit normal and the length; errors if an edge is not a
    /// boundary edge of the triangulation.
    fn facet_geometry(mesh: &PlaneMesh, side: &Side<Triangle>) -> Result<Vec<([f64; 2], f64)>> {
        let owner = mesh.facet_owners();
        side.facets
            .iter()
            .map(|&[a, b]| {
                let tris = owner.get(&super::key([a, b])).map(|v| v.as_slice()).unwrap_or(&[]);
                if tris.len() != 1 {
                    return Err(Error::mesh(
                        &mesh.source,
                        format!(
                            "the edge ({}) of side {:?} is {} — a side edge must be on the boundary of exactly one triangle",
                            node_list(mesh.tags.as_ref(), &[a, b]),
                            side.name,
                            if tris.is_empty() { "not an edge of any triangle".to_string() } else { format!("shared by {} triangles (interior)", tris.len()) }
                        ),
                    ));
                }
                let [p, q] = [mesh.nodes[a], mesh.nodes[b]];
                let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
                let mut n = [(q[1] - p[1]) / len, -(q[0] - p[0]) / len];
                // orient outward: away from the third vertex of the owning triangle
                let tri = mesh.cells[tris[0]];
                let c = tri.iter().copied().find(|&v| v != a && v != b).unwrap_or(a);
                let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
                let to_c = [mesh.nodes[c][0] - mid[0], mesh.nodes[c][1] - mid[1]];
                if n[0] * to_c[0] + n[1] * to_c[1] > 0.0 {
                    n = [-n[0], -n[1]];
                }
                Ok((n, len))
            })
            .collect()
    }
}

impl PlaneMesh {
    /// Structured rectangle [0, lx] × [0, ly] with nx × ny cells, each cut into two triangles
    /// along its (lower-left, upper-right) diagonal. Node n = j (nx + 1) + i sits at
    /// (lx i / nx, ly j / ny). Sides: "bottom", "right", "top", "left" (edges counterclockwise).
    pub fn rectangle(lx: f64, ly: f64, nx: usize, ny: usize) -> PlaneMesh {
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                nodes.push([lx * i as f64 / nx as f64, ly * j as f64 / ny as f64]);
            }
        }
        let mut cells = Vec::with_capacity(2 * nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                cells.push([a, b, c]);
                cells.push([a, c, d]);
            }
        }
        let bottom = (0..nx).map(|i| [id(i, 0), id(i + 1, 0)]).collect();
        let right = (0..ny).map(|j| [id(nx, j), id(nx, j + 1)]).collect();
        let top = (0..nx).rev().map(|i| [id(i + 1, ny), id(i, ny)]).collect();
        let left = (0..ny).rev().map(|j| [id(0, j + 1), id(0, j)]).collect();
        let sides = vec![
            Side { name: "bottom".into(), facets: bottom },
            Side { name: "right".into(), facets: right },
            Side { name: "top".into(), facets: top },
            Side { name: "left".into(), facets: left },
        ];
        Mesh { nodes, cells, sides, source: format!("rectangle {lx}x{ly}, {nx}x{ny} cells"), tags: None }
    }
}
