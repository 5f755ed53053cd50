//! The bodies over load cycles (issue 27): per body and simulated cycle the plastic
//! dissipation and the ratcheting strain, and per body and cyclic step a shakedown verdict
//! from its last simulated cycle.
//!
//! - **Plastic dissipation of a cycle**: Σ (σ:Δεᵖ − Δψ) dV over the cycle's increments (the
//!   energy ledger's plastic dissipation, ψ the backstresses' stored energy), per body.
//! - **Ratcheting strain of a cycle**: the largest, over the body's points, equivalent
//!   measure √(⅔ Δεᵖ:Δεᵖ) of the *net* change Δεᵖ of the plastic strain tensor from the
//!   cycle's start to its end. In a stabilised cycle that is the change of the cycle's mean
//!   plastic strain: zero in alternating plasticity (the loop closes), the strain added per
//!   cycle when the body ratchets.
//! - **Plastic strain increment of a cycle**: the largest increase of the accumulated
//!   equivalent plastic strain ε̄ᵖ at a point over the cycle (non-zero whenever the body
//!   flows, whether the loop closes or not).
//!
//! The verdict of a body for a cyclic step, from the step's last simulated cycle, with the
//! threshold [`SHAKEDOWN_THRESHOLD`] on both strains per cycle: "ratcheting" when the
//! ratcheting strain exceeds it and also [`RATCHET_SHARE`] of the cycle's plastic strain
//! increment, else "plastic shakedown" (alternating plasticity) when the plastic strain
//! increment exceeds it, else "elastic shakedown". The share keeps a loop that is still
//! closing (a perfectly plastic body settles into alternating plasticity over many cycles,
//! its net change falling from cycle to cycle) from counting as ratcheting. An elastic body always shakes
//! down elastically. Cycle jumping extrapolates wear only: the bodies' plastic strains are
//! those of the simulated cycles.

use crate::material::{PointState, Voigt, contraction, deviator};
use crate::model::Model;

/// Strain per cycle (dimensionless) above which a body counts as still flowing: a
/// thousandth of a typical metal's yield strain (σ_Y/E ≈ 10⁻³), far above the round-off of
/// the converged return (relative 10⁻¹² of the strains).
pub const SHAKEDOWN_THRESHOLD: f64 = 1e-6;

/// The share of a cycle's plastic strain increment its net (ratcheting) change must exceed
/// for the verdict "ratcheting": a tenth. Measured: a perfectly plastic thick cylinder in
/// alternating plasticity nets 2 % of its flow per cycle after 5 cycles and 0.3 % after 12;
/// Armstrong–Frederick ratcheting under a mean stress nets tens of per cent.
pub const RATCHET_SHARE: f64 = 0.1;

/// One body over one simulated cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyCycle {
    /// Plastic dissipation of the cycle (N·mm, per unit thickness as the forces are).
    pub plastic_dissipation: f64,
    /// The largest net equivalent plastic strain change of the cycle at a point.
    pub ratchet_strain: f64,
    /// The largest increase of ε̄ᵖ over the cycle at a point.
    pub plastic_strain_increment: f64,
}

/// A body's shakedown verdict for a cyclic step.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShakedownVerdict {
    /// The step's name and 1-based number.
    pub step: String,
    pub analysis_step: usize,
    /// The body's name (its physical group).
    pub body: String,
    /// "elastic shakedown", "plastic shakedown" or "ratcheting".
    pub shakedown: String,
    /// The threshold on the strains per cycle ([`SHAKEDOWN_THRESHOLD`]).
    pub threshold: f64,
    /// The share of the cycle's plastic strain increment the ratcheting strain must also
    /// exceed ([`RATCHET_SHARE`]).
    pub ratchet_share: f64,
    /// The last simulated cycle's values the verdict is made from.
    pub last_cycle: BodyCycle,
}

impl ShakedownVerdict {
    /// The verdict on a body whose last simulated cycle of a cyclic step was `last`.
    pub fn verdict(last: &BodyCycle) -> &'static str {
        if last.ratchet_strain
            > SHAKEDOWN_THRESHOLD.max(RATCHET_SHARE * last.plastic_strain_increment)
        {
            "ratcheting"
        } else if last.plastic_strain_increment > SHAKEDOWN_THRESHOLD {
            "plastic shakedown"
        } else {
            "elastic shakedown"
        }
    }
}

/// The bodies' cycle trackers: what a cycle's results need from its start, the last
/// completed cycle's results and the verdicts of the cyclic steps finished so far. Part of
/// the state a run continues from (restart records).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyCycles {
    /// Whether some body can flow plastically (else no plastic strain is tracked).
    plastic: bool,
    /// Plastic dissipation of every body since the start of the run.
    pub dissipation: Vec<f64>,
    /// Its value at the start of the current cycle.
    start_dissipation: Vec<f64>,
    /// Per continuum state slot, the plastic strain and ε̄ᵖ at the start of the current
    /// cycle (empty in a model without plastic bodies).
    start: Vec<(Voigt, f64)>,
    /// Per body, the last completed cycle.
    pub last: Vec<BodyCycle>,
    /// The verdicts of the finished cyclic steps, step after step, body after body.
    pub verdicts: Vec<ShakedownVerdict>,
}

impl BodyCycles {
    /// The trackers of `model`'s bodies before the first increment.
    pub fn new(model: &Model) -> Self {
        let bodies = model.bodies.len();
        Self {
            plastic: model.continuum.materials.iter().any(|m| !m.is_linear()),
            dissipation: vec![0.0; bodies],
            start_dissipation: vec![0.0; bodies],
            start: Vec::new(),
            last: vec![BodyCycle::default(); bodies],
            verdicts: Vec::new(),
        }
    }

    /// Whether some body can flow plastically.
    pub fn has_plastic_bodies(&self) -> bool {
        self.plastic
    }

    /// Adds a converged increment's plastic dissipation per body.
    pub fn record(&mut self, body_dissipation: &[f64]) {
        for (total, d) in self.dissipation.iter_mut().zip(body_dissipation) {
            *total += d;
        }
    }

    /// Starts a cycle at the committed `states`.
    pub fn start_cycle(&mut self, states: &[PointState]) {
        self.start_dissipation.clone_from(&self.dissipation);
        if self.plastic {
            self.start.clear();
            self.start.extend(
                states
                    .iter()
                    .map(|s| (s.plastic_strain, s.equivalent_plastic_strain)),
            );
        }
    }

    /// Ends the cycle of output increment `step` at the committed `states`: sets
    /// [`Self::last`] and, at the last simulated cycle of a cyclic step, adds the step's
    /// verdicts.
    pub fn end_cycle(&mut self, model: &Model, step: usize, states: &[PointState]) {
        let ppe = crate::element::quadrature::MAX_CELL_POINTS;
        for (b, last) in self.last.iter_mut().enumerate() {
            *last = BodyCycle {
                plastic_dissipation: self.dissipation[b] - self.start_dissipation[b],
                ..BodyCycle::default()
            };
        }
        if self.start.len() == states.len() {
            for (e, cell) in model.continuum.cells.iter().enumerate() {
                let last = &mut self.last[cell.body as usize];
                let points = crate::element::quadrature::cell_rule(cell.kind).len();
                let slots = e * ppe..e * ppe + points;
                for ((start, start_p), s) in self.start[slots.clone()].iter().zip(&states[slots]) {
                    let net = equivalent_strain(&(s.plastic_strain - start));
                    last.ratchet_strain = last.ratchet_strain.max(net);
                    let increment = s.equivalent_plastic_strain - start_p;
                    last.plastic_strain_increment = last.plastic_strain_increment.max(increment);
                }
            }
        }
        let timeline = model.schedule.timeline();
        let frame = timeline.frame(step as f64);
        let Some(plan) = timeline.steps().get(frame.analysis_step.wrapping_sub(1)) else {
            return;
        };
        if plan.is_cyclic() && frame.cycle == plan.simulated() {
            for (name, last) in model.bodies.iter().zip(&self.last) {
                self.verdicts.push(ShakedownVerdict {
                    step: plan.name.clone(),
                    analysis_step: frame.analysis_step,
                    body: name.clone(),
                    shakedown: ShakedownVerdict::verdict(last).into(),
                    threshold: SHAKEDOWN_THRESHOLD,
                    ratchet_share: RATCHET_SHARE,
                    last_cycle: *last,
                });
            }
        }
    }
}

/// √(⅔ ε:ε) of a deviatoric strain in Voigt form with engineering shear.
fn equivalent_strain(strain: &Voigt) -> f64 {
    // As a tensor: halve the engineering shear; contraction counts the shear twice.
    let mut tensor = deviator(strain);
    crate::material::SHEAR
        .iter()
        .for_each(|&i| tensor[i] = 0.5 * strain[i]);
    (2.0 / 3.0 * contraction(&tensor, &tensor)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equivalent_strain_of_uniaxial_plastic_flow_is_its_axial_strain() {
        // Isochoric uniaxial plastic strain (1, −½, 0, −½) ε: equivalent ε.
        let e = 2e-3;
        let strain = Voigt::new(e, -0.5 * e, 0.0, -0.5 * e);
        assert!((equivalent_strain(&strain) - e).abs() < 1e-15);
        // Pure shear γ: equivalent γ/√3.
        let shear = Voigt::new(0.0, 0.0, e, 0.0);
        assert!((equivalent_strain(&shear) - e / 3f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn verdicts_follow_the_thresholds() {
        let cycle = |ratchet, increment| BodyCycle {
            plastic_dissipation: 0.0,
            ratchet_strain: ratchet,
            plastic_strain_increment: increment,
        };
        assert_eq!(
            ShakedownVerdict::verdict(&cycle(0.0, 0.0)),
            "elastic shakedown"
        );
        assert_eq!(
            ShakedownVerdict::verdict(&cycle(1e-8, 1e-4)),
            "plastic shakedown"
        );
        assert_eq!(ShakedownVerdict::verdict(&cycle(1e-4, 1e-4)), "ratcheting");
        assert_eq!(
            ShakedownVerdict::verdict(&cycle(1e-5, 1e-3)),
            "plastic shakedown"
        );
    }
}
