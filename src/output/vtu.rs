//! VTU frames and the PVD series (ParaView, meshio). ASCII, f64 printed with the shortest
//! round-trip representation, so readers get the exact numbers back. Hand-written: see the
//! README's design notes (vtkio's only release pulls nom 3 and costs a minute of compile).

use std::fmt::Write as _;

use crate::fem::element;
use crate::mesh::Mesh;
use crate::model::material::Material;

/// Point and cell fields of one frame.
pub struct Frame<'a> {
    pub mesh: &'a Mesh,
    pub material: &'a Material,
    /// nodal displacement and velocity
    pub u: &'a [[f64; 2]],
    pub v: &'a [[f64; 2]],
    /// contact data per mesh node: (pressure q + λ, q, λ, friction −t, status code), status −1
    /// off Γ3
    pub contact: &'a [(f64, f64, f64, f64, i32)],
}

fn floats(out: &mut String, name: &str, comps: usize, vals: impl Iterator<Item = f64>) {
    let _ = write!(out, "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"ascii\">\n");
    for (k, x) in vals.enumerate() {
        // non-finite values never reach a frame (the time loop stops first); write 0 defensively
        let x = if x.is_finite() { x } else { 0.0 };
        let _ = write!(out, "{x:e}{}", if (k + 1) % comps == 0 { "\n" } else { " " });
    }
    out.push_str("</DataArray>\n");
}

/// The VTU document of a frame.
pub fn vtu(frame: &Frame) -> String {
    let mesh = frame.mesh;
    let (np, nc) = (mesh.nodes.len(), mesh.triangles.len());
    let mut s = String::with_capacity(200 * np);
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n");
    let _ = writeln!(s, "<Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nc}\">");
    s.push_str("<PointData Vectors=\"displacement\">\n");
    floats(&mut s, "displacement", 3, frame.u.iter().flat_map(|p| [p[0], p[1], 0.0]));
    floats(&mut s, "velocity", 3, frame.v.iter().flat_map(|p| [p[0], p[1], 0.0]));
    floats(&mut s, "contact_pressure", 1, frame.contact.iter().map(|c| c.0));
    floats(&mut s, "compliance_pressure", 1, frame.contact.iter().map(|c| c.1));
    floats(&mut s, "lambda", 1, frame.contact.iter().map(|c| c.2));
    floats(&mut s, "friction", 1, frame.contact.iter().map(|c| c.3));
    s.push_str("<DataArray type=\"Int32\" Name=\"contact_status\" format=\"ascii\">\n");
    for c in frame.contact {
        let _ = write!(s, "{} ", c.4);
    }
    s.push_str("\n</DataArray>\n</PointData>\n<CellData>\n");
    // stress (σ_xx, σ_yy, σ_xy, σ_zz) per triangle, from (P.1)
    let mut stress = Vec::with_capacity(4 * nc);
    for tri in &mesh.triangles {
        let x = [mesh.nodes[tri[0]], mesh.nodes[tri[1]], mesh.nodes[tri[2]]];
        let (grad, _) = element::gradients(x);
        let strain = |f: &[[f64; 2]]| {
            let mut e = [0.0; 3];
            for (k, g) in grad.iter().enumerate() {
                let w = f[tri[k]];
                e[0] += g[0] * w[0];
                e[1] += g[1] * w[1];
                e[2] += g[1] * w[0] + g[0] * w[1];
            }
            e
        };
        stress.extend(frame.material.stress(strain(frame.u), strain(frame.v)));
    }
    floats(&mut s, "stress", 4, stress.into_iter());
    s.push_str("</CellData>\n<Points>\n");
    floats(&mut s, "Points", 3, mesh.nodes.iter().flat_map(|p| [p[0], p[1], 0.0]));
    s.push_str("</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for t in &mesh.triangles {
        let _ = writeln!(s, "{} {} {}", t[0], t[1], t[2]);
    }
    s.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for k in 0..nc {
        let _ = write!(s, "{} ", 3 * (k + 1));
    }
    s.push_str("\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in 0..nc {
        s.push_str("5 ");
    }
    s.push_str("\n</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    s
}

/// The PVD collection listing (time, file) pairs.
pub fn pvd(frames: &[(f64, String)]) -> String {
    let mut s = String::from("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n");
    for (t, f) in frames {
        let _ = writeln!(s, "<DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{f}\"/>");
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    s
}
