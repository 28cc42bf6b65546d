//! Macklin & Müller (2013), "Position Based Fluids": its figures and tables, with the PCISPH
//! baseline (Solenthaler & Pajarola 2009), and the Martin & Moyce (1952) dam break.

pub mod dam_break_front;
pub mod fluid_runs;
pub mod front;
pub mod pbf_bunny_density;
pub mod pbf_convergence;
pub mod pbf_performance;
pub mod pbf_stability;
pub mod pbf_vorticity;
