//! Finished scene runs kept on disk, so that a long experiment stopped part way resumes where
//! it stopped: full mode's repose ensembles (eight pours of each case at the full spacing)
//! take hours on two cores, and an interrupted run would otherwise start over.
//!
//! A run is written when it has finished, atomically (a temporary file beside it, `fsync`,
//! rename: `sph_sim::checkpoint::write_atomically`), as JSON under `<dir>/<tag>.json` with
//! the key it ran under: the SHA-256 of the executable that ran it, of the scene's full
//! description ([`sph_sim::checkpoint::scene_fingerprint`]) and of the run's tag. A stored run
//! is reused only when its key is the key of the run about to start: the same build runs the
//! same scene to the same bits (the solvers' runs are bit-reproducible, whatever the
//! threads), so the reused run is the run that would have been made; its wall time is the
//! time it took then. Anything else (another build, another scene, a file that does not
//! read) is run again and replaces it. The frames' phase times are wall-clock measurements,
//! not results, and are not kept ([`sph_sim::FrameRecord`]).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::{Context as _, Result};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use sph_scene::Scene;

use super::SceneRun;

/// Largest stored run read (bytes): a run of 10⁶ particles with 10⁴ frames is about 0.1 GB
/// of JSON; a larger file is not a run this store wrote, and is run again.
pub const MAX_STORED_BYTES: u64 = 1 << 30;

/// Where finished runs are kept and under which build.
#[derive(Debug, Clone)]
pub struct RunStore {
    dir: PathBuf,
    build: [u8; 32],
}

/// One stored run with its key.
#[derive(Serialize, Deserialize)]
struct Stored {
    key: String,
    wall_s: f64,
    run: SceneRun,
}

impl RunStore {
    /// A store in `dir` for runs of the executable running now; `None` (with a note on
    /// stderr) when that executable cannot be read, so that nothing is ever reused unkeyed.
    pub fn for_this_build(dir: PathBuf) -> Option<Self> {
        static BUILD: OnceLock<Option<[u8; 32]>> = OnceLock::new();
        let build = BUILD.get_or_init(|| match executable_digest() {
            Ok(d) => Some(d),
            Err(e) => {
                eprintln!("  finished runs are not kept: {e:#}");
                None
            }
        });
        build.map(|build| Self { dir, build })
    }

    /// A store in `dir` keyed by `build` (tests).
    pub fn with_build(dir: PathBuf, build: [u8; 32]) -> Self {
        Self { dir, build }
    }

    /// The file of the run tagged `tag`: the tag's `/` and other characters outside
    /// `[A-Za-z0-9._=-]` as `_`.
    pub fn path(&self, tag: &str) -> PathBuf {
        let name: String = tag
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "._=-".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        self.dir.join(format!("{name}.json"))
    }

    fn key(&self, tag: &str, scene: &Scene) -> String {
        let mut h = Sha256::new();
        h.update(self.build);
        h.update(sph_sim::checkpoint::scene_fingerprint(scene));
        h.update(tag.as_bytes());
        h.finalize().iter().map(|b| format!("{b:02x}")).collect()
    }

    /// The stored run of `tag` on `scene` and its wall time (s), if one was kept under this
    /// build, scene and tag.
    pub fn load(&self, tag: &str, scene: &Scene) -> Option<(SceneRun, f64)> {
        let path = self.path(tag);
        let size = std::fs::metadata(&path).ok()?.len();
        if size > MAX_STORED_BYTES {
            return None;
        }
        let stored: Stored = serde_json::from_slice(&std::fs::read(&path).ok()?).ok()?;
        (stored.key == self.key(tag, scene)).then_some((stored.run, stored.wall_s))
    }

    /// Keeps the finished `run` of `tag` on `scene`, which took `wall_s` seconds.
    pub fn save(&self, tag: &str, scene: &Scene, run: &SceneRun, wall_s: f64) -> Result<()> {
        std::fs::create_dir_all(&self.dir)
            .with_context(|| format!("creating {}", self.dir.display()))?;
        let stored = Stored {
            key: self.key(tag, scene),
            wall_s,
            run: run.clone(),
        };
        let bytes = serde_json::to_vec(&stored).context("encoding a finished run")?;
        sph_sim::checkpoint::write_atomically(&self.path(tag), &bytes)?;
        Ok(())
    }
}

/// SHA-256 of the running executable's file.
fn executable_digest() -> Result<[u8; 32]> {
    let exe = std::env::current_exe().context("locating the running executable")?;
    digest_file(&exe)
}

fn digest_file(path: &Path) -> Result<[u8; 32]> {
    use std::io::Read as _;
    let mut f = std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
    let mut h = Sha256::new();
    let mut buf = vec![0_u8; 1 << 20];
    loop {
        let n = f
            .read(&mut buf)
            .with_context(|| format!("reading {}", path.display()))?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
    }
    Ok(h.finalize().into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use sph_core::Vec3;

    /// The shipped 30° poured heap in `mode` (two modes: two scenes).
    fn scene(mode: crate::Mode) -> Scene {
        crate::scene_runs::shipped_scene("granular_repose_poured_30", mode).expect("shipped")
    }

    fn run() -> SceneRun {
        SceneRun {
            particles: 2,
            frames: Vec::new(),
            rest_verdict: None,
            snapshots: vec![(0, vec![Vec3::new(0.1, 0.2, 0.3)])],
            snapshot_fields: Vec::new(),
            final_positions: vec![Vec3::new(1.0 / 3.0, -0.0, 1e-300), Vec3::new(0.5, 0.5, 0.5)],
            final_ids: vec![1, 0],
            initial_potential_energy_j: 9.81,
            blow_up: None,
            rest_from_s: Some(14.432),
            pour_finished: true,
        }
    }

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("run-store-{name}-{}", std::process::id()));
        std::fs::remove_dir_all(&d).ok();
        d
    }

    #[test]
    fn a_run_comes_back_bit_for_bit_under_its_key_only() {
        let d = dir("key");
        let store = RunStore::with_build(d.clone(), [7; 32]);
        let (s, r) = (scene(crate::Mode::Quick), run());
        assert!(store.load("a/pour=1", &s).is_none(), "nothing stored yet");
        store.save("a/pour=1", &s, &r, 12.5).unwrap();
        let (back, wall) = store.load("a/pour=1", &s).expect("stored");
        assert_eq!(wall, 12.5);
        assert_eq!(
            back.final_positions, r.final_positions,
            "positions bit for bit"
        );
        assert_eq!(back.final_ids, r.final_ids);
        assert_eq!(back.rest_from_s, r.rest_from_s);
        assert_eq!(back.snapshots, r.snapshots);
        // Another scene, another build, another tag: not reused.
        assert!(store.load("a/pour=1", &scene(crate::Mode::Full)).is_none());
        assert!(RunStore::with_build(d.clone(), [8; 32])
            .load("a/pour=1", &s)
            .is_none());
        assert!(store.load("a/pour=2", &s).is_none());
        std::fs::remove_dir_all(&d).ok();
    }

    /// Reals of 17 significant digits (what the JSON writer prints) read back bit for bit.
    #[test]
    fn reals_read_back_bit_for_bit() {
        let d = dir("reals");
        let store = RunStore::with_build(d.clone(), [7; 32]);
        let s = scene(crate::Mode::Quick);
        let mut r = run();
        let x =
            |k: u32| 0.1 + f64::from(k) * 0.012_345_678_901_234_567 + f64::from(k).sqrt() * 1e-9;
        r.final_positions = (0..2000)
            .map(|k| Vec3::new(x(k), x(k) * 1e-7, -x(k) * 1e5))
            .collect();
        store.save("t", &s, &r, 1.0).unwrap();
        let (back, _) = store.load("t", &s).unwrap();
        let bits = |v: &[Vec3<f64>]| -> Vec<u64> {
            v.iter()
                .flat_map(|p| p.iter().map(|c| c.to_bits()))
                .collect()
        };
        assert_eq!(bits(&back.final_positions), bits(&r.final_positions));
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn a_damaged_file_is_run_again_not_read() {
        let d = dir("damaged");
        let store = RunStore::with_build(d.clone(), [7; 32]);
        let s = scene(crate::Mode::Quick);
        store.save("t", &s, &run(), 1.0).unwrap();
        let p = store.path("t");
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
        assert!(store.load("t", &s).is_none(), "a truncated file");
        std::fs::write(&p, b"not json").unwrap();
        assert!(store.load("t", &s).is_none(), "a foreign file");
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn tags_map_to_plain_file_names() {
        let store = RunStore::with_build(PathBuf::from("/x"), [0; 32]);
        assert_eq!(
            store.path("simple-shear/theta=30/pour=8"),
            PathBuf::from("/x/simple-shear_theta=30_pour=8.json")
        );
        assert_eq!(store.path("../up"), PathBuf::from("/x/.._up.json"));
    }

    #[test]
    fn the_executable_digest_is_its_files() {
        let d = dir("digest");
        std::fs::create_dir_all(&d).unwrap();
        let p = d.join("f");
        std::fs::write(&p, b"abc").unwrap();
        // SHA-256("abc"), FIPS 180-2 appendix B.1.
        let want = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
        let got: String = digest_file(&p)
            .unwrap()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        assert_eq!(got, want);
        std::fs::remove_dir_all(&d).ok();
    }
}
