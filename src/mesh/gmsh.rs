//! Reader for Gmsh ASCII meshes, format 2.2 and 4.1. In 2-D, 3-node triangles (type 2) make
//! the domain and 2-node lines (type 1) in physical curves make the named sides; in 3-D (a file
//! with 4-node tetrahedra, type 4) the tetrahedra make the domain and the triangles in physical
//! surfaces the named sides (lines are then ignored). Points (type 15) are ignored. Why
//! hand-written: see the README's design notes (the maintained crate reads 4.1 only).

use std::collections::HashMap;
use std::path::Path;

use super::{Cell, Geometry, Mesh, PlaneMesh, Side, SolidMesh, key};
use crate::error::{Error, Result};

/// Read a 2-D `.msh` file (triangles); a file with tetrahedra is an error here (see [`read_any`]).
pub fn read(path: &Path) -> Result<PlaneMesh> {
    match read_any(path)? {
        Geometry::Plane(m) => Ok(m),
        Geometry::Solid(m) => {
            Err(Error::mesh(&m.source, "holds tetrahedra (a 3-D mesh) where a 2-D mesh of triangles is expected"))
        }
    }
}

/// Read a `.msh` file of either dimension: tetrahedra make a 3-D mesh, else triangles a 2-D one.
/// Its first line is checked before the rest is read: a large file that is not a mesh is
/// refused without being loaded.
pub fn read_any(path: &Path) -> Result<Geometry> {
    check_first_line(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::read(path, e))?;
    // A binary .msh is not UTF-8; decode lossily so that its ASCII header is still read and
    // the "binary files are not supported" message is given instead of an encoding error.
    let text = String::from_utf8_lossy(&bytes);
    parse_any(&text, &path.display().to_string())
}

/// A Gmsh file starts with `$MeshFormat` (after blank lines): read at most 4 KiB to see it.
fn check_first_line(path: &Path) -> Result<()> {
    use std::io::Read as _;
    let mut head = Vec::with_capacity(4096);
    std::fs::File::open(path).and_then(|f| f.take(4096).read_to_end(&mut head)).map_err(|e| Error::read(path, e))?;
    let text = String::from_utf8_lossy(&head);
    let Some((n, first)) = text.lines().enumerate().find(|(_, l)| !l.trim().is_empty()) else {
        return Err(Error::mesh(
            path.display().to_string(),
            "is empty (or starts with 4 KiB of blank lines): not a Gmsh mesh",
        ));
    };
    if first.trim() != "$MeshFormat" {
        let shown: String = first.trim().chars().take(40).collect();
        return Err(Error::mesh(
            path.display().to_string(),
            format!("line {}: a Gmsh mesh starts with $MeshFormat, found {shown:?}", n + 1),
        ));
    }
    Ok(())
}

struct Cursor<'a> {
    lines: Vec<(usize, &'a str)>,
    pos: usize,
    file: &'a str,
    /// the section being read (without `$`), for end-of-file messages
    section: String,
}

impl<'a> Cursor<'a> {
    fn err(&self, msg: impl std::fmt::Display) -> Error {
        let line = self.lines.get(self.pos.saturating_sub(1)).map(|l| l.0).unwrap_or(0);
        Error::mesh(self.file, format!("line {line}: {msg}"))
    }
    fn next_line(&mut self) -> Result<&'a str> {
        let Some(l) = self.lines.get(self.pos) else {
            return Err(if self.section.is_empty() {
                Error::mesh(self.file, "unexpected end of file")
            } else {
                Error::mesh(
                    self.file,
                    format!(
                        "unexpected end of file in ${0}: the file is truncated or $End{0} is missing; save the mesh again",
                        self.section.escape_debug()
                    ),
                )
            });
        };
        self.pos += 1;
        Ok(l.1)
    }
    fn nums<T: std::str::FromStr>(&mut self, what: &str) -> Result<Vec<T>> {
        let line = self.next_line()?;
        line.split_whitespace()
            .map(|w| w.parse::<T>().map_err(|_| self.err(format!("cannot read {what} from {w:?}"))))
            .collect()
    }
    fn expect(&mut self, tag: &str) -> Result<()> {
        let l = self.next_line()?;
        if l.trim() != tag {
            return Err(self.err(format!("expected {tag}, found {:?}", l.trim())));
        }
        Ok(())
    }
}

#[derive(Default)]
struct Raw {
    version: String,
    names: HashMap<(i64, i64), String>,         // (dim, physical tag) -> name
    entity_phys: HashMap<(i64, i64), Vec<i64>>, // (dim, entity tag) -> physical tags (4.1)
    nodes: HashMap<i64, [f64; 3]>,
    node_order: Vec<i64>,
    triangles: Vec<(i64, Vec<i64>, [i64; 3])>, // element tag, physical tags, node tags
    lines: Vec<(i64, Vec<i64>, [i64; 2])>,     // element tag, physical tags, node tags
    tets: Vec<(i64, [i64; 4])>,                // element tag, node tags
}

/// Parse the text of a 2-D `.msh` file; `file` names it in messages.
pub fn parse(text: &str, file: &str) -> Result<PlaneMesh> {
    match parse_any(text, file)? {
        Geometry::Plane(m) => Ok(m),
        Geometry::Solid(_) => {
            Err(Error::mesh(file, "holds tetrahedra (a 3-D mesh) where a 2-D mesh of triangles is expected"))
        }
    }
}

/// Parse the text of a `.msh` file of either dimension; `file` names it in messages.
pub fn parse_any(text: &str, file: &str) -> Result<Geometry> {
    let lines: Vec<(usize, &str)> =
        text.lines().enumerate().map(|(i, l)| (i + 1, l)).filter(|(_, l)| !l.trim().is_empty()).collect();
    let mut c = Cursor { lines, pos: 0, file, section: String::new() };
    let mut raw = Raw::default();
    while c.pos < c.lines.len() {
        let head = c.next_line()?.trim().to_string();
        c.section = head.strip_prefix('$').unwrap_or("").to_string();
        match head.as_str() {
            "$MeshFormat" => {
                let f = c.next_line()?;
                let mut it = f.split_whitespace();
                raw.version = it.next().unwrap_or("").to_string();
                match it.next() {
                    Some("0") => {}
                    Some("1") => {
                        return Err(c.err(
                            "binary .msh files are not supported; save as ASCII (Gmsh: File > Export, uncheck binary)",
                        ));
                    }
                    _ => {
                        return Err(c.err(format!(
                            "the $MeshFormat line should read \"4.1 0 8\" or \"2.2 0 8\" (version, 0 = ASCII, 8), found {:?}",
                            f.trim()
                        )));
                    }
                }
                if !(raw.version.starts_with("2.") || raw.version.starts_with("4.1")) {
                    return Err(
                        c.err(format!("format version {} is not supported; save as 4.1 or 2.2 ASCII", raw.version))
                    );
                }
                c.expect("$EndMeshFormat")?;
            }
            "$PhysicalNames" => {
                let n: Vec<i64> = c.nums("the number of physical names")?;
                for _ in 0..n.first().copied().unwrap_or(0) {
                    let l = c.next_line()?;
                    // dim tag "name": the name may contain spaces, the separators may be runs
                    let bad =
                        || c.err(format!("a physical name line should read: dim tag \"name\", found {:?}", l.trim()));
                    let (dim, rest) = l.trim().split_once(char::is_whitespace).ok_or_else(bad)?;
                    let (tag, name) = rest.trim_start().split_once(char::is_whitespace).ok_or_else(bad)?;
                    let dim: i64 = dim.parse().map_err(|_| bad())?;
                    let tag: i64 = tag.parse().map_err(|_| bad())?;
                    let name = name.trim().trim_matches('"').to_string();
                    raw.names.insert((dim, tag), name);
                }
                c.expect("$EndPhysicalNames")?;
            }
            "$Entities" => read_entities(&mut c, &mut raw)?,
            "$Nodes" => {
                if raw.version.starts_with('4') {
                    read_nodes_41(&mut c, &mut raw)?
                } else {
                    read_nodes_22(&mut c, &mut raw)?
                }
            }
            "$Elements" => {
                if raw.version.starts_with('4') {
                    read_elements_41(&mut c, &mut raw)?
                } else {
                    read_elements_22(&mut c, &mut raw)?
                }
            }
            s if s.starts_with('$') => {
                // skip unknown sections ($Periodic, $NodeData, ...)
                let end = format!("$End{}", &s[1..]);
                loop {
                    if c.next_line()?.trim() == end {
                        break;
                    }
                }
            }
            other => return Err(c.err(format!("unexpected line {other:?} outside a section"))),
        }
        c.section.clear();
    }
    if raw.version.is_empty() {
        return Err(Error::mesh(file, "no $MeshFormat section: is this a Gmsh .msh file?"));
    }
    if raw.tets.is_empty() {
        build(raw, file).map(Geometry::Plane)
    } else {
        build_solid(raw, file).map(Geometry::Solid)
    }
}

fn read_entities(c: &mut Cursor, raw: &mut Raw) -> Result<()> {
    let counts: Vec<usize> = c.nums("entity counts")?;
    if counts.len() < 4 {
        return Err(c.err("the $Entities header needs 4 counts"));
    }
    for (dim, &n) in counts.iter().enumerate().take(4) {
        for _ in 0..n {
            let w: Vec<f64> = c.nums("an entity")?;
            let tag = *w.first().ok_or_else(|| c.err("empty entity line"))? as i64;
            // points: tag x y z nphys phys...; others: tag minx miny minz maxx maxy maxz nphys phys...
            let at = if dim == 0 { 4 } else { 7 };
            let short = || c.err(format!("the line of entity {tag} (dim {dim}) is too short for its physical tags"));
            let np = *w.get(at).ok_or_else(short)?;
            if !(np >= 0.0 && np.fract() == 0.0 && np <= w.len() as f64) {
                let np = if np.abs() < 1e15 { format!("{np}") } else { format!("{np:e}") };
                return Err(
                    c.err(format!("entity {tag} (dim {dim}) lists {np} physical tags, which this line cannot hold"))
                );
            }
            let np = np as usize;
            let phys: Vec<i64> = w.get(at + 1..at + 1 + np).ok_or_else(short)?.iter().map(|v| *v as i64).collect();
            raw.entity_phys.insert((dim as i64, tag), phys);
        }
    }
    c.expect("$EndEntities")
}

fn read_nodes_22(c: &mut Cursor, raw: &mut Raw) -> Result<()> {
    let n: Vec<usize> = c.nums("the node count")?;
    for _ in 0..n.first().copied().unwrap_or(0) {
        let w: Vec<f64> = c.nums("a node")?;
        if w.len() < 3 {
            return Err(c.err("a node line needs: tag x y [z]"));
        }
        insert_node(c, raw, w[0] as i64, [w[1], w[2], w.get(3).copied().unwrap_or(0.0)])?;
    }
    c.expect("$EndNodes")
}

fn insert_node(c: &Cursor, raw: &mut Raw, tag: i64, x: [f64; 3]) -> Result<()> {
    if !x.iter().all(|v| v.is_finite()) {
        return Err(c.err(format!("node {tag} has non-finite coordinates")));
    }
    if raw.nodes.insert(tag, x).is_some() {
        return Err(c.err(format!("node tag {tag} appears twice")));
    }
    raw.node_order.push(tag);
    Ok(())
}

/// The count of a 4.1 block header, checked against what the section header announced.
fn block_count(c: &Cursor, what: &str, b: &[i64], left: &mut usize) -> Result<usize> {
    let count = usize::try_from(b[3]).map_err(|_| {
        c.err(format!("{what} block (dim {}, entity {}) has count {}; it must be >= 0", b[0], b[1], b[3]))
    })?;
    if count > *left {
        return Err(c.err(format!(
            "{what} block (dim {}, entity {}) holds {count} {what}s, more than the section header announces; the file is corrupt",
            b[0], b[1]
        )));
    }
    *left -= count;
    Ok(count)
}

fn read_nodes_41(c: &mut Cursor, raw: &mut Raw) -> Result<()> {
    let h: Vec<usize> = c.nums("the $Nodes header")?;
    if h.len() < 2 {
        return Err(c.err("the $Nodes header needs: numBlocks numNodes minTag maxTag"));
    }
    let (blocks, mut left) = (h[0], h[1]);
    for _ in 0..blocks {
        let b: Vec<i64> = c.nums("a node block header")?;
        if b.len() < 4 {
            return Err(c.err("a node block header needs: dim tag parametric count"));
        }
        let count = block_count(c, "node", &b, &mut left)?;
        let mut tags = Vec::new();
        for _ in 0..count {
            let t: Vec<i64> = c.nums("a node tag")?;
            tags.push(*t.first().ok_or_else(|| c.err("missing node tag"))?);
        }
        for tag in tags {
            // x y z, then u [v] for parametric nodes
            let w: Vec<f64> = c.nums("node coordinates")?;
            if w.len() < 3 {
                return Err(c.err(format!("node {tag}: coordinates need x y z")));
            }
            insert_node(c, raw, tag, [w[0], w[1], w[2]])?;
        }
    }
    c.expect("$EndNodes")
}

fn push_element(c: &Cursor, raw: &mut Raw, tag: i64, etype: i64, phys: Vec<i64>, nodes: &[i64]) -> Result<()> {
    // physical tag 0 (2.2 with Mesh.SaveAll) means "in no physical group"
    let phys: Vec<i64> = phys.into_iter().filter(|&p| p != 0).collect();
    let need = match etype {
        1 => 2,
        2 => 3,
        4 => 4,
        15 => 1,
        3 => return Err(c.err(format!("element {tag} is a quadrangle; dyncontact needs triangles (P1): mesh with triangles only"))),
        8..=11 => return Err(c.err(format!("element {tag} is second order (type {etype}); dyncontact uses P1: set Mesh.ElementOrder = 1"))),
        5..=7 => {
            return Err(c.err(format!(
                "element {tag} is a 3-D element of type {etype} (hexahedron, prism or pyramid); dyncontact needs tetrahedra (type 4): mesh the volume with tetrahedra only"
            )))
        }
        _ => return Err(c.err(format!("element {tag} has type {etype}, which is not supported (lines 1, triangles 2, tetrahedra 4, points 15)"))),
    };
    if nodes.len() < need {
        return Err(c.err(format!("element {tag} lists {} nodes, type {etype} needs {need}", nodes.len())));
    }
    match etype {
        1 => raw.lines.push((tag, phys, [nodes[0], nodes[1]])),
        2 => raw.triangles.push((tag, phys, [nodes[0], nodes[1], nodes[2]])),
        4 => raw.tets.push((tag, [nodes[0], nodes[1], nodes[2], nodes[3]])),
        _ => {}
    }
    Ok(())
}

fn read_elements_22(c: &mut Cursor, raw: &mut Raw) -> Result<()> {
    let n: Vec<usize> = c.nums("the element count")?;
    for _ in 0..n.first().copied().unwrap_or(0) {
        let w: Vec<i64> = c.nums("an element")?;
        if w.len() < 3 {
            return Err(c.err("an element line needs: tag type ntags tags... nodes..."));
        }
        let (tag, etype) = (w[0], w[1]);
        let ntags = usize::try_from(w[2])
            .map_err(|_| c.err(format!("element {tag} has {} tags; the count must be >= 0", w[2])))?;
        let phys = w.get(3).copied().filter(|_| ntags > 0).map(|p| vec![p]).unwrap_or_default();
        let nodes = ntags.checked_add(3).and_then(|k| w.get(k..)).unwrap_or(&[]);
        push_element(c, raw, tag, etype, phys, nodes)?;
    }
    c.expect("$EndElements")
}

fn read_elements_41(c: &mut Cursor, raw: &mut Raw) -> Result<()> {
    let h: Vec<usize> = c.nums("the $Elements header")?;
    if h.len() < 2 {
        return Err(c.err("the $Elements header needs: numBlocks numElements minTag maxTag"));
    }
    let (blocks, mut left) = (h[0], h[1]);
    for _ in 0..blocks {
        let b: Vec<i64> = c.nums("an element block header")?;
        if b.len() < 4 {
            return Err(c.err("an element block header needs: dim tag type count"));
        }
        let count = block_count(c, "element", &b, &mut left)?;
        let (dim, etag, etype) = (b[0], b[1], b[2]);
        let phys = raw.entity_phys.get(&(dim, etag)).cloned().unwrap_or_default();
        for _ in 0..count {
            let w: Vec<i64> = c.nums("an element")?;
            let tag = *w.first().ok_or_else(|| c.err("empty element line"))?;
            push_element(c, raw, tag, etype, phys.clone(), &w[1..])?;
        }
    }
    c.expect("$EndElements")
}

/// The file's nodes numbered in file order, for the elements to refer to.
struct Numbering<'a> {
    index: HashMap<i64, usize>,
    file: &'a str,
}

impl<'a> Numbering<'a> {
    fn new(raw: &Raw, file: &'a str) -> Numbering<'a> {
        Numbering { index: raw.node_order.iter().enumerate().map(|(i, &tag)| (tag, i)).collect(), file }
    }

    /// The indices of an element's node tags; an error names the element (`what`) and the
    /// first tag that is not in $Nodes.
    fn nodes<const N: usize>(&self, tags: [i64; N], what: &str) -> Result<[usize; N]> {
        let mut out = [0; N];
        for (v, t) in out.iter_mut().zip(tags) {
            *v =
                self.index.get(&t).copied().ok_or_else(|| {
                    Error::mesh(self.file, format!("{what} refers to node {t}, which is not in $Nodes"))
                })?;
        }
        Ok(out)
    }
}

/// Add facet `f` to the side `name`, which is created at its first facet.
fn add_facet<C: Cell>(sides: &mut Vec<Side<C>>, name: String, f: C::Facet) {
    match sides.iter_mut().find(|s| s.name == name) {
        Some(s) => s.facets.push(f),
        None => sides.push(Side { name, facets: vec![f] }),
    }
}

fn build(raw: Raw, file: &str) -> Result<PlaneMesh> {
    if raw.triangles.is_empty() {
        return Err(Error::mesh(file, "contains no triangles (element type 2); mesh the surface with triangles"));
    }
    // the solver reads x and y: a surface mesh must lie in one plane z = const
    if let Some(&first) = raw.node_order.first() {
        let z0 = raw.nodes[&first][2];
        let extent = raw.node_order.iter().fold(0.0f64, |m, t| m.max(raw.nodes[t][0].abs()).max(raw.nodes[t][1].abs()));
        if let Some(tag) = raw.node_order.iter().find(|t| (raw.nodes[*t][2] - z0).abs() > 1e-12 * extent.max(z0.abs()))
        {
            return Err(Error::mesh(
                file,
                format!(
                    "node {tag} has z = {} while node {first} has z = {z0}: a mesh of triangles is read in its plane \
                     z = const (x, y only); mesh the surface flat in the xy-plane",
                    raw.nodes[tag][2]
                ),
            ));
        }
    }
    // number nodes in file order; check that elements refer to known nodes
    let numbering = Numbering::new(&raw, file);
    let nodes = raw.node_order.iter().map(|tag| [raw.nodes[tag][0], raw.nodes[tag][1]]).collect();
    let mut cells = Vec::with_capacity(raw.triangles.len());
    let mut tags = Vec::with_capacity(raw.triangles.len());
    for (tag, _, t) in &raw.triangles {
        cells.push(numbering.nodes(*t, &format!("triangle {tag}"))?);
        tags.push(*tag);
    }
    // sides: one per physical curve (dim 1), named by $PhysicalNames or by the tag
    let mut sides: Vec<Side<_>> = Vec::new();
    // (element tag, side name, node tags, node indices) of every side edge, for the check below
    let mut side_lines: Vec<(i64, String, [i64; 2], [usize; 2])> = Vec::new();
    for (tag, phys, [ta, tb]) in &raw.lines {
        let edge = numbering.nodes([*ta, *tb], &format!("line element {tag}"))?;
        for p in phys {
            let name = raw.names.get(&(1, *p)).cloned().unwrap_or_else(|| p.to_string());
            side_lines.push((*tag, name.clone(), [*ta, *tb], edge));
            add_facet(&mut sides, name, edge);
        }
    }
    let mut mesh = Mesh {
        nodes,
        cells,
        sides,
        source: file.to_string(),
        tags: Some(super::Tags { nodes: raw.node_order.clone(), cells: tags.clone() }),
    };
    orient(&mut mesh, &tags, file)?;
    check_duplicates(&mesh, &raw.node_order, file)?;
    check_unreferenced(&mesh, &raw.node_order, file)?;
    check_side_edges(&mesh, &side_lines, file)?;
    mesh.check()?;
    Ok(mesh)
}

/// The 3-D mesh of a file with tetrahedra: nodes in file order, each tetrahedron oriented
/// positively (Gmsh's orientation is kept when positive, two vertices swapped otherwise), one
/// side per physical surface (dim 2; named by $PhysicalNames or by the tag) made of its
/// triangles. The structural checks are `Mesh::check`'s (degenerate tetrahedra, unused
/// nodes, side faces on the boundary).
fn build_solid(raw: Raw, file: &str) -> Result<SolidMesh> {
    let numbering = Numbering::new(&raw, file);
    let nodes = raw.node_order.iter().map(|tag| raw.nodes[tag]).collect();
    let mut cells = Vec::with_capacity(raw.tets.len());
    for (tag, t) in &raw.tets {
        cells.push(numbering.nodes(*t, &format!("tetrahedron {tag}"))?);
    }
    let mut sides: Vec<Side<_>> = Vec::new();
    for (tag, phys, t) in &raw.triangles {
        let face = numbering.nodes(*t, &format!("triangle {tag}"))?;
        for p in phys {
            let name = raw.names.get(&(2, *p)).cloned().unwrap_or_else(|| p.to_string());
            add_facet(&mut sides, name, face);
        }
    }
    let tags: Vec<i64> = raw.tets.iter().map(|(tag, _)| *tag).collect();
    let mut mesh = Mesh {
        nodes,
        cells,
        sides,
        source: file.to_string(),
        tags: Some(super::Tags { nodes: raw.node_order.clone(), cells: tags.clone() }),
    };
    orient_solid(&mut mesh, &tags, file)?;
    mesh.check()?;
    Ok(mesh)
}

/// Orientation in 3-D, as in 2-D ([`orient`]): every tetrahedron of one sign is a consistent
/// mesh (all negative ones get two vertices swapped); a mix means that the mesh folds over
/// itself (a node moved through a face) and is refused, naming a tetrahedron of the minority by
/// its tag in the file. Degenerate ones are left to `Mesh::check`.
fn orient_solid(mesh: &mut SolidMesh, tags: &[i64], file: &str) -> Result<()> {
    let signs: Vec<f64> = (0..mesh.cells.len()).map(|t| mesh.signed_measure(t)).collect();
    let negative = signs.iter().filter(|v| **v < 0.0).count();
    let positive = signs.iter().filter(|v| **v > 0.0).count();
    if negative > 0 && positive > 0 {
        let t = if negative <= positive {
            signs.iter().position(|v| *v < 0.0)
        } else {
            signs.iter().position(|v| *v > 0.0)
        }
        .unwrap_or(0);
        return Err(Error::mesh(
            file,
            format!(
                "tetrahedron {} is inverted: {} of {} tetrahedra have the other orientation; the mesh folds over itself \
                 (a node moved through a face) or has inconsistent orientation — regenerate it",
                tags[t],
                negative.min(positive),
                signs.len()
            ),
        ));
    }
    if negative > 0 {
        for t in mesh.cells.iter_mut() {
            t.swap(2, 3);
        }
    }
    Ok(())
}

/// Orientation: all clockwise (surface normal −z) is flipped; a mix means a folded mesh.
/// `tags` are the file's triangle tags, for messages.
fn orient(mesh: &mut PlaneMesh, tags: &[i64], file: &str) -> Result<()> {
    let signs: Vec<f64> = (0..mesh.cells.len()).map(|t| mesh.signed_measure(t)).collect();
    let scale = 1e-14 * mesh.bbox_diameter().powi(2);
    if let Some(t) = signs.iter().position(|a| !a.is_finite()) {
        return Err(Error::mesh(
            file,
            format!("the area of triangle {} overflows: the coordinates are too large; give them in metres", tags[t]),
        ));
    }
    if let Some(t) = signs.iter().position(|a| a.abs() <= scale) {
        return Err(Error::mesh(file, format!("triangle {} has zero area (degenerate); remove or fix it", tags[t])));
    }
    let negative = signs.iter().filter(|a| **a < 0.0).count();
    if negative == signs.len() {
        for t in mesh.cells.iter_mut() {
            t.swap(1, 2);
        }
    } else if negative > 0 {
        // name a triangle of the minority orientation: that is the one that is inverted
        let t = if 2 * negative <= signs.len() {
            signs.iter().position(|a| *a < 0.0)
        } else {
            signs.iter().position(|a| *a > 0.0)
        }
        .unwrap_or(0);
        return Err(Error::mesh(
            file,
            format!(
                "triangle {} is inverted: {negative} of {} triangles are clockwise and the rest counterclockwise; \
                 the mesh folds over itself or has inconsistent orientation — regenerate it",
                tags[t],
                signs.len()
            ),
        ));
    }
    Ok(())
}

/// Duplicate nodes: coordinates equal within tol under different tags. A grid of cells of
/// size tol finds every pair within tol in both coordinates among the 9 cells around a node.
fn check_duplicates(mesh: &PlaneMesh, node_tags: &[i64], file: &str) -> Result<()> {
    let tol = 1e-12 * mesh.bbox_diameter();
    let lo = mesh.nodes.iter().fold([f64::INFINITY; 2], |m, p| [m[0].min(p[0]), m[1].min(p[1])]);
    let cell = |p: [f64; 2]| (((p[0] - lo[0]) / tol).floor() as i64, ((p[1] - lo[1]) / tol).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, &p) in mesh.nodes.iter().enumerate() {
        let (cx, cy) = cell(p);
        for (dx, dy) in [-1i64, 0, 1].into_iter().flat_map(|dx| [-1i64, 0, 1].map(|dy| (dx, dy))) {
            let near = grid.get(&(cx.saturating_add(dx), cy.saturating_add(dy))).map(|v| v.as_slice()).unwrap_or(&[]);
            if let Some(&j) =
                near.iter().find(|&&j| (mesh.nodes[j][0] - p[0]).abs() <= tol && (mesh.nodes[j][1] - p[1]).abs() <= tol)
            {
                return Err(Error::mesh(
                    file,
                    format!(
                        "nodes {} and {} are duplicates (both at ({}, {})); merge them (Gmsh: `Coherence Mesh;` in the .geo file, or Geometry > Coherence)",
                        node_tags[j], node_tags[i], p[0], p[1]
                    ),
                ));
            }
        }
        grid.entry((cx, cy)).or_default().push(i);
    }
    Ok(())
}

/// Every node is a vertex of some triangle.
fn check_unreferenced(mesh: &PlaneMesh, node_tags: &[i64], file: &str) -> Result<()> {
    let mut used = vec![false; mesh.nodes.len()];
    mesh.cells.iter().flatten().for_each(|&v| used[v] = true);
    if let Some(v) = used.iter().position(|u| !u) {
        return Err(Error::mesh(
            file,
            format!(
                "node {} is not a vertex of any triangle; remove unreferenced nodes (Gmsh: save only physical groups, or Mesh.SaveAll = 0)",
                node_tags[v]
            ),
        ));
    }
    Ok(())
}

/// Side edges must be boundary edges (one owning triangle); say so in Gmsh's terms.
/// `side_lines` are (element tag, side name, node tags, node indices) of every side edge.
fn check_side_edges(mesh: &PlaneMesh, side_lines: &[(i64, String, [i64; 2], [usize; 2])], file: &str) -> Result<()> {
    let owners = mesh.facet_owners();
    for (tag, name, [ta, tb], edge) in side_lines {
        match owners.get(&key(*edge)).map_or(0, Vec::len) {
            1 => {}
            0 => {
                return Err(Error::mesh(
                    file,
                    format!(
                        "side {name:?}: line element {tag} (nodes {ta} {tb}) is not an edge of any triangle; \
                         the curve mesh and the surface mesh do not conform — mesh the curve as part of the surface boundary"
                    ),
                ));
            }
            n => {
                return Err(Error::mesh(
                    file,
                    format!(
                        "side {name:?}: line element {tag} (nodes {ta} {tb}) is an interior edge (shared by {n} triangles); \
                         a side must lie on the boundary: put only boundary curves in the physical group"
                    ),
                ));
            }
        }
    }
    Ok(())
}
