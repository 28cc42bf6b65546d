//! The room left on a file system, for checks made before a run writes output whose volume
//! the user's settings set (frames × particles), so that a run that cannot fit is refused
//! by name before it starts instead of failing part-way with the disk full.

use std::path::Path;

/// Bytes an unprivileged process may still write on the file system holding `path`
/// (`statvfs`: available blocks × fragment size). `None` where it is unknown (not Unix, or
/// the call failed, e.g. `path` does not exist).
pub fn available_bytes(path: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let s = nix::sys::statvfs::statvfs(path).ok()?;
        Some((s.blocks_available() as u64).saturating_mul(s.fragment_size() as u64))
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        None
    }
}

/// Why `bytes` more do not fit on the file system of `dir` (whose room is `free`, as
/// [`available_bytes`] gives it), naming both sizes; `None` when they fit or the room is
/// unknown.
pub fn room_shortfall(dir: &Path, bytes: u64, free: Option<u64>) -> Option<String> {
    let free = free?;
    (bytes > free).then(|| {
        format!(
            "needs about {} but {} has only {} free",
            human(bytes),
            dir.display(),
            human(free)
        )
    })
}

/// `bytes` as `12.35 MB` / `4.56 GB` (decimal units, two decimals).
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    let (value, unit) = match b {
        b if b >= 1e12 => (b / 1e12, "TB"),
        b if b >= 1e9 => (b / 1e9, "GB"),
        b if b >= 1e6 => (b / 1e6, "MB"),
        b if b >= 1e3 => (b / 1e3, "kB"),
        _ => return format!("{bytes} B"),
    };
    format!("{value:.2} {unit}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_temporary_directory_has_a_known_room_below_its_size() {
        if !cfg!(unix) {
            return;
        }
        let dir = std::env::temp_dir();
        let free = available_bytes(&dir).expect("statvfs of the temporary directory");
        let s = nix::sys::statvfs::statvfs(&dir).unwrap();
        let size = (s.blocks() as u64) * (s.fragment_size() as u64);
        assert!(free > 0 && free <= size, "{free} of {size}");
        assert_eq!(available_bytes(Path::new("/no/such/directory/here")), None);
    }

    #[test]
    fn a_shortfall_names_both_sizes_and_an_unknown_room_passes() {
        let dir = Path::new("/out");
        assert_eq!(
            room_shortfall(dir, 3_000_000_000, Some(2_500_000_000)).as_deref(),
            Some("needs about 3.00 GB but /out has only 2.50 GB free")
        );
        assert_eq!(
            room_shortfall(dir, 2_500_000_000, Some(2_500_000_000)),
            None
        );
        assert_eq!(room_shortfall(dir, u64::MAX, None), None);
    }

    #[test]
    fn sizes_read_as_a_person_writes_them() {
        assert_eq!(human(512), "512 B");
        assert_eq!(human(1_500), "1.50 kB");
        assert_eq!(human(2_000_000_000), "2.00 GB");
        assert_eq!(human(123_456_789), "123.46 MB");
    }
}
