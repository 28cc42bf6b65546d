//! The pair loops of the explicit step ([`crate::passes`]) in `f32` AVX-512 lanes, sixteen
//! pairs of one grain per vector, when the solver runs in `f32` with the 3D cubic spline, no
//! periodic images, on a processor with AVX-512 (detected at run time; never built for a
//! fixed target CPU): the kernel gradient of every listed pair, the velocity gradient and
//! continuity rate of the stress pass, and the pair forces of the momentum pass. Everything
//! else (another kernel, `f64`, periodic images, no AVX-512) runs the scalar loops,
//! unchanged.
//!
//! Layout as the water's lanes ([`sph_solver::pair_lanes`], whose public loads these reuse):
//! one grain at a time, its neighbour list read sixteen entries per vector, positions and
//! masses from the packed `[x, y, z, m]`, other per-particle fields gathered, the stored
//! gradients (three `f32` per pair, contiguous in list order) loaded three vectors at a time
//! and de-interleaved by permutes.
//!
//! Each pair's gradient is the scalar kernel's operations in the scalar order (`r = √r²`,
//! `q = r · (1/h)`, `t = 1 − q`, `dW/dr = (k/h) f'(q)` with the spline's two pieces selected
//! by masks, `∇W = x_ij · (dW/dr / r)`; no fused multiply–add), so the stored gradients are
//! bit for bit the scalar ones. The sums over the pairs are taken in sixteen partial sums
//! reduced once per grain instead of left to right, and a pair's product terms may be
//! associated differently (a dot product's order). Each computed sum of `N` terms whose
//! exact terms `t_k` take at most `m` roundings each lies within `γ_{N+m} Σ|t_k|` of the
//! exact sum (Higham 2002, *Accuracy and Stability of Numerical Algorithms*, §3.1 and §4.2;
//! `γ_n = n u / (1 − n u)`, `u = 2⁻²⁴`), so the lanes and the scalar loop differ by at most
//! `2 γ_{N+m} Σ|t_k|`: the bound the tests check. The order depends neither on the number
//! of threads nor on the scheduling. A pair of the momentum pass with a non-zero artificial
//! stress (rare: it needs a tensile principal stress) is handed to the scalar pair term.
#![allow(unsafe_code)] // AVX-512 intrinsics after run-time detection; f32 arrays seen as R = f32

use std::any::TypeId;

use nalgebra::Matrix3;
use sph_core::{Real, Vec3};
use sph_kernels::{CubicSpline, Kernel};
use sph_solver::pair_lanes::lanes_available;
use sph_solver::NeighbourLists;

use crate::kernels::Consts;

/// The constants of the lanes, each as the scalar code holds it in `f32`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GrainLanes {
    /// Support radius `h` (m).
    h: f32,
    /// `1/h`, rounded once from `f64` (as `sph_kernels`' scale).
    inv_h: f32,
    /// `k/h` with `k = 8/(π h³)`, rounded once from `f64`.
    k_h: f32,
    /// The squared distance beyond which a listed pair has a zero gradient (m²).
    support2_above: f32,
    /// The viscosity's smoothing length (m), `0.01 h²`, `(−α) c0`, `β`.
    visc_h: f32,
    eta2: f32,
    neg_alpha_c0: f32,
    beta: f32,
}

/// Whether `R` is `f32`.
fn is_f32<R: 'static>() -> bool {
    TypeId::of::<R>() == TypeId::of::<f32>()
}

/// `values` (each `per` values of `R`) seen as their `f32` values.
///
/// # Panics
/// When `R` is not `f32` or `T` is not `per` values of `R`.
pub(crate) fn flat<T, R: Real>(values: &[T], per: usize) -> &[f32] {
    assert!(is_f32::<R>(), "lanes need f32");
    assert_eq!(std::mem::size_of::<T>(), per * std::mem::size_of::<f32>());
    assert_eq!(std::mem::align_of::<T>(), std::mem::align_of::<f32>());
    // SAFETY: T is `per` packed f32 (R = f32, size and alignment checked above): nalgebra's
    // Vector3 and Matrix3 are arrays of R.
    unsafe { std::slice::from_raw_parts(values.as_ptr().cast::<f32>(), per * values.len()) }
}

impl GrainLanes {
    /// The lane constants of the loops of `c` on `listed` particles (the lists' particle
    /// count), or `None` where the lanes cannot run: `R` is not `f32`, the kernel is not the
    /// 3D cubic spline, the lists hold periodic images, the processor has no AVX-512, or the
    /// indices do not fit the gathers' 32-bit offsets (nine values per particle).
    pub(crate) fn new<R: Real, K: Kernel<R>>(
        c: &Consts<R, K>,
        nb: &NeighbourLists,
        listed: usize,
        images: bool,
    ) -> Option<Self> {
        if images
            || c.kernel.name() != CubicSpline::<R>::NAME
            || K::DIM != 3
            || 9 * listed >= i32::MAX as usize
            || !lanes_available::<R>(listed, nb)
        {
            return None;
        }
        // As `sph_kernels`' scale: 1/h, k = σ/h³ and k/h in f64, each rounded once.
        let h = c.kernel.support_radius().as_f64();
        let inv_h = 1.0 / h;
        let k = 8.0 / std::f64::consts::PI * inv_h.powi(3);
        let f = |v: R| v.as_f64() as f32;
        Some(Self {
            h: h as f32,
            inv_h: inv_h as f32,
            k_h: (k * inv_h) as f32,
            support2_above: f(c.support2_above),
            visc_h: f(c.h),
            eta2: f(c.eta2),
            neg_alpha_c0: f(-c.alpha * c.c0),
            beta: f(c.beta),
        })
    }
}

/// The arrays the momentum lanes read, as `f32`, over the `listed` particles of the lists.
pub(crate) struct MomentumArrays<'a> {
    /// Positions and masses packed `[x, y, z, m]`.
    pub xm: &'a [f32],
    /// Velocities, three per particle.
    pub v: &'a [f32],
    pub rho: &'a [f32],
    /// `σ/ρ²` of the new stress and density, nine per particle (column-major).
    pub sig_rho2: &'a [f32],
    /// Whether the particle's artificial stress is non-zero.
    pub art_on: &'a [bool],
}

/// The arrays the stress lanes read, as `f32`, over the `listed` particles of the lists.
pub(crate) struct StressArrays<'a> {
    /// Velocities, three per particle.
    pub v: &'a [f32],
    /// `m/ρ` of the step's densities.
    pub volume: &'a [f32],
    /// The masses of all the particles (grains, then boundary particles).
    pub mass: &'a [f32],
}

/// The sums of the stress pass of one grain: `Σ_j V_j (v_j − v_i) ⊗ ∇W_ij` (column-major,
/// 1/s), `−Σ_j m_j (v_j − v_i)·∇W_ij` (kg/(m³ s)), and whether a grain other than `i` lies
/// inside the support.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StressSums<R: Real> {
    pub grad_v: Matrix3<R>,
    pub drho: R,
    pub in_contact: bool,
}

impl GrainLanes {
    /// The kernel gradient of grain `i`'s listed pairs into `out` (its CSR range), zero
    /// beyond the support, bit for bit as the scalar loop (see the module docs).
    ///
    /// # Panics
    /// When `out` is not as long as the list or `xm` is not the lists' packed particles.
    pub(crate) fn gradients<R: Real>(
        &self,
        xm: &[f32],
        nb: &NeighbourLists,
        i: usize,
        out: &mut [Vec3<R>],
    ) {
        let list = nb.neighbours(i);
        assert_eq!(out.len(), list.len());
        assert_eq!(
            4 * (nb.offsets().len() - 1),
            xm.len(),
            "packed of the lists"
        );
        #[cfg(target_arch = "x86_64")]
        {
            let mut g = [[0f32; 16]; 3];
            for s in (0..list.len()).step_by(16) {
                // SAFETY: a GrainLanes exists only after avx512f was detected
                // (`lanes_available`); xm holds the listed particles (asserted), i < n, and
                // neighbour indices are clamped below the packed count inside.
                unsafe { avx512::gradients(self, xm, i, list, s, &mut g) };
                for (k, o) in out[s..].iter_mut().take(16).enumerate() {
                    let r = |a: usize| R::of_f64(f64::from(g[a][k]));
                    *o = Vec3::new(r(0), r(1), r(2));
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!("no lane constants off x86_64")
    }

    /// The stress pass's sums of grain `i` of `n` ([`StressSums`]), from its stored pair
    /// gradients `grads` (three `f32` per listed pair).
    ///
    /// # Panics
    /// When `grads` is not three values per listed pair or the arrays are not of the listed
    /// particles.
    pub(crate) fn stress_sums<R: Real>(
        &self,
        a: &StressArrays<'_>,
        nb: &NeighbourLists,
        n: usize,
        i: usize,
        grads: &[f32],
    ) -> StressSums<R> {
        let list = nb.neighbours(i);
        let listed = nb.offsets().len() - 1;
        assert_eq!(grads.len(), 3 * list.len());
        assert!(a.v.len() == 3 * listed && a.volume.len() == listed && a.mass.len() == listed);
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: as in `gradients`; the arrays hold the listed particles (asserted) and
            // indices are clamped below their count inside.
            let (g, drho, in_contact) = unsafe { avx512::stress_sums(a, n, i, list, grads) };
            let r = |v: f32| R::of_f64(f64::from(v));
            StressSums {
                grad_v: Matrix3::from_fn(|row, col| r(g[3 * col + row])),
                drho: r(drho),
                in_contact,
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!("no lane constants off x86_64")
    }

    /// `Σ_j m_j (σ_i/ρ_i² + σ_j/ρ_j² − Π_ij I) ∇W_ij` of grain `i` (m/s², no gravity) from
    /// its stored gradients, over the pairs whose artificial stress is zero on both sides
    /// (the caller's grain `i` has none); each other pair's index in the list is handed to
    /// `scalar`, which adds its whole term.
    ///
    /// # Panics
    /// When `grads` is not three values per listed pair or the arrays are not of the listed
    /// particles.
    pub(crate) fn acceleration<R: Real>(
        &self,
        a: &MomentumArrays<'_>,
        nb: &NeighbourLists,
        i: usize,
        grads: &[f32],
        scalar: &mut dyn FnMut(usize),
    ) -> Vec3<R> {
        let list = nb.neighbours(i);
        let listed = nb.offsets().len() - 1;
        assert_eq!(grads.len(), 3 * list.len());
        assert!(
            a.xm.len() == 4 * listed
                && a.v.len() == 3 * listed
                && a.rho.len() == listed
                && a.sig_rho2.len() == 9 * listed
                && a.art_on.len() == listed
        );
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: as in `stress_sums`.
            let s = unsafe { avx512::acceleration(self, a, i, list, grads, scalar) };
            let r = |v: f32| R::of_f64(f64::from(v));
            Vec3::new(r(s[0]), r(s[1]), r(s[2]))
        }
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!("no lane constants off x86_64")
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use sph_solver::pair_lanes::avx512::pairs;

    use super::{GrainLanes, MomentumArrays, StressArrays};

    /// The permutes that de-interleave sixteen `[x, y, z]` triples held in three vectors:
    /// for component `c`, element `p` is value `3p + c`, taken from the first two vectors
    /// (`FIRST`, indices 0–31) and then, for values 32–47, from the third (`SECOND`, bit 4
    /// selecting it).
    const fn deinterleave(c: usize) -> ([i32; 16], [i32; 16]) {
        let (mut first, mut second) = ([0i32; 16], [0i32; 16]);
        let mut p = 0;
        while p < 16 {
            let v = 3 * p + c;
            if v < 32 {
                first[p] = v as i32;
                second[p] = p as i32;
            } else {
                second[p] = 16 | (v - 32) as i32;
            }
            p += 1;
        }
        (first, second)
    }

    const SPLIT: [([i32; 16], [i32; 16]); 3] = [deinterleave(0), deinterleave(1), deinterleave(2)];

    /// The lanes holding pairs `s..s + 16` of a list of `len` pairs.
    #[inline]
    fn live(len: usize, s: usize) -> __mmask16 {
        let left = len - s;
        if left >= 16 {
            0xffff
        } else {
            (1u16 << left) - 1
        }
    }

    /// The stored gradients of pairs `s..s + 16` (zero beyond the list) per axis.
    ///
    /// # Safety
    /// avx512f; `grads` holds three values per pair, `s` below the pair count.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn stored(grads: &[f32], s: usize) -> [__m512; 3] {
        let left = grads.len() - 3 * s;
        let mask = |k: usize| -> __mmask16 {
            let from = 16 * k;
            if left >= from + 16 {
                0xffff
            } else if left > from {
                (1u16 << (left - from)) - 1
            } else {
                0
            }
        };
        let p = grads.as_ptr().add(3 * s);
        let v = [0, 1, 2].map(|k| _mm512_maskz_loadu_ps(mask(k), p.add(16 * k)));
        SPLIT.map(|(first, second)| {
            let t = _mm512_permutex2var_ps(v[0], _mm512_loadu_si512(first.as_ptr().cast()), v[1]);
            _mm512_permutex2var_ps(t, _mm512_loadu_si512(second.as_ptr().cast()), v[2])
        })
    }

    /// The lanes whose gradient is not the zero vector (NaN counts as non-zero, as the
    /// scalar `gw == 0` test), among `live`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn nonzero(g: &[__m512; 3], live: __mmask16) -> __mmask16 {
        let z = _mm512_setzero_ps();
        live & (_mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(g[0], z)
            | _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(g[1], z)
            | _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(g[2], z))
    }

    /// `values[per · j + at]` per lane of `mask` (0 elsewhere).
    ///
    /// # Safety
    /// avx512f; every `per · j + at` of `mask`'s lanes lies inside `values`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn gather(values: &[f32], j_per: __m512i, at: i32, mask: __mmask16) -> __m512 {
        let idx = _mm512_add_epi32(j_per, _mm512_set1_epi32(at));
        _mm512_mask_i32gather_ps::<4>(_mm512_setzero_ps(), mask, idx, values.as_ptr().cast())
    }

    /// The neighbour indices of pairs `s..s + 16` (0 beyond the list), clamped below
    /// `count`.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn indices(list: &[u32], s: usize, live: __mmask16, count: usize) -> __m512i {
        let j = _mm512_maskz_loadu_epi32(live, list.as_ptr().add(s).cast());
        _mm512_min_epu32(j, _mm512_set1_epi32(count.saturating_sub(1) as i32))
    }

    /// The cubic spline's gradient of pairs `s..s + 16` of grain `i` into `out` (per axis):
    /// zero beyond the support, at `r = 0` and in lanes without a pair.
    ///
    /// # Safety
    /// avx512f; `xm` holds the packed listed particles, `i` one of them, `s < list.len()`.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn gradients(
        c: &GrainLanes,
        xm: &[f32],
        i: usize,
        list: &[u32],
        s: usize,
        out: &mut [[f32; 16]; 3],
    ) {
        let p = pairs(xm, i, list, s);
        let zero = _mm512_setzero_ps();
        let one = _mm512_set1_ps(1.0);
        let r = _mm512_sqrt_ps(p.r2);
        let q = _mm512_mul_ps(r, _mm512_set1_ps(c.inv_h));
        let t = _mm512_sub_ps(one, q);
        // The scalar code's zeros: r² above the lists' cut, r = 0 or r ≥ h (the gradient),
        // t ≤ 0 (the spline); ordered comparisons, so NaN takes the formula as there.
        let inside = p.live
            & !_mm512_cmp_ps_mask::<_CMP_GT_OQ>(p.r2, _mm512_set1_ps(c.support2_above))
            & _mm512_cmp_ps_mask::<_CMP_GT_OQ>(r, zero)
            & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(r, _mm512_set1_ps(c.h))
            & !_mm512_cmp_ps_mask::<_CMP_LE_OQ>(t, zero);
        let near = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(q, _mm512_set1_ps(0.5));
        // f'(q): (6q)(3q − 2) near, ((−6)t)t far.
        let six_q = _mm512_mul_ps(_mm512_set1_ps(6.0), q);
        let df_near = _mm512_mul_ps(
            six_q,
            _mm512_sub_ps(_mm512_mul_ps(_mm512_set1_ps(3.0), q), _mm512_set1_ps(2.0)),
        );
        let df_far = _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(-6.0), t), t);
        let dw = _mm512_mul_ps(
            _mm512_set1_ps(c.k_h),
            _mm512_mask_blend_ps(near, df_far, df_near),
        );
        let scale = _mm512_maskz_div_ps(inside, dw, r);
        for (o, d) in out.iter_mut().zip(p.d) {
            _mm512_storeu_ps(o.as_mut_ptr(), _mm512_maskz_mul_ps(inside, d, scale));
        }
    }

    /// Sums sixteen partial sums.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn sum(v: __m512) -> f32 {
        _mm512_reduce_add_ps(v)
    }

    /// The stress pass's sums of grain `i` of `n`: `Σ V_j (v_j − v_i)_a ∇W_b` (column-major),
    /// `−Σ m_j (v_j − v_i)·∇W`, and whether a grain other than `i` has a non-zero gradient.
    ///
    /// # Safety
    /// avx512f; the arrays hold the listed particles, `grads` three values per pair.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn stress_sums(
        a: &StressArrays<'_>,
        n: usize,
        i: usize,
        list: &[u32],
        grads: &[f32],
    ) -> ([f32; 9], f32, bool) {
        let count = a.volume.len();
        let vi = [0, 1, 2].map(|k| _mm512_set1_ps(a.v[3 * i + k]));
        let mut acc = [_mm512_setzero_ps(); 9];
        let mut drho = _mm512_setzero_ps();
        let mut contact = 0u16;
        for s in (0..list.len()).step_by(16) {
            let g = stored(grads, s);
            let on = nonzero(&g, live(list.len(), s));
            let j = indices(list, s, on, count);
            let j3 = _mm512_mullo_epi32(j, _mm512_set1_epi32(3));
            let dv = [0, 1, 2].map(|k| _mm512_sub_ps(gather(a.v, j3, k as i32, on), vi[k]));
            let vol = gather(a.volume, j, 0, on);
            let m = gather(a.mass, j, 0, on);
            for col in 0..3 {
                for row in 0..3 {
                    let term = _mm512_mul_ps(_mm512_mul_ps(dv[row], g[col]), vol);
                    acc[3 * col + row] =
                        _mm512_mask_add_ps(acc[3 * col + row], on, acc[3 * col + row], term);
                }
            }
            let dot = _mm512_add_ps(
                _mm512_add_ps(_mm512_mul_ps(dv[0], g[0]), _mm512_mul_ps(dv[1], g[1])),
                _mm512_mul_ps(dv[2], g[2]),
            );
            drho = _mm512_mask_sub_ps(drho, on, drho, _mm512_mul_ps(m, dot));
            contact |= on
                & _mm512_cmplt_epu32_mask(j, _mm512_set1_epi32(n as i32))
                & _mm512_cmpneq_epi32_mask(j, _mm512_set1_epi32(i as i32));
        }
        let mut out = [0f32; 9];
        for (o, v) in out.iter_mut().zip(acc) {
            *o = sum(v);
        }
        (out, sum(drho), contact != 0)
    }

    /// The momentum pass's pair sum of grain `i` (see [`GrainLanes::acceleration`]).
    ///
    /// # Safety
    /// avx512f; the arrays hold the listed particles, `grads` three values per pair.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn acceleration(
        c: &GrainLanes,
        a: &MomentumArrays<'_>,
        i: usize,
        list: &[u32],
        grads: &[f32],
        scalar: &mut dyn FnMut(usize),
    ) -> [f32; 3] {
        let count = a.rho.len();
        let vi = [0, 1, 2].map(|k| _mm512_set1_ps(a.v[3 * i + k]));
        let si = [0, 1, 2, 3, 4, 5, 6, 7, 8].map(|e| _mm512_set1_ps(a.sig_rho2[9 * i + e]));
        let ri = _mm512_set1_ps(a.rho[i]);
        let zero = _mm512_setzero_ps();
        let mut acc = [zero; 3];
        for s in (0..list.len()).step_by(16) {
            let g = stored(grads, s);
            let mut on = nonzero(&g, live(list.len(), s));
            // Pairs with a non-zero artificial stress go to the scalar term.
            for k in 0..16usize.min(list.len() - s) {
                let j = (list[s + k] as usize).min(count - 1);
                if on & (1 << k) != 0 && a.art_on[j] {
                    on &= !(1 << k);
                    scalar(s + k);
                }
            }
            if on == 0 {
                continue;
            }
            let p = pairs(a.xm, i, list, s);
            let j = indices(list, s, on, count);
            let j3 = _mm512_mullo_epi32(j, _mm512_set1_epi32(3));
            let j9 = _mm512_mullo_epi32(j, _mm512_set1_epi32(9));
            let mut t = [zero; 9];
            for (e, te) in t.iter_mut().enumerate() {
                *te = _mm512_add_ps(si[e], gather(a.sig_rho2, j9, e as i32, on));
            }
            // Monaghan's viscosity on approaching pairs, the scalar's operations in order.
            let vij = [0, 1, 2].map(|k| _mm512_sub_ps(vi[k], gather(a.v, j3, k as i32, on)));
            let vx = _mm512_add_ps(
                _mm512_add_ps(_mm512_mul_ps(vij[0], p.d[0]), _mm512_mul_ps(vij[1], p.d[1])),
                _mm512_mul_ps(vij[2], p.d[2]),
            );
            let approach = on & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(vx, zero);
            if approach != 0 {
                let rj = gather(a.rho, j, 0, on);
                let phi = _mm512_div_ps(
                    _mm512_mul_ps(_mm512_set1_ps(c.visc_h), vx),
                    _mm512_add_ps(p.r2, _mm512_set1_ps(c.eta2)),
                );
                let num = _mm512_add_ps(
                    _mm512_mul_ps(_mm512_set1_ps(c.neg_alpha_c0), phi),
                    _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(c.beta), phi), phi),
                );
                let pi = _mm512_div_ps(
                    num,
                    _mm512_mul_ps(_mm512_add_ps(ri, rj), _mm512_set1_ps(0.5)),
                );
                for d in [0, 4, 8] {
                    t[d] = _mm512_mask_sub_ps(t[d], approach, t[d], pi);
                }
            }
            // (t ∇W)_row = (t_r0 g0 + t_r1 g1) + t_r2 g2, times m_j.
            for (row, ac) in acc.iter_mut().enumerate() {
                let tg = _mm512_add_ps(
                    _mm512_add_ps(_mm512_mul_ps(t[row], g[0]), _mm512_mul_ps(t[3 + row], g[1])),
                    _mm512_mul_ps(t[6 + row], g[2]),
                );
                *ac = _mm512_mask_add_ps(*ac, on, *ac, _mm512_mul_ps(tg, p.mj));
            }
        }
        acc.map(|v| sum(v))
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix3;
    use proptest::prelude::*;
    use sph_core::Vec3;
    use sph_kernels::CubicSpline;
    use sph_solver::pair_lanes::Packed;
    use sph_solver::scene_boundary::PeriodicImages;
    use sph_solver::step::StepNeighbours;
    use sph_solver::Method;

    use super::{flat, GrainLanes, MomentumArrays, StressArrays};
    use crate::kernels::Consts;
    use crate::passes::{
        pair_gradient, pair_stress, pair_term, stress_sums, support_pairs, MomentumFields, Pair,
        StressFields,
    };
    use crate::ElastoplasticParams;

    /// `|a − b| ≤ 2 γ_{N+m} Σ|t_k|` (`γ_n = n u / (1 − n u)`, `u = 2⁻²⁴`): two sums of the
    /// same `N` terms, each term `m` roundings from values both sides share (see the module
    /// docs). `abs_sum` is `Σ|t_k|` in `f64` from those shared values; its own rounding
    /// (about `N · 2⁻⁵³` relative) is far inside the one `γ_1` the bound holds in hand
    /// (Higham's bound is `γ_{N−1+m}`).
    fn within(
        what: &str,
        a: f32,
        b: f32,
        terms: usize,
        roundings: usize,
        abs_sum: f64,
    ) -> Result<(), TestCaseError> {
        let nu = (terms + roundings) as f64 * f64::from(f32::EPSILON) / 2.0;
        let bound = 2.0 * nu / (1.0 - nu) * abs_sum;
        let diff = (f64::from(a) - f64::from(b)).abs();
        prop_assert!(
            diff <= bound,
            "{what}: lanes {a} scalar {b} differ by {diff} > {bound} ({terms} terms)"
        );
        Ok(())
    }

    /// A generator of values in `[lo, hi)` from a seed (xorshift).
    struct Draw(u64);

    impl Draw {
        fn next(&mut self, lo: f32, hi: f32) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            lo + (hi - lo) * ((self.0 >> 40) as f32 / (1u64 << 24) as f32)
        }
        fn vec(&mut self, lo: f32, hi: f32) -> Vec3<f32> {
            Vec3::new(self.next(lo, hi), self.next(lo, hi), self.next(lo, hi))
        }
        fn matrix(&mut self, scale: f32) -> Matrix3<f32> {
            Matrix3::from_fn(|_, _| self.next(-scale, scale))
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// The three lane kernels against the scalar loops of the passes on random clouds of
        /// grains followed by boundary particles at the solver's spacing (2 cm, `h = 2.4 s`,
        /// lists searched within `h + skin` so that some listed pairs lie beyond the support,
        /// a coincident pair): each pair's gradient bit for bit; the velocity gradient and
        /// continuity rate within `2 γ_{N+4} Σ|t|` (a term is at most four roundings from the
        /// shared velocity difference, gradient, volume and mass); the pair forces within
        /// `2 γ_{N+5} Σ|t|` (four roundings from the shared pair stress, gradient and mass,
        /// and the pass's one addition of the lanes' sum and the scalar pairs'), with some
        /// particles carrying an artificial stress (their pairs go to the scalar term).
        /// Velocities up to 2 m/s, densities 1,700–2,300 kg/m³, stresses up to 10⁴ Pa.
        /// Skipped (nothing to compare) without AVX-512.
        #[test]
        fn the_lanes_match_the_scalar_passes(
            count in 20usize..300,
            boundary_share in 0.0f32..0.4,
            seed in 1u64..u64::MAX,
        ) {
            let s = 0.02f32;
            let p = ElastoplasticParams::<f32>::for_spacing(s, 30.0);
            let h = p.common.support_radius;
            let c = Consts::new(&p, CubicSpline::new(h).unwrap()).unwrap();
            let mut d = Draw(seed);
            let side = s * (count as f32).cbrt();
            let mut x: Vec<Vec3<f32>> = (0..count).map(|_| d.vec(0.0, side)).collect();
            x[7] = x[8];
            let grains = count - (boundary_share * count as f32) as usize;
            let boundary_mass = p.common.particle_mass();
            let mass_all: Vec<f32> = (0..count)
                .map(|k| if k < grains { boundary_mass * d.next(0.8, 1.2) } else { boundary_mass })
                .collect();
            let mut search = StepNeighbours::new(Method::CellStartGrid);
            search.find(&x, h + p.skin).unwrap();
            let nb = search.lists();
            let Some(lanes) = GrainLanes::new(&c, nb, count, false) else {
                return Ok(());
            };
            let mut packed = Packed::default();
            packed.fill(&x, &mass_all);
            // The gradients, bit for bit.
            let mut grads = vec![Vec3::<f32>::zeros(); nb.offsets()[grains]];
            for i in 0..grains {
                let (a, b) = (nb.offsets()[i], nb.offsets()[i + 1]);
                lanes.gradients(packed.values(), nb, i, &mut grads[a..b]);
                for (k, &j) in nb.neighbours(i).iter().enumerate() {
                    let want = pair_gradient(&c, &(x[i] - x[j as usize]));
                    for axis in 0..3 {
                        prop_assert_eq!(
                            grads[a + k][axis].to_bits(), want[axis].to_bits(),
                            "gradient of pair {} of {}", k, i
                        );
                    }
                }
            }
            let mut owner = Vec::new();
            PeriodicImages::<f32>::default().owners(count, &mut owner);
            let v: Vec<Vec3<f32>> = (0..count).map(|_| d.vec(-2.0, 2.0)).collect();
            let rho: Vec<f32> = (0..count).map(|_| d.next(1700.0, 2300.0)).collect();
            let volume: Vec<f32> = mass_all.iter().zip(&rho).map(|(m, r)| m / r).collect();
            // The stress pass's sums.
            let fields = StressFields {
                v: &v,
                volume: &volume,
                masses: &mass_all[..grains],
                boundary_mass,
            };
            let arrays = StressArrays { v: flat::<_, f32>(&v, 3), volume: &volume, mass: &mass_all };
            let mut pairs = vec![Pair::default(); nb.offsets()[grains]];
            for i in 0..grains {
                let grad_i = &grads[nb.offsets()[i]..nb.offsets()[i + 1]];
                let count = support_pairs(&c, &x, &owner, i, nb.neighbours(i), &mut pairs);
                let want = stress_sums(&fields, i, &pairs[..count]);
                let got = lanes.stress_sums::<f32>(&arrays, nb, grains, i, flat::<_, f32>(grad_i, 3));
                prop_assert_eq!(got.in_contact, want.in_contact, "contact of {}", i);
                let terms = grad_i.len();
                let mut abs = [[0f64; 3]; 3];
                let mut abs_rho = 0f64;
                for (&j, g) in nb.neighbours(i).iter().zip(grad_i) {
                    let j = j as usize;
                    let dv = v[j] - v[i];
                    for (r, row) in abs.iter_mut().enumerate() {
                        for (col, e) in row.iter_mut().enumerate() {
                            *e += f64::from((dv[r] * g[col]).abs()) * f64::from(volume[j]);
                        }
                    }
                    abs_rho += f64::from(mass_all[j])
                        * (0..3).map(|a| f64::from((dv[a] * g[a]).abs())).sum::<f64>();
                }
                for (r, row) in abs.iter().enumerate() {
                    for (col, e) in row.iter().enumerate() {
                        within("L", got.grad_v[(r, col)], want.grad_v[(r, col)], terms, 4, *e)?;
                    }
                }
                within("dρ/dt", got.drho, want.drho, terms, 4, abs_rho)?;
            }
            // The momentum pass's pair forces.
            let sig_rho2: Vec<Matrix3<f32>> = (0..count).map(|_| d.matrix(1e4) / (2000.0 * 2000.0)).collect();
            let art_on: Vec<bool> = (0..count).map(|_| d.next(0.0, 1.0) < 0.15).collect();
            let art: Vec<Matrix3<f32>> = art_on
                .iter()
                .map(|&on| if on { d.matrix(1e3) / (2000.0 * 2000.0) } else { Matrix3::zeros() })
                .collect();
            let f = MomentumFields {
                v: &v,
                rho: &rho,
                sig_rho2: &sig_rho2,
                art: &art,
                art_on: &art_on,
                masses: &mass_all[..grains],
                boundary_mass,
            };
            let arrays = MomentumArrays {
                xm: packed.values(),
                v: flat::<_, f32>(&v, 3),
                rho: &rho,
                sig_rho2: flat::<_, f32>(&sig_rho2, 9),
                art_on: &art_on,
            };
            for i in (0..grains).filter(|&i| !art_on[i]) {
                let list = nb.neighbours(i);
                let grad_i = &grads[nb.offsets()[i]..nb.offsets()[i + 1]];
                let mut want = Vec3::zeros();
                let mut abs = [0f64; 3];
                let count = support_pairs(&c, &x, &owner, i, list, &mut pairs);
                for p in &pairs[..count] {
                    want += pair_term(&c, &f, i, p);
                    let (t, m) = pair_stress(&c, &f, i, p);
                    for (r, e) in abs.iter_mut().enumerate() {
                        *e += f64::from(m)
                            * (0..3).map(|l| f64::from((t[(r, l)] * p.grad[l]).abs())).sum::<f64>();
                    }
                }
                let listed = |k: usize| {
                    let j = list[k];
                    Pair { j, xij: x[i] - x[j as usize], grad: grad_i[k] }
                };
                let mut rest = Vec3::zeros();
                let mut scalar = |k: usize| rest += pair_term(&c, &f, i, &listed(k));
                let lanes_sum: Vec3<f32> =
                    lanes.acceleration(&arrays, nb, i, flat::<_, f32>(grad_i, 3), &mut scalar);
                let got = lanes_sum + rest;
                for r in 0..3 {
                    within("a", got[r], want[r], list.len(), 5, abs[r])?;
                }
            }
        }
    }

    /// The lanes exist wherever the processor has AVX-512 (so the property test compares
    /// something there), for the 3D cubic spline in `f32` without periodic images only.
    #[test]
    fn the_lanes_run_on_avx512_in_f32_without_images_only() {
        let x = vec![Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(0.01, 0.0, 0.0)];
        let p = ElastoplasticParams::<f32>::for_spacing(0.02, 30.0);
        let h = p.common.support_radius;
        let c = Consts::new(&p, CubicSpline::new(h).unwrap()).unwrap();
        let mut nb = StepNeighbours::new(Method::CellStartGrid);
        nb.find(&x, h).unwrap();
        #[cfg(target_arch = "x86_64")]
        assert_eq!(
            GrainLanes::new(&c, nb.lists(), 2, false).is_some(),
            std::arch::is_x86_feature_detected!("avx512f")
        );
        assert!(GrainLanes::new(&c, nb.lists(), 2, true).is_none());
        let p64 = ElastoplasticParams::<f64>::for_spacing(0.02, 30.0);
        let c64 = Consts::new(&p64, CubicSpline::new(p64.common.support_radius).unwrap()).unwrap();
        let x64: Vec<Vec3<f64>> = x.iter().map(|q| q.cast()).collect();
        let mut nb64 = StepNeighbours::new(Method::CellStartGrid);
        nb64.find(&x64, 0.05).unwrap();
        assert!(GrainLanes::new(&c64, nb64.lists(), 2, false).is_none());
    }
}
