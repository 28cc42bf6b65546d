//! Volume maps: the boundary's share of the SPH density, precomputed per solid on a grid.
//!
//! J. Bender, T. Kugelstadt, M. Weiler, D. Koschier, "Volume Maps: An Implicit Boundary
//! Representation for SPH", Proc. ACM SIGGRAPH Conference on Motion, Interaction and Games
//! (MIG '19), <https://doi.org/10.1145/3359566.3360077>.
//!
//! # Equations
//!
//! Bender et al. write the density of particle `i` as `ρ_i = Σ_j m_j W_ij + Σ_b ρ0 V_b W_ib`
//! and represent the boundary term by the volume `V_b` of the solid inside the support,
//! placed as one virtual particle at the closest surface point. Here the boundary term is the
//! integral that this one-particle approximation stands for, the **kernel-weighted boundary
//! volume**
//!
//! `Ψ(x) = ∫_solid W(x − y) dy` (dimensionless), `ρ_B = ρ0 Ψ(x_i)`,
//! `Σ_b V_b W_ib ≡ Ψ(x_i)`, `Σ_b V_b ∇W_ib ≡ ∇Ψ(x_i)` (1/m, pointing into the solid),
//!
//! which is the density map of Koschier & Bender, "Density maps for improved SPH boundary
//! handling", SCA '17 (their `ρ̃(x)/ρ0`), with the kernel integral taken directly rather than
//! through a per-point volume. It is evaluated as
//!
//! `Ψ(x) = Ψ_plane(φ(x)) + C(x)`,
//!
//! with `φ` the solid's signed distance, `Ψ_plane(d) = 2π ∫_d^h W(r) r (r − d) dr` the exact
//! volume of the tangent half-space ([`half_space_volume`], tabulated with 4096 cubic Hermite
//! intervals, error < 1e-12), and `C` a correction that is exactly 0 wherever the solid inside
//! the support ball is that half-space (flat walls are exact), small and smooth near curved
//! surfaces, and non-zero near edges and corners. `C` is computed at grid nodes of spacing
//! `h / cells_per_support` over the solid's band by a spherical quadrature of the
//! **difference** between the solid and its tangent half-space, direction by direction (see
//! `quadrature::node_correction`), skipped where `|φ| ≥ h` or where 78 probes of the ball
//! agree with the tangent plane to `1e-9 h`.
//!
//! # Why not a trilinear `C`: second-order node models (default)
//!
//! A trilinear interpolation of `C(x) = Ψ_exact(x) − Ψ_plane(φ(x))` has an `O(cell)` error
//! wherever `φ` has a kink inside the band, i.e. on the medial axis of the distance field:
//! inside a tank, along the bisector planes of every edge and corner — exactly where fluid
//! particles sit. The jump of `∇C` there is `|Ψ_plane'(φ)| |n₁ − n₂|`, up to `1.7/h` for
//! Poly6; measured in a tank corner: 1.7e-2 of the bulk value. And even on a smooth sphere `C`
//! is not small: it reaches −0.08 for a radius of `1.5 h` and −0.03 for `4 h`, so its trilinear
//! error at `h/4` cells is ~2e-3. The default [`Interpolation::NodePlanes`] therefore stores at
//! each node `c` its own plane `(φ_c, n_c)` and the value, gradient and Hessian of
//! `D_c = Ψ_exact − Ψ_plane(φ_c + n_c·(x − x_c))` at `x_c` (all three from the same
//! spherical quadrature, planar parts cancelling direction by direction), and blends the
//! nodes' second-order models with the trilinear weights `w_c(x)`:
//!
//! `Ψ(x) = Σ_c w_c(x) [Ψ_plane(φ_c + n_c·Δ_c) + C_c + g_c·Δ_c + ½ Δ_cᵀ H_c Δ_c]`,
//! `Δ_c = x − x_c`.
//!
//! Each `D_c` is smooth (also across the medial axis of `φ`, since its plane is fixed), so the
//! blend errs by `O(cell³)`; it is exact for flat walls. `∇Ψ` is the exact gradient of this
//! interpolant (continuous inside cells, C⁰ across cell faces). Storage: 56 bytes (`f32`) per
//! node within `h + √3 cell` of the surface plus a 4-byte index per grid node.
//! [`Interpolation::TrilinearCorrection`] interpolates `C` trilinearly, kept for comparison.
//!
//! # Accuracy and cost (measured, tests `tests/volume_map.rs`; absolute, bulk value 1)
//!
//! | case | 16 × 32 directions (default) | 32 × 64 |
//! |---|---|---|
//! | half-space, tank wall away from edges | 1e-6 (f32 node storage) | same |
//! | sphere `a = 1.5 h`, `4 h` (Poly6) | 8.6e-3, 9.4e-3 | 1.8e-3, 2.1e-3 |
//! | sphere `a = h … 4 h` (Wendland C2, within 0.9 h of the surface) | — | 2.8e-3 … 6.1e-3 |
//! | tank corner (Poly6) | 3.4e-3 (trilinear `C`: 1.7e-2) | — |
//! | icosphere `GridSdf` (cell h/10) | — | 5.9e-3 |
//!
//! With 16 × 32 directions the error is that of the direction quadrature at the nodes (the
//! solid's ray integrals have kinks at grazing directions that the Gauss–Legendre rule in
//! `cos θ` does not resolve); 64 × 128 reaches ~3e-4 on the sphere.
//!
//! # Cost
//!
//! Every node costs one distance and one gradient; each band node 78 more distances (the
//! planarity probes); each quadrature node (near edges, corners and curved surfaces)
//! `polar × azimuth` rays. Along a ray, solids with closed-form ray intervals
//! ([`Sdf::ray_inside_intervals`](sph_core::Sdf::ray_inside_intervals): planes, spheres, boxes, vertical cylinders and their complements) give the
//! inside stretches directly (exact up to `f64` rounding of the stored shape). Other solids
//! (meshes, user solids) are searched: a ray samples `φ` at `ray_samples` points, refines
//! each sign change by regula falsi to `|φ| ≤ 1e-10 h` and searches intervals whose end
//! values leave room for a thin sliver of solid (bisection down to `1e-6 h`). For solids with
//! a known Lipschitz bound ([`Sdf::lipschitz_bound`](sph_core::Sdf::lipschitz_bound), 1 for exact distances) samples and
//! searches that the bound rules out are skipped: the crossings, and the brackets they are
//! refined from, are those of the full search, so the map is bit-identical (on the tank
//! below: 9.4 distance evaluations per ray instead of 19.3). For such solids the sliver
//! search is also skipped in the first interval of rays from nodes on the surface
//! (`|φ| ≤` rounding): it would bisect towards the surface the node lies on, down to
//! `1e-6 h`. This changes a map only where a solid sliver lies within `h / ray_samples` of
//! such a node (the property test `lipschitz_skips_are_bit_identical_to_the_full_search`
//! checks nodes on walls, edges and corners); closed-form intervals agree with the search to
//! its root tolerance (`closed_form_intervals_agree_with_the_search`). Nodes are built in
//! parallel by rows, each node on its own, so parallel and sequential builds are
//! bit-identical. SPlisHSPlasH's dam-break tank (4 × 3 × 1.5 m, cubic spline, `h = 0.05` m,
//! `f32`): 1.06e7 nodes, 2.3e6 in the band, 2.4e5 by quadrature, 2.9e6 stored (203 MB as a
//! cache file); dated timings against SPlisHSPlasH in `docs/performance.md`. 32 × 64
//! directions cost 4× the quadrature time.
//!
//! # Cache
//!
//! A map depends only on its [`VolumeMapKey`]: the solid's [`Sdf::fingerprint`](sph_core::Sdf::fingerprint), kernel,
//! support radius, domain, options, precision and the format and build versions
//! ([`FORMAT_VERSION`], [`BUILD_VERSION`]). [`VolumeMapBoundary::with_cache`] looks each map
//! up in a [`VolumeMapCache`] directory (file `<SHA-256 of the key>.vmap`), loads it when
//! the file passes every check (bit-identical to a cold build), and otherwise builds it and
//! writes the file atomically. [`VolumeMap::read_file`] documents the format and the
//! refusals ([`SolverError::MapFile`](crate::SolverError::MapFile)): a corrupt, truncated, foreign or other-version file
//! is never half-loaded; the boundary then rebuilds, replaces the file and reports the
//! refusal in [`VolumeMapBoundary::cache_warnings`] for the caller to log. Solids that do
//! not describe themselves (the default of [`Sdf::fingerprint`](sph_core::Sdf::fingerprint)) are rebuilt every time.
//!
//! # Grid size
//!
//! A solid's grid may have at most [`VolumeMapOptions::max_nodes`] nodes (default 2²⁵), and
//! that limit at most 2²⁶ ([`SampledGrid::MAX_NODES`](sph_core::grid::SampledGrid::MAX_NODES)), checked before any work.
//!
//! # Other deviations and limits
//!
//! - Overlapping solids double-count their overlap (each solid is integrated on its own).
//! - The viscosity kernel is rejected (its `W'' r²`, needed for the Hessians, diverges).
//! - Nodes equidistant to two surfaces (e.g. at `φ = h` from two tank walls) carry one of the
//!   planes; beyond `φ ≥ h` their correction is not computed, so within a cell of such
//!   nodes `Ψ` errs by up to `Ψ_plane(h − √3 cell)` (~1e-4 at `h/4` cells for Poly6).
//! - Root finding along rays assumes the distance is 2-Lipschitz (or the solid's
//!   [`Sdf::lipschitz_bound`](sph_core::Sdf::lipschitz_bound)); solid slivers thinner than `1e-6 h` between ray samples are
//!   ignored, and for solids with a declared bound, slivers in the first `h / ray_samples`
//!   of rays from nodes on the surface.
//! - Outside the grid box `C = 0`: for bounded solids the box is the solid's bounds grown by
//!   `h` (intersected with the domain grown by `h`), for unbounded solids the domain grown by
//!   `h`.

mod boundary;
mod file;
mod key;
mod map;
mod options;
mod quadrature;

pub use boundary::{VolumeMapBoundary, VolumeMapBuild};
pub use file::MAGIC;
pub use key::{VolumeMapCache, VolumeMapKey, BUILD_VERSION, FORMAT_VERSION};
pub use map::{CacheUse, VolumeMap, VolumeMapStats};
pub use options::{Interpolation, VolumeMapOptions};
pub use quadrature::{half_space_volume, half_space_volume_derivative};
