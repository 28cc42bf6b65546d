//! The pair sums of IISPH's pressure passes (the pressure accelerations, `A p`, the
//! predicted density's divergence) in `f32`, sixteen neighbours of one particle at a time in
//! AVX-512 lanes when the processor has them (detected at run time); the scalar loops of
//! [`crate::passes`] otherwise, and always for `f64`.
//!
//! Layout: one particle at a time, its neighbour list (contiguous in the CSR index array)
//! read sixteen entries per vector; every per-neighbour value from arrays packed four
//! `f32` per particle, loaded with one 128-bit load per neighbour and transposed
//! (`sph_solver::pair_lanes::avx512::packed`), never gathered (this AMD EPYC's gathers cost
//! more than the rest of a pair: `perf annotate` put a quarter of the pressure sum's samples
//! on the instruction waiting for the gather of `π_j`): the step's positions with
//! `m π` of the current pressure iterate (`[x, y, z, m π]`, `π = p/ρ²`, written over the
//! masses of the density pass's `Packed`), `[v^adv, m]` and the pressure accelerations
//! `[a, m]`; the pair's cached `W'(r)/r` read contiguously.
//!
//! The pressure sum is taken as `Σ_j m_j (π_i + π_j) ∇W_ij = π_i G_i + Σ_j (m π)_j ∇W_ij`
//! with `G_i = Σ_j m_j ∇W_ij` from the density pass, so that a neighbour's `m_j π_j` comes
//! with its position; the divergence and `A p` keep the scalar loop's pair terms (the same
//! operations in the same order, no fused multiply–add). The sums over the pairs are taken
//! in sixteen partial sums and then reduced, instead of left to right. For a sum of `N`
//! terms `t_k`, each of a few roundings, the computed sum is within `γ_{N+c} Σ|t_k|` of the
//! exact one (Higham 2002, *Accuracy and Stability of Numerical Algorithms*, §3.1 and §4.2;
//! `γ_n = n u / (1 − n u)`, `u = 2⁻²⁴`, `c` the roundings of a term), whatever the order, so
//! the lanes and the scalar loop are within `2 γ_{N+c} Σ|t_k|` of each other, `Σ|t_k|` over
//! the terms of both forms; the tests check that bound. The order does not depend on the
//! number of threads, so runs stay bit-reproducible for a thread count and beyond.
#![allow(unsafe_code)] // AVX-512 intrinsics after run-time detection

use neighbour_search::NeighbourLists;
use sph_core::{Real, Vec3};
use sph_solver::pair_lanes::{f32s, lanes_available, Packed};

/// The pressure passes' lanes; exists only where they can run ([`PressureLanes::new`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PressureLanes(());

/// `[a, b, c]` as a `Vec3<R>` (exact: `R` is `f32`).
fn vec3<R: Real>(v: [f32; 3]) -> Vec3<R> {
    Vec3::new(
        R::of_f64(v[0] as f64),
        R::of_f64(v[1] as f64),
        R::of_f64(v[2] as f64),
    )
}

impl PressureLanes {
    /// Whether the lanes can run for `n` particles with these lists: `f32`, AVX-512
    /// (`lanes_available`).
    pub(crate) fn available<R: Real>(n: usize, nb: &NeighbourLists) -> bool {
        lanes_available::<R>(n, nb)
    }

    /// The lanes for `n` particles with these lists and packed arrays, or `None` when the
    /// scalar loops must run: not `f32`, no AVX-512, lists or packed values not of `n`
    /// particles.
    pub(crate) fn new<R: Real>(n: usize, nb: &NeighbourLists, packed: &[&Packed]) -> Option<Self> {
        (Self::available::<R>(n, nb) && packed.iter().all(|p| p.len() == n)).then_some(Self(()))
    }

    /// The pair sum of the pressure acceleration, `−Σ_j m_j (π_i + π_j) ∇W_ij =
    /// −(Σ_j (m π)_j ∇W_ij + π_i G_i)` with `π = p/ρ²`, `∇W_ij = (x_i − x_j) gs_k` and
    /// `G_i = Σ_j m_j ∇W_ij` (`mass_grad`), of particle `i`, from `xp`, the packed
    /// `[x, y, z, m π]`; `gs` is the particle's slice of the per-pair `W'(r)/r`.
    pub(crate) fn pressure_sum<R: Real>(
        &self,
        xp: &Packed,
        nb: &NeighbourLists,
        gs: &[R],
        (pi, mass_grad): (R, Vec3<R>),
        i: usize,
    ) -> Vec3<R> {
        let list = nb.neighbours(i);
        assert_eq!(gs.len(), list.len());
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: a PressureLanes exists only after avx512f was detected, for lists of
            // the packed particles (indices clamped below n inside); `gs` has the list's
            // length (asserted).
            let s = unsafe { avx512::pressure_sum(xp.values(), f32s(gs), i, list) };
            vec3::<R>([s[0], s[1], s[2]]) - mass_grad * pi
        }
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!("no pressure lanes off x86_64")
    }

    /// `Σ_j m_j (a_i − a_j)·∇W_ij` of particle `i` (the pair sum of `(A p)_i`), from `xp`
    /// (its positions) and `am`, the packed `[a, m]`.
    pub(crate) fn a_dot<R: Real>(
        &self,
        (xp, am): (&Packed, &Packed),
        nb: &NeighbourLists,
        gs: &[R],
        i: usize,
    ) -> R {
        let list = nb.neighbours(i);
        assert!(gs.len() == list.len() && am.len() == xp.len());
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: as in `pressure_sum`; `am` is packed for the same particles (asserted).
            let s = unsafe { avx512::a_dot((xp.values(), am.values()), f32s(gs), i, list) };
            R::of_f64(s as f64)
        }
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!("no pressure lanes off x86_64")
    }

    /// The predicted density's divergence sum `Σ_j m_j (v_i − v_j)·∇W_ij` of `v = v^adv`,
    /// from `vm`, the packed `[v, m]`, and [`PressureLanes::pressure_sum`], of particle `i`,
    /// in one pass over its pairs.
    pub(crate) fn divergence_pressure_sum<R: Real>(
        &self,
        (xp, vm): (&Packed, &Packed),
        nb: &NeighbourLists,
        gs: &[R],
        (pi, mass_grad): (R, Vec3<R>),
        i: usize,
    ) -> (R, Vec3<R>) {
        let list = nb.neighbours(i);
        assert!(gs.len() == list.len() && xp.len() == vm.len());
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: as in `pressure_sum`; `vm` is packed for the same particles (asserted).
            let s = unsafe {
                avx512::divergence_pressure_sum((xp.values(), vm.values()), f32s(gs), i, list)
            };
            let a = vec3::<R>([s[1], s[2], s[3]]) - mass_grad * pi;
            (R::of_f64(s[0] as f64), a)
        }
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!("no pressure lanes off x86_64")
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use sph_solver::pair_lanes::avx512::{packed, pairs, sums, Pairs};

    /// `∇W_ij = (x_i − x_j) gs` per axis, as `passes::grad`.
    #[inline(always)]
    unsafe fn grad(p: &Pairs, f: __m512) -> [__m512; 3] {
        [
            _mm512_mul_ps(p.d[0], f),
            _mm512_mul_ps(p.d[1], f),
            _mm512_mul_ps(p.d[2], f),
        ]
    }

    /// `a − b` per axis.
    #[inline(always)]
    unsafe fn sub(a: [__m512; 3], b: [__m512; 3]) -> [__m512; 3] {
        [
            _mm512_sub_ps(a[0], b[0]),
            _mm512_sub_ps(a[1], b[1]),
            _mm512_sub_ps(a[2], b[2]),
        ]
    }

    /// The first three packed values of particle `i`, `v[4i..4i + 3]`, broadcast.
    #[inline(always)]
    unsafe fn splat(v: &[f32], i: usize) -> [__m512; 3] {
        let p = v.as_ptr().add(4 * i);
        [
            _mm512_set1_ps(*p),
            _mm512_set1_ps(*p.add(1)),
            _mm512_set1_ps(*p.add(2)),
        ]
    }

    /// `((a_x b_x + a_y b_y) + a_z b_z)`, nalgebra's `dot` of 3-vectors.
    #[inline(always)]
    unsafe fn dot(a: [__m512; 3], b: [__m512; 3]) -> __m512 {
        _mm512_add_ps(
            _mm512_add_ps(_mm512_mul_ps(a[0], b[0]), _mm512_mul_ps(a[1], b[1])),
            _mm512_mul_ps(a[2], b[2]),
        )
    }

    /// The lane sums `[−Σ_j (m π)_j ∇W_ij]` (three axes) of particle `i`.
    ///
    /// # Safety
    /// avx512f; `xp` holds `4n` packed values, `i < n`; `gs` has the list's
    /// length.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn pressure_sum(xp: &[f32], gs: &[f32], i: usize, list: &[u32]) -> [f32; 8] {
        let mut acc = [_mm512_setzero_ps(); 3];
        for s in (0..list.len()).step_by(16) {
            // `mj` is the fourth packed value, m_j π_j.
            let p = pairs(xp, i, list, s);
            let f = _mm512_maskz_loadu_ps(p.live, gs.as_ptr().add(s));
            let gw = grad(&p, f);
            for a in 0..3 {
                let term = _mm512_mul_ps(gw[a], p.mj);
                acc[a] = _mm512_mask_sub_ps(acc[a], p.live, acc[a], term);
            }
        }
        sums(acc)
    }

    /// The lane sum `Σ_j m_j (a_i − a_j)·∇W_ij` of particle `i`.
    ///
    /// # Safety
    /// avx512f; `xm` holds `4n` packed values, `a` `3n` coordinates, `i < n`;
    /// `gs` has the list's length.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn a_dot(
        (xp, am): (&[f32], &[f32]),
        gs: &[f32],
        i: usize,
        list: &[u32],
    ) -> f32 {
        let ai = splat(am, i);
        let mut acc = _mm512_setzero_ps();
        for s in (0..list.len()).step_by(16) {
            let p = pairs(xp, i, list, s);
            let f = _mm512_maskz_loadu_ps(p.live, gs.as_ptr().add(s));
            let [a0, a1, a2, mj] = packed(am, i, list, s);
            let t = _mm512_mul_ps(mj, dot(sub(ai, [a0, a1, a2]), grad(&p, f)));
            acc = _mm512_mask_add_ps(acc, p.live, acc, t);
        }
        _mm512_reduce_add_ps(acc)
    }

    /// The lane sums `[Σ_j m_j (v_i − v_j)·∇W_ij, −Σ_j (m π)_j ∇W_ij (three axes)]` of
    /// particle `i`.
    ///
    /// # Safety
    /// avx512f; `xp` and `vm` hold `4n` packed values, `i < n`; `gs` has the
    /// list's length.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn divergence_pressure_sum(
        (xp, vm): (&[f32], &[f32]),
        gs: &[f32],
        i: usize,
        list: &[u32],
    ) -> [f32; 8] {
        let vi = splat(vm, i);
        let mut acc = [_mm512_setzero_ps(); 4];
        for s in (0..list.len()).step_by(16) {
            let p = pairs(xp, i, list, s);
            let f = _mm512_maskz_loadu_ps(p.live, gs.as_ptr().add(s));
            let gw = grad(&p, f);
            let [v0, v1, v2, mj] = packed(vm, i, list, s);
            let div = _mm512_mul_ps(mj, dot(sub(vi, [v0, v1, v2]), gw));
            acc[0] = _mm512_mask_add_ps(acc[0], p.live, acc[0], div);
            for a in 0..3 {
                let term = _mm512_mul_ps(gw[a], p.mj);
                acc[1 + a] = _mm512_mask_sub_ps(acc[1 + a], p.live, acc[1 + a], term);
            }
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
    use sph_solver::pair_lanes::Packed;
    use sph_solver::step::StepNeighbours;

    use super::PressureLanes;

    /// The support radius of the clouds (twice their spacing, 0.025 m, as the dam break's).
    const H: f32 = 0.05;

    /// `|a − b| ≤ 2 γ_n Σ|t_k|` (`abs_sum`; see the module docs).
    fn within(what: &str, a: f32, b: f32, n: usize, abs_sum: f64) -> Result<(), TestCaseError> {
        sph_solver::testing::reordered_sums_agree(what, a, b, n, abs_sum)
            .map_err(TestCaseError::fail)
    }

    /// Positions, masses, `π = p/ρ² ≥ 0` (the unilateral solve's), and two vector fields
    /// (`a`, `v^adv`) of a cloud.
    type Cloud = (
        Vec<Vec3<f32>>,
        Vec<f32>,
        Vec<f32>,
        Vec<Vec3<f32>>,
        Vec<Vec3<f32>>,
    );

    /// `n` random positions in a cube of side `0.025 n^(1/3)` (about 30 neighbours each at
    /// `h` = 0.05 m, coincident and near-`h` pairs possible) with their values.
    fn cloud() -> impl Strategy<Value = Cloud> {
        (20usize..400).prop_flat_map(|n| {
            let side = 0.025 * (n as f32).cbrt();
            let p = (0.0..side, 0.0..side, 0.0..side).prop_map(|(a, b, c)| Vec3::new(a, b, c));
            let v =
                (-10f32..10.0, -10f32..10.0, -10f32..10.0).prop_map(|(a, b, c)| Vec3::new(a, b, c));
            (
                prop::collection::vec(p, n),
                prop::collection::vec(0.008f32..0.02, n),
                prop::collection::vec(0f32..1e-3, n),
                prop::collection::vec(v.clone(), n),
                prop::collection::vec(v, n),
            )
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// The three lane kernels against scalar sums in list order written here from the
        /// cubic spline (`∇W_ij = (x_i − x_j) W'(r)/r`): the pressure sum `−Σ_j m_j (π_i +
        /// π_j) ∇W_ij`, `Σ_j m_j (a_i − a_j)·∇W_ij` and the divergence `Σ_j m_j (v_i − v_j)
        /// ·∇W_ij`, each within `2 γ_{n+4} Σ_j|t_j|` (the pressure sum's two forms, see the
        /// module docs; with `π ≥ 0` their terms' magnitudes sum to the same
        /// `Σ_j m_j (π_i + π_j)|∇W_ij|`). Skipped (nothing to compare) without AVX-512.
        #[test]
        fn pressure_lanes_match_scalar_sums((x, m, pi, a, v) in cloud()) {
            let kernel = CubicSpline::new(H).unwrap();
            let mut search = StepNeighbours::new(Method::CellStartGrid);
            search.find(&x, H).unwrap();
            let nb = search.lists();
            let n = x.len();
            let mut xm = Packed::default();
            xm.fill(&x, &m);
            let mut xp = Packed::default();
            xp.fill_with(&x, |i| m[i] * pi[i]);
            let mut vm = Packed::default();
            vm.fill_with(&v, |i| m[i]);
            let mut am = Packed::default();
            am.fill_with(&a, |i| m[i]);
            let Some(l) = PressureLanes::new::<f32>(n, nb, &[&xm, &xp, &vm, &am]) else {
                return Ok(());
            };
            for i in 0..n {
                let list = nb.neighbours(i);
                let gs: Vec<f32> = list
                    .iter()
                    .map(|&j| {
                        let r = (x[i] - x[j as usize]).norm();
                        if r > 0.0 { kernel.derivative(r) / r } else { 0.0 }
                    })
                    .collect();
                let (mut g, mut p, mut ad, mut div) = (Vec3::zeros(), Vec3::zeros(), 0f32, 0f32);
                let (mut abs_p, mut abs_ad, mut abs_div) = ([0f64; 3], 0f64, 0f64);
                for (k, &j) in list.iter().enumerate() {
                    let j = j as usize;
                    let gw = (x[i] - x[j]) * gs[k];
                    g += gw * m[j];
                    let t = gw * (m[j] * (pi[i] + pi[j]));
                    p -= t;
                    for c in 0..3 {
                        abs_p[c] += f64::from(t[c].abs());
                    }
                    let ta = m[j] * (a[i] - a[j]).dot(&gw);
                    ad += ta;
                    abs_ad += f64::from(ta.abs());
                    let tv = m[j] * (v[i] - v[j]).dot(&gw);
                    div += tv;
                    abs_div += f64::from(tv.abs());
                }
                let len = list.len() + 4;
                let got = l.pressure_sum(&xp, nb, &gs, (pi[i], g), i);
                for c in 0..3 {
                    within("pressure sum", got[c], p[c], len, abs_p[c])?;
                }
                let got = l.a_dot((&xp, &am), nb, &gs, i);
                within("A p sum", got, ad, len, abs_ad)?;
                let (got_div, got_p) = l.divergence_pressure_sum((&xp, &vm), nb, &gs, (pi[i], g), i);
                within("divergence", got_div, div, len, abs_div)?;
                for c in 0..3 {
                    within("pressure sum (fused)", got_p[c], p[c], len, abs_p[c])?;
                }
            }
        }
    }

    /// The lanes run wherever the processor has AVX-512 (so the property test
    /// above compares something there), and never for `f64`.
    #[test]
    fn pressure_lanes_run_on_avx512_for_f32_only() {
        let x = vec![Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(0.01, 0.0, 0.0)];
        let mut search = StepNeighbours::new(Method::CellStartGrid);
        search.find(&x, H).unwrap();
        let mut xm = Packed::default();
        xm.fill(&x, &[1.0, 1.0]);
        #[cfg(target_arch = "x86_64")]
        assert_eq!(
            PressureLanes::new::<f32>(2, search.lists(), &[&xm]).is_some(),
            std::arch::is_x86_feature_detected!("avx512f")
        );
        assert!(PressureLanes::new::<f32>(3, search.lists(), &[&xm]).is_none());
        let x64: Vec<Vec3<f64>> = x.iter().map(|p| p.cast()).collect();
        let mut search64 = StepNeighbours::new(Method::CellStartGrid);
        search64.find(&x64, 0.05).unwrap();
        assert!(PressureLanes::new::<f64>(2, search64.lists(), &[]).is_none());
    }
}
