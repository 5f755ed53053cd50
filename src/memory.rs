//! The memory this process may still take: the least of the machine's available memory (the
//! kernel's `MemAvailable`, which counts the page cache the kernel can drop), the free part of
//! the process's cgroup memory limit (a batch job's `--mem`, a container's limit: the kernel
//! kills a process that exceeds it, whatever the machine has free) and its address-space limit
//! (`ulimit -v`) less what it has mapped (an allocation beyond that fails). The solver checks
//! its largest allocations against it before making them; runs side by side are scheduled
//! within it. Imports nothing of the crate.

use sysinfo::{MemoryRefreshKind, Pid, ProcessRefreshKind, ProcessesToUpdate, RefreshKind, System};

/// Which limit bounds the memory left ([`Headroom::limit`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// The machine's available memory.
    Machine,
    /// The process's cgroup memory limit.
    Cgroup,
    /// The process's address-space limit.
    AddressSpace,
}

impl Limit {
    /// What the limit is, for messages.
    pub fn describe(self) -> &'static str {
        match self {
            Limit::Machine => "the memory available on this machine",
            Limit::Cgroup => {
                "the free part of this process's cgroup memory limit (a batch job's or \
                 container's)"
            }
            Limit::AddressSpace => {
                "the address-space limit (ulimit -v) less what this process has mapped"
            }
        }
    }
}

/// Bytes this process may still take, and the limit that says so.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Headroom {
    pub bytes: u64,
    pub limit: Limit,
}

/// The memory this process may still take (module docs); `None` where the system tells none
/// of the limits.
pub fn headroom() -> Option<Headroom> {
    let system = System::new_with_specifics(
        RefreshKind::nothing().with_memory(MemoryRefreshKind::nothing().with_ram()),
    )
    .ok()?;
    let machine = Some(system.available_memory())
        .filter(|&m| m > 0)
        .map(|bytes| Headroom {
            bytes,
            limit: Limit::Machine,
        });
    let (cgroup, mapped) =
        own_process(system).map_or((None, None), |(cgroup, mapped)| (cgroup, Some(mapped)));
    least([
        machine,
        cgroup.map(|bytes| Headroom {
            bytes,
            limit: Limit::Cgroup,
        }),
        mapped
            .zip(address_space_limit())
            .map(|(mapped, cap)| Headroom {
                bytes: cap.saturating_sub(mapped),
                limit: Limit::AddressSpace,
            }),
    ])
}

/// Bytes [`headroom`] gives, if any limit is known.
pub fn available() -> Option<u64> {
    headroom().map(|h| h.bytes)
}

/// The free part of this process's cgroup memory limit (if it has one) and the bytes of
/// address space it has mapped.
fn own_process(mut system: System) -> Option<(Option<u64>, u64)> {
    let pid: Pid = sysinfo::get_current_pid().ok()?;
    system.refresh_processes_specifics(
        ProcessesToUpdate::Some(&[pid]),
        false,
        ProcessRefreshKind::nothing().with_memory(),
    );
    let process = system.process(pid)?;
    let cgroup = process.cgroup_limits().map(|l| l.free_memory);
    Some((cgroup, process.virtual_memory()))
}

/// The soft address-space limit, if there is one.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn address_space_limit() -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the limit into the struct it is given, nothing else.
    let status = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) };
    (status == 0 && limit.rlim_cur != libc::RLIM_INFINITY).then_some(limit.rlim_cur)
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn address_space_limit() -> Option<u64> {
    None
}

/// The smallest of the known headrooms.
fn least(candidates: impl IntoIterator<Item = Option<Headroom>>) -> Option<Headroom> {
    candidates.into_iter().flatten().min_by_key(|h| h.bytes)
}

/// Bytes in gigabytes (10⁹), for messages.
pub fn gigabytes(bytes: u64) -> f64 {
    bytes as f64 / 1e9
}

#[cfg(test)]
mod tests {
    use super::*;

    fn room(bytes: u64, limit: Limit) -> Option<Headroom> {
        Some(Headroom { bytes, limit })
    }

    #[test]
    fn the_least_known_limit_bounds_the_headroom() {
        assert_eq!(least([None, None, None]), None);
        assert_eq!(
            least([room(8, Limit::Machine), None, room(5, Limit::AddressSpace)]),
            room(5, Limit::AddressSpace)
        );
        assert_eq!(
            least([room(8, Limit::Machine), room(3, Limit::Cgroup), None]),
            room(3, Limit::Cgroup)
        );
    }

    /// The machine's part is the kernel's `MemAvailable`, read here from /proc/meminfo, up to
    /// what other processes allocate or free between the two reads (5 % on a quiet machine);
    /// the headroom is never more.
    #[cfg(target_os = "linux")]
    #[test]
    fn the_machines_part_is_the_kernels_mem_available() {
        let text = std::fs::read_to_string("/proc/meminfo").unwrap();
        let line = text
            .lines()
            .find(|l| l.starts_with("MemAvailable:"))
            .unwrap();
        let kb: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
        let kernel = kb * 1024.0;
        let system = System::new_with_specifics(
            RefreshKind::nothing().with_memory(MemoryRefreshKind::nothing().with_ram()),
        )
        .unwrap();
        let ours = system.available_memory() as f64;
        assert!(
            (ours - kernel).abs() <= 0.05 * kernel,
            "{ours} B vs MemAvailable {kernel} B"
        );
        let headroom = headroom().expect("Linux tells the available memory");
        assert!(headroom.bytes as f64 <= 1.05 * kernel, "{headroom:?}");
    }

    /// This process has mapped something, so its own part is found (the cgroup's where the
    /// process has a limited one).
    #[cfg(target_os = "linux")]
    #[test]
    fn the_process_finds_its_own_mappings() {
        let system = System::new_with_specifics(RefreshKind::nothing()).unwrap();
        let (_, mapped) = own_process(system).expect("the process is found");
        assert!(mapped > 1 << 20, "{mapped} bytes mapped");
    }
}
