//! The SPH density of every particle ([`crate::step::density_at`] for all `i`), with the
//! cubic spline in `f32` evaluated sixteen particles at a time in AVX-512 lanes when the
//! processor has them (detected at run time), bit for bit the scalar result.
//!
//! Each lane is one particle and walks its own neighbour list in order, so every lane
//! performs the scalar loop's operations in the scalar loop's order: the offset
//! `x_i − x_j` per axis, `r² = (dx² + dy²) + dz²` (nalgebra's `norm_squared` of a 3-vector),
//! `r = √r²` (correctly rounded in both), the kernel's `q = r · (1/h)`, `t = 1 − q`, the
//! piece `1 + ((6q)q)(q − 1)` for `q ≤ 1/2` and `((2t)t)t` above, times `k`, zero for
//! `r ≥ h` or `t ≤ 0` (ordered comparisons, so NaN propagates as in the scalar code), and
//! `ρ += m_j W` after the self term. No fused multiply–add is used (Rust does not contract
//! the scalar code either). Every other case (another kernel, `f64`, no AVX-512) runs the
//! scalar [`crate::step::density_at`]. The boundary's volume term is added per particle
//! after the pairs, as in the scalar sum.
//!
//! The lanes replace a branchy scalar loop bound by its latency and mispredicted branches
//! (about 5 ns per pair on the dam break) by one gather-bound pass.
#![allow(unsafe_code)] // AVX-512 intrinsics after run-time detection; f32 slices seen as R = f32

use std::any::TypeId;

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_kernels::{CubicSpline, Kernel};

use crate::step::density_at;
use crate::Boundary;

/// Particles per rayon task (a multiple of the 16 lanes).
const BLOCK: usize = 512;

/// `out[i] = density_at(kernel, rest_density, x, m, nb, volume, i)` for every particle `i`
/// (see the module docs), in parallel over fixed blocks, so that the result does not depend
/// on the number of threads.
pub fn densities_at<R: Real, K: Kernel<R>>(
    kernel: &K,
    rest_density: R,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    volume: Option<&dyn Boundary<R>>,
    out: &mut [R],
) {
    let lanes = lane_constants(kernel, x.len(), nb);
    out.par_chunks_mut(BLOCK)
        .enumerate()
        .for_each(|(b, block)| {
            let first = b * BLOCK;
            match lanes {
                #[cfg(target_arch = "x86_64")]
                Some(c) => {
                    // SAFETY: `lane_constants` returns `Some` only for R = f32 (so the
                    // slices are f32 data of the same layout), after detecting avx512f, for
                    // lists of `x.len()` particles; `pair_sums` bounds every gather.
                    unsafe {
                        let xf = std::slice::from_raw_parts(x.as_ptr().cast::<f32>(), 3 * x.len());
                        let mf = std::slice::from_raw_parts(m.as_ptr().cast::<f32>(), m.len());
                        let of = std::slice::from_raw_parts_mut(
                            block.as_mut_ptr().cast::<f32>(),
                            block.len(),
                        );
                        avx512::pair_sums(&c, xf, mf, nb, first, of);
                    }
                }
                _ => {
                    for (l, rho) in block.iter_mut().enumerate() {
                        *rho = density_at(kernel, rest_density, x, m, nb, None, first + l);
                    }
                }
            }
            if let Some(b) = volume {
                for (l, rho) in block.iter_mut().enumerate() {
                    *rho += rest_density * b.sample(&x[first + l]).volume;
                }
            }
        });
}

/// The cubic spline's constants in `f32`, as `sph_kernels`' scalar evaluation uses them.
#[derive(Debug, Clone, Copy)]
struct LaneConstants {
    /// Support radius `h`.
    h: f32,
    /// `1/h`, rounded once from `f64` (as the kernel's scale).
    inv_h: f32,
    /// `k = σ/h³`, as `W(0) = k · f(0) = k`.
    k: f32,
}

/// The constants of the lane kernel, or `None` when the scalar loop must run: not `f32`,
/// not the 3D cubic spline, no AVX-512, or lists not of `n` particles with pair and
/// coordinate indices that fit the gathers' 32-bit offsets.
fn lane_constants<R: Real, K: Kernel<R>>(
    kernel: &K,
    n: usize,
    nb: &NeighbourLists,
) -> Option<LaneConstants> {
    if TypeId::of::<R>() != TypeId::of::<f32>() || kernel.name() != CubicSpline::<R>::NAME {
        return None;
    }
    #[cfg(target_arch = "x86_64")]
    let detected = std::arch::is_x86_feature_detected!("avx512f");
    #[cfg(not(target_arch = "x86_64"))]
    let detected = false;
    let fits = nb.offsets().len() == n + 1
        && 3 * n < i32::MAX as usize
        && nb.indices().len() < i32::MAX as usize;
    (detected && fits).then(|| {
        let h = kernel.support_radius();
        LaneConstants {
            h: h.as_f64() as f32,
            inv_h: (1.0 / h.as_f64()) as f32,
            k: kernel.value(R::zero()).as_f64() as f32,
        }
    })
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use neighbour_search::NeighbourLists;

    use super::LaneConstants;

    /// `out[l]` = the self term plus the pair sum of particle `first + l`, sixteen particles
    /// per pass.
    ///
    /// # Safety
    /// avx512f must be available, `nb` lists the `n` particles whose `3n` coordinates are
    /// `x` and `n` masses `m`, and `n < 2³¹ / 3`. Every gather stays in bounds: a pair is
    /// read only below its particle's end offset, which `NeighbourLists::neighbours` checks
    /// against the index array, and neighbour indices are clamped to `n − 1` (a no-op for
    /// valid lists).
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn pair_sums(
        c: &LaneConstants,
        x: &[f32],
        m: &[f32],
        nb: &NeighbourLists,
        first: usize,
        out: &mut [f32],
    ) {
        let offsets = nb.offsets();
        let indices = nb.indices().as_ptr().cast::<i32>();
        let (h, inv_h, k) = (
            _mm512_set1_ps(c.h),
            _mm512_set1_ps(c.inv_h),
            _mm512_set1_ps(c.k),
        );
        let (one, half, two, six) = (
            _mm512_set1_ps(1.0),
            _mm512_set1_ps(0.5),
            _mm512_set1_ps(2.0),
            _mm512_set1_ps(6.0),
        );
        let zero = _mm512_setzero_ps();
        let three = _mm512_set1_epi32(3);
        let last = _mm512_set1_epi32(m.len().saturating_sub(1) as i32);
        for (g, lanes) in out.chunks_mut(16).enumerate() {
            let base = first + 16 * g;
            let mut start = [0i32; 16];
            let mut count = [0i32; 16];
            let (mut xi, mut yi, mut zi, mut sum) =
                ([0f32; 16], [0f32; 16], [0f32; 16], [0f32; 16]);
            let mut longest = 0;
            for l in 0..lanes.len() {
                let i = base + l;
                start[l] = offsets[i] as i32;
                // Slicing checks offsets[i] <= offsets[i + 1] <= indices.len().
                count[l] = nb.neighbours(i).len() as i32;
                longest = longest.max(count[l]);
                (xi[l], yi[l], zi[l]) = (x[3 * i], x[3 * i + 1], x[3 * i + 2]);
                // The self term m_i W(0) = m_i k.
                sum[l] = m[i] * c.k;
            }
            let start = _mm512_loadu_si512(start.as_ptr().cast());
            let count = _mm512_loadu_si512(count.as_ptr().cast());
            let (xi, yi, zi) = (
                _mm512_loadu_ps(xi.as_ptr()),
                _mm512_loadu_ps(yi.as_ptr()),
                _mm512_loadu_ps(zi.as_ptr()),
            );
            let mut acc = _mm512_loadu_ps(sum.as_ptr());
            for s in 0..longest {
                let step = _mm512_set1_epi32(s);
                let live = _mm512_cmplt_epi32_mask(step, count);
                let pair = _mm512_add_epi32(start, step);
                let j = _mm512_mask_i32gather_epi32::<4>(
                    _mm512_setzero_si512(),
                    live,
                    pair,
                    indices.cast(),
                );
                let j = _mm512_min_epu32(j, last);
                let j3 = _mm512_mullo_epi32(j, three);
                let xp = x.as_ptr();
                let xj = _mm512_mask_i32gather_ps::<4>(zero, live, j3, xp.cast());
                let yj = _mm512_mask_i32gather_ps::<4>(zero, live, j3, xp.add(1).cast());
                let zj = _mm512_mask_i32gather_ps::<4>(zero, live, j3, xp.add(2).cast());
                let mj = _mm512_mask_i32gather_ps::<4>(zero, live, j, m.as_ptr().cast());
                let (dx, dy, dz) = (
                    _mm512_sub_ps(xi, xj),
                    _mm512_sub_ps(yi, yj),
                    _mm512_sub_ps(zi, zj),
                );
                let r2 = _mm512_add_ps(
                    _mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)),
                    _mm512_mul_ps(dz, dz),
                );
                let r = _mm512_sqrt_ps(r2);
                let q = _mm512_mul_ps(r, inv_h);
                let t = _mm512_sub_ps(one, q);
                let outside = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(r, h)
                    | _mm512_cmp_ps_mask::<_CMP_LE_OQ>(t, zero);
                let near = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(q, half);
                let f_near = _mm512_add_ps(
                    one,
                    _mm512_mul_ps(
                        _mm512_mul_ps(_mm512_mul_ps(six, q), q),
                        _mm512_sub_ps(q, one),
                    ),
                );
                let f_far = _mm512_mul_ps(_mm512_mul_ps(_mm512_mul_ps(two, t), t), t);
                let f = _mm512_mask_blend_ps(near, f_far, f_near);
                let w = _mm512_mask_blend_ps(outside, _mm512_mul_ps(k, f), zero);
                acc = _mm512_mask_add_ps(acc, live, acc, _mm512_mul_ps(mj, w));
            }
            let mut sums = [0f32; 16];
            _mm512_storeu_ps(sums.as_mut_ptr(), acc);
            lanes.copy_from_slice(&sums[..lanes.len()]);
        }
    }
}

#[cfg(test)]
mod tests {
    use neighbour_search::Method;
    use sph_core::Vec3;
    use sph_kernels::{CubicSpline, Poly6};

    use super::{densities_at, lane_constants};
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

    /// The lanes (taken on a processor with AVX-512) give the scalar `density_at` bit for
    /// bit, for full and partial blocks of 16 and for pairs beyond `h`; other kernels take
    /// the scalar path and agree trivially. Bitwise equality is the contract (the module
    /// performs the scalar operations in the scalar order), so no tolerance.
    #[test]
    fn lanes_equal_the_scalar_density_bit_for_bit() {
        for (side, shift) in [(11, 0.0), (9, 0.3), (3, 0.1)] {
            let h = 2.1f32;
            let (x, m, nb) = scene(side, h, shift);
            let cubic = CubicSpline::new(h).unwrap();
            let mut out = vec![0.0f32; x.len()];
            densities_at(&cubic, 1000.0, &x, &m, nb.lists(), None, &mut out);
            for (i, rho) in out.iter().enumerate() {
                let want = density_at(&cubic, 1000.0, &x, &m, nb.lists(), None, i);
                assert_eq!(rho.to_bits(), want.to_bits(), "particle {i} of {side}³");
            }
            let poly6 = Poly6::new(h).unwrap();
            densities_at(&poly6, 1000.0, &x, &m, nb.lists(), None, &mut out);
            for (i, rho) in out.iter().enumerate() {
                let want = density_at(&poly6, 1000.0, &x, &m, nb.lists(), None, i);
                assert_eq!(rho.to_bits(), want.to_bits(), "Poly6, particle {i}");
            }
            assert!(out.iter().all(|r| *r > 0.0 && r.is_finite()));
            // The comparison above is of the lanes wherever the processor has them.
            #[cfg(target_arch = "x86_64")]
            assert_eq!(
                lane_constants(&cubic, x.len(), nb.lists()).is_some(),
                std::arch::is_x86_feature_detected!("avx512f")
            );
        }
    }
}
