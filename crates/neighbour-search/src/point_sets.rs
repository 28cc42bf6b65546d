//! Point sets for testing and benchmarking neighbour searches: reproducible (seeded
//! [`SplitMix64`] streams or a counter hash), in `f64` (convert with [`to_real`]), each
//! chosen for what it exercises. The validation experiment of Im & Chan (2016) checks every
//! method against the O(N²) oracle on the [`PointSet`]s and times them on
//! [`jittered_block`]; the criterion benchmarks use [`jittered_lattice`] and [`splash`].
//!
//! | set | what it exercises |
//! | --- | --- |
//! | [`lattice_block`] | pairs at exactly the radius (ties decided identically by every method) |
//! | [`random_cloud`] | the generic case, about 30 neighbours each |
//! | [`two_clusters`] | a domain far larger than the particles (hashed and table methods; a dense grid refuses it), f32 quantisation |
//! | [`negative_coordinates`] | cells on both sides of zero (floor, not truncation) |
//! | [`cell_faces`] | points on cell boundaries (the cell margin [`CELL_MARGIN`]) and at exactly the radius |
//! | [`jittered_block`] | a uniform fluid-like block, one point uniformly random in each cube |
//! | [`jittered_lattice`], [`splash`] | a settled pool; a pool with droplets scattered above it |
//!
//! The points are generated, not checked: a caller that sizes a set from user input bounds it
//! first (the sets allocate `n` or `side³` points).

use sph_core::random::SplitMix64;
use sph_core::sampling::cubic_lattice;
use sph_core::{Aabb, CoreError, Real, Vec3};

use crate::CELL_MARGIN;

/// A named point set with the search radius it is meant for.
#[derive(Debug, Clone, PartialEq)]
pub struct PointSet {
    /// Its name in tables and file names (`"random"`, `"cell-faces"`, …).
    pub name: &'static str,
    /// The points.
    pub points: Vec<[f64; 3]>,
    /// The search radius the set is meant for.
    pub radius: f64,
}

/// Search radius giving about 30 neighbours for `n` points spread uniformly over `volume`:
/// `(4/3) π r³ · n / volume = 30`.
pub fn radius_for(volume: f64, n: usize) -> f64 {
    (30.0 * volume * 3.0 / (4.0 * std::f64::consts::PI * n as f64)).cbrt()
}

/// `"uniform-block"`: the cubic lattice of `round(∛n)³` points at `spacing` from the origin,
/// radius `2 · spacing` (pairs at exactly the radius).
pub fn lattice_block(n: usize, spacing: f64) -> PointSet {
    let side = (n as f64).cbrt().round() as usize;
    let mut block = Vec::with_capacity(side * side * side);
    for i in 0..side {
        for j in 0..side {
            for k in 0..side {
                block.push([i as f64 * spacing, j as f64 * spacing, k as f64 * spacing]);
            }
        }
    }
    PointSet {
        name: "uniform-block",
        points: block,
        radius: 2.0 * spacing,
    }
}

/// `"random"`: `n` points uniform in the unit cube (draws `x, y, z` per point), about 30
/// neighbours each.
pub fn random_cloud(rng: &mut SplitMix64, n: usize) -> PointSet {
    let points = (0..n)
        .map(|_| [rng.unit(), rng.unit(), rng.unit()])
        .collect();
    PointSet {
        name: "random",
        points,
        radius: radius_for(1.0, n),
    }
}

/// `"two-clusters-1e6-apart"`: `n` points alternately in `[0, 0.5)³` and the same cube moved
/// by 10⁶ along x (f32 quantises the far one to a 0.0625 lattice), radius 0.1.
pub fn two_clusters(rng: &mut SplitMix64, n: usize) -> PointSet {
    let points = (0..n)
        .map(|i| {
            let off = if i % 2 == 0 { 0.0 } else { 1.0e6 };
            [off + 0.5 * rng.unit(), 0.5 * rng.unit(), 0.5 * rng.unit()]
        })
        .collect();
    PointSet {
        name: "two-clusters-1e6-apart",
        points,
        radius: 0.1,
    }
}

/// `"negative-coordinates"`: `n` points uniform in `[−1.2, 0.3)³` (straddling zero, where
/// floor ≠ truncation), about 30 neighbours each.
pub fn negative_coordinates(rng: &mut SplitMix64, n: usize) -> PointSet {
    let points = (0..n)
        .map(|_| {
            [
                rng.range(-1.2, 0.3),
                rng.range(-1.2, 0.3),
                rng.range(-1.2, 0.3),
            ]
        })
        .collect();
    PointSet {
        name: "negative-coordinates",
        points,
        radius: radius_for(1.5f64.powi(3), n),
    }
}

/// `"cell-faces"`: `n` points whose coordinates are, each independently, on a cell boundary
/// `k · h (1 + CELL_MARGIN)` (probability ½), on a multiple `k · h` of the radius (¼: pairs at
/// exactly `h`) or uniform (¼), in `[−4h, 4h]`, with `h = 0.1` the radius.
pub fn cell_faces(rng: &mut SplitMix64, n: usize) -> PointSet {
    let h = 0.1;
    let face = h * (1.0 + CELL_MARGIN);
    let coord = |rng: &mut SplitMix64| {
        let k = rng.below(9) as f64 - 4.0;
        match rng.below(4) {
            0 | 1 => k * face,
            2 => k * h,
            _ => rng.range(-4.0 * h, 4.0 * h),
        }
    };
    let points = (0..n)
        .map(|_| [coord(rng), coord(rng), coord(rng)])
        .collect();
    PointSet {
        name: "cell-faces",
        points,
        radius: h,
    }
}

/// `side³` points, one uniformly random in each cube `[i, i+1) × [j, j+1) × [k, k+1)` of edge
/// `spacing` (loop order `i`, `j`, `k`; draws `x, y, z` per point from `rng`).
pub fn jittered_block(rng: &mut SplitMix64, side: usize, spacing: f64) -> Vec<Vec3<f64>> {
    let mut pos = Vec::with_capacity(side * side * side);
    for i in 0..side {
        for j in 0..side {
            for k in 0..side {
                pos.push(Vec3::new(
                    (i as f64 + rng.unit()) * spacing,
                    (j as f64 + rng.unit()) * spacing,
                    (k as f64 + rng.unit()) * spacing,
                ));
            }
        }
    }
    pos
}

/// The counter hash of the benchmarks' sets: the first [`SplitMix64::unit`] of seed `x`.
fn hash01(x: u64) -> f64 {
    SplitMix64::new(x).unit()
}

/// A cube of about `n` points on the cubic lattice of `spacing` (`sph_core`'s
/// [`cubic_lattice`] of `round(∛n)` points per edge), each
/// coordinate moved by up to ±0.5 % of the spacing (`(hash01(1 ^ (3i + a)) − ½) · 0.01 ·
/// spacing` for point `i`, axis `a`), so that the lattice's exact distances do not all fall on
/// the radius; with radius `2 · spacing` each point has about 30 neighbours. Errors: a
/// spacing that is not finite and positive.
pub fn jittered_lattice<R: Real>(n: usize, spacing: f64) -> Result<Vec<Vec3<R>>, CoreError> {
    let side = (n as f64).cbrt().round().max(1.0);
    let edge = R::of_f64(side * spacing);
    let b = Aabb::new(Vec3::zeros(), Vec3::repeat(edge))?;
    let mut p = cubic_lattice(&b, R::of_f64(spacing), usize::MAX)?;
    let amplitude = 0.01 * spacing;
    for (i, q) in p.iter_mut().enumerate() {
        for a in 0..3 {
            let r = hash01(1 ^ (3 * i as u64 + a as u64)) - 0.5;
            q[a] += R::of_f64(r * amplitude);
        }
    }
    Ok(p)
}

/// A splash-like set of about `n` points: half a [`jittered_lattice`] pool, half droplets
/// scattered uniformly over a region 4× wider and 4× taller than the pool (a few neighbours
/// each at radius `2 · spacing`; droplet `i`'s coordinates from `hash01(0xdeadbeef ^ (3i + k))`).
/// Errors: as [`jittered_lattice`].
pub fn splash<R: Real>(n: usize, spacing: f64) -> Result<Vec<Vec3<R>>, CoreError> {
    let mut p = jittered_lattice::<R>(n / 2, spacing)?;
    let side = ((n / 2) as f64).cbrt().round() * spacing;
    let drops = n - p.len().min(n);
    for i in 0..drops as u64 {
        let u = |k: u64| hash01(0xdead_beef ^ (3 * i + k));
        p.push(Vec3::new(
            R::of_f64((u(0) * 4.0 - 1.5) * side),
            R::of_f64((1.0 + u(1) * 4.0) * side),
            R::of_f64((u(2) * 4.0 - 1.5) * side),
        ));
    }
    Ok(p)
}

/// The points in precision `R`.
pub fn to_real<R: Real>(points: &[[f64; 3]]) -> Vec<Vec3<R>> {
    points
        .iter()
        .map(|p| Vec3::new(R::of_f64(p[0]), R::of_f64(p[1]), R::of_f64(p[2])))
        .collect()
}
