//! Upscaling (Neder 2024 §5.12, left as "…" there; we follow Ihmsen, Wahl & Teschner 2012,
//! "High-Resolution Simulation of Granular Material with SPH", VRIPHYS '12, §5): passive
//! high-resolution points, several per simulation particle, advected with the velocity field
//! of the SPH particles.
//!
//! - **Seeding** (first step): `k` points per particle at `x_i + s (q_k − ½)` with `q_k` the
//!   `k`-th point of the 3D Halton sequence (bases 2, 3, 5), i.e. spread evenly over the
//!   particle's cube of side `s`, the same offsets for every particle.
//! - **Velocity** at a point `y` after each time step: the Shepard-normalised SPH interpolation
//!   `v(y) = Σ_j V_j v_j W(y − x_j) / Σ_j V_j W(y − x_j)` (`V_j = m_j/ρ_j`, the solver's cubic
//!   spline of support `h`) over the particles within `h` of `y`. Ihmsen et al. (2012)
//!   interpolate the same way with their own weighting; a point with no particle within `h`
//!   moves ballistically (`v += g Δt`).
//! - **Advection**: `y += Δt v(y)` (explicit Euler at the end of each time step), then the
//!   boundary's contact response.
//!
//! The particles are found through a hashed cell list of cell size `h` (rebuilt each time
//! step, a counting sort into a power-of-two table; a bucket shared by two of the 27 cells
//! around `y` is visited once).

use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_kernels::Kernel;
use sph_solver::step::MIN_LEN;
use sph_solver::Boundary;

/// The `i`-th element (1-based) of the van der Corput sequence in `base`.
fn radical_inverse(mut i: usize, base: usize) -> f64 {
    let mut f = 1.0;
    let mut r = 0.0;
    while i > 0 {
        f /= base as f64;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}

/// Offsets (in units of the spacing, in `[−½, ½)³`) of `k` points in a particle's cube.
pub fn seed_offsets(k: usize) -> Vec<[f64; 3]> {
    (1..=k)
        .map(|i| {
            [
                radical_inverse(i, 2) - 0.5,
                radical_inverse(i, 3) - 0.5,
                radical_inverse(i, 5) - 0.5,
            ]
        })
        .collect()
}

/// Passive high-resolution points and the hashed cell list used to advect them.
#[derive(Debug, Clone)]
pub struct Upscaler<R: Real> {
    per_particle: usize,
    seeded: bool,
    points: Vec<Vec3<R>>,
    velocities: Vec<Vec3<R>>,
    /// Bucket of each simulation particle, then the counting-sort arrays.
    bucket_of: Vec<u32>,
    bucket_start: Vec<u32>,
    sorted: Vec<u32>,
}

#[inline]
fn cell_of<R: Real>(x: &Vec3<R>, inv_h: f64) -> [i64; 3] {
    [
        (x.x.as_f64() * inv_h).floor() as i64,
        (x.y.as_f64() * inv_h).floor() as i64,
        (x.z.as_f64() * inv_h).floor() as i64,
    ]
}

#[inline]
fn bucket(c: [i64; 3], mask: u64) -> u32 {
    let h = (c[0] as u64).wrapping_mul(73_856_093)
        ^ (c[1] as u64).wrapping_mul(19_349_663)
        ^ (c[2] as u64).wrapping_mul(83_492_791);
    (h & mask) as u32
}

impl<R: Real> Upscaler<R> {
    /// `per_particle` passive points per simulation particle (not yet seeded).
    pub fn new(per_particle: usize) -> Self {
        Self {
            per_particle,
            seeded: false,
            points: Vec::new(),
            velocities: Vec::new(),
            bucket_of: Vec::new(),
            bucket_start: Vec::new(),
            sorted: Vec::new(),
        }
    }

    /// Whether [`Upscaler::seed`] has run.
    pub fn seeded(&self) -> bool {
        self.seeded
    }

    /// The passive points.
    pub fn points(&self) -> &[Vec3<R>] {
        &self.points
    }

    /// The velocities of the passive points (m/s): the interpolated velocity of the last
    /// step, or the last one advanced by gravity where no particle is within reach.
    pub fn velocities(&self) -> &[Vec3<R>] {
        &self.velocities
    }

    /// Puts back saved points and their velocities (of a checkpoint) and marks the points
    /// seeded. `points` and `velocities` must have the same length.
    pub fn restore(&mut self, points: Vec<Vec3<R>>, velocities: Vec<Vec3<R>>) {
        debug_assert_eq!(points.len(), velocities.len());
        self.points = points;
        self.velocities = velocities;
        self.seeded = true;
    }

    /// Seeds `per_particle` points around each of `positions` (spacing `s`), at rest.
    pub fn seed(&mut self, positions: &[Vec3<R>], s: R) {
        let offsets = seed_offsets(self.per_particle);
        self.points.clear();
        for x in positions {
            for o in &offsets {
                self.points
                    .push(x + Vec3::new(R::of_f64(o[0]), R::of_f64(o[1]), R::of_f64(o[2])) * s);
            }
        }
        self.velocities.clear();
        self.velocities.resize(self.points.len(), Vec3::zeros());
        self.seeded = true;
    }

    /// One time step `dt` of the points in the velocity field of the particles (`x`, `v`,
    /// `m`, `rho`), interpolated with `kernel`.
    #[allow(clippy::too_many_arguments)]
    pub fn advect<K: Kernel<R>>(
        &mut self,
        x: &[Vec3<R>],
        v: &[Vec3<R>],
        m: &[R],
        rho: &[R],
        kernel: &K,
        gravity: Vec3<R>,
        dt: R,
        boundary: &dyn Boundary<R>,
    ) {
        let h = kernel.support_radius();
        let inv_h = 1.0 / h.as_f64();
        let table = (2 * x.len()).next_power_of_two().max(1024);
        let mask = (table - 1) as u64;
        self.bucket_of.resize(x.len(), 0);
        self.bucket_of
            .par_iter_mut()
            .zip(x.par_iter())
            .with_min_len(MIN_LEN)
            .for_each(|(b, xi)| *b = bucket(cell_of(xi, inv_h), mask));
        self.bucket_start.clear();
        self.bucket_start.resize(table + 1, 0);
        for &b in &self.bucket_of {
            self.bucket_start[b as usize + 1] += 1;
        }
        for k in 0..table {
            self.bucket_start[k + 1] += self.bucket_start[k];
        }
        self.sorted.resize(x.len(), 0);
        // Fill using the start array as a cursor, then shift it back.
        for (i, &b) in self.bucket_of.iter().enumerate() {
            let slot = &mut self.bucket_start[b as usize];
            self.sorted[*slot as usize] = i as u32;
            *slot += 1;
        }
        for k in (1..=table).rev() {
            self.bucket_start[k] = self.bucket_start[k - 1];
        }
        self.bucket_start[0] = 0;
        let (starts, sorted) = (&self.bucket_start[..], &self.sorted[..]);
        let h2 = h * h;
        self.points
            .par_iter_mut()
            .zip(self.velocities.par_iter_mut())
            .with_min_len(MIN_LEN)
            .for_each(|(y, vy)| {
                let c = cell_of(y, inv_h);
                let mut seen = [u32::MAX; 27];
                let mut n_seen = 0;
                let mut num = Vec3::zeros();
                let mut den = R::zero();
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            let b = bucket([c[0] + dx, c[1] + dy, c[2] + dz], mask);
                            if seen[..n_seen].contains(&b) {
                                continue;
                            }
                            seen[n_seen] = b;
                            n_seen += 1;
                            let b = b as usize;
                            for &j in &sorted[starts[b] as usize..starts[b + 1] as usize] {
                                let j = j as usize;
                                let r2 = (*y - x[j]).norm_squared();
                                if r2 < h2 {
                                    let w = m[j] / rho[j] * kernel.value_r2(r2);
                                    num += v[j] * w;
                                    den += w;
                                }
                            }
                        }
                    }
                }
                *vy = if den > R::zero() {
                    num / den
                } else {
                    *vy + gravity * dt
                };
                *y = boundary.project(*y + *vy * dt);
            });
    }
}
