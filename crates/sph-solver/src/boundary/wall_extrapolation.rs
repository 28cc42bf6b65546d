//! The values of boundary (dummy) particles, extrapolated from the particles around them:
//! Adami, Hu & Adams (2012), "A generalized wall boundary condition for smoothed particle hydrodynamics", *J. Comput. Phys.*
//! 231:7057–7075, with the pressure generalised to the stress tensor as in Bui et al.
//! (2008, rows of fixed boundary particles) and Project Chrono's CRM (Hu, Rakhsha, Yang,
//! Negrut et al. 2021, *CMAME* 385:114022, boundary condition enforcing markers).
//!
//! For a boundary particle `b` with unit normal `n_b` (pointing into the particles' side),
//! over the particle neighbours `f` (Shepard weights `W_bf`, `r_bf = x_b − x_f`):
//!
//! ```text
//! σ̄_b = (Σ_f σ_f W_bf − I Σ_f ρ_f (g·r_bf) W_bf) / Σ_f W_bf     (Adami eq. 27, stress)
//! ṽ_b = Σ_f v_f W_bf / Σ_f W_bf
//! free-slip:  σ_b = P σ̄_b P,  v_b = P ṽ_b,   P = I − 2 n_b n_bᵀ (the mirror image)
//! no-slip:    σ_b = σ̄_b,      v_b = −ṽ_b                       (wall at rest)
//! Coulomb:    σ_b = σ̄_b − 2(1 − χ)(n t_tᵀ + t_t nᵀ),  v_b = −(ṽ·n) n + (1 − 2χ) ṽ_t
//! ```
//!
//! **Coulomb walls** (wall friction coefficient `μ_w`). Write the extrapolated traction on
//! the wall's plane as `σ̄ n = t_n n + t_t` (`t_n = nᵀσ̄n`, compressive when negative;
//! `t_t = (I − nnᵀ) σ̄ n` its tangential part) and the velocity as `ṽ = (ṽ·n) n + ṽ_t`. The
//! mirror is `P σ̄ P = σ̄ − 2(n t_tᵀ + t_t nᵀ)`: it keeps `t_n` and the in-plane block and
//! reverses `t_t`. A particle next to the wall and its boundary neighbours enter the
//! momentum sum through `σ_i/ρ_i² + σ_b/ρ_b²`, so the traction the wall carries is that of
//! the mean `(σ̄ + σ_b)/2`: its normal part is `t_n` for every model, its tangential part
//! `0` for free-slip (the mirror), `t_t` for no-slip, and `χ t_t` for
//! `σ_b = σ̄ − 2(1 − χ)(n t_tᵀ + t_t nᵀ)`. Coulomb's law, a tangential traction at most
//! `μ_w` times the compressive normal one, gives
//!
//! ```text
//! χ = min(1, μ_w max(−t_n, 0) / |t_t|)    (χ = 1 when t_t = 0; 0 ≤ χ ≤ 1)
//! ```
//!
//! so a wall below the limit acts as no-slip (`χ = 1`), a sliding one passes exactly
//! `μ_w |t_n|` in the direction of `t_t`, and a wall in tension (`t_n ≥ 0`, no contact)
//! is free-slip (`χ = 0`). The velocity follows the same blend between the mirror of the
//! tangential velocity (no-slip, `−ṽ_t`) and its copy (free-slip, `+ṽ_t`), so that the
//! velocity gradient at a wall that slides does not keep loading the shear the limit
//! removes. `μ_w = 0` is free-slip; a large `μ_w` is no-slip.
//!
//! **Moving walls.** A boundary particle with a wall velocity `v_w` moves with it (`x_b +=
//! v_w Δt` each explicit step) and its model acts on the relative velocity: `v_b = v_w +
//! f(ṽ − v_w)` with `f` the fixed wall's rule above (`−u`, the mirror `P u`, or Coulomb's
//! blend). The wall's acceleration is taken as zero (Adami et al. 2012, eq. 27, has
//! `g − a_w`): a wall moves at constant velocity between the changes its owner makes.
//!
//! A solver gives them a density and a mass (the elastic–plastic solver: `ρ0` and a
//! particle's) and lets them enter its sums as neighbours. A fluid's pressure is the
//! isotropic case `σ = −p I`, for which the rule is Adami et al.'s own. The
//! isotropic gravity term carries the hydrostatic gradient of the normal stress across the
//! wall (the part the wall must supply for a resting layer to carry its weight). A boundary
//! particle without particle neighbours carries no stress and no velocity; one that no
//! particle lists and that lists no particle (most of a wall's particles, away from the
//! material) is read by no sum and is skipped: its values are left as they were.

use nalgebra::Matrix3;
use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_kernels::Kernel;

use super::particles::BoundaryParticle;
use crate::scene_boundary::{PeriodicImages, WallModel};
use crate::step::MIN_LEN;
use crate::NeighbourLists;

/// The stress and velocity of a Coulomb boundary particle with unit normal `n` and wall
/// friction coefficient `mu` from the extrapolated `s_bar`, `v_bar` (module docs).
pub fn coulomb<R: Real>(
    s_bar: &Matrix3<R>,
    v_bar: &Vec3<R>,
    n: &Vec3<R>,
    mu: R,
) -> (Matrix3<R>, Vec3<R>) {
    let t = s_bar * n;
    let t_n = n.dot(&t);
    let t_t = t - n * t_n;
    let tau = t_t.norm();
    let limit = mu * (-t_n).max(R::zero());
    let chi = if tau > limit { limit / tau } else { R::one() };
    let two = R::of_f64(2.0);
    let s_b = s_bar - (n * t_t.transpose() + t_t * n.transpose()) * (two * (R::one() - chi));
    let v_n = n.dot(v_bar);
    let v_t = v_bar - n * v_n;
    (s_b, v_t * (R::one() - two * chi) - n * v_n)
}

/// What [`extrapolate`] reads.
#[derive(Debug, Clone, Copy)]
pub struct Extrapolation<'a, R: Real, K: Kernel<R>> {
    /// The kernel of the Shepard weights.
    pub kernel: K,
    /// The images of the particles near periodic ends (empty without periodic axes).
    pub images: &'a PeriodicImages<R>,
    /// Positions of the particles then the boundary particles.
    pub x: &'a [Vec3<R>],
    /// Densities of the particles (those of the boundary particles are not read).
    pub rho: &'a [R],
    /// The boundary particles.
    pub particles: &'a [BoundaryParticle<R>],
    /// Gravity (m/s²).
    pub gravity: Vec3<R>,
}

/// The particle neighbours of each boundary particle (from the neighbour lists, in their
/// order: the extrapolation's sums add in the same order as over the whole lists, whose
/// other entries, if the search listed them, are boundary particles; a search with the
/// boundary particles passive, `StepNeighbours::find_active`, lists none), rebuilt at each
/// neighbour search, and their
/// Shepard weights `W_bf` and gravity terms `ρ_f (g·r_bf) W_bf`, computed once per step for
/// both extrapolations of the step; and which boundary particles any particle's sum reads.
#[derive(Debug, Clone, Default)]
pub struct BoundaryLists<R: Real> {
    /// Whether boundary particle `k` lists a particle or a particle lists it (or an image
    /// of it): the boundary particles whose values a sum reads, the only ones
    /// [`extrapolate`] writes.
    read: Vec<bool>,
    /// Whether chunk `c` (boundary particles `c · READ_CHUNK..`, [`READ_CHUNK`]) holds a
    /// read one: the loops over the boundary particles skip the other chunks whole.
    chunk_read: Vec<bool>,
    /// CSR offsets: boundary particle `k`'s entries are `start[k]..start[k + 1]`.
    start: Vec<usize>,
    /// The lists' entry (a particle or an image of one).
    entry: Vec<u32>,
    /// The particle it resolves to.
    grain: Vec<u32>,
    /// The boundary particle (`0..`) whose entry it is.
    owner: Vec<u32>,
    weight: Vec<R>,
    weighted_gravity: Vec<R>,
}

impl<R: Real> BoundaryLists<R> {
    /// Keeps, for each of the `count` boundary particles `n..n + count` of `nb`, the entries
    /// that resolve to a particle (`< n`), and marks the boundary particles a particle's
    /// list holds. Grows its arrays to the pair count (reusing them).
    pub fn rebuild(
        &mut self,
        nb: &NeighbourLists,
        images: &PeriodicImages<R>,
        x: &[Vec3<R>],
        n: usize,
        count: usize,
    ) {
        self.start.clear();
        self.entry.clear();
        self.grain.clear();
        self.owner.clear();
        self.start.push(0);
        for k in 0..count {
            for &j in nb.neighbours(n + k) {
                let (f, _) = images.resolve(j as usize, x);
                if f < n {
                    self.entry.push(j);
                    self.grain.push(f as u32);
                    self.owner.push(k as u32);
                }
            }
            self.start.push(self.entry.len());
        }
        self.read.clear();
        self.read.extend(self.start.windows(2).map(|w| w[1] > w[0]));
        for i in 0..n {
            for &j in nb.neighbours(i) {
                let (f, _) = images.resolve(j as usize, x);
                if f >= n {
                    self.read[f - n] = true;
                }
            }
        }
        self.chunk_read.clear();
        self.chunk_read
            .extend(self.read.chunks(READ_CHUNK).map(|c| c.contains(&true)));
        let len = self.entry.len();
        self.weight.resize(len, R::zero());
        self.weighted_gravity.resize(len, R::zero());
    }

    /// Whether boundary particle `k` (`0..`) is read by a particle's sum or reads one (as of
    /// the last [`BoundaryLists::rebuild`]): [`extrapolate`] writes only those.
    pub fn is_read(&self, k: usize) -> bool {
        self.read.get(k).copied().unwrap_or(false)
    }

    /// Whether chunk `c` of [`READ_CHUNK`] boundary particles (`c · READ_CHUNK..`) holds
    /// one [`BoundaryLists::is_read`]: a loop over the boundary particles by chunks skips
    /// the others whole (most of a wall's, away from the material).
    pub fn is_chunk_read(&self, c: usize) -> bool {
        self.chunk_read.get(c).copied().unwrap_or(false)
    }

    /// The weights and gravity terms at the positions `e.x` (boundary particles from `n =
    /// e.x.len() − e.particles.len()` on).
    pub fn weigh<K: Kernel<R>>(&mut self, e: &Extrapolation<'_, R, K>) {
        let n = e.x.len() - e.particles.len();
        let (entry, owner) = (&self.entry, &self.owner);
        self.weight
            .par_iter_mut()
            .zip(self.weighted_gravity.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(m, (w, wg))| {
                let (j, xj) = e.images.resolve(entry[m] as usize, e.x);
                let r = e.x[n + owner[m] as usize] - xj;
                *w = e.kernel.value(r.norm());
                *wg = e.rho[j] * e.gravity.dot(&r) * *w;
            });
    }
}

/// Boundary particles per chunk of [`BoundaryLists::is_chunk_read`].
pub const READ_CHUNK: usize = 64;

/// Chunks of [`READ_CHUNK`] handed to one rayon task ([`MIN_LEN`] particles).
pub const CHUNKS_PER_TASK: usize = MIN_LEN / READ_CHUNK;

/// A tensor a solver derives from each boundary particle's stress (e.g. the elastic–plastic
/// solver's artificial stress), written by [`extrapolate`] beside it.
pub type Derived<'a, R> = (
    &'a mut [Matrix3<R>],
    &'a (dyn Fn(&Matrix3<R>) -> Matrix3<R> + Sync),
);

/// Writes the boundary particles' stress into `stress[n..]` from the particles' `stress[..n]`
/// (module docs), a tensor derived from it into `derived.0[n..]` if given (`derived.1` of
/// the stress), and their velocity into `v[n..]` if given (from `v[..n]`), with the weights
/// of the last [`BoundaryLists::weigh`]; only for the boundary particles a sum reads
/// ([`BoundaryLists::is_read`]), the others left as they were.
pub fn extrapolate<R: Real, K: Kernel<R>>(
    e: &Extrapolation<'_, R, K>,
    lists: &BoundaryLists<R>,
    stress: &mut [Matrix3<R>],
    v: Option<&mut [Vec3<R>]>,
    derived: Option<Derived<'_, R>>,
) {
    let n = e.x.len() - e.particles.len();
    let (s_head, s_tail) = stress.split_at_mut(n);
    let (v_head, v_tail) = match v {
        Some(v) => {
            let (h, t) = v.split_at_mut(n);
            (Some(&*h), Some(t))
        }
        None => (None, None),
    };
    let (art_tail, derive) = match derived {
        Some((a, f)) => (Some(&mut a[n..]), Some(f)),
        None => (None, None),
    };
    let two = R::of_f64(2.0);
    let work =
        |k: usize, sig: &mut Matrix3<R>, vel: Option<&mut Vec3<R>>, a: Option<&mut Matrix3<R>>| {
            if !lists.is_read(k) {
                return;
            }
            let mut sum_s = Matrix3::zeros();
            let mut sum_g = R::zero();
            let mut sum_v = Vec3::zeros();
            let mut sum_w = R::zero();
            for m in lists.start[k]..lists.start[k + 1] {
                let j = lists.grain[m] as usize;
                let w = lists.weight[m];
                sum_s += s_head[j] * w;
                sum_g += lists.weighted_gravity[m];
                if let Some(vh) = v_head {
                    sum_v += vh[j] * w;
                }
                sum_w += w;
            }
            let p = &e.particles[k];
            let mirror = Matrix3::identity() - p.normal * p.normal.transpose() * two;
            let (s_bar, v_bar) = if sum_w > R::zero() {
                ((sum_s - Matrix3::identity() * sum_g) / sum_w, sum_v / sum_w)
            } else {
                (Matrix3::zeros(), Vec3::zeros())
            };
            // A moving wall: its models act on the velocity relative to it.
            let moving = p.velocity != Vec3::zeros();
            let v_rel = if moving { v_bar - p.velocity } else { v_bar };
            let (s_b, v_b) = match p.model {
                WallModel::NoSlip => (s_bar, -v_rel),
                WallModel::Coulomb(mu) => coulomb(&s_bar, &v_rel, &p.normal, R::of_f64(mu)),
                _ => (mirror * s_bar * mirror, mirror * v_rel),
            };
            let v_b = if moving { v_b + p.velocity } else { v_b };
            *sig = s_b;
            if let Some(vel) = vel {
                *vel = v_b;
            }
            if let (Some(a), Some(f)) = (a, derive) {
                *a = f(&s_b);
            }
        };
    // By chunks of READ_CHUNK, those without a read boundary particle skipped whole.
    let (c, read) = (READ_CHUNK, |k: usize| lists.is_chunk_read(k));
    match (v_tail, art_tail) {
        (Some(vt), None) => s_tail
            .par_chunks_mut(c)
            .zip(vt.par_chunks_mut(c))
            .enumerate()
            .with_min_len(CHUNKS_PER_TASK)
            .filter(|(k, _)| read(*k))
            .for_each(|(k, (sig, vel))| {
                for (e, (sig, vel)) in sig.iter_mut().zip(vel).enumerate() {
                    work(k * c + e, sig, Some(vel), None);
                }
            }),
        (None, Some(at)) => s_tail
            .par_chunks_mut(c)
            .zip(at.par_chunks_mut(c))
            .enumerate()
            .with_min_len(CHUNKS_PER_TASK)
            .filter(|(k, _)| read(*k))
            .for_each(|(k, (sig, a))| {
                for (e, (sig, a)) in sig.iter_mut().zip(a).enumerate() {
                    work(k * c + e, sig, None, Some(a));
                }
            }),
        _ => s_tail
            .par_chunks_mut(c)
            .enumerate()
            .with_min_len(CHUNKS_PER_TASK)
            .filter(|(k, _)| read(*k))
            .for_each(|(k, sig)| {
                for (e, sig) in sig.iter_mut().enumerate() {
                    work(k * c + e, sig, None, None);
                }
            }),
    }
}

#[cfg(test)]
mod tests {
    use neighbour_search::Method;
    use sph_kernels::CubicSpline;

    use super::*;
    use crate::step::StepNeighbours;

    /// A wall of 600 boundary particles along `x` (spacing 0.01 m, ten chunks) under two
    /// clumps of particles, searched with the boundary particles passive: [`extrapolate`]
    /// writes exactly the boundary particles [`BoundaryLists::is_read`] marks (their values
    /// finite, the others left at the NaN they started with), a chunk is read exactly when
    /// one of its particles is, and the read ones are those within the search radius of a
    /// particle (counted here by distance). A chunk index off by one (planted once,
    /// 2026-12-06) fails it.
    #[test]
    fn extrapolate_writes_exactly_the_read_boundary_particles() {
        let (s, h) = (0.01f64, 0.02f64);
        let mut x: Vec<Vec3<f64>> = Vec::new();
        for (lo, count) in [(0.70, 12), (4.505, 30)] {
            x.extend((0..count).map(|i| Vec3::new(lo + i as f64 * 0.007, 0.006, 0.0)));
        }
        let n = x.len();
        let particles: Vec<BoundaryParticle<f64>> = (0..600)
            .map(|k| BoundaryParticle {
                position: Vec3::new(k as f64 * s, 0.0, 0.0),
                normal: Vec3::new(0.0, 1.0, 0.0),
                model: WallModel::NoSlip,
                velocity: Vec3::zeros(),
            })
            .collect();
        x.extend(particles.iter().map(|b| b.position));
        let mut search = StepNeighbours::new(Method::CellStartGrid);
        search.find_active(&x, n, h).unwrap();
        assert!(search.lists().neighbours(n + 100).is_empty());
        let images = PeriodicImages::default();
        let mut lists = BoundaryLists::default();
        lists.rebuild(search.lists(), &images, &x, n, particles.len());
        let rho = vec![1000.0; n];
        let e = Extrapolation {
            kernel: CubicSpline::new(h).unwrap(),
            images: &images,
            x: &x,
            rho: &rho,
            particles: &particles,
            gravity: Vec3::new(0.0, -9.81, 0.0),
        };
        lists.weigh(&e);
        let mut stress: Vec<Matrix3<f64>> = (0..x.len())
            .map(|i| Matrix3::identity() * -(i as f64))
            .collect();
        stress[n..].fill(Matrix3::from_element(f64::NAN));
        let mut v = vec![Vec3::new(0.1, 0.0, 0.0); x.len()];
        v[n..].fill(Vec3::from_element(f64::NAN));
        extrapolate(&e, &lists, &mut stress, Some(&mut v), None);
        // The other arm: the stress with a tensor derived from it, no velocity.
        let mut stress2 = stress.clone();
        stress2[n..].fill(Matrix3::from_element(f64::NAN));
        let mut derived = vec![Matrix3::from_element(f64::NAN); x.len()];
        let twice = |m: &Matrix3<f64>| m * 2.0;
        extrapolate(&e, &lists, &mut stress2, None, Some((&mut derived, &twice)));
        let mut read = 0;
        for k in 0..particles.len() {
            let near = x[..n]
                .iter()
                .any(|p| (p - particles[k].position).norm() < h);
            assert_eq!(lists.is_read(k), near, "boundary particle {k}");
            let written = stress[n + k].iter().all(|c| c.is_finite()) && v[n + k].x.is_finite();
            assert_eq!(written, near, "boundary particle {k} written");
            let derived_written = derived[n + k].iter().all(|c| c.is_finite());
            assert_eq!(
                derived_written, near,
                "boundary particle {k}'s derived tensor"
            );
            if near {
                assert_eq!(stress2[n + k], stress[n + k], "boundary particle {k}");
            }
            read += usize::from(near);
        }
        assert!(read > 0 && read < particles.len());
        for c in 0..particles.len().div_ceil(READ_CHUNK) {
            let any = (c * READ_CHUNK..((c + 1) * READ_CHUNK).min(particles.len()))
                .any(|k| lists.is_read(k));
            assert_eq!(lists.is_chunk_read(c), any, "chunk {c}");
        }
    }
}
