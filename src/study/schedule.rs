//! Scheduling of study levels under a memory budget.

use std::collections::BTreeSet;
use std::sync::{Condvar, Mutex};

/// Memory estimate per unknown for scheduling levels. Measured peak resident memory of whole
/// runs: 2.7 kB per unknown (flat punch, 7·10⁵ unknowns: 1.9 GB; tapered joint with friction,
/// 9·10⁴ unknowns: 0.26 GB), most of it the Cholesky factor (BENCHMARKS.md); 4 kB leaves a
/// margin for the slower-than-linear growth of the fill.
pub const BYTES_PER_UNKNOWN: u64 = 4096;

/// `MemAvailable` of /proc/meminfo in bytes.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// A memory budget shared by the levels running at once; finer levels are served first.
pub(super) struct MemoryGate {
    budget: u64,
    state: Mutex<(u64, BTreeSet<usize>)>,
    changed: Condvar,
}

pub(super) struct Permit<'a> {
    gate: &'a MemoryGate,
    amount: u64,
}

impl MemoryGate {
    pub(super) fn new(budget: u64) -> Self {
        Self {
            budget,
            state: Mutex::new((budget, BTreeSet::new())),
            changed: Condvar::new(),
        }
    }

    /// Waits until `estimate` bytes (at most the whole budget: then the level runs alone) are
    /// free and no finer level is waiting.
    pub(super) fn acquire(&self, level: usize, estimate: u64) -> Permit<'_> {
        let amount = estimate.min(self.budget);
        let mut state = self.state.lock().expect("memory gate");
        state.1.insert(level);
        while !(state.0 >= amount && state.1.last() == Some(&level)) {
            if state.0 < amount {
                tracing::info!(
                    "level {level}: waiting for {:.0} MB of memory ({:.0} MB free in the budget)",
                    amount as f64 / 1e6,
                    state.0 as f64 / 1e6
                );
            }
            state = self.changed.wait(state).expect("memory gate");
        }
        state.1.remove(&level);
        state.0 -= amount;
        self.changed.notify_all();
        Permit { gate: self, amount }
    }
}

impl Drop for Permit<'_> {
    fn drop(&mut self) {
        let mut state = self.gate.state.lock().expect("memory gate");
        state.0 += self.amount;
        self.gate.changed.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc;
    use std::time::Duration;

    #[test]
    fn a_level_larger_than_the_budget_runs_alone() {
        let gate = MemoryGate::new(10);
        let (tx, rx) = mpsc::channel();
        std::thread::scope(|s| {
            let big = gate.acquire(3, 100); // more than the budget: takes all of it
            s.spawn(|| {
                let _small = gate.acquire(1, 1);
                tx.send(()).unwrap();
            });
            assert!(
                rx.recv_timeout(Duration::from_millis(200)).is_err(),
                "ran beside the big level"
            );
            drop(big);
            rx.recv_timeout(Duration::from_secs(5))
                .expect("runs once the big level is done");
        });
        // Small levels share the budget.
        let a = gate.acquire(2, 4);
        let b = gate.acquire(1, 5);
        assert_eq!(gate.state.lock().unwrap().0, 1);
        drop((a, b));
        assert_eq!(gate.state.lock().unwrap().0, 10);
    }
}
