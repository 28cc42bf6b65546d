//! Reading input files with a stated size limit: only regular files are opened (a named
//! pipe would block, a device such as `/dev/zero` never ends), and a file larger than the
//! limit is refused from its metadata before any of it is read.

use std::io::Read;
use std::path::Path;

/// What kind of file system object `path` is, for a message, when it is not a regular file.
fn not_regular(meta: &std::fs::Metadata) -> Option<&'static str> {
    let t = meta.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a named pipe (FIFO)");
        }
        if t.is_char_device() {
            return Some("a character device");
        }
        if t.is_block_device() {
            return Some("a block device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

/// The bytes of the regular file `path`, refused when it is not a regular file or when it
/// holds more than `limit` bytes (`what` names the kind of file and the limit's constant in
/// the message). The error is the reason only; the caller names the file.
pub(crate) fn read_limited(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>, String> {
    // `metadata` follows symbolic links and does not open the file, so a FIFO is not waited on.
    let meta = std::fs::metadata(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => "file not found".to_string(),
        _ => e.to_string(),
    })?;
    if let Some(kind) = not_regular(&meta) {
        return Err(format!("is {kind}, not a regular file"));
    }
    let too_large = |n: u64| {
        format!(
            "{n} bytes, more than the {limit} bytes a {what} may have ({})",
            human(limit)
        )
    };
    if meta.len() > limit {
        return Err(too_large(meta.len()));
    }
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // The file may have grown since its metadata was read: read one byte past the limit.
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// `n` bytes in MiB or KiB.
fn human(n: u64) -> String {
    if n >= 1 << 20 {
        format!("{} MiB", n >> 20)
    } else {
        format!("{} KiB", n >> 10)
    }
}
