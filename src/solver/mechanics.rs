//! The mechanical problem of a model as the Newton loop sees it: internal forces and the
//! tangent of bodies and interfaces at given displacements, and the preconditioner matrix of
//! unsymmetric solves.

use faer::MatMut;

use crate::assembly::{
    AssemblyInput, DenseBlock, DenseScatter, DofMap, ElementNodes, GlobalSystem,
    PrescribedCouplings, combine_state_changes, evaluate_states,
};
use crate::contact::{ContactAlgorithm, InterfaceState};
use crate::element::interface6::evaluate_interface;
use crate::element::quadrature::cell_rule;
use crate::element::set::{
    ContinuumInContext, ElementSet, INTERFACE_POINTS, InterfaceSet, InternalLayout,
    TemperatureField,
};
use crate::element::thermal_load::ThermalLoad;
use crate::element::{ElementInput, ElementMatrix, ElementOutput};
use crate::material::{PointState, equivalent_strain};
use crate::model::{Model, continuum_connectivity};
use crate::solver::elastic_cells::ElasticCells;
use crate::solver::energy::largest;
use crate::solver::newton::Problem;
use crate::{Error, Result};

/// The interface elements seen as the difference between their elastic-tangent matrix and
/// the matrix of the iteration's tangent, K_elastic − K_algorithm. Added to the global
/// tangent it gives the tangent with the elastic contact matrix (Buczkowski & Kleiber (1994),
/// conclusion 3): symmetric positive definite, used as the preconditioner of unsymmetric
/// solves. Internal forces are zero, and the trial states are left as the iteration's
/// assembly wrote them: both evaluations write into scratch states of their own.
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

    fn dofs_per_node(&self) -> usize {
        self.0.dofs_per_node()
    }

    fn points_per_element(&self) -> usize {
        INTERFACE_POINTS
    }

    fn evaluate(
        &self,
        e: usize,
        input: &ElementInput<InterfaceState>,
        output: ElementOutput<InterfaceState>,
    ) {
        let Some(k) = output.k else { return };
        let set = self.0;
        let element = &set.elements[e];
        let pair = &set.pairs[element.pair as usize];
        let (analysis, law) = (&set.analysis, pair.law.as_ref());
        let matrix = |algorithm, k: &mut ElementMatrix| {
            let mut scratch = [InterfaceState::default(); INTERFACE_POINTS];
            let output = ElementOutput {
                trial: &mut scratch,
                k: Some(k),
                f: None,
            };
            let input = ElementInput {
                algorithm,
                ..*input
            };
            evaluate_interface(
                analysis,
                element,
                pair.interference,
                law,
                pair.wear(),
                &input,
                output,
            );
        };
        let mut consistent = ElementMatrix::zeros();
        let mut elastic = ElementMatrix::zeros();
        matrix(input.algorithm, &mut consistent);
        matrix(ContactAlgorithm::ElasticContact, &mut elastic);
        *k += elastic - consistent;
        if let Some(f) = output.f {
            f.fill(0.0);
        }
    }
}

/// The mechanical problem of a model: bodies and interfaces, with their states.
#[derive(Debug)]
pub struct Mechanics<'a> {
    pub model: &'a Model,
    /// Continuum states committed at the last converged increment, and of this iteration.
    pub committed: &'a [PointState],
    pub trial: &'a mut [PointState],
    /// Interface states committed at the last converged increment, and of this iteration.
    pub interface_committed: &'a [InterfaceState],
    pub interface_trial: &'a mut [InterfaceState],
    /// The continuum's internal variables (backstresses), committed and of this iteration;
    /// empty when no body has any.
    pub internal_layout: &'a InternalLayout,
    pub internal_committed: &'a [f64],
    pub internal_trial: &'a mut [f64],
    /// The temperature change driving the bodies' thermal strains.
    pub temperature: &'a TemperatureField,
}

impl<'a> Mechanics<'a> {
    /// The bodies in their context (temperatures, internal variables) and their committed
    /// and trial point states.
    fn bodies(&mut self) -> (ContinuumInContext<'_>, &'a [PointState], &mut [PointState]) {
        let bodies = ContinuumInContext::new(
            &self.model.continuum,
            self.temperature,
            self.internal_layout,
            self.internal_committed,
            &mut *self.internal_trial,
        );
        (bodies, self.committed, &mut *self.trial)
    }
}

impl Problem for Mechanics<'_> {
    fn assemble(&mut self, system: &mut GlobalSystem, input: &AssemblyInput) -> bool {
        self.assemble_bulk(system, input, None);
        let m = self.model;
        let (ic, it) = (self.interface_committed, &mut *self.interface_trial);
        system.assemble(input, &m.interface, &m.interface_coloring, ic, it);
        // Each point records whether the interface tangent it contributed was unsymmetric
        // (only the consistent tangent of the Newton algorithm can be).
        let symmetric = !it.iter().any(InterfaceState::has_unsymmetric_tangent);
        if input.tangent && !symmetric {
            // Preconditioner: the tangent with the elastic contact matrix (Buczkowski &
            // Kleiber (1994), conclusion 3).
            let correction = ElasticContactCorrection(&m.interface);
            system.assemble_preconditioner(input, &correction, &m.interface_coloring, ic, it);
        }
        symmetric
    }

    fn interface_dofs(&self) -> Vec<usize> {
        let d = self.model.interface.dofs_per_node();
        let mut dofs: Vec<usize> = (0..self.model.interface.len())
            .flat_map(|e| self.model.interface.nodes(e))
            .flat_map(|&n| (0..d).map(move |c| d * n as usize + c))
            .collect();
        dofs.sort_unstable();
        dofs.dedup();
        dofs
    }

    fn bulk_is_linear(&self) -> bool {
        self.model.continuum.is_linear()
    }

    /// Unsymmetric while a point of a body whose material has an unsymmetric tangent
    /// ([`Material::has_unsymmetric_tangent`](crate::material::Material::has_unsymmetric_tangent)) yields; a model without such a material never
    /// looks at its states.
    fn bulk_is_symmetric(&self) -> bool {
        let continuum = &self.model.continuum;
        let unsymmetric = |body: u32| continuum.materials[body as usize].has_unsymmetric_tangent();
        if !(0..continuum.materials.len() as u32).any(unsymmetric) {
            return true;
        }
        let points = continuum.points_per_element();
        !continuum
            .cells
            .iter()
            .zip(self.trial.chunks_exact(points))
            .any(|(cell, states)| unsymmetric(cell.body) && states.iter().any(|s| s.yielding))
    }

    /// The expanding bodies' G, when the model has temperatures.
    fn thermal_load(&self) -> Result<Option<ThermalLoad>> {
        if !self.model.has_temperature() {
            return Ok(None);
        }
        ThermalLoad::new(&self.model.continuum).map_err(|_| {
            Error::allocation_failed(
                "the bodies' thermal load matrices",
                self.model.dofs.dof_count(),
            )
        })
    }

    fn thermal_force(&self, load: &ThermalLoad, force: &mut [f64]) {
        load.force(&self.model.continuum, self.temperature, force);
    }

    fn interface_scatter(
        &self,
        dofs: &DofMap,
        local: &dyn Fn(usize) -> Option<usize>,
    ) -> DenseScatter {
        DenseScatter::new(&self.model.interface, dofs, local)
    }

    /// A nonlinear (plastic) continuum keeps the sum of its cells' elastic matrices and
    /// evaluates tangents only for cells with a yielding point, and with `elastic` cells
    /// nothing at all of the cells that provably stay elastic
    /// ([`GlobalSystem::assemble_reusing`]); a linear one
    /// is assembled plainly (its stiffness is assembled once per model, and keeping a copy
    /// would only cost memory).
    fn assemble_bulk(
        &mut self,
        system: &mut GlobalSystem,
        input: &AssemblyInput,
        mut elastic: Option<&mut ElasticCells>,
    ) {
        let m = self.model;
        let (bodies, cc, ct) = self.bodies();
        if !bodies.has_history() && m.continuum.is_linear() {
            if input.tangent {
                system.clear_values();
            }
            system.assemble(input, &bodies, &m.continuum_coloring, cc, ct);
            return;
        }
        let left_out = (elastic.as_deref_mut()).and_then(|cells| cells.select(m, input.u));
        system.assemble_reusing(input, &bodies, &m.continuum_coloring, cc, ct, left_out);
        if let Some(cells) = elastic.filter(|cells| !cells.anchored()) {
            cells.anchor(m, cc, ct, input.u);
        }
    }

    fn elastic_cells(&self, dofs: &DofMap) -> Option<ElasticCells> {
        ElasticCells::new(self.model, dofs)
    }

    /// The couplings are those of the cells with a node on a support.
    fn assemble_linear_bulk(
        &mut self,
        system: &mut GlobalSystem,
        input: &AssemblyInput,
    ) -> PrescribedCouplings {
        let m = self.model;
        let continuum = &m.continuum;
        let connectivity: Vec<ElementNodes> = continuum_connectivity(continuum).collect();
        let mut couplings = PrescribedCouplings::new(m.mesh.nodes.len(), input.dofs, &connectivity);
        let (bodies, cc, ct) = self.bodies();
        system.clear_values();
        system.assemble_with_prescribed(
            input,
            &bodies,
            &m.continuum_coloring,
            cc,
            ct,
            Some(&mut couplings),
        );
        couplings
    }

    fn bulk_states(&mut self, input: &AssemblyInput) {
        let (bodies, committed, trial) = self.bodies();
        evaluate_states(input, &bodies, committed, trial);
    }

    fn bulk_strain_increment(&mut self, input: &AssemblyInput, start_u: &[f64]) -> f64 {
        let cells = &self.model.continuum.cells;
        let (bodies, committed, _) = self.bodies();
        // The arithmetic of a pass over stored states ([`crate::solver::energy`]), point by
        // point: ε at the end less ε at the start.
        let change = |e: usize, start: &[PointState], end: &[PointState]| {
            let points = cell_rule(cells[e].kind).len();
            (end.iter().zip(start).take(points))
                .map(|(t, c)| equivalent_strain(&(t.strain - c.strain)))
                .fold(0.0, largest)
        };
        combine_state_changes(input, start_u, &bodies, committed, change, largest)
    }

    fn assemble_interface(
        &mut self,
        system: &mut GlobalSystem,
        input: &AssemblyInput,
        block: MatMut<'_, f64>,
        map: &DenseScatter,
    ) -> bool {
        let m = self.model;
        let (ic, it) = (self.interface_committed, &mut *self.interface_trial);
        system.assemble_dense(
            input,
            &m.interface,
            &m.interface_coloring,
            ic,
            it,
            DenseBlock { values: block, map },
        );
        !it.iter().any(InterfaceState::has_unsymmetric_tangent)
    }
}
