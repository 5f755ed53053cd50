//! Scheduling of study levels: at most `jobs` at once, within a memory budget.

use std::sync::{Condvar, Mutex};

/// Memory estimate per unknown for scheduling levels. Measured peak resident memory of whole
/// runs: 2.7 kB per unknown (flat punch, 7·10⁵ unknowns: 1.9 GB; tapered joint with friction,
/// 9·10⁴ unknowns: 0.26 GB), most of it the Cholesky factor (BENCHMARKS.md); 4 kB leaves a
/// margin for the slower-than-linear growth of the fill.
pub const BYTES_PER_UNKNOWN: u64 = 4096;

/// The levels running at once: at most `jobs` of them, and their memory estimates within a
/// budget. Levels acquire it one after another from the thread that schedules them (finest
/// first), so the order is the caller's.
pub(super) struct Gate {
    budget: u64,
    jobs: usize,
    /// (free memory, running levels).
    state: Mutex<(u64, usize)>,
    changed: Condvar,
}

/// A running level's share of the [`Gate`], returned when dropped.
pub(super) struct Permit<'a> {
    gate: &'a Gate,
    amount: u64,
}

impl Gate {
    pub(super) fn new(budget: u64, jobs: usize) -> Self {
        Self {
            budget,
            jobs: jobs.max(1),
            state: Mutex::new((budget, 0)),
            changed: Condvar::new(),
        }
    }

    /// Waits until fewer than `jobs` levels run and `estimate` bytes (at most the whole
    /// budget: then the level runs alone) are free.
    pub(super) fn acquire(&self, level: usize, estimate: u64) -> Permit<'_> {
        let amount = estimate.min(self.budget);
        let mut state = self.state.lock().expect("gate");
        while !(state.0 >= amount && state.1 < self.jobs) {
            if state.0 < amount {
                tracing::info!(
                    "level {level}: waiting for {:.0} MB of memory ({:.0} MB free in the budget)",
                    amount as f64 / 1e6,
                    state.0 as f64 / 1e6
                );
            }
            state = self.changed.wait(state).expect("gate");
        }
        state.0 -= amount;
        state.1 += 1;
        Permit { gate: self, amount }
    }
}

impl Drop for Permit<'_> {
    fn drop(&mut self) {
        let mut state = self.gate.state.lock().expect("gate");
        state.0 += self.amount;
        state.1 -= 1;
        self.gate.changed.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc;
    use std::time::Duration;

    /// Checks that acquiring `(level, estimate)` on another thread waits until `release` has
    /// run, and then succeeds.
    fn waits_until(gate: &Gate, level: usize, estimate: u64, release: impl FnOnce()) {
        std::thread::scope(|s| {
            let (acquired, heard) = mpsc::channel();
            let (_done, hold) = mpsc::channel::<()>();
            s.spawn(move || {
                let _permit = gate.acquire(level, estimate);
                acquired.send(()).unwrap();
                let _ = hold.recv(); // keep the permit until the check is over
            });
            assert!(
                heard.recv_timeout(Duration::from_millis(200)).is_err(),
                "level {level} did not wait"
            );
            release();
            heard
                .recv_timeout(Duration::from_secs(5))
                .expect("acquired once released");
        });
    }

    #[test]
    fn a_level_larger_than_the_budget_runs_alone() {
        let gate = Gate::new(10, 4);
        let big = gate.acquire(3, 100); // more than the budget: takes all of it
        waits_until(&gate, 1, 1, || drop(big));
        // Small levels share the budget.
        let a = gate.acquire(2, 4);
        let b = gate.acquire(1, 5);
        assert_eq!(*gate.state.lock().unwrap(), (1, 2));
        drop((a, b));
        assert_eq!(*gate.state.lock().unwrap(), (10, 0));
    }

    #[test]
    fn no_more_than_jobs_levels_run_at_once() {
        let gate = Gate::new(u64::MAX, 2);
        let a = gate.acquire(3, 1);
        let _b = gate.acquire(2, 1);
        waits_until(&gate, 1, 1, || drop(a));
    }
}
