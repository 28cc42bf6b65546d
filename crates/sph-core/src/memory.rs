//! The memory a process may still allocate, for checks made before an allocation whose
//! size the user's input sets (an image, a grid), so that it is refused by name instead of
//! aborting the process.

/// Bytes this process may still allocate: the kernel's estimate of the memory available
/// (`MemAvailable` of `/proc/meminfo`), lowered to the room left under the process's
/// address-space limit (`RLIMIT_AS`, the soft "Max address space" of `/proc/self/limits`,
/// less the address space in use, `VmSize` of `/proc/self/status`) when there is one.
/// `None` where neither is known (not Linux).
pub fn available_bytes() -> Option<u64> {
    let mem = read_kib("/proc/meminfo", "MemAvailable:").map(|k| k.saturating_mul(1024));
    let room = address_space_limit().map(|limit| {
        let used = read_kib("/proc/self/status", "VmSize:").map_or(0, |k| k.saturating_mul(1024));
        limit.saturating_sub(used)
    });
    match (mem, room) {
        (Some(m), Some(r)) => Some(m.min(r)),
        (m, r) => m.or(r),
    }
}

/// The value in kiB of the line of `file` that starts with `key` (`key   1234 kB`).
fn read_kib(file: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(file).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    line[key.len()..].split_whitespace().next()?.parse().ok()
}

/// The soft address-space limit in bytes, `None` when unlimited or unknown.
fn address_space_limit() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = text.lines().find(|l| l.starts_with("Max address space"))?;
    let soft = line["Max address space".len()..]
        .split_whitespace()
        .next()?;
    soft.parse().ok() // "unlimited" does not parse
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn available_memory_is_known_on_linux_and_below_the_machine_total() {
        if !cfg!(target_os = "linux") {
            return;
        }
        let total = read_kib("/proc/meminfo", "MemTotal:").unwrap() * 1024;
        let available = available_bytes().unwrap();
        assert!(
            available > 0 && available <= total,
            "{available} of {total}"
        );
    }
}
