//! Reading user input files with a stated size limit.
//!
//! A path that is not a regular file (a directory, `/dev/zero`, a named pipe, a socket) is
//! refused by name before anything is read, and a file larger than the caller's limit is
//! refused with its size and the limit, before it is read into memory. The limit is also
//! enforced while reading, so a file that grows after the size check cannot exceed it.

use std::io::Read;
use std::path::Path;

use crate::CoreError;

/// One mebibyte (bytes), for stating limits.
pub const MIB: u64 = 1 << 20;

fn refuse(path: &Path, reason: impl Into<String>) -> CoreError {
    CoreError::Input {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// The bytes of the regular file at `path`, refused with [`CoreError::Input`] (naming the
/// path and the reason) when it is missing, not a regular file, or larger than `limit`
/// bytes (`what` names the kind of file in that message, e.g. `"scene file"`).
pub fn read_bytes_limited(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>, CoreError> {
    let meta =
        std::fs::metadata(path).map_err(|e| refuse(path, format!("cannot read {what}: {e}")))?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a device, pipe or socket)"
        };
        return Err(refuse(path, format!("{what} is {kind}")));
    }
    if meta.len() > limit {
        return Err(refuse(
            path,
            format!(
                "{what} is {} bytes, above the limit of {limit} bytes",
                meta.len()
            ),
        ));
    }
    let file =
        std::fs::File::open(path).map_err(|e| refuse(path, format!("cannot open {what}: {e}")))?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| refuse(path, format!("cannot read {what}: {e}")))?;
    if bytes.len() as u64 > limit {
        return Err(refuse(
            path,
            format!("{what} grew above the limit of {limit} bytes while being read"),
        ));
    }
    Ok(bytes)
}

/// [`read_bytes_limited`] for UTF-8 text.
pub fn read_text_limited(path: &Path, limit: u64, what: &str) -> Result<String, CoreError> {
    let bytes = read_bytes_limited(path, limit, what)?;
    String::from_utf8(bytes).map_err(|e| {
        refuse(
            path,
            format!(
                "{what} is not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_devices_directories_and_large_files_by_name() {
        let zero = read_bytes_limited(Path::new("/dev/zero"), MIB, "scene file").unwrap_err();
        assert!(
            zero.to_string().contains("/dev/zero")
                && zero.to_string().contains("not a regular file"),
            "{zero}"
        );
        let dir = std::env::temp_dir();
        let e = read_bytes_limited(&dir, MIB, "mesh").unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
        let f = dir.join(format!("input-limit-{}", std::process::id()));
        std::fs::write(&f, vec![b'a'; 100]).unwrap();
        assert_eq!(read_bytes_limited(&f, 100, "x").unwrap().len(), 100);
        let e = read_bytes_limited(&f, 99, "VTK frame").unwrap_err();
        assert!(
            e.to_string().contains("100 bytes, above the limit of 99"),
            "{e}"
        );
        std::fs::write(&f, [0xff, 0xfe]).unwrap();
        assert!(read_text_limited(&f, 10, "x")
            .unwrap_err()
            .to_string()
            .contains("not UTF-8"));
        std::fs::remove_file(&f).ok();
        let missing = read_bytes_limited(Path::new("/nonexistent/x"), 1, "scene file").unwrap_err();
        assert!(missing.to_string().contains("/nonexistent/x"), "{missing}");
    }
}
