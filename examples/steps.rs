//! The library in fifteen lines: scene text → validated model → `Problem` (mesh, operators,
//! initial data) → `Simulation`, and the one time loop, `sim.steps()`, driven by the caller —
//! what `dyncontact run` does, without writing outputs. It runs the embedded academic scene on a
//! coarse mesh for 0.05 s and prints each step's energies and (E.1) defect (zero to the solver's
//! tolerance for the midpoint scheme). Run it with `cargo run --release --example steps`;
//! `cargo test` runs it too (tests/contract/example.rs).

use dyncontact::model::Model;
use dyncontact::overrides::Override;
use dyncontact::problem::Problem;
use dyncontact::scene::{DEFAULT_SCENE, Scene};
use dyncontact::simulation::Simulation;

pub fn main() -> Result<(), dyncontact::Error> {
    let coarse = [Override::parse("domain.cells=[16, 8]")?, Override::parse("time.end=0.05")?];
    let scene = Scene::from_toml_with(DEFAULT_SCENE, "academic", &coarse)?;
    let model: Model = scene.validate()?; // typed, checked values: every error names its key
    let problem = Problem::new(model, std::path::Path::new("."))?;
    let mut sim = Simulation::new(&problem)?;
    for rec in sim.steps() {
        let rec = rec?; // a step that fails says why, with its residuals
        let e = rec.energy;
        println!(
            "t = {:.4}  kinetic {:.4e}  elastic {:.4e}  (E.1) defect {:+.1e}",
            rec.t, e.kinetic, e.elastic, e.residual
        );
    }
    Ok(())
}
