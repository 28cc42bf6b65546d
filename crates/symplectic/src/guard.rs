//! Guards of the long and large operations: a process-wide stop request (Ctrl-C) that every
//! long loop checks, and allocations sized by the user's input made fallible and checked
//! against the memory available.
//!
//! A front end turns Ctrl-C into [`request_stop`] (the Python package from its main thread,
//! the command line from its signal handler); the loops of
//! [`Population::advance_to`](crate::Population::advance_to), the ephemeris' extension and
//! the readers return [`SymplecticError::Interrupted`] at their next check, leaving a state
//! that goes on: each particle on its own clock, the planets' grid as far as it was built.
//! The front end calls [`clear_stop`] before its next run.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::SymplecticError;

static STOP: AtomicBool = AtomicBool::new(false);

/// Asks every running loop of this crate to stop at its next check (Ctrl-C).
pub fn request_stop() {
    STOP.store(true, Ordering::Relaxed);
}

/// Withdraws a stop request (a front end, before its next run).
pub fn clear_stop() {
    STOP.store(false, Ordering::Relaxed);
}

/// Whether a stop was requested (one relaxed atomic load: cheap enough for a particle step).
#[inline(always)]
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// `Err(Interrupted)` naming `what` if a stop was requested.
#[inline]
pub fn check_stop(what: &'static str) -> Result<(), SymplecticError> {
    if stop_requested() {
        Err(SymplecticError::Interrupted { what })
    } else {
        Ok(())
    }
}

/// `MemAvailable` of `/proc/meminfo` in bytes, where there is one.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Reserves room for `additional` more elements in `v`, refusing by name (`what`) when the
/// bytes asked for exceed the memory available or the allocator refuses them, instead of
/// aborting the process.
pub fn try_reserve<T>(
    v: &mut Vec<T>,
    additional: usize,
    what: &'static str,
) -> Result<(), SymplecticError> {
    let requested = additional as u128 * std::mem::size_of::<T>().max(1) as u128;
    // Reading /proc/meminfo costs microseconds: only for allocations that could matter.
    let available = if requested >= 1 << 26 {
        available_memory()
    } else {
        None
    };
    let refuse = |available: Option<u64>| SymplecticError::AllocationFailed {
        what,
        requested_bytes: requested,
        available_bytes: available,
    };
    if let Some(a) = available {
        if requested > u128::from(a) {
            return Err(refuse(Some(a)));
        }
    }
    v.try_reserve(additional)
        .map_err(|_| refuse(available.or_else(available_memory)))
}

/// What kind of file system object it is, for a message, when it is not a regular file.
fn not_regular(meta: &std::fs::Metadata) -> Option<&'static str> {
    let t = meta.file_type();
    #[cfg(unix)]
    use std::os::unix::fs::FileTypeExt;
    #[cfg(unix)]
    let special = [
        (t.is_fifo(), "a named pipe (FIFO)"),
        (t.is_char_device() || t.is_block_device(), "a device"),
        (t.is_socket(), "a socket"),
    ];
    #[cfg(not(unix))]
    let special: [(bool, &str); 0] = [];
    (!t.is_file()).then(|| {
        std::iter::once((t.is_dir(), "a directory"))
            .chain(special)
            .find_map(|(is, kind)| is.then_some(kind))
            .unwrap_or("not a regular file")
    })
}

/// The size of the regular file `path`, from its metadata (which does not open it: a named
/// pipe is not waited on, a device such as `/dev/zero` is not read); refused, with the
/// reason as the error, when it is not a regular file or holds more than `limit` bytes
/// (`limit_name` names the limit in the message).
pub fn regular_file_size(
    path: &std::path::Path,
    limit: u64,
    limit_name: &str,
) -> Result<u64, String> {
    let meta = std::fs::metadata(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => "file not found".to_string(),
        _ => e.to_string(),
    })?;
    if let Some(kind) = not_regular(&meta) {
        return Err(format!("is {kind}, not a regular file"));
    }
    if meta.len() > limit {
        return Err(format!(
            "{} bytes, more than the {limit} bytes allowed ({limit_name})",
            meta.len()
        ));
    }
    Ok(meta.len())
}

/// The text of the regular file `path` of at most `limit` bytes ([`regular_file_size`]),
/// read into a fallible allocation (the file may grow while it is read: at most one byte
/// past the limit is read).
pub fn read_text_limited(
    path: &std::path::Path,
    limit: u64,
    limit_name: &str,
) -> Result<String, String> {
    use std::io::Read;
    let size = regular_file_size(path, limit, limit_name)?;
    let mut bytes = Vec::new();
    try_reserve(&mut bytes, size as usize, "file text").map_err(|e| e.to_string())?;
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "grew past the {limit} bytes allowed ({limit_name}) while read"
        ));
    }
    String::from_utf8(bytes).map_err(|e| format!("not UTF-8 text: {e}"))
}
