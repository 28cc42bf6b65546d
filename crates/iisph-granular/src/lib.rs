//! Implicit incompressible SPH for water and granular matter (Neder 2024). Under
//! construction: nothing public yet.

pub mod measure;
