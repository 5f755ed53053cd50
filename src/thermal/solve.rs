//! The solve of the conduction system: prescribed temperatures, sparse Cholesky (faer) for
//! the free ones, and the heat flows of the supports (reactions and films), sources and joints.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::LltError;
use faer::sparse::{FaerError, SparseColMat, Triplet};
use faer::{Mat, Side};

use super::assembly::System;
use super::{Conduction, HeatSolution, ThermalCondition};
use crate::contact::InterfaceState;
use crate::element::set::{ContinuumSet, InterfaceSet};
use crate::{Error, Result};

impl Conduction {
    /// The steady temperature with the supports' and sources' values scaled by
    /// `multiplier(amplitude)`, the joints conducting according to the interface `states`.
    pub fn solve(
        &self,
        continuum: &ContinuumSet,
        interface: &InterfaceSet,
        states: &[InterfaceState],
        multiplier: impl Fn(usize) -> f64,
    ) -> Result<HeatSolution> {
        let mut system = System::new(self.nodes.len());
        self.add_cells(continuum, &multiplier, &mut system);
        self.add_supports(&multiplier, &mut system);
        self.add_joints(interface, states, &mut system);
        self.hold_cut_off_regions(continuum, &mut system)?;
        let mut t = vec![0.0; self.nodes.len()];
        for (i, f) in self.fixed.iter().enumerate() {
            if let Some(s) = f {
                let support = &self.supports[*s as usize];
                if let ThermalCondition::Temperature(v) = support.condition {
                    t[i] = v * multiplier(support.amplitude);
                }
            }
        }
        self.solve_free(&system, &mut t)?;
        // The heat a temperature support lets in is its nodes' reaction K T − f.
        let mut reaction: Vec<f64> = system.f.iter().map(|f| -f).collect();
        for &(i, j, v) in &system.entries {
            reaction[i as usize] += v * t[j as usize];
        }
        let mut supports = system.boundary_heat;
        for (i, f) in self.fixed.iter().enumerate() {
            if let Some(s) = f {
                supports[*s as usize] += reaction[i];
            }
        }
        // The joints' heat from the solved temperatures.
        let mut nodal = vec![0.0; self.index.len()];
        for (i, &n) in self.nodes.iter().enumerate() {
            nodal[n as usize] = t[i];
        }
        let mut joints = vec![0.0; self.joints.len()];
        self.for_joint_points(interface, states, &nodal, |at| {
            joints[at.pair] += at.point.flux * at.da;
        });
        Ok(HeatSolution {
            nodal,
            supports: supports
                .iter()
                .zip(&self.supports)
                .map(|(q, s)| match s.condition {
                    ThermalCondition::Film { h, ambient } => {
                        q + self.film_heat(s, h, ambient * multiplier(s.amplitude), &t)
                    }
                    _ => *q,
                })
                .collect(),
            sources: system.source_heat,
            joints,
        })
    }

    /// Solves for the free temperatures in `t` (conduction indices; the fixed ones given).
    fn solve_free(&self, system: &System, t: &mut [f64]) -> Result<()> {
        if self.free == 0 {
            return Ok(());
        }
        let mut rhs = vec![0.0; self.free];
        let mut triplets = Vec::with_capacity(system.entries.len());
        for &(i, j, v) in &system.entries {
            let (Some(ei), ej) = (self.equation[i as usize], self.equation[j as usize]) else {
                continue;
            };
            match ej {
                Some(ej) if ei >= ej => {
                    triplets.push(Triplet::new(ei as usize, ej as usize, v));
                }
                Some(_) => {}
                None => rhs[ei as usize] -= v * t[j as usize],
            }
        }
        for (i, e) in self.equation.iter().enumerate() {
            if let Some(e) = e {
                rhs[*e as usize] += system.f[i];
            }
        }
        let matrix =
            SparseColMat::<usize, f64>::try_new_from_triplets(self.free, self.free, &triplets)
                .map_err(|e| {
                    Error::Conduction(format!("cannot build the conductivity matrix: {e:?}"))
                })?;
        let llt = matrix
            .sp_cholesky(Side::Lower)
            .map_err(|e| factor_error(e, self.free))?;
        let mut x = Mat::from_fn(self.free, 1, |i, _| rhs[i]);
        llt.solve_in_place(x.as_mut());
        for (i, e) in self.equation.iter().enumerate() {
            if let Some(e) = e {
                t[i] = x[(*e as usize, 0)];
            }
        }
        if t.iter().any(|v| !v.is_finite()) {
            return Err(Error::Conduction(
                "the temperature is not finite: the conductivity matrix is singular".into(),
            ));
        }
        Ok(())
    }
}

/// The error of the conductivity matrix's Cholesky factorisation (`free` unknowns): a failed
/// allocation is the model's size (exit code 3, as the mechanical solver's), anything else a
/// matrix that is not positive definite.
fn factor_error(e: LltError, free: usize) -> Error {
    match e {
        LltError::Generic(FaerError::OutOfMemory) => {
            Error::allocation_failed("the Cholesky factor of the heat conduction", free)
        }
        e => Error::Conduction(format!(
            "the conductivity matrix is not positive definite ({e:?}): does every conducting \
             body have a temperature support or a film, directly or through a closed joint?"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_allocation_of_the_factor_is_memory_not_definiteness() {
        let memory = factor_error(LltError::Generic(FaerError::OutOfMemory), 7);
        assert!(
            matches!(memory, Error::AllocationFailed { unknowns: 7, .. }),
            "{memory}"
        );
        assert_eq!(memory.exit_code(), 3);
        let other = factor_error(LltError::Generic(FaerError::IndexOverflow), 7);
        assert!(matches!(other, Error::Conduction(_)), "{other}");
    }
}
