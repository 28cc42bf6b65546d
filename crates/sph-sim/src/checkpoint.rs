//! Checkpoints of a scene run: the whole state a run needs to continue bit for bit.
//!
//! A checkpoint holds the frame counter and time, the particles (positions, velocities,
//! densities, masses, in the solver's current order, with the ids that map them to the
//! scene's initial order) and the solver's carried state ([`sph_solver::SolverState`]:
//! warm-started pressures, stresses, passive points, its own frame counter). Resuming it
//! into a fresh [`SceneSim`] of the same scene continues the run exactly as if it had never
//! stopped: the frames and statistics (but for their wall-clock columns) are bit-identical
//! to an uninterrupted run's.
//!
//! # File format (`checkpoint.sphck`, little-endian)
//!
//! ```text
//! magic      8 bytes  "SPHSIMCK"
//! version    u32      FORMAT_VERSION
//! length     u64      bytes of the payload
//! payload    …        see below
//! checksum   32 bytes SHA-256 of the payload
//! ```
//!
//! The payload: the writing crate's version (string), the scene fingerprint (32 bytes:
//! SHA-256 of the loaded scene, quick overrides applied), the precision (bytes per real,
//! 4 or 8), the frame (u64), the time (f64), the particle count `n` (u64), the ids (`n` u32),
//! positions and velocities (`3n` reals each), densities and masses (`n` reals each), then
//! the solver state: its solver name (string), frame count (u64), array count (u32) and each
//! array's name (string), length (u64) and values. Strings are a u32 byte length and UTF-8.
//!
//! A file is read whole (after a size check against its header) and verified before anything
//! is taken from it: a foreign file (no magic), another format version, a truncated or
//! overlong file, a checksum mismatch, another crate version, another scene, another
//! precision or inconsistent lengths are refused with [`SimError::Input`] naming the file
//! and the reason, and the simulation is left untouched. Writing is atomic: a temporary file
//! in the same directory, `fsync`, rename.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};
use sph_core::{Real, Vec3};
use sph_scene::Scene;
use sph_solver::SolverState;

use crate::error::SimError;
use crate::frame_loop::{Ending, Flow, FrameObserver, RunOutcome, RunPlan};
use crate::record::FrameRecord;
use crate::run_dir::RunDir;
use crate::sim::SceneSim;

/// The magic bytes opening a checkpoint.
pub const MAGIC: &[u8; 8] = b"SPHSIMCK";
/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;
/// The version of the crate that writes checkpoints; a checkpoint of another version is
/// refused (the solvers' carried state may differ between versions).
pub const WRITER_VERSION: &str = env!("CARGO_PKG_VERSION");
/// Largest checkpoint read (bytes): 64 GiB, about 400 million particles in `f64`.
pub const MAX_CHECKPOINT_BYTES: u64 = 64 << 30;

const HEADER_BYTES: usize = 8 + 4 + 8;
const CHECKSUM_BYTES: usize = 32;

/// The fingerprint of a loaded scene (SHA-256 of its full description, quick overrides and
/// meshes included): what a checkpoint must have been written for.
pub fn scene_fingerprint(scene: &Scene) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(format!("{scene:?}").as_bytes());
    h.finalize().into()
}

/// The contents of a checkpoint, in precision `R`.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint<R: Real> {
    /// Fingerprint of the scene it was written for ([`scene_fingerprint`]).
    pub scene: [u8; 32],
    /// Frames done.
    pub frame: u64,
    /// Simulated time (s).
    pub time_s: f64,
    /// For each particle, its index in the scene's initial order.
    pub ids: Vec<u32>,
    /// The particles, in the solver's current order.
    pub state: sph_core::ParticleSet<R>,
    /// The solver's carried state.
    pub solver: SolverState<R>,
}

// ---- writing ----

struct Out(Vec<u8>);

impl Out {
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.0.extend_from_slice(s.as_bytes());
    }
    fn reals<R: Real>(&mut self, v: impl IntoIterator<Item = R>) {
        for x in v {
            if std::mem::size_of::<R>() == 4 {
                self.0.extend_from_slice(&(x.as_f64() as f32).to_le_bytes());
            } else {
                self.0.extend_from_slice(&x.as_f64().to_le_bytes());
            }
        }
    }
    fn vecs<R: Real>(&mut self, v: &[Vec3<R>]) {
        self.reals(v.iter().flat_map(|p| [p.x, p.y, p.z]));
    }
}

/// The bytes of `c` in the checkpoint format.
pub fn encode<R: Real>(c: &Checkpoint<R>) -> Vec<u8> {
    let mut p = Out(Vec::new());
    p.str(WRITER_VERSION);
    p.0.extend_from_slice(&c.scene);
    p.u32(std::mem::size_of::<R>() as u32);
    p.u64(c.frame);
    p.0.extend_from_slice(&c.time_s.to_le_bytes());
    p.u64(c.ids.len() as u64);
    for &i in &c.ids {
        p.u32(i);
    }
    p.vecs(&c.state.positions);
    p.vecs(&c.state.velocities);
    p.reals(c.state.densities.iter().copied());
    p.reals(c.state.masses.iter().copied());
    p.str(&c.solver.solver);
    p.u64(c.solver.frames);
    p.u32(c.solver.arrays.len() as u32);
    for (name, values) in &c.solver.arrays {
        p.str(name);
        p.u64(values.len() as u64);
        p.reals(values.iter().copied());
    }
    let payload = p.0;
    let mut file = Vec::with_capacity(HEADER_BYTES + payload.len() + CHECKSUM_BYTES);
    file.extend_from_slice(MAGIC);
    file.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    file.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    file.extend_from_slice(&payload);
    file.extend_from_slice(&Sha256::digest(&payload));
    file
}

/// Writes `bytes` to `path` atomically (`atomic-write-file`: a temporary file beside it,
/// `fsync`, rename, `fsync` of the directory); a failed write leaves `path` as it was.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), SimError> {
    let write = || -> std::io::Result<()> {
        let mut f = atomic_write_file::AtomicWriteFile::open(path)?;
        f.write_all(bytes)?;
        f.commit()
    };
    write().map_err(|e| SimError::output(path, format!("writing the checkpoint: {e}")))
}

// ---- reading ----

struct In<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> In<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| format!("the payload ends inside {what}"))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4, what)?.try_into().unwrap_or_default(),
        ))
    }
    fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8, what)?.try_into().unwrap_or_default(),
        ))
    }
    fn f64(&mut self, what: &str) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64(what)?))
    }
    fn str(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)? as usize;
        String::from_utf8(self.take(n, what)?.to_vec()).map_err(|_| format!("{what} is not UTF-8"))
    }
    fn count(&mut self, per_item: usize, what: &str) -> Result<usize, String> {
        let n = self.u64(what)?;
        let left = (self.bytes.len() - self.at) as u64;
        if n.saturating_mul(per_item as u64) > left {
            return Err(format!(
                "{what}: {n} entries do not fit the {left} bytes left"
            ));
        }
        Ok(n as usize)
    }
    fn reals<R: Real>(&mut self, n: usize, what: &str) -> Result<Vec<R>, String> {
        let size = std::mem::size_of::<R>();
        let bytes = self.take(n.checked_mul(size).ok_or("overflow")?, what)?;
        Ok(bytes
            .chunks_exact(size)
            .map(|c| match size {
                4 => R::of_f64(f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64),
                _ => R::of_f64(f64::from_le_bytes(c.try_into().unwrap_or_default())),
            })
            .collect())
    }
    fn vecs<R: Real>(&mut self, n: usize, what: &str) -> Result<Vec<Vec3<R>>, String> {
        let flat = self.reals::<R>(3 * n, what)?;
        Ok(flat
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect())
    }
}

/// Verifies the frame of `file` (magic, version, length, checksum) and returns its payload.
fn verified_payload(file: &[u8]) -> Result<&[u8], String> {
    if file.len() < 8 || &file[..8] != MAGIC {
        return Err("not a scene-run checkpoint (no SPHSIMCK magic)".into());
    }
    if file.len() < HEADER_BYTES {
        return Err(format!(
            "truncated: {} bytes, shorter than the header",
            file.len()
        ));
    }
    let version = u32::from_le_bytes(file[8..12].try_into().unwrap_or_default());
    if version != FORMAT_VERSION {
        return Err(format!(
            "checkpoint format version {version}; this build reads version {FORMAT_VERSION}"
        ));
    }
    let len = u64::from_le_bytes(file[12..20].try_into().unwrap_or_default());
    let expected = len.saturating_add((HEADER_BYTES + CHECKSUM_BYTES) as u64);
    if file.len() as u64 != expected {
        return Err(format!(
            "{} bytes where the header announces {expected}: the file is {}",
            file.len(),
            if (file.len() as u64) < expected {
                "truncated"
            } else {
                "longer than written"
            }
        ));
    }
    let payload = &file[HEADER_BYTES..file.len() - CHECKSUM_BYTES];
    if Sha256::digest(payload).as_slice() != &file[file.len() - CHECKSUM_BYTES..] {
        return Err("checksum mismatch: the file is corrupt".into());
    }
    Ok(payload)
}

/// Decodes a checkpoint written in precision `R`; errors say what is wrong (the caller
/// names the file).
pub fn decode<R: Real>(file: &[u8]) -> Result<Checkpoint<R>, String> {
    let mut r = In {
        bytes: verified_payload(file)?,
        at: 0,
    };
    let version = r.str("the writer's version")?;
    if version != WRITER_VERSION {
        return Err(format!(
            "written by sph-sim {version}; this is sph-sim {WRITER_VERSION} (the solvers' state may differ: rerun without --resume)"
        ));
    }
    let scene: [u8; 32] = r
        .take(32, "the scene fingerprint")?
        .try_into()
        .unwrap_or_default();
    let size = r.u32("the precision")? as usize;
    if size != std::mem::size_of::<R>() {
        return Err(format!(
            "written in f{} precision, the scene runs in f{}",
            8 * size,
            8 * std::mem::size_of::<R>()
        ));
    }
    let frame = r.u64("the frame")?;
    let time_s = r.f64("the time")?;
    let n = r.count(4 + 8 * size, "the particles")?;
    let ids = (0..n)
        .map(|_| r.u32("the ids"))
        .collect::<Result<Vec<u32>, String>>()?;
    let positions = r.vecs(n, "the positions")?;
    let velocities = r.vecs(n, "the velocities")?;
    let densities = r.reals(n, "the densities")?;
    let masses = r.reals(n, "the masses")?;
    let name = r.str("the solver name")?;
    let frames = r.u64("the solver's frame count")?;
    let k = r.u32("the solver's array count")?;
    let mut arrays = Vec::new();
    for _ in 0..k {
        let a = r.str("an array name")?;
        let len = r.count(size, &format!("array {a}"))?;
        let values = r.reals(len, &format!("array {a}"))?;
        arrays.push((a, values));
    }
    if r.at != r.bytes.len() {
        return Err(format!(
            "{} unread bytes after the solver state",
            r.bytes.len() - r.at
        ));
    }
    Ok(Checkpoint {
        scene,
        frame,
        time_s,
        ids,
        state: sph_core::ParticleSet {
            positions,
            velocities,
            masses,
            densities,
        },
        solver: SolverState::new(name, frames, arrays),
    })
}

/// Reads and verifies the checkpoint at `path` for a run in precision `R`.
pub fn read<R: Real>(path: &Path) -> Result<Checkpoint<R>, SimError> {
    let bytes = sph_core::input::read_bytes_limited(path, MAX_CHECKPOINT_BYTES, "checkpoint")?;
    decode(&bytes).map_err(|reason| SimError::input(path, reason))
}

impl<R: Real> SceneSim<R> {
    /// The checkpoint of the current frame.
    pub fn checkpoint(&self) -> Checkpoint<R> {
        Checkpoint {
            scene: scene_fingerprint(&self.scene),
            frame: self.frame as u64,
            time_s: self.time_s,
            ids: self.ids.clone(),
            state: self.state.clone(),
            solver: self.solver().save_state(),
        }
    }

    /// Writes the checkpoint of the current frame to `path`, atomically.
    pub fn save_checkpoint(&self, path: &Path) -> Result<(), SimError> {
        write_atomically(path, &encode(&self.checkpoint()))
    }

    /// Continues from checkpoint `c`: refuses (naming what, and leaving the simulation
    /// untouched) a checkpoint of another scene, or one whose particles or solver state do
    /// not fit this simulation.
    pub fn restore(&mut self, c: Checkpoint<R>) -> Result<(), String> {
        if c.scene != scene_fingerprint(&self.scene) {
            return Err(format!(
                "written for another scene (or other [quick] overrides) than {}",
                self.scene.source.display()
            ));
        }
        let (first, poured) = (self.initial_particles(), self.scene.poured_grains());
        let n = c.ids.len();
        if n < first || n > first + poured {
            return Err(if poured == 0 {
                format!("{n} particles; the scene has {first}")
            } else {
                format!("{n} particles; the scene has {first} and pours {poured} more")
            });
        }
        let mut seen = vec![false; n];
        for &i in &c.ids {
            match seen.get_mut(i as usize) {
                Some(s) if !*s => *s = true,
                _ => return Err(format!("particle id {i} is out of range or repeated")),
            }
        }
        sph_solver::step::check_state(&c.state).map_err(|e| e.to_string())?;
        self.solver_mut()
            .restore_state(&c.solver, n)
            .map_err(|e| e.to_string())?;
        self.state = c.state;
        self.ids = c.ids;
        self.frame = c.frame as usize;
        self.time_s = c.time_s;
        Ok(())
    }

    /// [`SceneSim::restore`] from the checkpoint file at `path`; errors name the file.
    pub fn resume_from(&mut self, path: &Path) -> Result<(), SimError> {
        if !path.exists() {
            return Err(SimError::input(
                path,
                "no checkpoint to resume from (a run writes one every --checkpoint-every frames, 25 by default)",
            ));
        }
        let c = read::<R>(path)?;
        self.restore(c)
            .map_err(|reason| SimError::input(path, reason))
    }
}

/// Writes the run's checkpoint every `every` frames and when the run ends at a completed
/// frame (completed, stopped or interrupted; not after a blow-up, whose state is a
/// substep's), after the frame's other outputs, so that the files up to a checkpoint are
/// always complete.
#[derive(Debug)]
pub struct CheckpointObserver {
    path: PathBuf,
    every: Option<usize>,
}

impl CheckpointObserver {
    /// Checkpoints of `run` every `every` frames (`None`: none).
    pub fn new(run: &RunDir, every: Option<usize>) -> Self {
        Self {
            path: run.checkpoint(),
            every: every.filter(|&e| e > 0),
        }
    }
}

impl<R: Real> FrameObserver<R> for CheckpointObserver {
    fn start(&mut self, _: &SceneSim<R>, _: &RunPlan) -> Result<(), SimError> {
        Ok(())
    }
    fn frame(&mut self, sim: &SceneSim<R>, _: &FrameRecord) -> Result<Flow, SimError> {
        match self.every {
            Some(e) if sim.frame.is_multiple_of(e) => sim.save_checkpoint(&self.path)?,
            _ => {}
        }
        Ok(Flow::Continue)
    }
    fn finish(&mut self, sim: &SceneSim<R>, outcome: Option<&RunOutcome>) -> Result<(), SimError> {
        let at_a_frame = outcome.is_some_and(|o| !matches!(o.ending, Ending::Diverged(_)));
        match self.every {
            Some(_) if at_a_frame => sim.save_checkpoint(&self.path),
            _ => Ok(()),
        }
    }
}
