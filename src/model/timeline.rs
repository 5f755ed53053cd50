//! Where an output frame lies in the case's load history: analysis step, load cycle and
//! time within them.
//!
//! The solver runs in a pseudo-time τ in which output increment j (1-based, over all steps
//! and simulated cycles) ends at τ = j. Analysis step k takes `increments` × simulated
//! cycles output increments; within a cycle the local time u ∈ [0, increments] is the step
//! time (fraction of the step, or of one cycle) times `increments`. A point on a boundary
//! belongs to what ends there (the step whose last increment ends at τ, the cycle that ends
//! at τ), as a converged state belongs to the increment that reached it. The simple
//! `[steps]` schedule is one non-cyclic step of `count` (or `factors.len()`) increments.

/// The position of a converged increment (an output frame) in the load history.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frame {
    /// 1-based analysis step (`[[step]]`); 1 for a case with a `[steps]` schedule.
    pub analysis_step: usize,
    /// 1-based simulated cycle within the step (1 in a non-cyclic step).
    pub cycle: usize,
    /// Load cycles of the step completed when this frame's cycle ends, counting the cycles
    /// a wear jump stands for.
    pub cycles: f64,
    /// Time within the step, or within the cycle in a cyclic step, in [0, 1].
    pub step_time: f64,
    /// Whether this frame ends its cycle (or its step).
    pub cycle_end: bool,
}

/// One analysis step as it is simulated.
#[derive(Clone, Debug, PartialEq)]
pub struct StepPlan {
    /// Name used in output.
    pub name: String,
    /// Output increments per (simulated) cycle.
    pub increments: usize,
    /// Load cycles the step stands for (1: not cyclic).
    pub cycles: usize,
    /// Cycles one simulated cycle stands for (cycle jumping).
    pub cycles_per_jump: usize,
    /// Output increments of the steps before this one.
    pub first: usize,
}

impl StepPlan {
    /// A step of `increments` output increments and `cycles` load cycles of which every
    /// `cycles_per_jump`-th is simulated (both ≥ 1).
    pub fn new(name: String, increments: usize, cycles: usize, cycles_per_jump: usize) -> Self {
        Self {
            name,
            increments: increments.max(1),
            cycles: cycles.max(1),
            cycles_per_jump: cycles_per_jump.clamp(1, cycles.max(1)),
            first: 0,
        }
    }

    /// Simulated cycles: the first cycle on its own (the transient from the previous step's
    /// state, which the later cycles do not repeat), then one per `cycles_per_jump` of the
    /// rest: 1 + ceil((cycles − 1) / cycles_per_jump).
    pub fn simulated(&self) -> usize {
        1 + (self.cycles - 1).div_ceil(self.cycles_per_jump)
    }

    /// Output increments of the step.
    pub fn frames(&self) -> usize {
        self.increments * self.simulated()
    }

    /// Whether the step repeats its amplitudes.
    pub fn is_cyclic(&self) -> bool {
        self.cycles > 1
    }

    /// Load cycles simulated cycle `cycle` (1-based) stands for: 1 for the first,
    /// `cycles_per_jump` for the next ones, the remainder for the last.
    pub fn jump(&self, cycle: usize) -> usize {
        if cycle <= 1 {
            1
        } else if cycle < self.simulated() {
            self.cycles_per_jump
        } else {
            self.cycles - self.cycles_done(cycle - 1)
        }
    }

    /// Load cycles completed when simulated cycle `cycle` ends.
    pub fn cycles_done(&self, cycle: usize) -> usize {
        match cycle {
            0 => 0,
            c => (c - 1)
                .saturating_mul(self.cycles_per_jump)
                .saturating_add(1)
                .min(self.cycles),
        }
    }
}

/// A point of pseudo-time in the steps: step index (0-based), simulated cycle (1-based) and
/// local time u ∈ [0, increments] within the cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Position {
    pub step: usize,
    pub cycle: usize,
    pub u: f64,
}

/// An output increment: step index (0-based), simulated cycle and increment within the
/// cycle (both 1-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Increment {
    pub step: usize,
    pub cycle: usize,
    pub index: usize,
}

/// The analysis steps of a case in sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct Timeline {
    steps: Vec<StepPlan>,
}

impl Timeline {
    /// The steps in order (their `first` is set here); at least one.
    pub fn new(mut steps: Vec<StepPlan>) -> Self {
        if steps.is_empty() {
            steps.push(StepPlan::new("step-1".into(), 1, 1, 1));
        }
        let mut first = 0;
        for s in &mut steps {
            s.first = first;
            first += s.frames();
        }
        Self { steps }
    }

    /// The analysis steps.
    pub fn steps(&self) -> &[StepPlan] {
        &self.steps
    }

    /// Output increments of all steps (every simulated increment).
    pub fn frames(&self) -> usize {
        self.steps.last().map_or(0, |s| s.first + s.frames())
    }

    /// Where pseudo-time `time` lies (clamped to the steps; see the module docs).
    pub fn locate(&self, time: f64) -> Position {
        let end = |s: &StepPlan| (s.first + s.frames()) as f64;
        let step = self
            .steps
            .partition_point(|s| end(s) < time)
            .min(self.steps.len() - 1);
        let plan = &self.steps[step];
        let local = time - plan.first as f64;
        let n = plan.increments as f64;
        let cycle = ((local / n).ceil().max(1.0) as usize).min(plan.simulated());
        Position {
            step,
            cycle,
            u: local - (cycle - 1) as f64 * n,
        }
    }

    /// Output increment `j` (1-based, at most [`Self::frames`]).
    pub fn increment(&self, j: usize) -> Increment {
        let step = self
            .steps
            .partition_point(|s| s.first + s.frames() < j)
            .min(self.steps.len() - 1);
        let plan = &self.steps[step];
        let local = j.saturating_sub(plan.first + 1);
        Increment {
            step,
            cycle: local / plan.increments + 1,
            index: local % plan.increments + 1,
        }
    }

    /// The frame of the state at pseudo-time `time` (an output increment's end, or a
    /// sub-increment's).
    pub fn frame(&self, time: f64) -> Frame {
        let p = self.locate(time);
        let plan = &self.steps[p.step];
        let n = plan.increments as f64;
        Frame {
            analysis_step: p.step + 1,
            cycle: p.cycle,
            cycles: plan.cycles_done(p.cycle) as f64,
            step_time: (p.u / n).clamp(0.0, 1.0),
            cycle_end: p.u >= n,
        }
    }

    /// Whether output increment `j` is the first of its step or cycle.
    pub fn starts_cycle(&self, j: usize) -> bool {
        self.increment(j).index == 1
    }

    /// The load cycles the cycle ending with output increment `j` stands for, if `j` ends
    /// a cycle (or a non-cyclic step).
    pub fn ends_cycle(&self, j: usize) -> Option<usize> {
        let i = self.increment(j);
        let plan = &self.steps[i.step];
        (i.index == plan.increments).then(|| plan.jump(i.cycle))
    }

    /// Whether output increment `j` gets field output when only cycle ends are wanted:
    /// every increment of a non-cyclic step and of the first and last simulated cycle of a
    /// cyclic one, and the last increment of every other cycle.
    pub fn is_end_frame(&self, j: usize) -> bool {
        let i = self.increment(j);
        let plan = &self.steps[i.step];
        !plan.is_cyclic()
            || i.cycle == 1
            || i.cycle == plan.simulated()
            || i.index == plan.increments
    }

    /// Total analysis time at pseudo-time `time`: step k (1-based) runs from k − 1 to k,
    /// its simulated cycles dividing it equally.
    pub fn analysis_time(&self, time: f64) -> f64 {
        let p = self.locate(time);
        let plan = &self.steps[p.step];
        let local = time - plan.first as f64;
        p.step as f64 + (local / plan.frames() as f64).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timeline() -> Timeline {
        Timeline::new(vec![
            StepPlan::new("press".into(), 2, 1, 1),
            StepPlan::new("service".into(), 4, 10, 3),
        ])
    }

    #[test]
    fn a_cyclic_step_simulates_its_first_cycle_then_one_per_jump() {
        let t = timeline();
        let service = &t.steps()[1];
        assert_eq!((service.simulated(), service.first), (4, 2));
        assert_eq!(t.frames(), 2 + 16);
        // 1 + 3 + 3 + 3: the first cycle on its own, the last standing for the remainder.
        let jumps: Vec<usize> = (1..=4).map(|c| service.jump(c)).collect();
        assert_eq!(jumps, [1, 3, 3, 3]);
        let done: Vec<usize> = (1..=4).map(|c| service.cycles_done(c)).collect();
        assert_eq!(done, [1, 4, 7, 10]);
        assert_eq!(jumps.iter().sum::<usize>(), service.cycles);
        assert_eq!(service.cycles_done(4), 10);
    }

    #[test]
    fn increments_and_pseudo_times_map_to_steps_and_cycles() {
        let t = timeline();
        let i = t.increment(2);
        assert_eq!((i.step, i.cycle, i.index), (0, 1, 2));
        let i = t.increment(7);
        assert_eq!((i.step, i.cycle, i.index), (1, 2, 1));
        assert!(t.starts_cycle(7) && t.starts_cycle(3) && !t.starts_cycle(8));
        assert_eq!(t.ends_cycle(2), Some(1));
        assert_eq!(t.ends_cycle(10), Some(3));
        assert_eq!(t.ends_cycle(6), Some(1));
        assert_eq!(t.ends_cycle(18), Some(3));
        assert_eq!(t.ends_cycle(9), None);
        // A boundary belongs to what ends there.
        let p = t.locate(6.0);
        assert_eq!((p.step, p.cycle, p.u), (1, 1, 4.0));
        let p = t.locate(6.5);
        assert_eq!((p.step, p.cycle, p.u), (1, 2, 0.5));
        let f = t.frame(8.0);
        assert_eq!((f.analysis_step, f.cycle, f.cycles), (2, 2, 4.0));
        assert_eq!((f.step_time, f.cycle_end), (0.5, false));
        assert!(t.frame(10.0).cycle_end);
        assert_eq!(t.analysis_time(2.0), 1.0);
        assert_eq!(t.analysis_time(10.0), 1.5);
        assert_eq!(t.analysis_time(18.0), 2.0);
    }

    #[test]
    fn field_output_at_cycle_ends_keeps_the_first_and_last_cycle_whole() {
        let t = timeline();
        let kept: Vec<usize> = (1..=t.frames()).filter(|&j| t.is_end_frame(j)).collect();
        assert_eq!(kept, [1, 2, 3, 4, 5, 6, 10, 14, 15, 16, 17, 18]);
    }
}
