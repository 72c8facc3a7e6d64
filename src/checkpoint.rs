//! Checkpoints (`--checkpoint-every N`, `--resume DIR`): the full state of a run at the end of
//! a step — u, v, the multipliers λ and friction forces t that warm-start the next step, the
//! energy totals and the run's counters — stored with every f64 as its exact bit pattern, so a
//! resumed run reproduces an uninterrupted one bit for bit on the same machine.

use serde::{Deserialize, Serialize};

use crate::energy::EnergyTerms;
use crate::simulation::State;
use crate::error::{Error, Result};

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
}

/// What a checkpoint stores.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    pub format: u32,
    /// identifies the scene (FNV-1a of its parsed form): a checkpoint resumes only its scene
    pub scene_hash: String,
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
    pub counters: Counters,
    /// the contact solve's kept factorization (format 3 on): the next Newton systems are solved
    /// with it, so the resumed run rebuilds it
    #[serde(default)]
    pub factor: Option<crate::step::delassus::FactorKey>,
}

/// FNV-1a 64 of a text, as hex.
pub fn fingerprint(text: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

impl Checkpoint {
    pub fn new(scene_hash: String, s: &State, counters: Counters, factor: Option<crate::step::delassus::FactorKey>) -> Checkpoint {
        let e = &s.energy;
        Checkpoint {
            format: 3,
            scene_hash,
            step: s.n,
            u: bits(&s.u),
            v: bits(&s.v),
            lambda: bits(&s.lambda),
            t_fric: bits(&s.t_fric),
            energy: [
                e.kinetic, e.elastic, e.compliance, e.external_work, e.viscous_dissipation, e.friction_dissipation,
                e.constraint_dissipation, e.persistency_dissipation, e.residual,
            ]
            .map(f64::to_bits),
            energy_scale: s.energy_scale.to_bits(),
            active: s.active.clone(),
            stick: s.stick.clone(),
            counters,
            factor,
        }
    }

    pub fn state(&self) -> State {
        let e = self.energy.map(f64::from_bits);
        State {
            n: self.step,
            u: unbits(&self.u),
            v: unbits(&self.v),
            lambda: unbits(&self.lambda),
            t_fric: unbits(&self.t_fric),
            energy: EnergyTerms {
                kinetic: e[0],
                elastic: e[1],
                compliance: e[2],
                external_work: e[3],
                viscous_dissipation: e[4],
                friction_dissipation: e[5],
                constraint_dissipation: e[6],
                persistency_dissipation: e[7],
                residual: e[8],
            },
            energy_scale: f64::from_bits(self.energy_scale),
            active: self.active.clone(),
            stick: self.stick.clone(),
        }
    }

    /// Write to `dir/checkpoint.json` (through a temporary file and a rename).
    pub fn write(&self, dir: &std::path::Path) -> Result<()> {
        let text = serde_json::to_string(self).map_err(|e| Error::Output(format!("checkpoint.json: {e}")))?;
        crate::output::fs::write_atomic(&dir.join("checkpoint.json"), text.as_bytes())
    }

    /// Read `dir/checkpoint.json`.
    pub fn read(dir: &std::path::Path) -> Result<Checkpoint> {
        let p = dir.join("checkpoint.json");
        let text = std::fs::read_to_string(&p).map_err(|e| Error::io(&p, e))?;
        let cp: Checkpoint = serde_json::from_str(&text)
            .map_err(|e| Error::Output(format!("{}: not a dyncontact checkpoint ({e})", p.display())))?;
        if !(2..=3).contains(&cp.format) {
            return Err(Error::Output(format!("{}: checkpoint format {} is not supported", p.display(), cp.format)));
        }
        Ok(cp)
    }
}
