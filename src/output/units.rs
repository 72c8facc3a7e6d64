//! The units of the outputs, which follow the space dimension d: a 2-D run is a slice of unit
//! thickness out of the plane, so its forces are per unit thickness (N/m) and its energies too
//! (J/m); a 3-D run's forces are N and its energies J. Stresses and tractions (Pa), lengths (m),
//! velocities (m/s) and times (s) are the same in both. Charts, summary.json (`model.units`) and
//! the README take their units from here.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// The unit of energies (every (E.1) term, works, dissipations) in dimension `dim`.
pub fn energy(dim: usize) -> &'static str {
    if dim == 3 { "J" } else { "J/m" }
}

/// The unit of forces (sums of tractions over Γ3) in dimension `dim`.
pub fn force(dim: usize) -> &'static str {
    if dim == 3 { "N" } else { "N/m" }
}

/// The force axis of a chart: "force [N]" in 3-D, "force per unit thickness [N/m]" in 2-D.
pub fn force_axis(dim: usize) -> String {
    if dim == 3 { format!("force [{}]", force(dim)) } else { format!("force per unit thickness [{}]", force(dim)) }
}

/// The unit of a figure of sweep.csv (`FIGURES`) or of refine.csv's impulses
/// (`normal_impulse`, `friction_impulse_x_w2`, …) in dimension `dim`; None for counts, ratios
/// and names it does not know. Impulses are forces times time: N·s/m in 2-D, N·s in 3-D.
pub fn figure(name: &str, dim: usize) -> Option<String> {
    let unit = match name {
        n if n.starts_with("normal_impulse") || n.starts_with("friction_impulse_") => {
            if dim == 3 {
                "N·s"
            } else {
                "N·s/m"
            }
        }
        "final_kinetic"
        | "final_elastic"
        | "final_compliance"
        | "external_work"
        | "viscous_dissipation"
        | "friction_dissipation"
        | "constraint_dissipation"
        | "persistency_dissipation"
        | "max_abs_energy_residual" => energy(dim),
        "max_normal_force" | "max_tangential_force" => force(dim),
        "max_penetration" => "m",
        "final_time" => "s",
        _ => return None,
    };
    Some(unit.to_string())
}

/// A chart's axis for a figure: `name [unit]`, or the name alone where it has none.
pub fn figure_axis(name: &str, dim: usize) -> String {
    match figure(name, dim) {
        Some(u) => format!("{name} [{u}]"),
        None => name.to_string(),
    }
}

/// The history.csv column families: (family, unit in 2-D, unit in 3-D, columns). "1" is a
/// count or a ratio.
const HISTORY_FAMILIES: [(&str, &str, &str, &[&str]); 7] = [
    ("time", "s", "s", &["t"]),
    (
        "energy",
        "J/m",
        "J",
        &[
            "kinetic",
            "elastic",
            "compliance",
            "external_work",
            "viscous_dissipation",
            "friction_dissipation",
            "constraint_dissipation",
            "energy_residual",
            "energy_scale",
            "persistency_dissipation",
            "trapped_kinetic",
        ],
    ),
    (
        "force",
        "N/m",
        "N",
        &["normal_force", "tangential_force", "friction_force_x", "friction_force_y", "friction_force_z"],
    ),
    ("length", "m", "m", &["max_penetration"]),
    ("velocity", "m/s", "m/s", &["chatter"]),
    (
        "count",
        "1",
        "1",
        &[
            "step",
            "contact_nodes",
            "slip_nodes",
            "stick_nodes",
            "newton_iterations",
            "fixed_point_iterations",
            "fixed_point_converged",
        ],
    ),
    ("relative", "1", "1", &["inner_residual"]),
];

/// The contact.csv column families, as [`HISTORY_FAMILIES`] (the columns of either dimension;
/// `status` is a word, not a number).
const CONTACT_FAMILIES: [(&str, &str, &str, &[&str]); 5] = [
    ("time", "s", "s", &["t"]),
    ("length", "m", "m", &["x", "y", "z", "u_n", "u_t"]),
    ("velocity", "m/s", "m/s", &["v_t", "v_tx", "v_ty", "v_tz"]),
    ("stress", "Pa", "Pa", &["p", "lambda", "friction", "friction_x", "friction_y", "friction_z", "friction_bound"]),
    ("index", "1", "1", &["step", "node"]),
];

/// One family of columns and its unit.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Family {
    pub unit: String,
    pub columns: Vec<String>,
}

/// summary.json's `model.units`: the unit of every numeric column of history.csv and
/// contact.csv, by family, for the run's dimension.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Units {
    /// "per unit thickness (2-D)" or "absolute (3-D)": what the force and energy units mean
    pub basis: String,
    pub history: BTreeMap<String, Family>,
    pub contact: BTreeMap<String, Family>,
}

impl Units {
    /// The units of a run in dimension `dim`.
    pub fn of(dim: usize) -> Units {
        // contact.csv's columns of this dimension only (2-D has no z, v_tx, friction_x, …);
        // history.csv has the same columns in both (friction_force_z is 0 in 2-D)
        let contact_csv: Vec<&str> = crate::output::contact_columns(dim).split(',').collect();
        let families = |table: &[(&str, &str, &str, &[&str])], keep: &dyn Fn(&str) -> bool| {
            table
                .iter()
                .map(|(name, two, three, cols)| {
                    let unit = if dim == 3 { three } else { two };
                    let columns = cols.iter().filter(|c| keep(c)).map(|c| (*c).to_string()).collect();
                    ((*name).to_string(), Family { unit: (*unit).to_string(), columns })
                })
                .collect()
        };
        Units {
            basis: if dim == 3 { "absolute (3-D)" } else { "per unit thickness (2-D)" }.to_string(),
            history: families(&HISTORY_FAMILIES, &|_| true),
            contact: families(&CONTACT_FAMILIES, &|c| contact_csv.contains(&c)),
        }
    }

    /// The unit of history.csv column `column`, if it has one here.
    pub fn history_unit(&self, column: &str) -> Option<&str> {
        self.history.values().find(|f| f.columns.iter().any(|c| c == column)).map(|f| f.unit.as_str())
    }

    /// The unit of contact.csv column `column`, if it has one here (`status` has none).
    pub fn contact_unit(&self, column: &str) -> Option<&str> {
        self.contact.values().find(|f| f.columns.iter().any(|c| c == column)).map(|f| f.unit.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every history.csv and contact.csv column (but contact.csv's `status`) is in exactly one
    /// family, and the forces and energies follow the dimension.
    #[test]
    fn every_column_has_one_unit() {
        for dim in [2, 3] {
            let u = Units::of(dim);
            for (name, _) in crate::output::HISTORY {
                let n = u.history.values().filter(|f| f.columns.iter().any(|c| c == name)).count();
                assert_eq!(n, 1, "history.csv {name} is in {n} families");
            }
            for name in crate::output::contact_columns(dim).split(',').filter(|c| *c != "status") {
                let n = u.contact.values().filter(|f| f.columns.iter().any(|c| c == name)).count();
                assert_eq!(n, 1, "contact.csv {name} is in {n} families");
            }
            // and lists no column the dimension's contact.csv does not have
            let listed = u.contact.values().flat_map(|f| &f.columns).count();
            assert_eq!(listed, crate::output::contact_columns(dim).split(',').count() - 1, "{dim}-D");
            assert_eq!(u.history_unit("normal_force"), Some(force(dim)));
            assert_eq!(u.history_unit("kinetic"), Some(energy(dim)));
        }
        assert_eq!((force(2), force(3), energy(2), energy(3)), ("N/m", "N", "J/m", "J"));
    }
}
