//! The mechanical problem of a model as the Newton loop sees it: internal forces and the
//! tangent of bodies and interfaces at given displacements, and the preconditioner matrix of
//! unsymmetric solves.

use crate::assembly::GlobalSystem;
use crate::contact::{ContactAlgorithm, InterfaceState};
use crate::element::interface6::evaluate_interface;
use crate::element::set::{ElementSet, INTERFACE_POINTS, InterfaceSet};
use crate::element::{ElementMatrix, ElementVector};
use crate::material::PointState;
use crate::model::Model;
use crate::solver::newton::Problem;

/// The interface elements seen as the difference between their elastic-tangent matrix and
/// their consistent one, K_elastic − K_consistent. Added to the consistent global tangent it
/// gives the tangent with the elastic contact matrix (paper conclusion 3): symmetric positive
/// definite, used as the preconditioner of unsymmetric solves. Internal forces are zero.
#[derive(Debug)]
pub struct ElasticContactCorrection<'a>(pub &'a InterfaceSet);

impl ElementSet for ElasticContactCorrection<'_> {
    type State = InterfaceState;

    fn len(&self) -> usize {
        self.0.len()
    }

    fn nodes(&self, e: usize) -> &[u32] {
        self.0.nodes(e)
    }

    fn points_per_element(&self) -> usize {
        INTERFACE_POINTS
    }

    fn evaluate(
        &self,
        e: usize,
        u: &ElementVector,
        committed: &[InterfaceState],
        trial: &mut [InterfaceState],
        k: Option<&mut ElementMatrix>,
        f: &mut ElementVector,
    ) {
        let Some(k) = k else { return };
        let set = self.0;
        let element = &set.elements[e];
        let pair = &set.pairs[element.pair as usize];
        let law = pair.law.as_ref();
        let mut consistent = ElementMatrix::zeros();
        let mut elastic = ElementMatrix::zeros();
        let mut scratch = ElementVector::zeros();
        let analysis = &set.analysis;
        evaluate_interface(
            analysis,
            element,
            pair.interference,
            law,
            set.algorithm,
            u,
            committed,
            trial,
            Some(&mut consistent),
            &mut scratch,
        );
        evaluate_interface(
            analysis,
            element,
            pair.interference,
            law,
            ContactAlgorithm::ElasticContact,
            u,
            committed,
            trial,
            Some(&mut elastic),
            &mut scratch,
        );
        *k += elastic - consistent;
        f.fill(0.0);
    }
}

/// The mechanical problem of a model: bodies and interfaces, with their states.
pub(crate) struct Mechanics<'a> {
    pub(crate) model: &'a Model,
    pub(crate) committed: &'a [PointState],
    pub(crate) trial: &'a mut [PointState],
    pub(crate) interface_committed: &'a [InterfaceState],
    pub(crate) interface_trial: &'a mut [InterfaceState],
}

impl Problem for Mechanics<'_> {
    fn assemble(&mut self, u: &[f64], system: &mut GlobalSystem, with_tangent: bool) -> bool {
        let m = self.model;
        system.assemble(
            &m.continuum,
            &m.continuum_coloring,
            &m.dofs,
            u,
            self.committed,
            self.trial,
            with_tangent,
        );
        let (ic, it) = (self.interface_committed, &mut *self.interface_trial);
        system.assemble(
            &m.interface,
            &m.interface_coloring,
            &m.dofs,
            u,
            ic,
            it,
            with_tangent,
        );
        // Each point records whether the interface tangent it contributed was unsymmetric
        // (only the consistent tangent of the Newton algorithm can be).
        let symmetric = !self
            .interface_trial
            .iter()
            .any(InterfaceState::has_unsymmetric_tangent);
        if with_tangent && !symmetric {
            // Preconditioner: the tangent with the elastic contact matrix (paper conclusion 3).
            system.preconditioner.clone_from(&system.values);
            let mut scratch = self.interface_trial.to_vec();
            let mut target = std::mem::take(&mut system.preconditioner);
            let correction = ElasticContactCorrection(&m.interface);
            system.assemble_matrix_into(
                &correction,
                &m.interface_coloring,
                &m.dofs,
                u,
                ic,
                &mut scratch,
                &mut target,
            );
            system.preconditioner = target;
        }
        symmetric
    }
}
