//! Meshes (spec/model.md §4.1): conforming P1 simplicial meshes of either dimension with named
//! boundary sides — [`PlaneMesh`] (triangles, d = 2, [`plane`]) and [`SolidMesh`] (tetrahedra,
//! d = 3, [`solid`]) are one type [`Mesh`] over its [`Cell`] — the structured generators, the
//! Gmsh reader, and nodal boundary data (outward normals ν_i and weights ω_i = ∫ φ_i over a set
//! of sides).

pub mod gmsh;
pub mod plane;
pub mod solid;

use std::collections::HashMap;
use std::fmt::Debug;
use std::hash::Hash;

use crate::error::{Error, Result};

pub use plane::{PlaneMesh, Triangle};
pub use solid::{SolidMesh, Tetrahedron};

/// The cell of a P1 simplicial mesh in d dimensions: what a [`Mesh`] needs that depends on d.
/// Implemented by [`Triangle`] (d = 2; facets are edges) and [`Tetrahedron`] (d = 3; facets are
/// triangular faces).
pub trait Cell: Sized {
    /// The space dimension d.
    const D: usize;
    /// How the structural checks and messages name the cells and their facets.
    const NAMES: CellNames;
    /// A node's coordinates, `[f64; d]`.
    type Point: Copy + Debug + PartialEq + Default + AsRef<[f64]> + AsMut<[f64]>;
    /// A cell's vertices, `[usize; d + 1]`.
    type Vertices: Copy + Debug + PartialEq + AsRef<[usize]>;
    /// A boundary facet's vertices, `[usize; d]`: an edge in 2-D, a face in 3-D.
    type Facet: Copy + Debug + Eq + Hash + AsRef<[usize]> + AsMut<[usize]>;

    /// The facets of cell `c` (2-D: its edges (v_k, v_k+1); 3-D: its faces, outward when `c` is
    /// positively oriented).
    fn facets(c: Self::Vertices) -> impl Iterator<Item = Self::Facet>;

    /// The signed measure (area, volume) of cell `t`, positive when it is positively oriented.
    fn signed_measure(mesh: &Mesh<Self>, t: usize) -> f64;

    /// For every facet of a side, the outward unit normal and the measure (length, area);
    /// errors if a facet is not on the boundary of exactly one cell (or is degenerate).
    fn facet_geometry(mesh: &Mesh<Self>, side: &Side<Self>) -> Result<Vec<(Self::Point, f64)>>;

    /// Checks on the facets of the sides `names` together, before their nodal normals are
    /// formed (3-D: the surface is a manifold); none by default.
    fn check_sides(_mesh: &Mesh<Self>, _names: &[String], _facets: &[Self::Facet]) -> Result<()> {
        Ok(())
    }
}

/// How the structural checks name a mesh's cells and facets.
#[derive(Debug, Clone, Copy)]
pub struct CellNames {
    /// "triangle" / "tetrahedron"
    pub one: &'static str,
    /// "triangles" / "tetrahedra"
    pub many: &'static str,
    /// "area" or "volume"
    pub measure: &'static str,
    /// the word for a cell of measure 0
    pub zero: &'static str,
    /// "edge" or "face"
    pub facet: &'static str,
}

/// A named part of the boundary: a list of facets (edges in 2-D; in 3-D triangles oriented
/// with the outward normal (x1 − x0) × (x2 − x0)).
#[derive(Debug, Clone)]
pub struct Side<C: Cell> {
    pub name: String,
    pub facets: Vec<C::Facet>,
}

/// A conforming P1 mesh of positively oriented cells (counterclockwise triangles, positive
/// tetrahedra) with named sides.
#[derive(Debug, Clone)]
pub struct Mesh<C: Cell> {
    pub nodes: Vec<C::Point>,
    pub cells: Vec<C::Vertices>,
    pub sides: Vec<Side<C>>,
    /// where the mesh came from, for messages
    pub source: String,
    /// the file's node and element tags (a Gmsh mesh): messages name nodes and cells by them
    pub tags: Option<Tags>,
}

/// Nodes of a set of sides with outward nodal normals and boundary weights.
#[derive(Debug, Clone)]
pub struct SideNodes<C: Cell> {
    pub nodes: Vec<usize>,
    /// ω-weighted mean of the outward normals of the adjacent facets, normalized (decision 9)
    pub normals: Vec<C::Point>,
    /// ω_i = ∫ φ_i over the sides (1/d of the measure of each adjacent facet; exact for P1)
    pub omega: Vec<f64>,
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

/// A facet's vertices sorted: the key under which the cells owning it are found.
pub(crate) fn key<F: AsMut<[usize]>>(mut f: F) -> F {
    f.as_mut().sort_unstable();
    f
}

impl<C: Cell> Mesh<C> {
    pub fn side(&self, name: &str) -> Option<&Side<C>> {
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

    /// The named side, or an error naming the sides there are.
    fn named(&self, name: &str) -> Result<&Side<C>> {
        self.side(name).ok_or_else(|| {
            Error::mesh(&self.source, format!("no side named {name:?}; the mesh has {}", self.side_list()))
        })
    }

    /// Signed measure of cell `t` (area, volume): positive when positively oriented.
    pub fn signed_measure(&self, t: usize) -> f64 {
        C::signed_measure(self, t)
    }

    /// Total measure (area in 2-D, volume in 3-D).
    pub fn measure(&self) -> f64 {
        (0..self.cells.len()).map(|t| self.signed_measure(t)).sum()
    }

    /// For every facet of a side, the outward unit normal and the measure (see
    /// [`Cell::facet_geometry`]).
    pub fn facet_geometry(&self, side: &Side<C>) -> Result<Vec<(C::Point, f64)>> {
        C::facet_geometry(self, side)
    }

    /// The cells of each facet of the cells, by the facet's sorted vertices ([`key`]).
    pub(crate) fn facet_owners(&self) -> HashMap<C::Facet, Vec<usize>> {
        let mut m: HashMap<C::Facet, Vec<usize>> = HashMap::new();
        for (t, &c) in self.cells.iter().enumerate() {
            for f in C::facets(c) {
                m.entry(key(f)).or_default().push(t);
            }
        }
        m
    }

    /// Nodes of the named sides, sorted, with outward nodal normals (the ω-weighted mean of the
    /// adjacent facet normals, decision 9) and weights ω_i = Σ |F|/d over adjacent facets F.
    /// Nodes in `exclude` are left out (Γ̄1 nodes from Γ3). Errors if a side is missing, a
    /// facet is not on the boundary, [`Cell::check_sides`] fails (3-D: an edge of these sides
    /// shared by more than two of their faces) or a nodal normal vanishes.
    pub fn side_nodes(&self, names: &[String], exclude: &[bool]) -> Result<SideNodes<C>> {
        let mut acc: HashMap<usize, (C::Point, f64)> = HashMap::new();
        let mut all: Vec<C::Facet> = Vec::new();
        for name in names {
            let side = self.named(name)?;
            for (&f, (n, measure)) in side.facets.iter().zip(self.facet_geometry(side)?) {
                let w = measure / C::D as f64;
                for &v in f.as_ref() {
                    let e = acc.entry(v).or_insert((C::Point::default(), 0.0));
                    for (s, c) in e.0.as_mut().iter_mut().zip(n.as_ref()) {
                        *s += w * c;
                    }
                    e.1 += w;
                }
            }
            all.extend_from_slice(&side.facets);
        }
        C::check_sides(self, names, &all)?;
        let mut nodes: Vec<usize> =
            acc.keys().copied().filter(|&v| !exclude.get(v).copied().unwrap_or(false)).collect();
        nodes.sort_unstable();
        let mut out = SideNodes { nodes: Vec::new(), normals: Vec::new(), omega: Vec::new() };
        for v in nodes {
            let (mut n, w) = acc[&v];
            let norm = n.as_ref().iter().fold(0.0, |s, c| s + c * c).sqrt();
            if !(norm > 1e-12 * w) {
                return Err(Error::mesh(
                    &self.source,
                    format!(
                        "{} sits where adjacent side {}s have opposite normals; its nodal normal is undefined",
                        node_name(self.tags.as_ref(), v),
                        C::NAMES.facet
                    ),
                ));
            }
            n.as_mut().iter_mut().for_each(|c| *c /= norm);
            out.nodes.push(v);
            out.normals.push(n);
            out.omega.push(w);
        }
        Ok(out)
    }

    /// Per-node flag: the node lies on one of the named sides.
    pub fn nodes_on(&self, names: &[String]) -> Result<Vec<bool>> {
        let mut on = vec![false; self.nodes.len()];
        for name in names {
            for f in &self.named(name)?.facets {
                f.as_ref().iter().for_each(|&v| on[v] = true);
            }
        }
        Ok(on)
    }

    /// Structural checks: cells exist, their indices are in range, their signed measure (area
    /// or volume) is finite and above 1e-14 × diam^d (positively oriented, not degenerate),
    /// every node is a vertex of some cell, side facets are on the boundary.
    pub fn check(&self) -> Result<()> {
        let CellNames { one, many, measure: what, zero, .. } = C::NAMES;
        let (source, n, tags) = (&self.source, self.nodes.len(), self.tags.as_ref());
        let cell = |t: usize| cell_name(tags, one, t);
        if self.cells.is_empty() {
            return Err(Error::mesh(source, format!("has no {many}")));
        }
        let scale = self.bbox_diameter().powi(C::D as i32);
        let mut used = vec![false; n];
        for (t, c) in self.cells.iter().enumerate() {
            for &v in c.as_ref() {
                if v >= n {
                    return Err(Error::mesh(
                        source,
                        format!("{} refers to node {v}, but there are {n} nodes", cell(t)),
                    ));
                }
                used[v] = true;
            }
            let a = self.signed_measure(t);
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
                        node_list(tags, c.as_ref()),
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
        for s in &self.sides {
            self.facet_geometry(s)?;
        }
        Ok(())
    }

    /// The diameter of the nodes' bounding box.
    pub fn bbox_diameter(&self) -> f64 {
        let (mut lo, mut hi) = (vec![f64::INFINITY; C::D], vec![f64::NEG_INFINITY; C::D]);
        for p in &self.nodes {
            for (k, &x) in p.as_ref().iter().enumerate() {
                lo[k] = lo[k].min(x);
                hi[k] = hi[k].max(x);
            }
        }
        lo.iter().zip(&hi).fold(0.0, |s, (l, h)| s + (h - l) * (h - l)).sqrt()
    }
}

/// The body's mesh in either dimension: P1 triangles (d = 2) or P1 tetrahedra (d = 3). The
/// time loop and the outputs ask it for what they need; 2-D-only consumers (the Γ3 charts, the
/// convergence probes) take [`Geometry::plane`].
#[derive(Debug, Clone)]
pub enum Geometry {
    Plane(PlaneMesh),
    Solid(SolidMesh),
}

/// Nodes of a set of sides (Γ3) in either dimension: outward unit normals with three
/// components (z = 0 in 2-D) and weights ω_i.
#[derive(Debug, Clone, Default)]
pub struct BoundaryNodes {
    pub nodes: Vec<usize>,
    pub normals: Vec<[f64; 3]>,
    pub omega: Vec<f64>,
}

/// `$body` with `$m` bound to the mesh of either dimension.
macro_rules! each {
    ($geometry:expr, $m:ident => $body:expr) => {
        match $geometry {
            Geometry::Plane($m) => $body,
            Geometry::Solid($m) => $body,
        }
    };
}

impl Geometry {
    /// The space dimension d.
    pub fn dim(&self) -> usize {
        match self {
            Geometry::Plane(_) => Triangle::D,
            Geometry::Solid(_) => Tetrahedron::D,
        }
    }
    pub fn n_nodes(&self) -> usize {
        each!(self, m => m.nodes.len())
    }
    /// Triangles or tetrahedra.
    pub fn n_cells(&self) -> usize {
        each!(self, m => m.cells.len())
    }
    /// Node i's coordinates (z = 0 in 2-D).
    pub fn point(&self, i: usize) -> [f64; 3] {
        match self {
            Geometry::Plane(m) => [m.nodes[i][0], m.nodes[i][1], 0.0],
            Geometry::Solid(m) => m.nodes[i],
        }
    }
    /// The 2-D mesh, if the body is planar.
    pub fn plane(&self) -> Option<&PlaneMesh> {
        match self {
            Geometry::Plane(m) => Some(m),
            Geometry::Solid(_) => None,
        }
    }
    /// The tetrahedral mesh, if the body is three-dimensional.
    pub fn solid(&self) -> Option<&SolidMesh> {
        match self {
            Geometry::Plane(_) => None,
            Geometry::Solid(m) => Some(m),
        }
    }
    pub fn source(&self) -> &str {
        each!(self, m => &m.source)
    }
    pub fn has_side(&self, name: &str) -> bool {
        each!(self, m => m.side(name).is_some())
    }
    /// "node 17" for a message: the file's tag for a Gmsh mesh, else the index.
    pub fn node_name(&self, v: usize) -> String {
        each!(self, m => node_name(m.tags.as_ref(), v))
    }
    pub fn side_list(&self) -> String {
        each!(self, m => m.side_list())
    }
    pub fn nodes_on(&self, names: &[String]) -> Result<Vec<bool>> {
        each!(self, m => m.nodes_on(names))
    }
    /// Nodes of the named sides with outward nodal normals and weights (see
    /// [`Mesh::side_nodes`]).
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
        each!(self, m => m.check())
    }
    pub fn bbox_diameter(&self) -> f64 {
        each!(self, m => m.bbox_diameter())
    }
}

/// The sides of a mesh for a message: "a, b, c", or a sentence when there are none (a Gmsh
/// file without physical groups).
pub fn side_names<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let list: Vec<String> = names.map(|s| s.escape_debug().to_string()).collect();
    if list.is_empty() { "no named sides (the mesh file defines no physical groups)".into() } else { list.join(", ") }
}
