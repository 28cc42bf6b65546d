//! Macklin & Müller (2013), "Position Based Fluids" (crates `sph-kernels`, `pbf`, with the
//! PCISPH baseline of Solenthaler & Pajarola 2009 in `pcisph`): the paper's figures and
//! tables; the kernels it builds on (Müller et al. 2003; Monaghan 1992; Wendland 1995); its
//! fluids at rest against collision and volume-map walls (Bender, Kugelstadt, Weiler &
//! Koschier 2019); and the Martin & Moyce (1952) dam break, with IISPH beside PBF.

pub mod boundary_rest;
pub mod dam_break_front;
pub mod kernels;
pub mod pbf_bunny_density;
pub mod pbf_convergence;
pub mod pbf_performance;
pub mod pbf_stability;
pub mod pbf_vorticity;
