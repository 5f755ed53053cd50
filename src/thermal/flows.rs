//! The heat flows of a solved conduction: through the supports (the reactions of the
//! prescribed temperatures, the films' convection, the fluxes), from the sources and across
//! the joints.

use super::{Conduction, HeatLoad, HeatSolution, ThermalCondition};
use crate::contact::InterfaceState;
use crate::element::set::InterfaceSet;

impl Conduction {
    /// The solution of temperatures `t` (conduction indices) solved under `load` with the
    /// supports' values scaled by `multiplier(amplitude)` and the joints in the contact
    /// `states`; `reaction` is K T − f at the prescribed nodes (the heat a temperature
    /// support lets in there; other entries are not read).
    pub fn heat_solution(
        &self,
        interface: &InterfaceSet,
        states: &[InterfaceState],
        multiplier: &impl Fn(usize) -> f64,
        t: &[f64],
        reaction: &[f64],
        load: HeatLoad,
    ) -> HeatSolution {
        let mut supports = load.boundary_heat;
        for (f, r) in self.fixed.iter().zip(reaction) {
            if let Some(s) = f {
                supports[*s as usize] += r;
            }
        }
        for (q, s) in supports.iter_mut().zip(&self.supports) {
            if let ThermalCondition::Film { h, ambient } = s.condition {
                *q += self.film_heat(s, h, ambient * multiplier(s.amplitude), t);
            }
        }
        let mut nodal = vec![0.0; self.index.len()];
        for (&n, &ti) in self.nodes.iter().zip(t) {
            nodal[n as usize] = ti;
        }
        let mut joints = vec![0.0; self.joints.len()];
        self.for_joint_points(interface, states, &nodal, |at| {
            joints[at.pair] += at.point.flux * at.da;
        });
        HeatSolution {
            nodal,
            supports,
            sources: load.source_heat,
            joints,
        }
    }
}
