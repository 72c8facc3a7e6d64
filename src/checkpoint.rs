//! Checkpoints (`--checkpoint-every N`, `--resume DIR`): the full state of a run at the end of
//! a step — u, v, the multipliers λ and friction forces t that warm-start the next step, the
//! energy totals, the run's counters and the solver state (`SolverState`: the key of the contact
//! solve's kept factorization) — stored with every f64 as its exact bit pattern, so a resumed
//! run reproduces an uninterrupted one bit for bit on the same machine.
//!
//! A checkpoint names the run it belongs to (the `run_id` of its folder's summary.json) and
//! the inputs it was computed from (their fingerprint), and carries a checksum of everything
//! else in it: an edited, truncated or foreign checkpoint is refused when read, as is one whose
//! state (u, v, λ, t, the energy terms and scale) holds a value that is not finite. That it agrees with the folder's history.csv, contact.csv and
//! frames is checked when the folder is reopened (output/resume.rs).

use serde::{Deserialize, Serialize};

use crate::energy::EnergyTerms;
use crate::error::{Error, Result};
use crate::simulation::{SolverState, State};

/// The checkpoint format this version writes and reads (6: t_n is the decimal of n·k,
/// `problem::step_time`, and the loads are sampled there; a format-5 state continued with it
/// would equal neither version's uninterrupted run).
const FORMAT: u32 = 6;

/// Bits of an f64 vector (JSON numbers would round-trip through decimal text).
fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

fn unbits(x: &[u64]) -> Vec<f64> {
    x.iter().map(|b| f64::from_bits(*b)).collect()
}

/// The run's counters that summary.json reports.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Counters {
    pub newton_iterations_total: usize,
    pub fixed_point_iterations_total: usize,
    pub fixed_point_iterations_max: usize,
    pub fixed_point_cap_hits: usize,
    #[serde(default)]
    pub unfrozen_fallbacks: usize,
    pub first_cap: Option<usize>,
    pub max_abs_energy_residual: u64,
    pub max_relative_energy_residual: u64,
    #[serde(default)]
    pub energy_guard_exceeded_steps: usize,
    /// how the contact solve's Newton systems were solved up to the checkpoint (summary.json's
    /// contact_* counts continue from them)
    #[serde(default)]
    pub contact: crate::step::delassus::FactorCounts,
}

/// What a checkpoint stores.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checkpoint {
    pub format: u32,
    /// the run this checkpoint belongs to (summary.json's `run_id` in the same folder)
    pub run_id: String,
    /// the fingerprint of the inputs (crate::fingerprint::inputs): a checkpoint resumes only a
    /// run of the same scene and mesh
    pub inputs: String,
    pub step: usize,
    u: Vec<u64>,
    v: Vec<u64>,
    lambda: Vec<u64>,
    t_fric: Vec<u64>,
    /// kinetic, elastic, compliance, work, viscous, friction, constraint, persistency, residual
    energy: [u64; 9],
    /// contact nodes that were on the constraint / in stick at the end of the step (R.2)
    active: Vec<bool>,
    stick: Vec<bool>,
    energy_scale: u64,
    /// (Ps.1) the out-of-plane strain per triangle where it is an internal variable; absent
    /// otherwise (so every other scene's checkpoint reads as before)
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    eps_zz: Vec<u64>,
    pub counters: Counters,
    /// what the solver needs to continue bit for bit (the key of the contact solve's kept
    /// factorization, format 3 on; JSON key `factor`): the resumed run rebuilds it
    #[serde(rename = "factor", default)]
    pub solver: SolverState,
    /// FNV-1a of the checkpoint's JSON with this field empty
    pub checksum: String,
}

impl Checkpoint {
    pub fn new(run_id: &str, inputs: &str, s: &State, counters: Counters, solver: SolverState) -> Checkpoint {
        let e = &s.energy;
        let mut cp = Checkpoint {
            format: FORMAT,
            run_id: run_id.to_string(),
            inputs: inputs.to_string(),
            step: s.n,
            u: bits(&s.u),
            v: bits(&s.v),
            lambda: bits(&s.lambda),
            t_fric: bits(&s.t_fric),
            energy: e.to_array().map(f64::to_bits),
            energy_scale: s.energy_scale.to_bits(),
            active: s.active.clone(),
            stick: s.stick.clone(),
            eps_zz: bits(&s.eps_zz),
            counters,
            solver,
            checksum: String::new(),
        };
        cp.checksum = cp.sum();
        cp
    }

    /// The checksum of everything but the checksum.
    fn sum(&self) -> String {
        let mut bare = self.clone();
        bare.checksum.clear();
        crate::fingerprint::text(&serde_json::to_string(&bare).unwrap_or_default())
    }

    /// The first stored number that is not finite, by name.
    fn non_finite(&self) -> Option<String> {
        let bad = |name: &str, x: &[u64]| {
            x.iter().position(|b| !f64::from_bits(*b).is_finite()).map(|i| format!("{name}[{i}]"))
        };
        bad("u", &self.u)
            .or_else(|| bad("v", &self.v))
            .or_else(|| bad("lambda", &self.lambda))
            .or_else(|| bad("t_fric", &self.t_fric))
            .or_else(|| bad("energy", &self.energy))
            .or_else(|| bad("energy_scale", &[self.energy_scale]))
            .or_else(|| bad("eps_zz", &self.eps_zz))
    }

    pub fn state(&self) -> State {
        State {
            n: self.step,
            u: unbits(&self.u),
            v: unbits(&self.v),
            lambda: unbits(&self.lambda),
            t_fric: unbits(&self.t_fric),
            energy: EnergyTerms::from_array(self.energy.map(f64::from_bits)),
            energy_scale: f64::from_bits(self.energy_scale),
            active: self.active.clone(),
            stick: self.stick.clone(),
            eps_zz: unbits(&self.eps_zz),
        }
    }

    /// Write to `dir/checkpoint.json` (through a temporary file and a rename).
    pub fn write(&self, dir: &std::path::Path) -> Result<()> {
        let text = serde_json::to_string(self).map_err(|e| Error::Output(format!("checkpoint.json: {e}")))?;
        crate::files::write_atomic(&dir.join("checkpoint.json"), text.as_bytes())
    }

    /// Read `dir/checkpoint.json`, checked: this version's format, the checksum, every value of
    /// the state finite. Any defect is a folder error naming the file and what is wrong.
    pub fn read(dir: &std::path::Path) -> Result<Checkpoint> {
        let p = dir.join("checkpoint.json");
        let refuse = |m: String| Error::folder(&p, m);
        let text = std::fs::read_to_string(&p)
            .map_err(|e| refuse(format!("cannot be read ({e}): there is nothing to resume from")))?;
        let format = serde_json::from_str::<serde_json::Value>(&text).ok().and_then(|v| v.get("format")?.as_u64());
        if format.is_some_and(|f| f != u64::from(FORMAT)) {
            return Err(refuse(format!(
                "checkpoint format {} was written by another version of dyncontact (this one reads format {FORMAT}): run the scene again",
                format.unwrap_or(0)
            )));
        }
        let cp: Checkpoint =
            serde_json::from_str(&text).map_err(|e| refuse(format!("not a dyncontact checkpoint ({e})")))?;
        if cp.checksum != cp.sum() {
            return Err(refuse(
                "its checksum does not match its contents: the file was changed or damaged after it was written".into(),
            ));
        }
        if let Some(what) = cp.non_finite() {
            return Err(refuse(format!("{what} is not finite: a checkpoint holds only finite values")));
        }
        Ok(cp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulation::State;

    fn state(u0: f64) -> State {
        State {
            n: 7,
            u: vec![u0, 2.0],
            v: vec![0.5, -0.5],
            lambda: vec![0.0],
            t_fric: vec![0.0],
            energy: EnergyTerms::default(),
            energy_scale: 1.0,
            active: vec![false],
            stick: vec![true],
            eps_zz: Vec::new(),
        }
    }

    /// A fresh folder under the system's temporary folder, removed when the test ends (passed
    /// or not: each run of these tests left three folders behind before).
    struct Scratch(std::path::PathBuf);

    impl std::ops::Deref for Scratch {
        type Target = std::path::Path;
        fn deref(&self) -> &std::path::Path {
            &self.0
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn dir(name: &str) -> Scratch {
        let d = std::env::temp_dir().join(format!("dyncontact-checkpoint-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("dir");
        Scratch(d)
    }

    /// (issue 22) A checkpoint reads back to the state it was written from, bit for bit.
    #[test]
    fn a_checkpoint_round_trips() {
        let d = dir("roundtrip");
        Checkpoint::new("run", "inputs", &state(1.25), Counters::default(), SolverState::default())
            .write(&d)
            .expect("write");
        let cp = Checkpoint::read(&d).expect("read");
        assert_eq!((cp.run_id.as_str(), cp.inputs.as_str(), cp.step), ("run", "inputs", 7));
        assert_eq!(cp.state(), state(1.25));
    }

    /// A checkpoint keeps format 4's `factor` field: null without a kept factorization, and the
    /// key of one (U, D and the slip frames as bits) reads and writes back as the same JSON.
    #[test]
    fn the_solver_state_is_format_4_s_factor_field() {
        let d = dir("factor");
        Checkpoint::new("run", "inputs", &state(1.25), Counters::default(), SolverState::default())
            .write(&d)
            .expect("write");
        let text = std::fs::read_to_string(d.join("checkpoint.json")).expect("read");
        assert!(text.contains("\"factor\":null"), "{text}");
        let key = r#"{"unknown":[0,2],"diag":[0,4607182418800017408],"frames_dim":3,"frames":[null,[4607182418800017408,0]]}"#;
        let solver: SolverState = serde_json::from_str(key).expect("a format-4 factor key");
        assert_ne!(solver, SolverState::default());
        assert_eq!(serde_json::to_string(&solver).expect("json"), key);
    }

    /// (issue 22) A checkpoint with a value that is not finite is refused even when its checksum
    /// is right (it was written so), naming the value; one whose bytes changed is refused by
    /// its checksum.
    #[test]
    fn non_finite_and_changed_checkpoints_are_refused() {
        let d = dir("nonfinite");
        Checkpoint::new("run", "inputs", &state(f64::NAN), Counters::default(), SolverState::default())
            .write(&d)
            .expect("write");
        let e = Checkpoint::read(&d).expect_err("refused").to_string();
        assert!(e.contains("u[0] is not finite"), "{e}");
        Checkpoint::new("run", "inputs", &state(1.25), Counters::default(), SolverState::default())
            .write(&d)
            .expect("write");
        let p = d.join("checkpoint.json");
        let text = std::fs::read_to_string(&p).expect("read");
        std::fs::write(&p, text.replacen("\"run_id\":\"run\"", "\"run_id\":\"other\"", 1)).expect("edit");
        let e = Checkpoint::read(&d).expect_err("refused").to_string();
        assert!(e.contains("checksum"), "{e}");
    }
}
