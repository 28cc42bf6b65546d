//! [`VolumeMapBoundary`]: one [`VolumeMap`] per solid behind the [`Boundary`] trait.

use std::fmt;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use sph_core::{Aabb, Real, Sdf, Vec3};
use sph_kernels::{Kernel, KernelKind};

use super::key::{VolumeMapCache, VolumeMapKey};
use super::map::{CacheUse, VolumeMap};
use super::options::{invalid, VolumeMapOptions};
use super::quadrature::KernelTables;
use crate::boundary::{project_out, Boundary, BoundarySample};
use crate::SolverError;

/// How the maps of a [`VolumeMapBoundary`] are obtained besides its inputs
/// ([`VolumeMapBoundary::build`]): a cache to load them from and store them in, and a
/// cancellation flag (set by a Ctrl-C handler or another thread) checked once per row of
/// nodes of each map being built.
#[derive(Debug, Clone, Copy, Default)]
pub struct VolumeMapBuild<'a> {
    /// Load maps from (and store built ones into) this cache.
    pub cache: Option<&'a VolumeMapCache>,
    /// Once set, the build stops within a row of nodes and returns
    /// [`SolverError::Cancelled`] naming the solid.
    pub cancel: Option<&'a AtomicBool>,
}

/// Solids with volume maps (Bender et al. 2019; equations in the module docs of
/// `volume_map`): [`Boundary::sample`] returns `Ψ(x) = Σ_k Ψ_k(x)` and
/// `∇Ψ(x) = Σ_k ∇Ψ_k(x)` summed over the solids (overlapping solids double-count their
/// overlap), [`Boundary::project`] moves particles out of the solids to `contact_distance`
/// (m) as a safety net against tunnelling.
pub struct VolumeMapBoundary<R: Real> {
    solids: Vec<Box<dyn Sdf<R>>>,
    maps: Vec<VolumeMap<R>>,
    kernel: KernelKind,
    support_radius: R,
    contact_distance: R,
    cache_warnings: Vec<SolverError>,
}

impl<R: Real> fmt::Debug for VolumeMapBoundary<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("VolumeMapBoundary")
            .field("solids", &self.solids.len())
            .field("kernel", &self.kernel)
            .field("support_radius", &self.support_radius)
            .field("contact_distance", &self.contact_distance)
            .field(
                "maps",
                &self.maps.iter().map(|m| m.stats()).collect::<Vec<_>>(),
            )
            .finish()
    }
}

impl<R: Real> VolumeMapBoundary<R> {
    /// Builds one volume map per solid for `kernel` with support radius `support_radius`
    /// (m, finite and > 0), over `domain` (m; finite, `min ≤ max`; the grids of unbounded
    /// solids cover it grown by `h`, those of bounded solids their bounds grown by `h`
    /// intersected with it). `contact_distance` (m, finite, ≥ 0) is the distance
    /// [`Boundary::project`] keeps particles from the surfaces.
    ///
    /// Errors: [`SolverError::InvalidParameter`] (`solver: "volume map"`) for bad options,
    /// distances or domain; [`SolverError::Kernel`] for an unusable `h`;
    /// [`SolverError::Boundary`] naming the solid when its grid is too large.
    pub fn new(
        solids: Vec<Box<dyn Sdf<R>>>,
        kernel: KernelKind,
        support_radius: R,
        domain: Aabb<R>,
        contact_distance: R,
        options: VolumeMapOptions,
    ) -> Result<Self, SolverError> {
        Self::with_cache(
            solids,
            kernel,
            support_radius,
            domain,
            contact_distance,
            options,
            None,
        )
    }

    /// As [`VolumeMapBoundary::new`], reusing maps from `cache` (see [`VolumeMapCache`]):
    /// each solid's map is loaded from the cache when its file exists and passes every
    /// check (bit-identical to a cold build), and otherwise built and written. A refused
    /// cache file or a failed write is not an error: the map is built, and the refusal is
    /// kept in [`VolumeMapBoundary::cache_warnings`] for the caller to log.
    /// [`VolumeMapStats::cache`](super::VolumeMapStats::cache) says what happened per map.
    ///
    /// Errors: those of [`VolumeMapBoundary::new`].
    pub fn with_cache(
        solids: Vec<Box<dyn Sdf<R>>>,
        kernel: KernelKind,
        support_radius: R,
        domain: Aabb<R>,
        contact_distance: R,
        options: VolumeMapOptions,
        cache: Option<&VolumeMapCache>,
    ) -> Result<Self, SolverError> {
        let how = VolumeMapBuild {
            cache,
            cancel: None,
        };
        Self::build(
            solids,
            kernel,
            support_radius,
            domain,
            contact_distance,
            options,
            how,
        )
    }

    /// As [`VolumeMapBoundary::with_cache`] with `how.cache`, stopping when `how.cancel`
    /// is set (checked once per row of nodes while a map is built).
    ///
    /// Errors: those of [`VolumeMapBoundary::new`], and [`SolverError::Cancelled`] naming
    /// the solid whose map was being built when the flag was set.
    pub fn build(
        solids: Vec<Box<dyn Sdf<R>>>,
        kernel: KernelKind,
        support_radius: R,
        domain: Aabb<R>,
        contact_distance: R,
        options: VolumeMapOptions,
        how: VolumeMapBuild<'_>,
    ) -> Result<Self, SolverError> {
        let cache = how.cache;
        options.validate()?;
        if !(contact_distance.is_finite_value() && contact_distance >= R::zero()) {
            return Err(invalid(
                "contact_distance",
                contact_distance.as_f64(),
                "must be finite and >= 0",
            ));
        }
        for a in 0..3 {
            for v in [domain.min[a], domain.max[a]] {
                if !v.is_finite_value() {
                    return Err(invalid("domain", v.as_f64(), "corners must be finite"));
                }
            }
            if domain.min[a] > domain.max[a] {
                return Err(invalid(
                    "domain",
                    domain.max[a].as_f64(),
                    "max must be >= min",
                ));
            }
        }
        if kernel == KernelKind::Viscosity {
            return Err(invalid(
                "kernel",
                f64::NAN,
                "the viscosity kernel is singular at r = 0 (its W'' r² is not integrable)",
            ));
        }
        let k = kernel.build(support_radius.as_f64())?;
        // The kernel must also be representable in the solver's precision.
        kernel.build(support_radius)?;
        let tables = Arc::new(KernelTables::new(&k));
        let mut cache_warnings = Vec::new();
        let mut maps = Vec::with_capacity(solids.len());
        for (i, s) in solids.iter().enumerate() {
            let build = || {
                VolumeMap::build(s.as_ref(), tables.clone(), &domain, &options, how.cancel).map_err(
                    |e| match e {
                        SolverError::Boundary(m) => {
                            SolverError::Boundary(format!("solid {i}: {m}"))
                        }
                        SolverError::Cancelled { what } => SolverError::Cancelled {
                            what: format!("solid {i}: {what}"),
                        },
                        e => e,
                    },
                )
            };
            let Some(cache) = cache else {
                maps.push(build()?);
                continue;
            };
            let Some(key) =
                VolumeMapKey::new(s.as_ref(), kernel, support_radius, &domain, &options)
            else {
                let mut map = build()?;
                map.stats.cache = CacheUse::Uncacheable;
                maps.push(map);
                continue;
            };
            let path = cache.path(&key);
            let mut refused = false;
            if path.exists() {
                match VolumeMap::read_with_tables(&path, &key, tables.clone()) {
                    Ok(map) => {
                        maps.push(map);
                        continue;
                    }
                    Err(e) => {
                        cache_warnings.push(e);
                        refused = true;
                    }
                }
            }
            let mut map = build()?;
            map.stats.cache = match map.write_file(&path, &key) {
                Ok(()) if refused => CacheUse::Replaced,
                Ok(()) => CacheUse::Stored,
                Err(e) => {
                    cache_warnings.push(e);
                    CacheUse::WriteFailed
                }
            };
            maps.push(map);
        }
        debug_assert_eq!(k.name(), kernel.name());
        Ok(Self {
            solids,
            maps,
            kernel,
            support_radius,
            contact_distance,
            cache_warnings,
        })
    }

    /// Cache files refused (and replaced) or not written during construction, as
    /// [`SolverError::MapFile`] errors naming the file and the reason; empty without a cache.
    pub fn cache_warnings(&self) -> &[SolverError] {
        &self.cache_warnings
    }

    /// The maps, one per solid (in [`Boundary::solids`] order), with their build statistics.
    pub fn maps(&self) -> &[VolumeMap<R>] {
        &self.maps
    }
}

impl<R: Real> Boundary<R> for VolumeMapBoundary<R> {
    fn name(&self) -> &'static str {
        "volume-map"
    }
    fn solids(&self) -> &[Box<dyn Sdf<R>>] {
        &self.solids
    }
    fn has_volume(&self) -> bool {
        true
    }
    fn volume_kernel(&self) -> Option<(KernelKind, R)> {
        Some((self.kernel, self.support_radius))
    }
    fn sample(&self, x: &Vec3<R>) -> BoundarySample<R> {
        let mut out = BoundarySample::default();
        for (s, m) in self.solids.iter().zip(&self.maps) {
            let (v, g) = m.sample(s.as_ref(), x);
            out.volume += v;
            out.volume_gradient += g;
        }
        out
    }
    #[inline]
    fn project(&self, x: Vec3<R>) -> Vec3<R> {
        project_out(&self.solids, x, self.contact_distance)
    }
    fn contact_distance(&self) -> R {
        self.contact_distance
    }
    /// Each map samples zero where its solid's distance is at least its support radius
    /// (`VolumeMap::sample`); the largest of them.
    fn volume_reach(&self) -> Option<f64> {
        Some(
            self.maps
                .iter()
                .map(VolumeMap::support_radius)
                .fold(f64::NEG_INFINITY, f64::max),
        )
    }
    fn contact_guard(&self) -> Option<crate::boundary::ContactGuard<R>> {
        crate::boundary::ContactGuard::for_solids(&self.solids, self.contact_distance)
    }
}
