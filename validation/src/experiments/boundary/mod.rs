//! Solid boundaries: the collision and volume-map models (Bender, Kugelstadt, Weiler &
//! Koschier 2019) under PBF and PCISPH.

pub mod boundary_rest;
