//! The floor of a run (issue 29): the time no run of the method can go below on its model and
//! machine — reading the mesh, one assembly, one factorisation, one solve per increment and
//! writing the frames, and with conducting bodies one factorisation of the conduction and one
//! conduction solve per increment ([`ConductionWork`]) — measured in the run itself, and the
//! run's ratio to it.
//!
//! The Newton solver tallies its work by kind ([`SolverWork`]: element loops with and
//! without the tangent, interface loops, K·u products, factorisations of the bulk and of the
//! interface system, solves); the drivers add the increments and frames ([`Work`]); the run
//! turns them into its [`Floor`], written to `summary.json` (documented in
//! `docs/guide/outputs.md`, "The floor of a run").
//!
//! Everything here is what the process measured itself: not kept in a restart record, so a
//! resumed run's floor is that of the part it ran, as its `seconds.total` is.

use serde::Serialize;

use crate::solver::conduction::ConductionWork;

/// The calls of one kind of work: how many, their seconds in all, and the first call's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tally {
    pub calls: usize,
    pub seconds: f64,
    /// Seconds of the first call (0 without calls).
    pub first: f64,
}

impl Tally {
    /// Records a call that took `seconds`.
    pub fn add(&mut self, seconds: f64) {
        if self.calls == 0 {
            self.first = seconds;
        }
        self.calls += 1;
        self.seconds += seconds;
    }

    /// Records the time since `start` as a call.
    pub fn since(&mut self, start: std::time::Instant) {
        self.add(start.elapsed().as_secs_f64());
    }

    /// Mean seconds per call (0 without calls).
    pub fn mean(&self) -> f64 {
        if self.calls == 0 {
            0.0
        } else {
            self.seconds / self.calls as f64
        }
    }
}

/// The Newton solver's work by kind, over the life of the solver (every increment, attempt
/// and thermal exchange it solved). Wall-clock seconds of the calls themselves, each inside
/// the phase `summary.json` `seconds` counts it in.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolverWork {
    /// Element loops that evaluate the tangent: over the continuum on the condensed path
    /// (there, for a linear bulk, once, for the factored free block and, from the supports'
    /// cells, the entries in prescribed rows and columns that K·u also needs),
    /// over the whole model otherwise (its interface elements included). Matrix zeroing
    /// included.
    pub tangent_assemblies: Tally,
    /// The same loops for the internal force alone (a line search's steps shorter than the
    /// full one, whose trial is a tangent loop; a resumed run's states left out of its
    /// record).
    pub force_assemblies: Tally,
    /// Linear bulk, whose force is K·u (K·u − G·ΔT under a temperature field): the loops that
    /// evaluate point states alone (no force, no matrix) other than a frame's — the exact
    /// strain increment of an increment whose bound exceeds the plausibility limit, and
    /// under a temperature field the states of each converged increment (its energy terms).
    pub state_evaluations: Tally,
    /// The same loops making the point states of a converged state that a frame's fields
    /// read (its increments evaluate none: their force is K·u). Part of the frame's output
    /// time ([`Work::frames`]).
    pub frame_states: Tally,
    /// Condensed path: the interface elements' loops with their tangent, and for the
    /// internal force alone.
    pub interface_tangent_assemblies: Tally,
    pub interface_force_assemblies: Tally,
    /// Linear bulk on the condensed path: the continuum's internal force as K·u, under a
    /// temperature field K·u − G·ΔT and the G·ΔT of each Newton solve's temperatures.
    pub products: Tally,
    /// Residual evaluations of line searches (also counted by the kinds above).
    pub line_search_evaluations: usize,
    /// Numeric factorisations: of the bulk on the condensed path, of the whole tangent
    /// otherwise (the symbolic analysis of the first one left out).
    pub factorisations: Tally,
    /// Condensed path: calls that kept the last bulk factorisation (the scaled change of the
    /// bulk matrix below the reuse threshold), with the time the check took.
    pub kept_factorisations: Tally,
    /// Condensed path: dense LU factorisations of the interface system, and the calls that
    /// kept the last one (the interface tangent and S_c unchanged, bit for bit), with the
    /// time the check took.
    pub interface_factorisations: Tally,
    pub kept_interface_factorisations: Tally,
    /// Condensed path: interface iterations, the steps beyond a Newton iteration's first
    /// (each after an interface LU, counted above).
    pub interface_iterations: usize,
    /// Linear solves with a factored tangent, and BiCGSTAB solves.
    pub solves: Tally,
}

/// What a run (its part since a resume) did: the solver's work, its converged increments
/// and the frames it wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Work {
    pub solver: SolverWork,
    /// Converged increments (sub-increments of a cut-back and the re-equilibrium after a
    /// wear jump included).
    pub increments: usize,
    /// Frames written and the seconds spent writing (the last wait for the writer thread
    /// included, with no frame; a linear bulk's point states made for a frame's fields,
    /// [`SolverWork::frame_states`], included).
    pub frames: Tally,
    /// The heat conduction's factorisation and solves.
    pub conduction: ConductionWork,
}

/// A run's floor and its ratio to it, as written to `summary.json` (`"floor"`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Floor {
    /// The floor: the sum of `parts`.
    pub seconds: f64,
    /// The run without gmsh (`seconds.total` − `seconds.gmsh`) over the floor; `null` for a
    /// floor of zero.
    pub ratio: Option<f64>,
    pub parts: FloorParts,
    pub counts: FloorCounts,
    /// The seconds of the calls `counts` counts: where a run's time beyond its floor went.
    pub work_seconds: WorkSeconds,
}

/// The terms of the floor (seconds).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FloorParts {
    /// Reading the mesh: the mesh phase without gmsh.
    pub mesh: f64,
    /// One assembly: the run's first tangent assembly (on the condensed path the bulk's
    /// first and the interface's first), the one that evaluates every element.
    pub assembly: f64,
    /// One factorisation: the mean numeric factorisation (on the condensed path the mean
    /// bulk factorisation plus the mean interface LU).
    pub factorisation: f64,
    /// One mean solve per converged increment (at most as many as the run did).
    pub solves: f64,
    /// Writing the frames: all of the run's output time, the point states a frame's fields
    /// need included.
    pub output: f64,
    /// Heat conduction: its one factorisation and one mean solve per converged increment
    /// (at most as many as the run did; 0 without conducting bodies).
    pub conduction: f64,
}

/// The counts the floor is made from ([`SolverWork`], [`Work`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FloorCounts {
    pub increments: usize,
    pub frames: usize,
    pub assemblies: usize,
    pub force_assemblies: usize,
    pub state_evaluations: usize,
    pub frame_states: usize,
    pub interface_assemblies: usize,
    pub interface_force_assemblies: usize,
    pub products: usize,
    pub line_search_evaluations: usize,
    pub factorisations: usize,
    pub kept_factorisations: usize,
    pub interface_factorisations: usize,
    pub kept_interface_factorisations: usize,
    pub interface_iterations: usize,
    pub solves: usize,
    pub conduction_factorisations: usize,
    pub conduction_solves: usize,
}

impl Floor {
    /// The floor of a run that did `work`, read its mesh in `mesh_seconds` (gmsh left out)
    /// and took `run_seconds` in all (gmsh left out).
    ///
    /// Each part is the time of calls the run made, measured on intervals of the run that do
    /// not overlap (one call of a kind never costs more than all of them), so the floor
    /// never exceeds the run and the ratio is at least 1.
    pub fn new(work: &Work, mesh_seconds: f64, run_seconds: f64) -> Self {
        let s = &work.solver;
        let c = &work.conduction;
        let parts = FloorParts {
            mesh: mesh_seconds,
            assembly: s.tangent_assemblies.first + s.interface_tangent_assemblies.first,
            factorisation: s.factorisations.mean() + s.interface_factorisations.mean(),
            solves: per_increment(&s.solves, work.increments),
            output: work.frames.seconds,
            conduction: c.factorisation.seconds + per_increment(&c.solves, work.increments),
        };
        let seconds = parts.mesh
            + parts.assembly
            + parts.factorisation
            + parts.solves
            + parts.output
            + parts.conduction;
        Self {
            seconds,
            ratio: (seconds > 0.0).then(|| run_seconds / seconds),
            parts,
            counts: FloorCounts {
                increments: work.increments,
                frames: work.frames.calls,
                assemblies: s.tangent_assemblies.calls,
                force_assemblies: s.force_assemblies.calls,
                state_evaluations: s.state_evaluations.calls,
                frame_states: s.frame_states.calls,
                interface_assemblies: s.interface_tangent_assemblies.calls,
                interface_force_assemblies: s.interface_force_assemblies.calls,
                products: s.products.calls,
                line_search_evaluations: s.line_search_evaluations,
                factorisations: s.factorisations.calls,
                kept_factorisations: s.kept_factorisations.calls,
                interface_factorisations: s.interface_factorisations.calls,
                kept_interface_factorisations: s.kept_interface_factorisations.calls,
                interface_iterations: s.interface_iterations,
                solves: s.solves.calls,
                conduction_factorisations: c.factorisation.calls,
                conduction_solves: c.solves.calls,
            },
            work_seconds: WorkSeconds::of(work),
        }
    }
}

/// The seconds of one mean call of `tally` per increment of `increments`, at most all of its
/// calls: their sum itself when there were no more calls than increments (not
/// n × (sum / n), which can round above it).
fn per_increment(tally: &Tally, increments: usize) -> f64 {
    let calls = increments.min(tally.calls);
    if calls == tally.calls {
        tally.seconds
    } else {
        calls as f64 * tally.mean()
    }
}

/// Wall-clock seconds of each kind of call [`FloorCounts`] counts (all of them, the floor's
/// own included), under the same names.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WorkSeconds {
    pub frames: f64,
    pub assemblies: f64,
    pub force_assemblies: f64,
    pub state_evaluations: f64,
    pub frame_states: f64,
    pub interface_assemblies: f64,
    pub interface_force_assemblies: f64,
    pub products: f64,
    pub factorisations: f64,
    pub kept_factorisations: f64,
    pub interface_factorisations: f64,
    pub kept_interface_factorisations: f64,
    pub solves: f64,
    pub conduction_factorisations: f64,
    pub conduction_solves: f64,
}

impl WorkSeconds {
    fn of(work: &Work) -> Self {
        let s = &work.solver;
        Self {
            frames: work.frames.seconds,
            assemblies: s.tangent_assemblies.seconds,
            force_assemblies: s.force_assemblies.seconds,
            state_evaluations: s.state_evaluations.seconds,
            frame_states: s.frame_states.seconds,
            interface_assemblies: s.interface_tangent_assemblies.seconds,
            interface_force_assemblies: s.interface_force_assemblies.seconds,
            products: s.products.seconds,
            factorisations: s.factorisations.seconds,
            kept_factorisations: s.kept_factorisations.seconds,
            interface_factorisations: s.interface_factorisations.seconds,
            kept_interface_factorisations: s.kept_interface_factorisations.seconds,
            solves: s.solves.seconds,
            conduction_factorisations: work.conduction.factorisation.seconds,
            conduction_solves: work.conduction.solves.seconds,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tally(calls: &[f64]) -> Tally {
        let mut t = Tally::default();
        calls.iter().for_each(|&s| t.add(s));
        t
    }

    #[test]
    fn the_floor_takes_one_call_of_each_kind_and_one_solve_per_increment() {
        let work = Work {
            solver: SolverWork {
                tangent_assemblies: tally(&[0.5, 0.25, 0.25]),
                interface_tangent_assemblies: tally(&[0.125, 0.375]),
                factorisations: tally(&[1.0, 3.0]),
                interface_factorisations: tally(&[0.5, 0.5, 0.5]),
                solves: tally(&[0.25, 0.5, 0.75]),
                ..SolverWork::default()
            },
            increments: 2,
            frames: tally(&[0.5, 0.25]),
            conduction: ConductionWork {
                factorisation: tally(&[2.0]),
                solves: tally(&[0.25, 0.25, 0.25]),
            },
        };
        let floor = Floor::new(&work, 1.0, 16.0);
        // 1 + (0.5 + 0.125) + (2 + 0.5) + 2 × 0.5 + 0.75 + (2 + 2 × 0.25)
        assert_eq!(floor.parts.assembly, 0.625);
        assert_eq!(floor.parts.factorisation, 2.5);
        assert_eq!(floor.parts.solves, 1.0);
        assert_eq!(floor.parts.conduction, 2.5);
        assert_eq!(floor.seconds, 8.375);
        assert_eq!(floor.ratio, Some(16.0 / 8.375));
        assert_eq!(floor.counts.conduction_solves, 3);
        assert_eq!(floor.work_seconds.conduction_solves, 0.75);
        assert_eq!((floor.counts.assemblies, floor.counts.solves), (3, 3));
        assert_eq!(floor.work_seconds.assemblies, 1.0);
        assert_eq!(floor.work_seconds.interface_factorisations, 1.5);
        assert_eq!(
            (floor.work_seconds.solves, floor.work_seconds.frames),
            (1.5, 0.75)
        );
    }

    #[test]
    fn increments_without_a_solve_add_none_and_an_empty_floor_has_no_ratio() {
        let work = Work {
            solver: SolverWork {
                solves: tally(&[0.5]),
                ..SolverWork::default()
            },
            increments: 3,
            ..Work::default()
        };
        assert_eq!(Floor::new(&work, 0.0, 1.0).parts.solves, 0.5);
        assert_eq!(Floor::new(&Work::default(), 0.0, 1.0).ratio, None);
    }
}
