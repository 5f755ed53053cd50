//! Where an output frame lies in the case's load history: analysis step, load cycle and
//! time within them.
//!
//! (Interface defined ahead of its implementation: the load-history work fills it in.)

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
