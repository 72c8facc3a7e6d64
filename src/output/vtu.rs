//! VTU frames and the PVD series (ParaView, meshio). Arrays are inline binary (VTK's
//! `format="binary"`: base64 of a UInt64 byte count followed by the little-endian values,
//! encoded together as meshio writes them), so readers get the exact f64 values back and a
//! frame of a 66k-unknown mesh costs milliseconds instead of the ~80 ms of decimal printing.
//! Hand-written: see the README's design notes (vtkio's only release pulls nom 3 and costs a
//! minute of compile).

use std::fmt::Write as _;

use base64::Engine as _;

use crate::fem::{element, tet};
use crate::mesh::Geometry;
use crate::model::material::Material;

/// Point and cell fields of one frame.
pub struct Snapshot<'a> {
    pub mesh: &'a Geometry,
    pub material: &'a Material,
    /// nodal displacement and velocity (z = 0 in 2-D)
    pub u: &'a [[f64; 3]],
    pub v: &'a [[f64; 3]],
    /// contact data per mesh node ([`NodeContact::OFF`] off Γ3)
    pub contact: &'a [NodeContact],
    /// (Ps.1) ε_zz per triangle where it is an internal variable (the state's `eps_zz`), else empty
    pub eps_zz: &'a [f64],
}

/// The contact fields of one mesh node in a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeContact {
    /// contact pressure q + λ
    pub pressure: f64,
    /// compliance pressure q
    pub q: f64,
    /// constraint multiplier λ
    pub lambda: f64,
    /// the friction traction −t on the body in global components (along τ in 2-D, z = 0)
    pub friction: [f64; 3],
    /// `NodeStatus::code` (0 separated, 1 stick, 2 slip, 3 contact without friction), −1 off Γ3
    pub status: i32,
}

impl NodeContact {
    /// A node off the contact boundary Γ3: zero fields, status −1.
    pub const OFF: NodeContact = NodeContact { pressure: 0.0, q: 0.0, lambda: 0.0, friction: [0.0; 3], status: -1 };

    /// The fields of a Γ3 node from its step record.
    pub fn of(nr: &crate::simulation::NodeRecord) -> NodeContact {
        NodeContact {
            pressure: nr.p + nr.lambda,
            q: nr.p,
            lambda: nr.lambda,
            friction: nr.friction_vec,
            status: nr.status.code(),
        }
    }
}

/// Names of the components of a 3-vector (`ComponentName0..2`).
const VECTOR: &[&str] = &["x", "y", "z"];
/// Names of the components of a symmetric tensor in VTK's order (`ComponentName0..5`).
const SYMMETRIC_TENSOR: &[&str] = &["XX", "YY", "ZZ", "XY", "YZ", "XZ"];

/// One inline binary DataArray of `vtk_type` with the little-endian bytes `data`; `names`
/// (empty, or one per component) become its `ComponentName0..` attributes.
fn array(out: &mut String, vtk_type: &str, name: &str, comps: usize, names: &[&str], data: &[u8]) {
    let _ = write!(out, "<DataArray type=\"{vtk_type}\" Name=\"{name}\" NumberOfComponents=\"{comps}\"");
    debug_assert!(names.is_empty() || names.len() == comps);
    for (k, c) in names.iter().enumerate() {
        let _ = write!(out, " ComponentName{k}=\"{c}\"");
    }
    out.push_str(" format=\"binary\">\n");
    let mut bytes = Vec::with_capacity(8 + data.len());
    bytes.extend_from_slice(&(data.len() as u64).to_le_bytes());
    bytes.extend_from_slice(data);
    base64::engine::general_purpose::STANDARD.encode_string(&bytes, out);
    out.push_str("\n</DataArray>\n");
}

fn floats(out: &mut String, name: &str, comps: usize, names: &[&str], vals: impl Iterator<Item = f64>) {
    // non-finite values never reach a frame (the time loop stops first); write 0 defensively
    let data: Vec<u8> = vals.flat_map(|x| if x.is_finite() { x } else { 0.0 }.to_le_bytes()).collect();
    array(out, "Float64", name, comps, names, &data);
}

fn ints(out: &mut String, name: &str, vals: impl Iterator<Item = i64>) {
    let data: Vec<u8> = vals.flat_map(i64::to_le_bytes).collect();
    array(out, "Int64", name, 1, &[], &data);
}

/// The VTU document of a frame: triangles (VTK type 5) in 2-D, tetrahedra (VTK type 10) in 3-D;
/// vectors with 3 components (z = 0 in 2-D) named x, y, z; the (P.1) stress per cell as VTK's
/// symmetric tensor (σ_xx, σ_yy, σ_zz, σ_xy, σ_yz, σ_xz) named XX, YY, ZZ, XY, YZ, XZ (in 2-D
/// σ_yz = σ_xz = 0 and σ_zz the out-of-plane stress: 0 in plane stress).
pub fn vtu(frame: &Snapshot) -> String {
    let mesh = frame.mesh;
    let (np, nc) = (mesh.n_nodes(), mesh.n_cells());
    let mut s = String::with_capacity(120 * np + 60 * nc);
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n");
    let _ = writeln!(s, "<Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nc}\">");
    s.push_str("<PointData Vectors=\"displacement\">\n");
    floats(&mut s, "displacement", 3, VECTOR, frame.u.iter().flatten().copied());
    floats(&mut s, "velocity", 3, VECTOR, frame.v.iter().flatten().copied());
    floats(&mut s, "contact_pressure", 1, &[], frame.contact.iter().map(|c| c.pressure));
    floats(&mut s, "compliance_pressure", 1, &[], frame.contact.iter().map(|c| c.q));
    floats(&mut s, "lambda", 1, &[], frame.contact.iter().map(|c| c.lambda));
    floats(&mut s, "friction", 3, VECTOR, frame.contact.iter().flat_map(|c| c.friction));
    let status: Vec<u8> = frame.contact.iter().flat_map(|c| c.status.to_le_bytes()).collect();
    array(&mut s, "Int32", "contact_status", 1, &[], &status);
    s.push_str("</PointData>\n<CellData>\n");
    let stress = stress(frame);
    let (connectivity, nv, vtk_type) = match mesh {
        Geometry::Plane(m) => (m.cells.iter().flatten().map(|&i| i as i64).collect::<Vec<_>>(), 3, 5u8),
        Geometry::Solid(m) => (m.cells.iter().flatten().map(|&i| i as i64).collect::<Vec<_>>(), 4, 10u8),
    };
    floats(&mut s, "stress", 6, SYMMETRIC_TENSOR, stress.into_iter());
    s.push_str("</CellData>\n<Points>\n");
    floats(&mut s, "Points", 3, &[], (0..np).flat_map(|i| mesh.point(i)));
    s.push_str("</Points>\n<Cells>\n");
    ints(&mut s, "connectivity", connectivity.into_iter());
    ints(&mut s, "offsets", (1..=nc).map(|k| (nv * k) as i64));
    array(&mut s, "UInt8", "types", 1, &[], &vec![vtk_type; nc]);
    s.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    s
}

/// (P.1) The stress of every cell of a frame, 6 values per cell in VTK's order (σ_xx, σ_yy,
/// σ_zz, σ_xy, σ_yz, σ_xz): the frames' `stress` cell field (in 2-D σ_yz = σ_xz = 0 and σ_zz
/// the out-of-plane stress, 0 in plane stress). The Python package's `fields(i)` reads it too.
pub fn stress(frame: &Snapshot) -> Vec<f64> {
    let mesh = frame.mesh;
    let nc = mesh.n_cells();
    match mesh {
        Geometry::Plane(m) => {
            // (P.1) stress per triangle: material.stress gives (σ_xx, σ_yy, σ_xy, σ_zz)
            let mut stress = Vec::with_capacity(6 * nc);
            for (t, tri) in m.cells.iter().enumerate() {
                let x = [m.nodes[tri[0]], m.nodes[tri[1]], m.nodes[tri[2]]];
                let (grad, _) = element::gradients(x);
                let strain = |f: &[[f64; 3]]| {
                    let mut e = [0.0; 3];
                    for (k, g) in grad.iter().enumerate() {
                        let w = f[tri[k]];
                        e[0] += g[0] * w[0];
                        e[1] += g[1] * w[1];
                        e[2] += g[1] * w[0] + g[0] * w[1];
                    }
                    e
                };
                let eps_zz = frame.eps_zz.get(t).copied().unwrap_or(0.0);
                let [sxx, syy, sxy, szz] = frame.material.stress(strain(frame.u), strain(frame.v), eps_zz);
                stress.extend([sxx, syy, szz, sxy, 0.0, 0.0]);
            }
            stress
        }
        Geometry::Solid(m) => {
            // (P.1) stress per tetrahedron: the Voigt order (σ_xx, σ_yy, σ_zz, σ_yz, σ_xz, σ_xy)
            // of tet::strain_matrix, written in VTK's order XX, YY, ZZ, XY, YZ, XZ
            let (b, a) = (frame.material.elasticity_3d(), frame.material.viscosity_3d());
            let mut stress = Vec::with_capacity(6 * nc);
            for t in &m.cells {
                let Some((grad, _)) = tet::gradients(t.map(|v| m.nodes[v])) else {
                    stress.extend([0.0; 6]);
                    continue;
                };
                let sm = tet::strain_matrix(&grad);
                let nodal = |f: &[[f64; 3]]| nalgebra::SVector::<f64, 12>::from_iterator(t.iter().flat_map(|&v| f[v]));
                let sigma = b * (sm * nodal(frame.u)) + a * (sm * nodal(frame.v));
                stress.extend([sigma[0], sigma[1], sigma[2], sigma[5], sigma[3], sigma[4]]);
            }
            stress
        }
    }
}

/// The PVD collection listing (time, file) pairs.
pub fn pvd(frames: &[(f64, String)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for (t, f) in frames {
        let _ = writeln!(s, "<DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{f}\"/>");
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    s
}
