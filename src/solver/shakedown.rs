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
//! Each simulated cycle *reads* as one of three states, with the threshold
//! [`SHAKEDOWN_THRESHOLD`] on both strains per cycle: "ratcheting" when the ratcheting strain
//! exceeds it and also [`RATCHET_SHARE`] of the cycle's plastic strain increment, else
//! "plastic shakedown" (alternating plasticity) when the plastic strain increment exceeds
//! it, else "elastic shakedown". The share keeps a loop that is still closing (a perfectly
//! plastic body settles into alternating plasticity over many cycles, its net change falling
//! from cycle to cycle) from counting as ratcheting.
//!
//! The **verdict** of a body for a cyclic step is its last simulated cycle's reading when
//! that reading is settled: "elastic shakedown" at once (a cycle without plastic flow under a
//! periodic load repeats itself exactly), a flowing reading when the last
//! [`SETTLED_CYCLES`] simulated cycles after the step's first (the transient from the
//! previous state) all read alike and the trend of their share (ratchet strain over plastic
//! strain increment), extrapolated linearly over as many cycles again, stays on the same side
//! of [`RATCHET_SHARE`]. Otherwise the verdict is "not settled": too few cycles were
//! simulated to tell a loop still closing from ratcheting (the press fit of
//! `make cyclic_press_fit` reads "ratcheting" in its first four cycles, its share falling
//! from 23 % to 11 %, and "plastic shakedown" from the fifth on). An elastic body always
//! shakes down elastically.
//!
//! **Cycle jumping** carries the bodies' plastic state (plastic strains, backstresses)
//! through the jumped cycles unchanged: right for a body whose simulated cycle closed its
//! loop (elastic or plastic shakedown), wrong for one that ratchets, whose jumped cycles would
//! each add their ratcheting strain. A jump after a cycle that reads "ratcheting" is refused
//! ([`BodyCycles::check_jump`]). Extrapolating the plastic strain instead would break
//! the return's consistency (the stress would leave the yield surface) and the equilibrium,
//! and the Armstrong–Frederick backstresses do not change linearly over cycles, so there is
//! no sound extrapolation short of simulating the cycles.

use crate::error::{Error, Result};
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

/// Simulated cycles after a cyclic step's first that must read alike for a flowing body's
/// verdict to be settled: three, so that a reading is confirmed twice (the press fit's
/// reading changes once, from "ratcheting" to "plastic shakedown", as its loop closes).
pub const SETTLED_CYCLES: usize = 3;

/// What one simulated cycle of a body reads as (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Reading {
    #[default]
    #[serde(rename = "elastic shakedown")]
    ElasticShakedown,
    #[serde(rename = "plastic shakedown")]
    PlasticShakedown,
    #[serde(rename = "ratcheting")]
    Ratcheting,
}

impl Reading {
    /// The reading of a body's cycle `cycle`.
    pub fn of(cycle: &BodyCycle) -> Self {
        if cycle.ratchet_strain
            > SHAKEDOWN_THRESHOLD.max(RATCHET_SHARE * cycle.plastic_strain_increment)
        {
            Reading::Ratcheting
        } else if cycle.plastic_strain_increment > SHAKEDOWN_THRESHOLD {
            Reading::PlasticShakedown
        } else {
            Reading::ElasticShakedown
        }
    }

    /// The words of summary.json.
    pub fn as_str(self) -> &'static str {
        match self {
            Reading::ElasticShakedown => "elastic shakedown",
            Reading::PlasticShakedown => "plastic shakedown",
            Reading::Ratcheting => "ratcheting",
        }
    }
}

/// A body's readings over the current cyclic step: the last one, how many simulated cycles
/// after the step's first in a row ended with it, and the shares of their net change in
/// their flow (ratchet strain / plastic strain increment) over the last [`SETTLED_CYCLES`]
/// of them.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Readings {
    pub last: Reading,
    pub alike: usize,
    shares: Vec<f64>,
}

impl Readings {
    /// The readings after simulated cycle `cycle` (1-based in its step) of values `values`.
    pub fn after(&self, cycle: usize, values: &BodyCycle) -> Self {
        let reading = Reading::of(values);
        let (alike, mut shares) = match cycle {
            0 | 1 => {
                return Self {
                    last: reading,
                    ..Self::default()
                };
            }
            _ if reading == self.last => (self.alike + 1, self.shares.clone()),
            _ => (1, Vec::new()),
        };
        if shares.len() == SETTLED_CYCLES {
            shares.remove(0);
        }
        shares.push(share(values));
        Self {
            last: reading,
            alike,
            shares,
        }
    }

    /// The verdict (module docs): a flowing reading is settled when it held over the last
    /// [`SETTLED_CYCLES`] cycles and the trend of its share, extrapolated linearly over as
    /// many cycles again, does not cross [`RATCHET_SHARE`].
    pub fn verdict(&self) -> &'static str {
        let settled = || {
            let (Some(first), Some(last)) = (self.shares.first(), self.shares.last()) else {
                return false;
            };
            let slope = (last - first) / (self.shares.len() - 1).max(1) as f64;
            let projected = last + slope * SETTLED_CYCLES as f64;
            (projected > RATCHET_SHARE) == (self.last == Reading::Ratcheting)
        };
        match self.last {
            Reading::ElasticShakedown => self.last.as_str(),
            r if self.alike >= SETTLED_CYCLES && settled() => r.as_str(),
            _ => "not settled",
        }
    }
}

/// The share of a cycle's net plastic strain change in its flow (0 without flow).
fn share(cycle: &BodyCycle) -> f64 {
    if cycle.plastic_strain_increment > SHAKEDOWN_THRESHOLD {
        cycle.ratchet_strain / cycle.plastic_strain_increment
    } else {
        0.0
    }
}

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
    /// "elastic shakedown", "plastic shakedown", "ratcheting" or "not settled".
    pub shakedown: String,
    /// What the step's last simulated cycle reads as (the verdict when settled).
    pub last_cycle_reads: Reading,
    /// How many simulated cycles after the step's first, up to its last, read alike.
    pub cycles_alike: usize,
    /// How many must, for a flowing body's verdict to be settled ([`SETTLED_CYCLES`]).
    pub settled_cycles: usize,
    /// The threshold on the strains per cycle ([`SHAKEDOWN_THRESHOLD`]).
    pub threshold: f64,
    /// The share of the cycle's plastic strain increment the ratcheting strain must also
    /// exceed ([`RATCHET_SHARE`]).
    pub ratchet_share: f64,
    /// The last simulated cycle's values the verdict is made from.
    pub last_cycle: BodyCycle,
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
    /// Per body, its readings over the current cyclic step.
    pub readings: Vec<Readings>,
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
            readings: vec![Readings::default(); bodies],
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
        for (readings, last) in self.readings.iter_mut().zip(&self.last) {
            *readings = readings.after(frame.cycle, last);
        }
        let Some(plan) = timeline.steps().get(frame.analysis_step.wrapping_sub(1)) else {
            return;
        };
        if plan.is_cyclic() && frame.cycle == plan.simulated() {
            let bodies = model.bodies.iter().zip(&self.last).zip(&self.readings);
            for ((name, last), readings) in bodies {
                self.verdicts.push(ShakedownVerdict {
                    step: plan.name.clone(),
                    analysis_step: frame.analysis_step,
                    body: name.clone(),
                    shakedown: readings.verdict().into(),
                    last_cycle_reads: readings.last,
                    cycles_alike: readings.alike,
                    settled_cycles: SETTLED_CYCLES,
                    threshold: SHAKEDOWN_THRESHOLD,
                    ratchet_share: RATCHET_SHARE,
                    last_cycle: *last,
                });
            }
        }
    }

    /// Refuses a cycle jump over `jump_cycles` cycles (> 1) after a simulated cycle in which
    /// some body ratcheted: the jump would carry its plastic state unchanged through cycles
    /// that each add to it (module docs). Call after [`Self::end_cycle`]; the caller adds the
    /// step with [`Error::in_analysis_step`].
    pub fn check_jump(&self, model: &Model, jump_cycles: usize) -> Result<()> {
        if jump_cycles <= 1 {
            return Ok(());
        }
        let ratcheting = self
            .readings
            .iter()
            .position(|r| r.last == Reading::Ratcheting);
        let Some(b) = ratcheting else {
            return Ok(());
        };
        let last = &self.last[b];
        Err(Error::RatchetingJump {
            body: model.bodies[b].clone(),
            step_index: None,
            jump_cycles,
            ratchet_strain: last.ratchet_strain,
            plastic_strain_increment: last.plastic_strain_increment,
            threshold: SHAKEDOWN_THRESHOLD,
            ratchet_share: RATCHET_SHARE,
        })
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
    use crate::material::voigt;

    #[test]
    fn equivalent_strain_of_uniaxial_plastic_flow_is_its_axial_strain() {
        // Isochoric uniaxial plastic strain (1, −½, 0, −½) ε: equivalent ε.
        let e = 2e-3;
        let strain = voigt(e, -0.5 * e, 0.0, -0.5 * e);
        assert!((equivalent_strain(&strain) - e).abs() < 1e-15);
        // Pure shear γ: equivalent γ/√3.
        let shear = voigt(0.0, 0.0, e, 0.0);
        assert!((equivalent_strain(&shear) - e / 3f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn readings_follow_the_thresholds() {
        let cycle = |ratchet, increment| BodyCycle {
            plastic_dissipation: 0.0,
            ratchet_strain: ratchet,
            plastic_strain_increment: increment,
        };
        let reads = |ratchet, increment| Reading::of(&cycle(ratchet, increment));
        assert_eq!(reads(0.0, 0.0), Reading::ElasticShakedown);
        assert_eq!(reads(1e-8, 1e-4), Reading::PlasticShakedown);
        assert_eq!(reads(1e-4, 1e-4), Reading::Ratcheting);
        assert_eq!(reads(1e-5, 1e-3), Reading::PlasticShakedown);
    }

    /// A flowing reading is the verdict once the last `SETTLED_CYCLES` cycles after the
    /// step's first read alike and the trend of their share does not cross the limit within
    /// as many cycles again; an elastic cycle is the verdict at once.
    #[test]
    fn verdicts_need_settled_readings() {
        let verdict = |cycles: &[(f64, f64)]| {
            let mut r = Readings::default();
            for (c, &(ratchet, increment)) in cycles.iter().enumerate() {
                r = r.after(
                    c + 1,
                    &BodyCycle {
                        plastic_dissipation: 0.0,
                        ratchet_strain: ratchet,
                        plastic_strain_increment: increment,
                    },
                );
            }
            r.verdict()
        };
        // The press fit's kinematic hub (cycles.csv): shares 0.23, 0.17, 0.135, 0.11, 0.091,
        // 0.078, 0.067, 0.058 of a flow of about 5e-4: a loop closing.
        let press_fit: Vec<(f64, f64)> = [0.23, 0.17, 0.135, 0.11, 0.091, 0.078, 0.067, 0.058]
            .iter()
            .map(|share| (share * 5e-4, 5e-4))
            .collect();
        assert_eq!(verdict(&press_fit[..3]), "not settled");
        // Three cycles read "ratcheting", but their share falls through the limit.
        assert_eq!(verdict(&press_fit[..4]), "not settled");
        assert_eq!(verdict(&press_fit[..6]), "not settled");
        assert_eq!(verdict(&press_fit[..7]), "plastic shakedown");
        assert_eq!(verdict(&press_fit), "plastic shakedown");
        // Ratcheting at a steady share, and a share rising towards the limit.
        assert_eq!(verdict(&[(2e-4, 5e-4); 4]), "ratcheting");
        let rising: Vec<(f64, f64)> = [0.01, 0.05, 0.07, 0.09]
            .iter()
            .map(|share| (share * 5e-4, 5e-4))
            .collect();
        assert_eq!(verdict(&rising), "not settled");
        // The first cycle (the transient) does not count; an elastic cycle settles at once.
        assert_eq!(verdict(&[(0.0, 1e-4); 3]), "not settled");
        assert_eq!(verdict(&[(0.0, 1e-4); 4]), "plastic shakedown");
        assert_eq!(verdict(&[(1e-4, 1e-4), (0.0, 0.0)]), "elastic shakedown");
    }
}
