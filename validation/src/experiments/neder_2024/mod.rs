//! Neder (2024), granular matter with SPH (crate `iisph-granular`: IISPH after Ihmsen et al.
//! 2014, Drucker–Prager friction after Alduán & Otaduy 2011): the angle of repose of the
//! thesis's fixed-base heaps, the collapse of granular columns against Lube et al. (2005,
//! planar; 2004, axisymmetric), the convergence of the IISPH pressure solve the thesis builds
//! on, and the cost of a granular step. Scene runs and the scene loader are shared by every
//! paper ([`crate::scene_runs`]).

pub mod granular_column_collapse;
pub mod granular_column_collapse_axisymmetric;
pub mod granular_performance;
pub mod granular_repose_thesis;
pub mod iisph_convergence;
