//! Pair sums of one particle in `f32` AVX-512 lanes, sixteen neighbours at a time, for the
//! solvers' pair passes: the cubic spline's density and gradient sums with the per-pair
//! `W'(r)/r` (IISPH's density pass), the packed positions and masses and the loads the
//! solvers' lane kernels share ([`avx512`]), and the `f32` views of the particle arrays.
//!
//! Layout: one particle at a time, its neighbour list (contiguous in the CSR index array)
//! read sixteen entries per vector; the neighbours' positions and masses, packed as
//! `[x, y, z, m]` (16 bytes, [`Packed`]), loaded with one 128-bit load each and transposed
//! (measured faster than four gathers on this AMD EPYC, whose gathers are slow); other
//! per-neighbour fields gathered; per-pair values (`W'(r)/r`) written contiguously. Each pair's terms are the scalar code's
//! operations in the scalar order (no fused multiply–add, the spline's two pieces selected
//! by masks instead of a branch), so the per-pair values are bit for bit the scalar ones;
//! only the sums over the pairs are taken in sixteen partial sums and then reduced, instead
//! of left to right. Two orders of a sum of `N` terms `t_k` differ by at most
//! `2 γ_{N−1} Σ|t_k|` (Higham 2002, *Accuracy and Stability of Numerical Algorithms*, §4.2;
//! `γ_n = n u / (1 − n u)`, `u = 2⁻²⁴`); the tests check that bound. The order does not
//! depend on the number of threads.
#![allow(unsafe_code)] // AVX-512 intrinsics after run-time detection; f32 slices seen as R = f32

use std::any::TypeId;

use neighbour_search::NeighbourLists;
use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_kernels::{CubicSpline, Kernel};

/// `values` seen as `f32`.
///
/// # Panics
/// When `R` is not `f32` (a lane kernel is built only for `f32`).
pub fn f32s<R: Real>(values: &[R]) -> &[f32] {
    assert_eq!(TypeId::of::<R>(), TypeId::of::<f32>(), "lanes need f32");
    // SAFETY: R is f32 (checked above), so the slice is f32 data of the same layout.
    unsafe { std::slice::from_raw_parts(values.as_ptr().cast::<f32>(), values.len()) }
}

/// `values` seen as `f32`, mutable (see [`f32s`]).
///
/// # Panics
/// When `R` is not `f32`.
pub fn f32s_mut<R: Real>(values: &mut [R]) -> &mut [f32] {
    assert_eq!(TypeId::of::<R>(), TypeId::of::<f32>(), "lanes need f32");
    // SAFETY: as in `f32s`.
    unsafe { std::slice::from_raw_parts_mut(values.as_mut_ptr().cast::<f32>(), values.len()) }
}

/// 3-vectors seen as their `3n` coordinates in `f32` (nalgebra's `Vector3` is three packed
/// `R`).
///
/// # Panics
/// When `R` is not `f32`.
pub fn coords<R: Real>(v: &[Vec3<R>]) -> &[f32] {
    assert_eq!(TypeId::of::<R>(), TypeId::of::<f32>(), "lanes need f32");
    // SAFETY: R is f32, and Vec3<f32> is [f32; 3] in memory.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<f32>(), 3 * v.len()) }
}

/// Whether the `f32` lanes can run on `n` particles with these lists: `R` is `f32`, the
/// processor has AVX-512 (detected at run time), and the lists are of `n` particles with
/// pair and coordinate indices that fit the gathers' 32-bit offsets.
pub fn lanes_available<R: Real>(n: usize, nb: &NeighbourLists) -> bool {
    if TypeId::of::<R>() != TypeId::of::<f32>() {
        return false;
    }
    #[cfg(target_arch = "x86_64")]
    let detected = std::arch::is_x86_feature_detected!("avx512f");
    #[cfg(not(target_arch = "x86_64"))]
    let detected = false;
    detected
        && nb.offsets().len() == n + 1
        && 3 * n < i32::MAX as usize
        && nb.indices().len() < i32::MAX as usize
}

/// Positions and masses packed as `[x, y, z, m]` in `f32` per particle (16 bytes), so that
/// the lanes load a neighbour's four values with one 128-bit load and transpose sixteen of
/// them, instead of four gathers.
#[derive(Debug, Clone, Default)]
pub struct Packed {
    xyzm: Vec<f32>,
}

impl Packed {
    /// Packs `x` and `m`, in parallel.
    ///
    /// # Panics
    /// When `R` is not `f32` or the lengths differ.
    pub fn fill<R: Real>(&mut self, x: &[Vec3<R>], m: &[R]) {
        assert_eq!(x.len(), m.len(), "one mass per position");
        self.fill_with(x, |i| m[i]);
    }

    /// Packs `x` with a fourth value `w(i)` per particle (`[x, y, z, w]`), in parallel: a
    /// lane kernel then loads a neighbour's position and that value as [`Packed::fill`]'s
    /// position and mass.
    ///
    /// # Panics
    /// When `R` is not `f32`.
    pub fn fill_with<R: Real>(&mut self, x: &[Vec3<R>], w: impl Fn(usize) -> R + Sync) {
        self.xyzm.resize(4 * x.len(), 0.0);
        let xf = coords(x);
        self.xyzm
            .par_chunks_mut(4 * 1024)
            .enumerate()
            .for_each(|(b, chunk)| {
                for (l, p) in chunk.chunks_exact_mut(4).enumerate() {
                    let i = 1024 * b + l;
                    let wi = w(i).as_f64() as f32;
                    p.copy_from_slice(&[xf[3 * i], xf[3 * i + 1], xf[3 * i + 2], wi]);
                }
            });
    }

    /// Sets the fourth value of every particle to `w(i)`, in parallel, keeping the first
    /// three.
    pub fn set_fourth<R: Real>(&mut self, w: impl Fn(usize) -> R + Sync) {
        self.xyzm
            .par_chunks_mut(4 * 1024)
            .enumerate()
            .for_each(|(b, chunk)| {
                for (l, p) in chunk.chunks_exact_mut(4).enumerate() {
                    p[3] = w(1024 * b + l).as_f64() as f32;
                }
            });
    }

    /// Forgets the packed values (keeps the storage): a reader that checks
    /// [`Packed::len`] against its particles then sees none.
    pub fn clear(&mut self) {
        self.xyzm.clear();
    }

    /// The packed values, four per particle.
    pub fn values(&self) -> &[f32] {
        &self.xyzm
    }

    /// The number of particles packed.
    pub fn len(&self) -> usize {
        self.xyzm.len() / 4
    }

    /// Whether no particle is packed.
    pub fn is_empty(&self) -> bool {
        self.xyzm.is_empty()
    }
}

/// The 3D cubic spline (`sph_kernels::CubicSpline`) in `f32` lanes: its constants as the
/// scalar kernel evaluates them; exists only where [`lanes_available`].
#[derive(Debug, Clone, Copy)]
pub struct CubicLanes {
    /// Support radius `h` (m).
    h: f32,
    /// `1/h`, rounded once from `f64`.
    inv_h: f32,
    /// `k = 8/(π h³)`.
    k: f32,
    /// `k/h`, rounded once from `f64`.
    k_h: f32,
}

/// The sums over one particle's pairs of [`CubicLanes::density_gradient`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DensityGradientSums<R: Real> {
    /// `m_i W(0) + Σ_j m_j W_ij` (kg/m³).
    pub density: R,
    /// `Σ_j m_j ∇W_ij` (kg/m⁴).
    pub grad: Vec3<R>,
    /// `Σ_j m_j |∇W_ij|²` (kg/m⁸).
    pub grad_sq: R,
}

impl CubicLanes {
    /// The lane constants of `kernel` for `n` particles and these lists, or `None` where the
    /// lanes cannot run (see [`lanes_available`]).
    pub fn new<R: Real>(kernel: &CubicSpline<R>, n: usize, nb: &NeighbourLists) -> Option<Self> {
        if !lanes_available::<R>(n, nb) {
            return None;
        }
        // As `sph_kernels`' Scale: 1/h, k = σ/h³ and k/h in f64, each rounded once.
        let h = kernel.support_radius().as_f64();
        let inv_h = 1.0 / h;
        let k = 8.0 / std::f64::consts::PI * inv_h.powi(3);
        Some(Self {
            h: h as f32,
            inv_h: inv_h as f32,
            k: k as f32,
            k_h: (k * inv_h) as f32,
        })
    }

    /// Particle `i`'s density `m_i W(0) + Σ_j m_j W_ij` and gradient sums
    /// ([`DensityGradientSums`]), writing each pair's `W'(r)/r` (0 at `r = 0`) to
    /// `grad_scale` (the slice of its CSR range), as IISPH's scalar density loop does.
    ///
    /// # Panics
    /// When `grad_scale` is not as long as the list, or the slices are not of the particles
    /// the constants were made for.
    pub fn density_gradient<R: Real>(
        &self,
        packed: &Packed,
        nb: &NeighbourLists,
        i: usize,
        grad_scale: &mut [R],
    ) -> DensityGradientSums<R> {
        let list = nb.neighbours(i);
        assert_eq!(grad_scale.len(), list.len());
        assert_eq!(
            nb.offsets().len(),
            packed.len() + 1,
            "lists of other particles"
        );
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: a CubicLanes exists only after avx512f was detected and R = f32
            // (`lanes_available`); the lists are of the packed particles (asserted),
            // neighbour indices are clamped below n inside, and grad_scale has the list's
            // length.
            let s = unsafe {
                avx512::density_gradient(self, packed.values(), i, list, f32s_mut(grad_scale))
            };
            let r = |v: f32| R::of_f64(v as f64);
            let mi = r(packed.values()[4 * i + 3]);
            DensityGradientSums {
                density: mi * r(self.k) + r(s[0]),
                grad: Vec3::new(r(s[1]), r(s[2]), r(s[3])),
                grad_sq: r(s[4]),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!("no lane constants off x86_64")
    }
}

impl CubicLanes {
    /// Particle `i`'s density `m_i W(0) + Σ_j m_j W_ij` alone (no boundary term), the
    /// pairs' terms as [`CubicLanes::density_gradient`] computes them.
    ///
    /// # Panics
    /// When the lists are not of the packed particles.
    pub fn density<R: Real>(&self, packed: &Packed, nb: &NeighbourLists, i: usize) -> R {
        let list = nb.neighbours(i);
        assert_eq!(
            nb.offsets().len(),
            packed.len() + 1,
            "lists of other particles"
        );
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: as in `density_gradient` (no per-pair output here).
            let s = unsafe { avx512::density(self, packed.values(), i, list) };
            let r = |v: f32| R::of_f64(v as f64);
            r(packed.values()[4 * i + 3]) * r(self.k) + r(s)
        }
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!("no lane constants off x86_64")
    }
}

/// The loads the solvers' lane kernels share: sixteen pairs of one particle from the packed
/// positions and masses, and gathers of other per-particle fields.
#[cfg(target_arch = "x86_64")]
pub mod avx512 {
    use std::arch::x86_64::*;

    use super::CubicLanes;

    /// Sixteen (or fewer) pairs of one particle: which lanes hold a pair, the neighbours'
    /// indices (clamped to `n − 1`), the offsets `x_i − x_j` per axis, `r²` and `m_j`
    /// (the particle's own values in lanes without a pair).
    pub struct Pairs {
        /// The lanes that hold a pair.
        pub live: __mmask16,
        /// The neighbours' indices.
        pub j: __m512i,
        /// `x_i − x_j` per axis.
        pub d: [__m512; 3],
        /// `r² = (dx² + dy²) + dz²`.
        pub r2: __m512,
        /// `m_j`.
        pub mj: __m512,
    }

    /// The pairs `list[s..s + 16]` (fewer at the end) of particle `i`, from the packed
    /// `[x, y, z, m]`: sixteen 128-bit loads into four registers, neighbour `4l + r` in
    /// 128-bit lane `l` of register `r`, then a 4 × 4 transpose within each 128-bit lane,
    /// which leaves neighbour `e` in element `e` of the `x`, `y`, `z` and `m` registers.
    ///
    /// Always inlined, so that the sixteen pairs stay in registers: as an out-of-line call
    /// (what `#[inline]` gave: `perf` showed a call per sixteen pairs from every lane
    /// kernel) the result went through memory and the caller's accumulators, all in
    /// caller-saved vector registers, were spilled around it. `#[inline(always)]` excludes
    /// `#[target_feature]`; the intrinsics inside are compiled with the caller's AVX-512.
    ///
    /// # Safety
    /// avx512f (the caller must be compiled with it); `xm` holds `4n` values, `i < n`,
    /// `s < list.len()`.
    #[inline(always)]
    pub unsafe fn pairs(xm: &[f32], i: usize, list: &[u32], s: usize) -> Pairs {
        let left = list.len() - s;
        let live: __mmask16 = if left >= 16 {
            0xffff
        } else {
            (1u16 << left) - 1
        };
        let last = (xm.len() / 4).saturating_sub(1);
        let j = _mm512_maskz_loadu_epi32(live, list.as_ptr().add(s).cast());
        let j = _mm512_min_epu32(j, _mm512_set1_epi32(last as i32));
        let [x0, x1, x2, mj] = packed(xm, i, list, s);
        let xj = [x0, x1, x2];
        let own = xm.as_ptr().add(4 * i);
        // No closure calls an intrinsic here: a closure of this function (which has no
        // `#[target_feature]`) is compiled without AVX-512 when it is not inlined, and its
        // intrinsics become calls (measured: IISPH's step took 1.9× as long).
        let d = [
            _mm512_sub_ps(_mm512_set1_ps(*own), xj[0]),
            _mm512_sub_ps(_mm512_set1_ps(*own.add(1)), xj[1]),
            _mm512_sub_ps(_mm512_set1_ps(*own.add(2)), xj[2]),
        ];
        // nalgebra's norm_squared: (dx² + dy²) + dz².
        let r2 = _mm512_add_ps(
            _mm512_add_ps(_mm512_mul_ps(d[0], d[0]), _mm512_mul_ps(d[1], d[1])),
            _mm512_mul_ps(d[2], d[2]),
        );
        Pairs { live, j, d, r2, mj }
    }

    /// The neighbours' packed 4-vectors (`[x, y, z, m]` of [`super::Packed`]) of the pairs
    /// `list[s..s + 16]` of particle `i` (its own past the list's end): sixteen 128-bit
    /// loads into four registers, neighbour `4l + r` in 128-bit lane `l` of register `r`,
    /// then [`transpose`], which leaves neighbour `e` in element `e` of each of the four
    /// registers (one per component). Always inlined, as [`pairs`].
    ///
    /// # Safety
    /// avx512f (the caller must be compiled with it); `xm` holds `4n` values, `i < n`,
    /// `s < list.len()`.
    #[inline(always)]
    pub unsafe fn packed(xm: &[f32], i: usize, list: &[u32], s: usize) -> [__m512; 4] {
        let left = list.len() - s;
        let last = (xm.len() / 4).saturating_sub(1);
        let p = xm.as_ptr();
        // The neighbour of entry k (particle i itself past the list's end).
        let at = |k: usize| {
            if k < left {
                (*list.get_unchecked(s + k) as usize).min(last)
            } else {
                i
            }
        };
        let mut z = [_mm512_setzero_ps(); 4];
        for (r, zr) in z.iter_mut().enumerate() {
            let v = _mm512_castps128_ps512(_mm_loadu_ps(p.add(4 * at(r))));
            let v = _mm512_insertf32x4::<1>(v, _mm_loadu_ps(p.add(4 * at(4 + r))));
            let v = _mm512_insertf32x4::<2>(v, _mm_loadu_ps(p.add(4 * at(8 + r))));
            *zr = _mm512_insertf32x4::<3>(v, _mm_loadu_ps(p.add(4 * at(12 + r))));
        }
        transpose(z)
    }

    /// Sixteen 4-vectors, vector `4l + r` in 128-bit lane `l` of `z[r]`, transposed within
    /// each 128-bit lane: element `e` of the result's `c`-th register is component `c` of
    /// vector `e`.
    ///
    /// # Safety
    /// avx512f (the caller must be compiled with it).
    #[inline(always)]
    pub unsafe fn transpose(z: [__m512; 4]) -> [__m512; 4] {
        let t0 = _mm512_unpacklo_ps(z[0], z[1]);
        let t1 = _mm512_unpackhi_ps(z[0], z[1]);
        let t2 = _mm512_unpacklo_ps(z[2], z[3]);
        let t3 = _mm512_unpackhi_ps(z[2], z[3]);
        [
            _mm512_shuffle_ps::<0x44>(t0, t2),
            _mm512_shuffle_ps::<0xEE>(t0, t2),
            _mm512_shuffle_ps::<0x44>(t1, t3),
            _mm512_shuffle_ps::<0xEE>(t1, t3),
        ]
    }

    /// `_mm512_reduce_add_ps` of each of up to eight accumulators (0 past `N`), returned
    /// as one 256-bit vector's elements.
    ///
    /// One vector store, not `N` scalar ones: a caller that reads several of the sums with
    /// one wider load (the compiler copies `[s[1], s[2], s[3]]` and the next sum into a
    /// struct with a 16-byte load) then gets them forwarded from that store, where `N`
    /// scalar stores make the load wait for them to reach the cache (`perf annotate` of
    /// the lane kernels' callers showed half of their samples on that load). The sums
    /// are the same values. The closure below calls an intrinsic, which [`pairs`] avoids;
    /// it is inlined in the solvers' kernels as built here (the examples' binaries have no
    /// symbol of it, of `sums` or of an intrinsic).
    ///
    /// # Safety
    /// avx512f (the caller must be compiled with it).
    #[inline(always)]
    pub unsafe fn sums<const N: usize>(acc: [__m512; N]) -> [f32; 8] {
        const { assert!(N <= 8, "at most eight sums") };
        let s = |k: usize| {
            if k < N {
                _mm512_reduce_add_ps(acc[k])
            } else {
                0.0
            }
        };
        let v = _mm256_setr_ps(s(0), s(1), s(2), s(3), s(4), s(5), s(6), s(7));
        std::mem::transmute::<__m256, [f32; 8]>(v)
    }

    /// `values[j]` per live lane (0 elsewhere).
    ///
    /// # Safety
    /// avx512f; `values` holds a value per particle of the lists `p` came from.
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub unsafe fn gather(values: &[f32], p: &Pairs) -> __m512 {
        _mm512_mask_i32gather_ps::<4>(_mm512_setzero_ps(), p.live, p.j, values.as_ptr().cast())
    }

    /// The cubic spline's `W(r)` and `W'(r)` per lane, each pair's operations in the
    /// scalar kernel's order (`q = r · (1/h)`, `t = 1 − q`; the two pieces selected by
    /// masks; 0 for `r ≥ h` or `t ≤ 0`, ordered comparisons so that NaN propagates as in
    /// the scalar code).
    ///
    /// # Safety
    /// avx512f.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn cubic(c: &CubicLanes, r: __m512) -> (__m512, __m512) {
        let zero = _mm512_setzero_ps();
        let (one, half, two, three, six) = (
            _mm512_set1_ps(1.0),
            _mm512_set1_ps(0.5),
            _mm512_set1_ps(2.0),
            _mm512_set1_ps(3.0),
            _mm512_set1_ps(6.0),
        );
        let q = _mm512_mul_ps(r, _mm512_set1_ps(c.inv_h));
        let t = _mm512_sub_ps(one, q);
        let outside = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(r, _mm512_set1_ps(c.h))
            | _mm512_cmp_ps_mask::<_CMP_LE_OQ>(t, zero);
        let near = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(q, half);
        // f: 1 + ((6q)q)(q − 1) near, ((2t)t)t far; f': (6q)((3q) − 2), ((−6)t)t.
        let f_near = _mm512_add_ps(
            one,
            _mm512_mul_ps(
                _mm512_mul_ps(_mm512_mul_ps(six, q), q),
                _mm512_sub_ps(q, one),
            ),
        );
        let f_far = _mm512_mul_ps(_mm512_mul_ps(_mm512_mul_ps(two, t), t), t);
        let df_near = _mm512_mul_ps(
            _mm512_mul_ps(six, q),
            _mm512_sub_ps(_mm512_mul_ps(three, q), two),
        );
        let df_far = _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(-6.0), t), t);
        let w = _mm512_mul_ps(
            _mm512_set1_ps(c.k),
            _mm512_mask_blend_ps(near, f_far, f_near),
        );
        let dw = _mm512_mul_ps(
            _mm512_set1_ps(c.k_h),
            _mm512_mask_blend_ps(near, df_far, df_near),
        );
        (
            _mm512_mask_blend_ps(outside, w, zero),
            _mm512_mask_blend_ps(outside, dw, zero),
        )
    }

    /// The lane sum `Σ m_j W_ij` of particle `i`.
    ///
    /// # Safety
    /// avx512f; `xm` holds `4n` packed values, `i < n`.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn density(c: &CubicLanes, xm: &[f32], i: usize, list: &[u32]) -> f32 {
        let mut acc = _mm512_setzero_ps();
        for s in (0..list.len()).step_by(16) {
            let p = pairs(xm, i, list, s);
            let (w, _) = cubic(c, _mm512_sqrt_ps(p.r2));
            acc = _mm512_mask_add_ps(acc, p.live, acc, _mm512_mul_ps(p.mj, w));
        }
        _mm512_reduce_add_ps(acc)
    }

    /// The lane sums `[Σ m_j W, Σ m_j ∇W_x, … y, … z, Σ m_j |∇W|²]` of particle `i`.
    ///
    /// # Safety
    /// avx512f; `xm` holds `4n` packed values, `i < n`; `gs` has the list's length.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn density_gradient(
        c: &CubicLanes,
        xm: &[f32],
        i: usize,
        list: &[u32],
        gs: &mut [f32],
    ) -> [f32; 8] {
        let zero = _mm512_setzero_ps();
        let mut acc = [zero; 5];
        for s in (0..list.len()).step_by(16) {
            let p = pairs(xm, i, list, s);
            let (live, d, mj) = (p.live, p.d, p.mj);
            // r = √((dx² + dy²) + dz²), nalgebra's norm.
            let r = _mm512_sqrt_ps(p.r2);
            let (w, dw) = cubic(c, r);
            // W'(r)/r for r > 0, else 0.
            let f = _mm512_maskz_div_ps(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(r, zero), dw, r);
            _mm512_mask_storeu_ps(gs.as_mut_ptr().add(s), live, f);
            acc[0] = _mm512_mask_add_ps(acc[0], live, acc[0], _mm512_mul_ps(mj, w));
            let gw = d.map(|da| _mm512_mul_ps(da, f));
            for a in 0..3 {
                let t = _mm512_mul_ps(gw[a], mj);
                acc[1 + a] = _mm512_mask_add_ps(acc[1 + a], live, acc[1 + a], t);
            }
            let g2 = _mm512_add_ps(
                _mm512_add_ps(_mm512_mul_ps(gw[0], gw[0]), _mm512_mul_ps(gw[1], gw[1])),
                _mm512_mul_ps(gw[2], gw[2]),
            );
            acc[4] = _mm512_mask_add_ps(acc[4], live, acc[4], _mm512_mul_ps(mj, g2));
        }
        sums(acc)
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // an axis indexes a vector and its bound in step
mod tests {
    use neighbour_search::Method;
    use proptest::prelude::*;
    use sph_core::Vec3;
    use sph_kernels::{CubicSpline, Kernel};

    use super::{CubicLanes, Packed};
    use crate::step::StepNeighbours;

    /// `|a − b| ≤ 2 γ_n Σ|t_k|` with `γ_n = n u / (1 − n u)`, `u = 2⁻²⁴`: two summation
    /// orders of `n + 1` terms (Higham 2002, §4.2; see the module docs).
    fn within(what: &str, a: f32, b: f32, n: usize, abs_sum: f64) -> Result<(), TestCaseError> {
        let nu = n as f64 * f64::from(f32::EPSILON) / 2.0;
        let bound = 2.0 * nu / (1.0 - nu) * abs_sum;
        let diff = (f64::from(a) - f64::from(b)).abs();
        prop_assert!(
            diff <= bound,
            "{what}: lanes {a} scalar {b} differ by {diff} > {bound}"
        );
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// The cubic spline's lane kernels against the scalar loop written here from
        /// `CubicSpline::value` and `derivative` in list order (IISPH's density loop): each
        /// pair's `W'(r)/r` bit for bit, the sums (and the density alone) within
        /// `2 γ_n Σ|t_k|`. Random clouds at
        /// spacing 1 with `h = 2` (about 30 neighbours, coincident pairs possible).
        /// Skipped (nothing to compare) without AVX-512.
        #[test]
        fn cubic_lanes_match_the_scalar_loop(
            x in (20usize..400).prop_flat_map(|n| {
                let side = (n as f32).cbrt();
                prop::collection::vec(
                    (0.0..side, 0.0..side, 0.0..side).prop_map(|(a, b, c)| Vec3::new(a, b, c)),
                    n,
                )
            }),
            mass in 0.5f32..2.0,
        ) {
            let h = 2.0f32;
            let kernel = CubicSpline::new(h).unwrap();
            let mut nb = StepNeighbours::new(Method::CellStartGrid);
            nb.find(&x, h).unwrap();
            let nb = nb.lists();
            let m: Vec<f32> = (0..x.len()).map(|i| mass * (1.0 + 0.1 * (i % 7) as f32)).collect();
            let Some(lanes) = CubicLanes::new(&kernel, x.len(), nb) else {
                return Ok(());
            };
            let mut packed = Packed::default();
            packed.fill(&x, &m);
            for i in 0..x.len() {
                let list = nb.neighbours(i);
                let mut gs = vec![f32::NAN; list.len()];
                let got = lanes.density_gradient(&packed, nb, i, &mut gs);
                let mut rho = m[i] * kernel.value(0.0);
                let (mut grad, mut grad_sq) = (Vec3::<f32>::zeros(), 0f32);
                let mut abs = [f64::from(rho), 0.0, 0.0, 0.0, 0.0];
                for (k, &j) in list.iter().enumerate() {
                    let j = j as usize;
                    let d = x[i] - x[j];
                    let r = d.norm();
                    let w = m[j] * kernel.value(r);
                    let f = if r > 0.0 { kernel.derivative(r) / r } else { 0.0 };
                    prop_assert_eq!(gs[k].to_bits(), f.to_bits(), "W'/r of pair {} of {}", k, i);
                    let gw = d * f;
                    let (g, g2) = (gw * m[j], m[j] * gw.norm_squared());
                    rho += w;
                    grad += g;
                    grad_sq += g2;
                    abs[0] += f64::from(w);
                    for a in 0..3 {
                        abs[1 + a] += f64::from(g[a].abs());
                    }
                    abs[4] += f64::from(g2);
                }
                within("density", got.density, rho, list.len(), abs[0])?;
                let alone: f32 = lanes.density(&packed, nb, i);
                within("density alone", alone, rho, list.len(), abs[0])?;
                for a in 0..3 {
                    within("gradient", got.grad[a], grad[a], list.len(), abs[1 + a])?;
                }
                within("Σ m|∇W|²", got.grad_sq, grad_sq, list.len(), abs[4])?;
            }
        }
    }

    /// The lanes exist wherever the processor has AVX-512 (so the property test compares
    /// something there), and never for `f64`.
    #[test]
    fn cubic_lanes_run_on_avx512_for_f32_only() {
        let x = vec![Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0)];
        let mut nb = StepNeighbours::new(Method::CellStartGrid);
        nb.find(&x, 2.0).unwrap();
        #[cfg(target_arch = "x86_64")]
        assert_eq!(
            CubicLanes::new(&CubicSpline::new(2.0f32).unwrap(), 2, nb.lists()).is_some(),
            std::arch::is_x86_feature_detected!("avx512f")
        );
        let x64: Vec<Vec3<f64>> = x.iter().map(|p| p.cast()).collect();
        let mut nb64 = StepNeighbours::new(Method::CellStartGrid);
        nb64.find(&x64, 2.0).unwrap();
        assert!(CubicLanes::new(&CubicSpline::new(2.0f64).unwrap(), 2, nb64.lists()).is_none());
    }
}
