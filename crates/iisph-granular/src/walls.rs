//! Walls as the shipped IISPH and granular scenes build them: volume maps (Bender,
//! Kugelstadt, Weiler & Koschier 2019) integrated with the solver's density kernel
//! ([`IISPH_KERNEL`]) at its support radius, with the recommended contact distance
//! ([`CommonParams::volume_map_contact_distance`](sph_solver::CommonParams::volume_map_contact_distance)).
//!
//! [`Iisph::new`](crate::Iisph) takes collision walls (projection out of the solids at the
//! particle radius, no share in the density); [`Iisph::with_boundary`](crate::Iisph) with
//! [`volume_map_walls`] takes what scene files get by default (`[boundary] model =
//! "volume-map"`) and what the IISPH and granular scenes use.

use sph_core::{Aabb, Real};
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapCache, VolumeMapOptions};
use sph_solver::{Solids, SolverError};

use crate::{IisphParams, IISPH_KERNEL};

/// Volume-map walls of `solids` for an IISPH solver with `params`, over `domain` (the region
/// the fluid can reach, e.g. the tank's box), with default [`VolumeMapOptions`] and
/// optionally a [`VolumeMapCache`] directory (maps are then loaded from or written to it).
///
/// Errors: those of [`VolumeMapBoundary::with_cache`] (bad domain, unusable support radius,
/// a solid whose grid would be too large).
pub fn volume_map_walls<R: Real>(
    solids: Solids<R>,
    params: &IisphParams<R>,
    domain: Aabb<R>,
    cache: Option<&VolumeMapCache>,
) -> Result<VolumeMapBoundary<R>, SolverError> {
    VolumeMapBoundary::with_cache(
        solids,
        IISPH_KERNEL,
        params.common.support_radius,
        domain,
        params.common.volume_map_contact_distance(),
        VolumeMapOptions::default(),
        cache,
    )
}
