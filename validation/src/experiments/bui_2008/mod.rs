//! Bui, Fukagawa, Sako & Ohno (2008), elastic–plastic SPH for geomaterials (crate
//! `elastoplastic-granular`: a per-particle stress, elastic and capped by the
//! Drucker–Prager cone matched to Mohr–Coulomb in plane strain): the collapse of their
//! column of aluminium bars against Rankine's active wedge, and the angle of repose of
//! poured heaps, in a slab and as a 3D cone on a circular base, against the slope the yield
//! cone predicts.

pub mod granular_column_bui;
pub mod granular_funnel_heap;
pub mod granular_repose;
