#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Scene running as a library.
//!
//! - [`SceneSetup`]: a checked scene (`sph_scene::Scene`) built once — the solver's
//!   parameters, the fluid particles sampled once (masses calibrated if asked) and the
//!   boundary, with its walls as SDF collisions or volume maps (Bender, Kugelstadt, Weiler &
//!   Koschier 2019), see [`build_boundary`].
//! - [`build_solver`]: the one factory from those parameters and boundary to a
//!   `Box<dyn sph_solver::FluidSolver<R>>` — PBF (Macklin & Müller 2013), PCISPH
//!   (Solenthaler & Pajarola 2009) or IISPH (Ihmsen et al. 2014; granular, Neder 2024).
//! - [`SceneSim`]: the particles, the solver and the ids that follow particles across the
//!   solver's reordering, advanced frame by frame.
//! - [`run_frames`]: the one frame loop, with [`FrameObserver`]s that may stop it
//!   ([`Flow`]) and a typed [`RunOutcome`] (completed, stopped, interrupted, diverged); each
//!   frame's [`FrameRecord`] feeds `stats.csv`, Python and the experiments; the observers
//!   of [`observe`] record, stop at rest, stop at a density limit, keep snapshots.
//! - [`run_scene`]: the run behind `cargo xtask run SCENE`, with a progress bar,
//!   ParaView frames (legacy VTK, [`vtk::write_particle_frame`]) and `stats.csv`.
//!
//! ```no_run
//! use sph_scene::Scene;
//! use sph_sim::SceneSim;
//!
//! let scene = Scene::load(std::path::Path::new("scenes/dam_break.toml")).unwrap().quick();
//! use sph_sim::observe::Recorder;
//! use sph_sim::{run_frames, RunPlan};
//!
//! let mut sim = SceneSim::<f32>::new(&scene).unwrap();
//! let mut recorder = Recorder::default();
//! let plan = RunPlan::next(&sim, 10); // ten 16 ms frames
//! let outcome = run_frames(&mut sim, &plan, &mut [&mut recorder]).unwrap();
//! for r in &recorder.records {
//!     println!("{} rho_max/rho0 {:.4}", r.frame, r.max_density_ratio);
//! }
//! println!("{} at frame {}", outcome.ending.name(), outcome.frame);
//! ```

pub mod checkpoint;
mod error;
mod factory;
pub mod frame_loop;
pub mod observe;
mod record;
pub mod render;
pub mod rest_log;
pub mod run;
pub mod run_dir;
pub mod saved;
mod setup;
mod sim;
mod source;
pub mod vtk;

pub use error::SimError;
pub use factory::{build_boundary, build_solver, density_kernel, VOLUME_MAP_CONTACT_FRACTION};
pub use frame_loop::{run_frames, Divergence, Ending, Flow, FrameObserver, RunOutcome, RunPlan};
pub use record::{FrameRecord, STATS_COLUMNS, STATS_EXTRA_COLUMNS};
pub use run::{run_scene, SceneRunOptions};
pub use run_dir::{RunDir, RunSource};
pub use setup::SceneSetup;
pub use sim::SceneSim;
pub use source::SceneSource;
pub use sph_scene::{Precision, Scene};

/// Runs `$body` with the type `$R` bound to the real type of precision `$p` (an
/// `sph_scene::Precision`): the workspace's one precision dispatch.
///
/// ```
/// use sph_sim::{with_precision, Precision};
/// fn bytes<R>() -> usize { std::mem::size_of::<R>() }
/// assert_eq!(with_precision!(Precision::F64, R => bytes::<R>()), 8);
/// ```
#[macro_export]
macro_rules! with_precision {
    ($p:expr, $R:ident => $body:expr) => {
        match $p {
            $crate::Precision::F32 => {
                type $R = f32;
                $body
            }
            $crate::Precision::F64 => {
                type $R = f64;
                $body
            }
        }
    };
}
