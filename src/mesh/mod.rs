//! Meshes (spec/model.md §4.1): P1 triangulations with named boundary sides, the structured
//! `rectangle` generator, the Gmsh reader, and nodal boundary data (outward normals ν_i and
//! weights ω_i = ∫ φ_i over a set of sides).

pub mod gmsh;
pub mod solid;

use std::collections::HashMap;

use crate::error::{Error, Result};

/// A named part of the boundary: a list of edges (node pairs).
#[derive(Debug, Clone)]
pub struct Side {
    pub name: String,
    pub edges: Vec<[usize; 2]>,
}

/// A conforming P1 triangulation with counterclockwise triangles and named sides.
#[derive(Debug, Clone)]
pub struct Mesh {
    pub nodes: Vec<[f64; 2]>,
    pub triangles: Vec<[usize; 3]>,
    pub sides: Vec<Side>,
    /// where the mesh came from, for messages
    pub source: String,
    /// the file's node and element tags (a Gmsh mesh): messages name nodes and cells by them
    pub tags: Option<Tags>,
}

/// A mesh file's tags of the nodes and cells, in the mesh's order.
#[derive(Debug, Clone, PartialEq)]
pub struct Tags {
    pub nodes: Vec<i64>,
    pub cells: Vec<i64>,
}

/// "node 17" for a message: the file's tag when the mesh was read from a file, else the index.
pub fn node_name(tags: Option<&Tags>, v: usize) -> String {
    match tags.and_then(|t| t.nodes.get(v)) {
        Some(tag) => format!("node {tag}"),
        None => format!("node {v}"),
    }
}

/// "triangle 5" / "tetrahedron 5" (`one`) for a message, by the file's tag where there is one.
pub fn cell_name(tags: Option<&Tags>, one: &str, t: usize) -> String {
    match tags.and_then(|g| g.cells.get(t)) {
        Some(tag) => format!("{one} {tag}"),
        None => format!("{one} {t}"),
    }
}

/// The nodes of a cell or an edge by name: "nodes 3, 8, 9".
fn node_list(tags: Option<&Tags>, vs: &[usize]) -> String {
    let names: Vec<String> = vs.iter().map(|&v| node_name(tags, v).trim_start_matches("node ").to_string()).collect();
    format!("nodes {}", names.join(", "))
}

/// Nodes of a set of sides with outward nodal normals and boundary weights.
#[derive(Debug, Clone, Default)]
pub struct SideNodes {
    pub nodes: Vec<usize>,
    /// ω-weighted mean of the outward normals of the adjacent edges, normalized (decision 9)
    pub normals: Vec<[f64; 2]>,
    /// ω_i = ∫ φ_i over the sides (half the length of each adjacent edge; exact for P1)
    pub omega: Vec<f64>,
}

impl Mesh {
    /// Structured rectangle [0, lx] × [0, ly] with nx × ny cells, each cut into two triangles
    /// along its (lower-left, upper-right) diagonal. Node n = j (nx + 1) + i sits at
    /// (lx i / nx, ly j / ny). Sides: "bottom", "right", "top", "left" (edges counterclockwise).
    pub fn rectangle(lx: f64, ly: f64, nx: usize, ny: usize) -> Mesh {
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                nodes.push([lx * i as f64 / nx as f64, ly * j as f64 / ny as f64]);
            }
        }
        let mut triangles = Vec::with_capacity(2 * nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        let bottom = (0..nx).map(|i| [id(i, 0), id(i + 1, 0)]).collect();
        let right = (0..ny).map(|j| [id(nx, j), id(nx, j + 1)]).collect();
        let top = (0..nx).rev().map(|i| [id(i + 1, ny), id(i, ny)]).collect();
        let left = (0..ny).rev().map(|j| [id(0, j + 1), id(0, j)]).collect();
        let sides = vec![
            Side { name: "bottom".into(), edges: bottom },
            Side { name: "right".into(), edges: right },
            Side { name: "top".into(), edges: top },
            Side { name: "left".into(), edges: left },
        ];
        Mesh { nodes, triangles, sides, source: format!("rectangle {lx}x{ly}, {nx}x{ny} cells"), tags: None }
    }

    pub fn side(&self, name: &str) -> Option<&Side> {
        self.sides.iter().find(|s| s.name == name)
    }

    pub fn side_names(&self) -> Vec<String> {
        self.sides.iter().map(|s| s.name.clone()).collect()
    }

    /// The side names for messages: comma-separated, control characters escaped (a physical
    /// name read from a file may hold any character but a newline).
    pub fn side_list(&self) -> String {
        side_names(self.sides.iter().map(|s| s.name.as_str()))
    }

    /// Signed area of triangle `t` (positive when counterclockwise).
    pub fn signed_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangles[t];
        let (p, q, r) = (self.nodes[a], self.nodes[b], self.nodes[c]);
        0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]))
    }

    /// Total area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len()).map(|t| self.signed_area(t)).sum()
    }

    /// For every side edge, the outward unit normal and the length; errors if an edge is not a
    /// boundary edge of the triangulation.
    pub fn edge_geometry(&self, side: &Side) -> Result<Vec<([f64; 2], f64)>> {
        let owner = self.edge_owners();
        side.edges
            .iter()
            .map(|&[a, b]| {
                let key = (a.min(b), a.max(b));
                let tris = owner.get(&key).map(|v| v.as_slice()).unwrap_or(&[]);
                if tris.len() != 1 {
                    return Err(Error::mesh(
                        &self.source,
                        format!(
                            "the edge ({}) of side {:?} is {} — a side edge must be on the boundary of exactly one triangle",
                            node_list(self.tags.as_ref(), &[a, b]),
                            side.name,
                            if tris.is_empty() { "not an edge of any triangle".to_string() } else { format!("shared by {} triangles (interior)", tris.len()) }
                        ),
                    ));
                }
                let [p, q] = [self.nodes[a], self.nodes[b]];
                let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
                let mut n = [(q[1] - p[1]) / len, -(q[0] - p[0]) / len];
                // orient outward: away from the third vertex of the owning triangle
                let tri = self.triangles[tris[0]];
                let c = tri.iter().copied().find(|&v| v != a && v != b).unwrap_or(a);
                let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
                let to_c = [self.nodes[c][0] - mid[0], self.nodes[c][1] - mid[1]];
                if n[0] * to_c[0] + n[1] * to_c[1] > 0.0 {
                    n = [-n[0], -n[1]];
                }
                Ok((n, len))
            })
            .collect()
    }

    fn edge_owners(&self) -> HashMap<(usize, usize), Vec<usize>> {
        let mut m: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                m.entry((a.min(b), a.max(b))).or_default().push(t);
            }
        }
        m
    }

    /// Nodes of the named sides, sorted, with outward nodal normals (the ω-weighted mean of the
    /// adjacent edge normals, decision 9) and weights ω_i = Σ |e|/2 over adjacent edges.
    /// Nodes in `exclude` are left out (used to drop Γ̄1 nodes from Γ3).
    pub fn side_nodes(&self, names: &[String], exclude: &[bool]) -> Result<SideNodes> {
        let mut acc: HashMap<usize, ([f64; 2], f64)> = HashMap::new();
        for name in names {
            let side = self.side(name).ok_or_else(|| {
                Error::mesh(&self.source, format!("no side named {name:?}; the mesh has {}", self.side_list()))
            })?;
            for (&[a, b], (n, len)) in side.edges.iter().zip(self.edge_geometry(side)?) {
                for v in [a, b] {
                    let e = acc.entry(v).or_insert(([0.0, 0.0], 0.0));
                    e.0[0] += 0.5 * len * n[0];
                    e.0[1] += 0.5 * len * n[1];
                    e.1 += 0.5 * len;
                }
            }
        }
        let mut nodes: Vec<usize> =
            acc.keys().copied().filter(|&v| !exclude.get(v).copied().unwrap_or(false)).collect();
        nodes.sort_unstable();
        let mut out = SideNodes::default();
        for v in nodes {
            let (n, w) = acc[&v];
            let norm = (n[0] * n[0] + n[1] * n[1]).sqrt();
            if !(norm > 1e-12 * w) {
                return Err(Error::mesh(
                    &self.source,
                    format!(
                        "{} sits where adjacent side edges have opposite normals; its nodal normal is undefined",
                        node_name(self.tags.as_ref(), v)
                    ),
                ));
            }
            out.nodes.push(v);
            out.normals.push([n[0] / norm, n[1] / norm]);
            out.omega.push(w);
        }
        Ok(out)
    }

    /// Per-node flag: the node lies on one of the named sides.
    pub fn nodes_on(&self, names: &[String]) -> Result<Vec<bool>> {
        let mut on = vec![false; self.nodes.len()];
        for name in names {
            let side = self.side(name).ok_or_else(|| {
                Error::mesh(&self.source, format!("no side named {name:?}; the mesh has {}", self.side_list()))
            })?;
            for e in &side.edges {
                on[e[0]] = true;
                on[e[1]] = true;
            }
        }
        Ok(on)
    }

    /// Structural checks: triangles counterclockwise with positive area, indices in range,
    /// every node used by a triangle, side edges on the boundary.
    pub fn check(&self) -> Result<()> {
        let names = CellNames { one: "triangle", many: "triangles", measure: "area", zero: "zero" };
        check_cells(
            &self.source,
            self.nodes.len(),
            &self.triangles,
            |t| self.signed_area(t),
            self.bbox_diameter().powi(2),
            &names,
            self.tags.as_ref(),
        )?;
        for s in &self.sides {
            self.edge_geometry(s)?;
        }
        Ok(())
    }

    pub fn bbox_diameter(&self) -> f64 {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &self.nodes {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt()
    }
}

/// How the structural checks name a mesh's cells.
pub(crate) struct CellNames {
    pub one: &'static str,
    pub many: &'static str,
    /// "area" or "volume"
    pub measure: &'static str,
    /// the word for a cell of measure 0
    pub zero: &'static str,
}

/// The structural checks of either dimension: cells exist, their indices are in range, their
/// signed measure (area or volume) is finite and above 1e-14 × `scale` (positively oriented,
/// not degenerate), and every node is a vertex of some cell.
pub(crate) fn check_cells<const N: usize>(
    source: &str,
    n: usize,
    cells: &[[usize; N]],
    measure: impl Fn(usize) -> f64,
    scale: f64,
    names: &CellNames,
    tags: Option<&Tags>,
) -> Result<()> {
    let CellNames { one, many, measure: what, zero } = names;
    let cell = |t: usize| cell_name(tags, one, t);
    if cells.is_empty() {
        return Err(Error::mesh(source, format!("has no {many}")));
    }
    let mut used = vec![false; n];
    for (t, c) in cells.iter().enumerate() {
        for &v in c {
            if v >= n {
                return Err(Error::mesh(source, format!("{} refers to node {v}, but there are {n} nodes", cell(t))));
            }
            used[v] = true;
        }
        let a = measure(t);
        if !a.is_finite() {
            return Err(Error::mesh(
                source,
                format!("the {what} of {} overflows: the coordinates are too large; give them in metres", cell(t)),
            ));
        }
        if !(a > 1e-14 * scale) {
            return Err(Error::mesh(
                source,
                format!(
                    "{} ({}) has {} {what} {a:.3e}; fix or remove it",
                    cell(t),
                    node_list(tags, c),
                    if a < 0.0 { "negative (inverted)" } else { zero }
                ),
            ));
        }
    }
    if let Some(v) = used.iter().position(|u| !u) {
        return Err(Error::mesh(
            source,
            format!("{} is not a vertex of any {one}; remove unreferenced nodes", node_name(tags, v)),
        ));
    }
    Ok(())
}

/// The body's mesh in either dimension: P1 triangles (d = 2) or P1 tetrahedra (d = 3). The
/// time loop and the outputs ask it for what they need; 2-D-only consumers (the Γ3 charts, the
/// convergence probes) take [`Geometry::plane`].
#[derive(Debug, Clone)]
pub enum Geometry {
    Plane(Mesh),
    Solid(solid::SolidMesh),
}

/// Nodes of a set of sides (Γ3) in either dimension: outward unit normals with three
/// components (z = 0 in 2-D) and weights ω_i.
#[derive(Debug, Clone, Default)]
pub struct BoundaryNodes {
    pub nodes: Vec<usize>,
    pub normals: Vec<[f64; 3]>,
    pub omega: Vec<f64>,
}

impl Geometry {
    /// The space dimension d.
    pub fn dim(&self) -> usize {
        match self {
            Geometry::Plane(_) => 2,
            Geometry::Solid(_) => 3,
        }
    }
    pub fn n_nodes(&self) -> usize {
        match self {
            Geometry::Plane(m) => m.nodes.len(),
            Geometry::Solid(m) => m.nodes.len(),
        }
    }
    /// Triangles or tetrahedra.
    pub fn n_cells(&self) -> usize {
        match self {
            Geometry::Plane(m) => m.triangles.len(),
            Geometry::Solid(m) => m.tets.len(),
        }
    }
    /// Node i's coordinates (z = 0 in 2-D).
    pub fn point(&self, i: usize) -> [f64; 3] {
        match self {
            Geometry::Plane(m) => [m.nodes[i][0], m.nodes[i][1], 0.0],
            Geometry::Solid(m) => m.nodes[i],
        }
    }
    /// The 2-D mesh, if the body is planar.
    pub fn plane(&self) -> Option<&Mesh> {
        match self {
            Geometry::Plane(m) => Some(m),
            Geometry::Solid(_) => None,
        }
    }
    /// The tetrahedral mesh, if the body is three-dimensional.
    pub fn solid(&self) -> Option<&solid::SolidMesh> {
        match self {
            Geometry::Plane(_) => None,
            Geometry::Solid(m) => Some(m),
        }
    }
    pub fn source(&self) -> &str {
        match self {
            Geometry::Plane(m) => &m.source,
            Geometry::Solid(m) => &m.source,
        }
    }
    pub fn has_side(&self, name: &str) -> bool {
        match self {
            Geometry::Plane(m) => m.side(name).is_some(),
            Geometry::Solid(m) => m.side(name).is_some(),
        }
    }
    /// "node 17" for a message: the file's tag for a Gmsh mesh, else the index.
    pub fn node_name(&self, v: usize) -> String {
        match self {
            Geometry::Plane(m) => node_name(m.tags.as_ref(), v),
            Geometry::Solid(m) => node_name(m.tags.as_ref(), v),
        }
    }

    pub fn side_list(&self) -> String {
        match self {
            Geometry::Plane(m) => m.side_list(),
            Geometry::Solid(m) => side_names(m.sides.iter().map(|s| s.name.as_str())),
        }
    }
    pub fn nodes_on(&self, names: &[String]) -> Result<Vec<bool>> {
        match self {
            Geometry::Plane(m) => m.nodes_on(names),
            Geometry::Solid(m) => m.nodes_on(names),
        }
    }
    /// Nodes of the named sides with outward nodal normals and weights (see
    /// [`Mesh::side_nodes`], [`solid::SolidMesh::side_nodes`]).
    pub fn side_nodes(&self, names: &[String], exclude: &[bool]) -> Result<BoundaryNodes> {
        Ok(match self {
            Geometry::Plane(m) => {
                let s = m.side_nodes(names, exclude)?;
                BoundaryNodes {
                    nodes: s.nodes,
                    normals: s.normals.iter().map(|n| [n[0], n[1], 0.0]).collect(),
                    omega: s.omega,
                }
            }
            Geometry::Solid(m) => {
                let s = m.side_nodes(names, exclude)?;
                BoundaryNodes { nodes: s.nodes, normals: s.normals, omega: s.omega }
            }
        })
    }
    pub fn check(&self) -> Result<()> {
        match self {
            Geometry::Plane(m) => m.check(),
            Geometry::Solid(m) => m.check(),
        }
    }
    pub fn bbox_diameter(&self) -> f64 {
        match self {
            Geometry::Plane(m) => m.bbox_diameter(),
            Geometry::Solid(m) => m.bbox_diameter(),
        }
    }
}

/// The sides of a mesh for a message: "a, b, c", or a sentence when there are none (a Gmsh
/// file without physical groups).
pub fn side_names<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let list: Vec<String> = names.map(|s| s.escape_debug().to_string()).collect();
    if list.is_empty() { "no named sides (the mesh file defines no physical groups)".into() } else { list.join(", ") }
}
