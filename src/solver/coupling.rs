//! The temperatures of an increment and their staggered coupling with the mechanics
//! (Abaqus' sequentially coupled thermal-stress analysis, iterated within the increment):
//! the conduction is solved with the contact states of the last converged increment, the
//! mechanics with its temperature; when a joint's conductance depends on the contact
//! (pressure, open or closed), the conduction is solved again with the new contact states
//! and the mechanics again with the new temperature, until the temperature changes by no more
//! than the Newton displacement tolerance (relative to its largest value). The increment's
//! pressures then agree with its temperatures to the same tolerance.

use crate::Result;
use crate::contact::InterfaceState;
use crate::model::Model;
use crate::solver::conduction::{ConductionSolver, ConductionWork};
use crate::solver::newton::{Newton, NewtonLog, NewtonSettings};
use crate::solver::state::Solution;
use crate::thermal::HeatSolution;

/// Most conduction–mechanics exchanges of one increment; an increment that needs more is
/// cut back like one whose Newton iterations do not converge.
pub const MAX_EXCHANGES: usize = 50;

/// The temperatures of a run: the conduction solver, if some body conducts, made once.
#[derive(Debug)]
pub struct Temperatures {
    conduction: Option<ConductionSolver>,
    /// The largest relative temperature change of an exchange that ends the increment's
    /// exchanges (the Newton displacement tolerance).
    tolerance: f64,
}

impl Temperatures {
    /// The temperatures of `model`'s run with the Newton `settings` (factors its
    /// conduction, if some body conducts).
    pub fn new(model: &Model, settings: &NewtonSettings) -> Result<Self> {
        Ok(Self {
            conduction: ConductionSolver::new(model)?,
            tolerance: settings.displacement_tolerance,
        })
    }

    /// The conduction's work so far (none without conduction).
    pub fn work(&self) -> ConductionWork {
        self.conduction
            .as_ref()
            .map_or_else(ConductionWork::default, ConductionSolver::work)
    }

    /// The steady conduction at pseudo-time `time` with the joints in the interface
    /// `states`, if some body conducts.
    fn heat(
        &mut self,
        model: &Model,
        time: f64,
        states: &[InterfaceState],
    ) -> Result<Option<HeatSolution>> {
        self.conduction
            .as_mut()
            .map(|c| c.solve(model, time, states))
            .transpose()
    }

    /// Sets the temperatures of `solution` to those of pseudo-time `time` with the joints
    /// in the committed contact states (the start of an increment, or of a resumed run).
    pub fn start(&mut self, model: &Model, solution: &mut Solution, time: f64) -> Result<()> {
        if !model.has_temperature() {
            return Ok(());
        }
        let heat = self.heat(model, time, &solution.interface_committed)?;
        solution.thermal.field = model.temperature_field(time, heat.as_ref());
        solution.thermal.heat = heat;
        solution.thermal.exchanges = 0;
        Ok(())
    }

    /// Solves the increment ending at pseudo-time `time` (prescribed displacements already
    /// set in `solution.u`): temperatures, then Newton, then, for a coupled model, the
    /// exchanges. The log's iterations, solves and seconds count every Newton solve of the
    /// exchanges; an increment whose exchanges do not settle within [`MAX_EXCHANGES`]
    /// returns a log that did not converge.
    pub fn solve_increment(
        &mut self,
        model: &Model,
        newton: &mut Newton,
        solution: &mut Solution,
        time: f64,
        external_force: &[f64],
        force_floor: f64,
    ) -> Result<NewtonLog> {
        self.start(model, solution, time)?;
        let coupled = model.is_thermally_coupled();
        if coupled {
            newton.begin_coupled_increment();
        }
        let log = {
            let mut mechanics = |solution: &mut Solution| {
                let (u, mut problem) = solution.split(model);
                newton.solve_increment(&mut problem, u, external_force, force_floor)
            };
            if coupled {
                self.exchanges(model, solution, time, mechanics)
            } else {
                mechanics(solution)
            }
        };
        if coupled {
            let converged = log.as_ref().is_ok_and(|log| log.converged);
            newton.end_coupled_increment(converged.then_some((&solution.u[..], external_force)));
        }
        log
    }

    /// The exchanges of a coupled increment at pseudo-time `time` ([`Self::solve_increment`]),
    /// `mechanics` solving the mechanics with the temperatures of `solution`.
    fn exchanges(
        &mut self,
        model: &Model,
        solution: &mut Solution,
        time: f64,
        mut mechanics: impl FnMut(&mut Solution) -> Result<NewtonLog>,
    ) -> Result<NewtonLog> {
        let mut earlier = NewtonLog::default();
        loop {
            let mut log = mechanics(solution)?;
            log.add_earlier(&earlier);
            earlier = log.totals();
            if !log.converged {
                return Ok(log);
            }
            let heat = self.heat(model, time, &solution.interface_trial)?;
            let change = relative_change(
                solution.thermal.heat.as_ref().map(|h| h.nodal.as_slice()),
                heat.as_ref().map(|h| h.nodal.as_slice()),
            );
            let thermal = &mut solution.thermal;
            thermal.exchanges += 1;
            thermal.field = model.temperature_field(time, heat.as_ref());
            thermal.heat = heat;
            if change <= self.tolerance {
                tracing::info!(
                    "thermal-mechanical coupling: {} exchange(s), last temperature change \
                     {change:.2e} (relative)",
                    thermal.exchanges
                );
                return Ok(log);
            }
            if thermal.exchanges >= MAX_EXCHANGES {
                tracing::info!(
                    "thermal-mechanical coupling: no agreement after {MAX_EXCHANGES} exchanges \
                     (temperature change {change:.2e}, relative)"
                );
                log.converged = false;
                return Ok(log);
            }
            tracing::debug!(
                "thermal-mechanical exchange {}: temperature change {change:.2e} (relative)",
                thermal.exchanges
            );
        }
    }
}

/// Largest change from `old` to `new` relative to the largest |new| (0 when both vanish).
fn relative_change(old: Option<&[f64]>, new: Option<&[f64]>) -> f64 {
    let (Some(old), Some(new)) = (old, new) else {
        return 0.0;
    };
    let scale = new.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let change = old
        .iter()
        .zip(new)
        .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    if change == 0.0 {
        0.0
    } else {
        change / scale.max(f64::MIN_POSITIVE)
    }
}
