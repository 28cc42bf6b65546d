//! A saved simulation: the scene it runs (its file's text, the overrides and quick mode
//! applied to it) with a [`crate::checkpoint`] of its state, in one self-contained file
//! that continues bit for bit where it was saved.
//!
//! # File format (little-endian)
//!
//! ```text
//! magic        8 bytes  "SPHSIMSV"
//! version      u32      SAVED_FORMAT_VERSION
//! scene path   u32 length + UTF-8   (mesh paths are relative to its directory)
//! scene text   u64 length + UTF-8   (the file as it was read)
//! quick        u8       1 when the scene's [quick] overrides apply
//! overrides    u32 count, each u32 length + UTF-8 `KEY=VALUE` (TOML value)
//! checkpoint   u64 length + bytes   (the checkpoint format of `crate::checkpoint`)
//! checksum     32 bytes SHA-256 of everything before it
//! ```
//!
//! The scene text is kept whole, so the scene file may change or disappear after a save;
//! mesh files are read again from their paths, and the checkpoint's scene fingerprint
//! refuses a mesh that changed since.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};
use sph_core::Real;
use sph_scene::Override;

use crate::checkpoint::{encode, write_atomically, MAX_CHECKPOINT_BYTES};
use crate::error::SimError;
use crate::sim::SceneSim;
pub use crate::source::SceneSource;

/// The magic bytes opening a saved simulation.
pub const SAVED_MAGIC: &[u8; 8] = b"SPHSIMSV";
/// The saved-simulation format this build writes and reads.
pub const SAVED_FORMAT_VERSION: u32 = 1;

/// The bytes of a saved simulation: `source` and the checkpoint of `sim`.
pub fn encode_saved<R: Real>(source: &SceneSource, sim: &SceneSim<R>) -> Vec<u8> {
    let checkpoint = encode(&sim.checkpoint());
    let mut out = Vec::with_capacity(checkpoint.len() + source.text.len() + 256);
    out.extend_from_slice(SAVED_MAGIC);
    out.extend_from_slice(&SAVED_FORMAT_VERSION.to_le_bytes());
    let path = source.path.to_string_lossy();
    out.extend_from_slice(&(path.len() as u32).to_le_bytes());
    out.extend_from_slice(path.as_bytes());
    out.extend_from_slice(&(source.text.len() as u64).to_le_bytes());
    out.extend_from_slice(source.text.as_bytes());
    out.push(u8::from(source.quick));
    out.extend_from_slice(&(source.overrides.len() as u32).to_le_bytes());
    for o in &source.overrides {
        let arg = o.to_arg();
        out.extend_from_slice(&(arg.len() as u32).to_le_bytes());
        out.extend_from_slice(arg.as_bytes());
    }
    out.extend_from_slice(&(checkpoint.len() as u64).to_le_bytes());
    out.extend_from_slice(&checkpoint);
    let sum = Sha256::digest(&out);
    out.extend_from_slice(&sum);
    out
}

/// Writes the saved simulation of `sim` (with its `source`) to `path` atomically
/// (`atomic-write-file`: a failed write leaves `path` as it was).
pub fn save<R: Real>(path: &Path, source: &SceneSource, sim: &SceneSim<R>) -> Result<(), SimError> {
    write_atomically(path, &encode_saved(source, sim))
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: u64, what: &str) -> Result<&'a [u8], String> {
        let left = (self.bytes.len() - self.at) as u64;
        if n > left {
            return Err(format!("the file ends inside {what}"));
        }
        let s = &self.bytes[self.at..self.at + n as usize];
        self.at += n as usize;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn u64(&mut self, what: &str) -> Result<u64, String> {
        let b = self.take(8, what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }
    fn text(&mut self, n: u64, what: &str) -> Result<String, String> {
        String::from_utf8(self.take(n, what)?.to_vec()).map_err(|_| format!("{what} is not UTF-8"))
    }
}

/// Decodes a saved simulation: its scene source and its checkpoint's bytes (decoded by
/// [`crate::checkpoint::decode`] in the scene's precision). Errors say what is wrong (the
/// caller names the file).
pub fn decode_saved(bytes: &[u8]) -> Result<(SceneSource, &[u8]), String> {
    if bytes.len() < 8 || &bytes[..8] != SAVED_MAGIC {
        return Err("not a saved simulation (no SPHSIMSV magic)".into());
    }
    if bytes.len() < 12 + 32 {
        return Err(format!("truncated: {} bytes", bytes.len()));
    }
    let (body, sum) = bytes.split_at(bytes.len() - 32);
    if Sha256::digest(body).as_slice() != sum {
        return Err("checksum mismatch: the file is truncated or corrupt".into());
    }
    let mut r = Reader { bytes: body, at: 8 };
    let version = r.u32("the format version")?;
    if version != SAVED_FORMAT_VERSION {
        return Err(format!(
            "saved-simulation format version {version}; this build reads version {SAVED_FORMAT_VERSION}"
        ));
    }
    let n = r.u32("the scene path")?;
    let path = PathBuf::from(r.text(n.into(), "the scene path")?);
    let n = r.u64("the scene text")?;
    let text = r.text(n, "the scene text")?;
    let quick = r.take(1, "the quick flag")?[0] != 0;
    let count = r.u32("the overrides")?;
    let mut overrides = Vec::new();
    for _ in 0..count {
        let n = r.u32("an override")?;
        let arg = r.text(n.into(), "an override")?;
        overrides.push(Override::parse(&arg)?);
    }
    let n = r.u64("the checkpoint")?;
    let checkpoint = r.take(n, "the checkpoint")?;
    if r.at != body.len() {
        return Err(format!(
            "{} unread bytes after the checkpoint",
            body.len() - r.at
        ));
    }
    let source = SceneSource {
        path,
        text,
        overrides,
        quick,
    };
    Ok((source, checkpoint))
}

/// Reads the saved simulation at `path` (a regular file of at most
/// [`MAX_CHECKPOINT_BYTES`] plus its scene) and returns its bytes, verified by
/// [`decode_saved`] when the caller decodes them.
pub fn read_saved(path: &Path) -> Result<Vec<u8>, SimError> {
    let limit = MAX_CHECKPOINT_BYTES + (2 << 20);
    Ok(sph_core::input::read_bytes_limited(
        path,
        limit,
        "saved simulation",
    )?)
}
