//! The SPH density of every particle ([`crate::step::density_at`] for all `i`), with the
//! cubic spline in `f32` AVX-512 lanes when the processor has them (detected at run time):
//! one particle at a time, sixteen of its neighbours per vector, from the packed positions
//! and masses ([`crate::pair_lanes::CubicLanes::density`]).
//!
//! Each pair's term is the scalar kernel's operations in the scalar order (no fused
//! multiply–add; the spline's pieces selected by masks), so only the order of the sum over
//! the pairs differs from the scalar loop: sixteen partial sums, reduced once per particle.
//! Two orders of a sum of `N` terms `t_k` differ by at most `2 γ_{N−1} Σ|t_k|` (Higham 2002,
//! *Accuracy and Stability of Numerical Algorithms*, §4.2; `γ_n = n u / (1 − n u)`,
//! `u = 2⁻²⁴`), the bound the test checks; the order depends neither on the number of
//! threads nor on the scheduling. Every other case (another kernel, `f64`, no AVX-512) runs
//! the scalar [`crate::step::density_at`], unchanged. The boundary's volume term is added per
//! particle after the pairs, as in the scalar sum.
//!
//! The lanes replace a branchy scalar loop bound by its latency and mispredicted branches
//! (about 5 ns per pair on the dam break).

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_kernels::{CubicSpline, Kernel};

use crate::pair_lanes::{CubicLanes, Packed};
use crate::step::density_at;
use crate::Boundary;

/// Particles per rayon task.
const BLOCK: usize = 512;

/// `out[i] = density_at(kernel, rest_density, x, m, nb, volume, i)` for every particle `i`
/// (see the module docs: in lanes, within the bound of a reordered sum), in parallel over
/// fixed blocks, so that the result does not depend on the number of threads. `packed` is
/// the lanes' working copy of `x` and `m` (filled only when they run).
#[allow(clippy::too_many_arguments)] // the density's inputs and the lanes' working copy
pub fn densities_at<R: Real, K: Kernel<R>>(
    kernel: &K,
    rest_density: R,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    volume: Option<&dyn Boundary<R>>,
    packed: &mut Packed,
    out: &mut [R],
) {
    let lanes = cubic_lanes(kernel, x.len(), nb);
    if lanes.is_some() {
        packed.fill(x, m);
    }
    let packed = &*packed;
    out.par_chunks_mut(BLOCK)
        .enumerate()
        .for_each(|(b, block)| {
            let first = b * BLOCK;
            for (l, rho) in block.iter_mut().enumerate() {
                let i = first + l;
                *rho = match &lanes {
                    Some(c) => c.density(packed, nb, i),
                    None => density_at(kernel, rest_density, x, m, nb, None, i),
                };
                if let Some(b) = volume {
                    *rho += rest_density * b.sample(&x[i]).volume;
                }
            }
        });
}

/// The lane constants where the lanes run for `kernel`: the 3D cubic spline (by name, as
/// `sph_kernels` builds it from the support radius) and [`crate::pair_lanes::lanes_available`].
fn cubic_lanes<R: Real, K: Kernel<R>>(
    kernel: &K,
    n: usize,
    nb: &NeighbourLists,
) -> Option<CubicLanes> {
    if kernel.name() != CubicSpline::<R>::NAME {
        return None;
    }
    let cubic = CubicSpline::new(kernel.support_radius()).ok()?;
    CubicLanes::new(&cubic, n, nb)
}

#[cfg(test)]
mod tests {
    use neighbour_search::Method;
    use sph_core::Vec3;
    use sph_kernels::{CubicSpline, Kernel, Poly6};

    use super::{cubic_lanes, densities_at};
    use crate::pair_lanes::Packed;
    use crate::step::{density_at, StepNeighbours};

    /// A jittered lattice of `side³` particles at spacing 1 (a fixed pseudo-random jitter
    /// of up to ±0.45), with a few coincident pairs (r = 0) and unequal masses, and its
    /// neighbour lists within `h` searched at positions shifted by `shift` (so that some
    /// listed pairs lie beyond `h` at the evaluated positions, as at the end of a step).
    fn scene(side: usize, h: f32, shift: f32) -> (Vec<Vec3<f32>>, Vec<f32>, StepNeighbours<f32>) {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut jitter = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32 * 0.9 - 0.45
        };
        let mut x = Vec::new();
        for i in 0..side {
            for j in 0..side {
                for k in 0..side {
                    let p = Vec3::new(i as f32, j as f32, k as f32);
                    x.push(p + Vec3::new(jitter(), jitter(), jitter()));
                }
            }
        }
        x[7] = x[8];
        let m: Vec<f32> = (0..x.len()).map(|i| 1.0 + 0.01 * (i % 13) as f32).collect();
        let searched: Vec<Vec3<f32>> = x
            .iter()
            .enumerate()
            .map(|(i, p)| p + Vec3::new(shift * (i % 3) as f32, 0.0, -shift))
            .collect();
        let mut nb = StepNeighbours::new(Method::CellStartGrid);
        nb.find(&searched, h).expect("search");
        (x, m, nb)
    }

    /// The lanes (taken on a processor with AVX-512) against the scalar `density_at`, for
    /// full and partial blocks and for pairs beyond `h`: within `2 γ_n Σ|t_k|` of the
    /// scalar sum of `n + 1` terms (Higham 2002, §4.2: the lanes reorder the sum, the terms
    /// are the scalar ones; see the module docs). Other kernels take the scalar path and
    /// agree bit for bit.
    #[test]
    fn lanes_match_the_scalar_density_within_the_reordering_bound() {
        for (side, shift) in [(11, 0.0), (9, 0.3), (3, 0.1)] {
            let h = 2.1f32;
            let (x, m, nb) = scene(side, h, shift);
            let cubic = CubicSpline::new(h).unwrap();
            let mut out = vec![0.0f32; x.len()];
            let mut packed = Packed::default();
            densities_at(
                &cubic,
                1000.0,
                &x,
                &m,
                nb.lists(),
                None,
                &mut packed,
                &mut out,
            );
            for (i, rho) in out.iter().enumerate() {
                let want = density_at(&cubic, 1000.0, &x, &m, nb.lists(), None, i);
                let list = nb.lists().neighbours(i);
                let abs_sum: f64 = f64::from(m[i] * cubic.value(0.0))
                    + list
                        .iter()
                        .map(|&j| {
                            let r2 = (x[i] - x[j as usize]).norm_squared();
                            f64::from((m[j as usize] * cubic.value_r2(r2)).abs())
                        })
                        .sum::<f64>();
                let nu = list.len() as f64 * f64::from(f32::EPSILON) / 2.0;
                let bound = 2.0 * nu / (1.0 - nu) * abs_sum;
                let diff = (f64::from(*rho) - f64::from(want)).abs();
                assert!(
                    diff <= bound,
                    "particle {i} of {side}³: lanes {rho} scalar {want} differ by {diff} > {bound}"
                );
            }
            let poly6 = Poly6::new(h).unwrap();
            densities_at(
                &poly6,
                1000.0,
                &x,
                &m,
                nb.lists(),
                None,
                &mut packed,
                &mut out,
            );
            for (i, rho) in out.iter().enumerate() {
                let want = density_at(&poly6, 1000.0, &x, &m, nb.lists(), None, i);
                assert_eq!(rho.to_bits(), want.to_bits(), "Poly6, particle {i}");
            }
            assert!(out.iter().all(|r| *r > 0.0 && r.is_finite()));
            // The comparison above is of the lanes wherever the processor has them.
            #[cfg(target_arch = "x86_64")]
            assert_eq!(
                cubic_lanes(&cubic, x.len(), nb.lists()).is_some(),
                std::arch::is_x86_feature_detected!("avx512f")
            );
        }
    }
}
