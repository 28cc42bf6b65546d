//! The pair sums of PBF's three pair passes (the `λ` pass, the `Δp` pass and the final
//! densities with XSPH) in `f32`, sixteen neighbours of one particle at a time in AVX-512
//! lanes when the processor has them (detected at run time); the scalar loops of
//! [`crate::passes`] otherwise, and always for `f64`.
//!
//! Layout: one particle at a time, its neighbour list (contiguous in the CSR index array)
//! read sixteen entries per vector, the neighbours' positions, masses, `λ` and velocities
//! gathered, the per-pair cache (`W'(r)/r`, `s_corr`) read and written contiguously. Each
//! pair's terms are the scalar code's operations in the scalar order (no fused multiply–add,
//! the kernels' two cases selected by masks instead of branches), so the cache is bit for
//! bit the scalar one; only the sums over the pairs differ, being summed in sixteen partial
//! sums and then reduced, instead of left to right. For `N` terms `t_k` both orders are
//! within `γ_{N−1} Σ|t_k|` of the exact sum (Higham 2002, *Accuracy and Stability of
//! Numerical Algorithms*, §4.2; `γ_n = n u / (1 − n u)`, `u = 2⁻²⁴`), so within
//! `2 γ_{N−1} Σ|t_k|` of each other; the tests check that bound. The order does not depend
//! on the number of threads, so runs stay bit-reproducible for a thread count and beyond.
#![allow(unsafe_code)] // AVX-512 intrinsics after run-time detection

use neighbour_search::NeighbourLists;
use sph_core::{Real, Vec3};
use sph_kernels::Kernel;
use sph_solver::pair_lanes::{f32s, f32s_mut, lanes_available, Packed};

use crate::kernels::Consts;

/// The constants of the pair terms in `f32`, as `sph_kernels`' Poly6 and Spiky and the
/// artificial pressure evaluate them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LaneConsts {
    /// `h²` (Poly6's support test on `r²`).
    h2: f32,
    /// `1/h²`, rounded once from `f64`.
    inv_h2: f32,
    /// Poly6's `k = 315/(64π h³)`.
    k_poly6: f32,
    /// `h`.
    h: f32,
    /// `1/h`, rounded once from `f64`.
    inv_h: f32,
    /// Spiky's `−3 k/h` (its derivative at `r = 0`).
    spiky_d0: f32,
    /// `1/ρ0`.
    inv_rho0: f32,
    /// `−k` and `1/W(Δq)` of `s_corr` (eq. 13, `n = 4`), `None` when it is off.
    scorr: Option<(f32, f32)>,
}

/// The sums over one particle's pairs that the `λ` pass needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LambdaSums<R: Real> {
    /// `m_i W(0) + Σ_j m_j W_ij` (kg/m³).
    pub density: R,
    /// `Σ_j (m_j/ρ0) ∇W_ij` (1/m).
    pub grad: Vec3<R>,
    /// `Σ_j |(m_j/ρ0) ∇W_ij|²` (1/m²).
    pub grad_sq: R,
}

impl LaneConsts {
    /// The lane constants, or `None` when the scalar loops must run: not `f32`, no AVX-512,
    /// an `s_corr` exponent other than 4, or lists not of `n` particles with pair and
    /// coordinate indices that fit the gathers' 32-bit offsets.
    pub(crate) fn new<R: Real>(c: &Consts<R>, n: usize, nb: &NeighbourLists) -> Option<Self> {
        let scorr_fits = !c.scorr_on || c.scorr.exponent() == 4;
        (scorr_fits && lanes_available::<R>(n, nb)).then(|| Self::of(c))
    }

    /// The constants, whatever the processor (for [`LaneConsts::new`]).
    fn of<R: Real>(c: &Consts<R>) -> Self {
        let h = c.h.as_f64();
        let inv_h = 1.0 / h;
        let h = h as f32;
        Self {
            h2: h * h,
            inv_h2: (inv_h * inv_h) as f32,
            k_poly6: c.poly6.value_r2(R::zero()).as_f64() as f32,
            h,
            inv_h: inv_h as f32,
            spiky_d0: c.spiky.derivative(R::zero()).as_f64() as f32,
            inv_rho0: c.inv_rho0.as_f64() as f32,
            scorr: c.scorr_on.then(|| {
                (
                    -c.scorr.strength().as_f64() as f32,
                    c.scorr.inverse_w_delta_q().as_f64() as f32,
                )
            }),
        }
    }
}

/// The particle `i` of the lane kernels: its position and its list.
fn position_of<R: Real>(x: &[Vec3<R>], i: usize) -> [f32; 3] {
    let p = x[i];
    [
        p.x.as_f64() as f32,
        p.y.as_f64() as f32,
        p.z.as_f64() as f32,
    ]
}

/// `[a, b, c]` as a `Vec3<R>` (exact: `R` is `f32`).
fn vec3<R: Real>(v: [f32; 3]) -> Vec3<R> {
    Vec3::new(
        R::of_f64(v[0] as f64),
        R::of_f64(v[1] as f64),
        R::of_f64(v[2] as f64),
    )
}

/// The `λ` pass's sums of particle `i` (see [`LambdaSums`]), writing its pairs' Spiky
/// factors `W'(r)/r` to `grad_factor` and `s_corr` to `scorr` (the slices of its CSR range),
/// as the scalar loop of [`crate::passes`] does; without the artificial pressure (no
/// `s_corr`) `scorr` receives the neighbours' masses `m_j` instead, which [`delta_sum`]
/// then reads in list order rather than gathering them.
#[allow(clippy::too_many_arguments)] // the pass's inputs, one particle
pub(crate) fn lambda_sums<R: Real>(
    k: &LaneConsts,
    (x, m, packed): (&[Vec3<R>], &[R], &Packed),
    nb: &NeighbourLists,
    i: usize,
    grad_factor: &mut [R],
    scorr: &mut [R],
) -> LambdaSums<R> {
    let list = nb.neighbours(i);
    assert!(grad_factor.len() == list.len() && scorr.len() == list.len());
    assert_eq!(
        packed.values().len(),
        4 * x.len(),
        "packed values of other particles"
    );
    #[cfg(target_arch = "x86_64")]
    {
        let (gf, sc) = (f32s_mut(grad_factor), f32s_mut(scorr));
        // SAFETY: a LaneConsts exists only after avx512f was detected, for lists of
        // x.len() particles (indices clamped below n inside), packed holds 4 values per
        // particle; the slices have the list's length (asserted above).
        let s = unsafe { avx512::lambda(k, packed.values(), i, list, gf, sc) };
        LambdaSums {
            density: m[i] * R::of_f64(k.k_poly6 as f64) + R::of_f64(s[0] as f64),
            grad: vec3([s[1], s[2], s[3]]),
            grad_sq: R::of_f64(s[4] as f64),
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    unreachable!("no lane constants off x86_64")
}

/// The `Δp` pass's sum `Σ_j (λ_i m_j + λ_j m_i + s_corr (m_i + m_j) unit/2) ∇W_ij` of
/// particle `i` (before the factor `1/ρ0`), from the pair cache of [`lambda_sums`] and the
/// packed `[x, y, z, λ]` ([`pack_lambda`]): `λ_j` comes with the neighbour's position and,
/// without `s_corr`, `m_j` from the pair cache, so the lanes gather nothing (with `s_corr`
/// they gather `m_j`). The same operations in the same order as before either way.
#[allow(clippy::too_many_arguments)] // the pass's inputs, one particle
pub(crate) fn delta_sum<R: Real>(
    k: &LaneConsts,
    (m, packed): (&[R], &Packed),
    lambda: &[R],
    nb: &NeighbourLists,
    i: usize,
    cache: (&[R], &[R]),
    half_unit: R,
) -> Vec3<R> {
    let list = nb.neighbours(i);
    assert!(cache.0.len() == list.len() && cache.1.len() == list.len() && lambda.len() == m.len());
    assert_eq!(
        packed.values().len(),
        4 * m.len(),
        "packed values of other particles"
    );
    #[cfg(target_arch = "x86_64")]
    {
        let own = [lambda[i], m[i], half_unit].map(|v| v.as_f64() as f32);
        // SAFETY: as in `lambda_sums`; `m` has one value per particle (asserted).
        let s = unsafe {
            avx512::delta(
                k,
                (packed.values(), f32s(m)),
                i,
                own,
                list,
                (f32s(cache.0), f32s(cache.1)),
            )
        };
        vec3([s[0], s[1], s[2]])
    }
    #[cfg(not(target_arch = "x86_64"))]
    unreachable!("no lane constants off x86_64")
}

/// Packs the velocities `[v, 0]` for [`density_xsph`].
pub(crate) fn pack_velocities<R: Real>(packed_v: &mut Packed, v: &[Vec3<R>]) {
    packed_v.fill_with(v, |_| R::zero());
}

/// The final density's pair sum `Σ_j m_j W_ij` of particle `i` and XSPH's
/// `Σ_j (v_j − v_i) (m_j/ρ0) W_ij` (eq. 17, before the factor `c`); `packed_v` holds the
/// velocities packed as `[v, 0]` ([`pack_velocities`]), loaded as the positions are (no
/// gather; the same values, so the same sums).
pub(crate) fn density_xsph<R: Real>(
    k: &LaneConsts,
    (packed, packed_v): (&Packed, &Packed),
    v: &[Vec3<R>],
    nb: &NeighbourLists,
    i: usize,
) -> (R, Vec3<R>) {
    let list = nb.neighbours(i);
    assert_eq!(
        4 * v.len(),
        packed.values().len(),
        "packed values of other particles"
    );
    assert_eq!(
        packed_v.len(),
        v.len(),
        "packed velocities of other particles"
    );
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: as in `lambda_sums`; both packed arrays hold 4 values per particle
        // (asserted).
        let s = unsafe {
            avx512::density_xsph(
                k,
                (packed.values(), packed_v.values()),
                i,
                position_of(v, i),
                list,
            )
        };
        (R::of_f64(s[0] as f64), vec3([s[1], s[2], s[3]]))
    }
    #[cfg(not(target_arch = "x86_64"))]
    unreachable!("no lane constants off x86_64")
}

/// Puts `λ` in the fourth slot of the packed `[x, y, z, m]` of the `λ` pass, for the `Δp`
/// lanes ([`delta_sum`]); the next iteration packs the masses again.
pub(crate) fn pack_lambda<R: Real>(packed: &mut Packed, lambda: &[R]) {
    assert_eq!(packed.len(), lambda.len(), "one λ per packed particle");
    packed.set_fourth(|i| lambda[i]);
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use sph_solver::pair_lanes::avx512::{gather, packed, pairs, sums};

    use super::LaneConsts;

    /// Poly6 `W(r²)`: `((k t) t) t` with `t = 1 − r²/h²`, 0 for `r² ≥ h²` or `t ≤ 0`
    /// (ordered comparisons: NaN propagates, as in `Poly6::value_r2`).
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn poly6(c: &LaneConsts, r2: __m512) -> __m512 {
        let zero = _mm512_setzero_ps();
        let t = _mm512_sub_ps(
            _mm512_set1_ps(1.0),
            _mm512_mul_ps(r2, _mm512_set1_ps(c.inv_h2)),
        );
        let outside = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(r2, _mm512_set1_ps(c.h2))
            | _mm512_cmp_ps_mask::<_CMP_LE_OQ>(t, zero);
        let w = _mm512_mul_ps(
            _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(c.k_poly6), t), t),
            t,
        );
        _mm512_mask_blend_ps(outside, w, zero)
    }

    /// Spiky `W'(r)/r`: `((d0 t) t)/r` with `t = 1 − r/h` for `0 < r < h` and `t > 0`, else 0
    /// (NaN gives 0, as `passes::spiky_factor`'s comparisons do).
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn spiky_factor(c: &LaneConsts, r2: __m512) -> __m512 {
        let zero = _mm512_setzero_ps();
        let r = _mm512_sqrt_ps(r2);
        let t = _mm512_sub_ps(
            _mm512_set1_ps(1.0),
            _mm512_mul_ps(r, _mm512_set1_ps(c.inv_h)),
        );
        let inside = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(r, zero)
            & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(r, _mm512_set1_ps(c.h))
            & _mm512_cmp_ps_mask::<_CMP_GT_OQ>(t, zero);
        let d = _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(c.spiky_d0), t), t);
        _mm512_maskz_div_ps(inside, d, r)
    }

    /// The lane sums `[Σ m_j W, Σ g_x, Σ g_y, Σ g_z, Σ |g|²]` of the `λ` pass (see
    /// `super::lambda_sums`); `sc` receives each pair's `s_corr`, or without the
    /// artificial pressure the neighbour's mass `m_j`.
    ///
    /// # Safety
    /// avx512f; `xm` holds `4n` packed values, `i < n`; `gf` and `sc` have the
    /// list's length.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn lambda(
        c: &LaneConsts,
        xm: &[f32],
        i: usize,
        list: &[u32],
        gf: &mut [f32],
        sc: &mut [f32],
    ) -> [f32; 8] {
        let inv_rho0 = _mm512_set1_ps(c.inv_rho0);
        let mut acc = [_mm512_setzero_ps(); 5];
        for s in (0..list.len()).step_by(16) {
            let p = pairs(xm, i, list, s);
            let mj = p.mj;
            let w = poly6(c, p.r2);
            acc[0] = _mm512_mask_add_ps(acc[0], p.live, acc[0], _mm512_mul_ps(mj, w));
            let scorr = match c.scorr {
                Some((neg_k, inv_w_dq)) => {
                    let q = _mm512_mul_ps(w, _mm512_set1_ps(inv_w_dq));
                    let q2 = _mm512_mul_ps(q, q);
                    _mm512_mul_ps(_mm512_set1_ps(neg_k), _mm512_mul_ps(q2, q2))
                }
                // Without the artificial pressure the slot holds m_j, for the Δp lanes.
                None => mj,
            };
            _mm512_mask_storeu_ps(sc.as_mut_ptr().add(s), p.live, scorr);
            let f = spiky_factor(c, p.r2);
            _mm512_mask_storeu_ps(gf.as_mut_ptr().add(s), p.live, f);
            let vol = _mm512_mul_ps(mj, inv_rho0);
            let g = p.d.map(|d| _mm512_mul_ps(_mm512_mul_ps(d, f), vol));
            for a in 0..3 {
                acc[1 + a] = _mm512_mask_add_ps(acc[1 + a], p.live, acc[1 + a], g[a]);
            }
            let g2 = _mm512_add_ps(
                _mm512_add_ps(_mm512_mul_ps(g[0], g[0]), _mm512_mul_ps(g[1], g[1])),
                _mm512_mul_ps(g[2], g[2]),
            );
            acc[4] = _mm512_mask_add_ps(acc[4], p.live, acc[4], g2);
        }
        sums(acc)
    }

    /// The `Δp` pass's lane sum (see `super::delta_sum`); `xl` is the packed
    /// `[x, y, z, λ]`, `own` is `[λ_i, m_i, unit/2]`.
    ///
    /// # Safety
    /// avx512f; `xl` holds `4n` packed values, `m` `n`, `i < n`; both cache slices have
    /// the list's length.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn delta(
        c: &LaneConsts,
        (xl, m): (&[f32], &[f32]),
        i: usize,
        own: [f32; 3],
        list: &[u32],
        (gf, sc): (&[f32], &[f32]),
    ) -> [f32; 8] {
        let [li, mi, half_unit] = own.map(|v| _mm512_set1_ps(v));
        let mut acc = [_mm512_setzero_ps(); 3];
        for s in (0..list.len()).step_by(16) {
            let p = pairs(xl, i, list, s);
            // The packed fourth value is λ_j; m_j is in the pair cache without s_corr.
            let lj = p.mj;
            let mj = match c.scorr {
                Some(_) => gather(m, &p),
                None => _mm512_maskz_loadu_ps(p.live, sc.as_ptr().add(s)),
            };
            let f = _mm512_maskz_loadu_ps(p.live, gf.as_ptr().add(s));
            // λ_i m_j + λ_j m_i (+ s_corr (m_i + m_j) unit/2).
            let mut coeff = _mm512_add_ps(_mm512_mul_ps(li, mj), _mm512_mul_ps(lj, mi));
            if c.scorr.is_some() {
                let scorr = _mm512_maskz_loadu_ps(p.live, sc.as_ptr().add(s));
                let t = _mm512_mul_ps(_mm512_mul_ps(scorr, _mm512_add_ps(mi, mj)), half_unit);
                coeff = _mm512_add_ps(coeff, t);
            }
            for (sum, d) in acc.iter_mut().zip(p.d) {
                let g = _mm512_mul_ps(_mm512_mul_ps(d, f), coeff);
                *sum = _mm512_mask_add_ps(*sum, p.live, *sum, g);
            }
        }
        sums(acc)
    }

    /// `[Σ m_j W, Σ (v_j − v_i)_x (m_j/ρ0) W, … y, … z]` (see `super::density_xsph`).
    ///
    /// # Safety
    /// avx512f; `xm` and `vp` hold `4n` packed values each, `i < n`.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn density_xsph(
        c: &LaneConsts,
        (xm, vp): (&[f32], &[f32]),
        i: usize,
        vi: [f32; 3],
        list: &[u32],
    ) -> [f32; 8] {
        let vi = vi.map(|v| _mm512_set1_ps(v));
        let inv_rho0 = _mm512_set1_ps(c.inv_rho0);
        let zero = _mm512_setzero_ps();
        let mut acc = [zero; 4];
        for s in (0..list.len()).step_by(16) {
            let p = pairs(xm, i, list, s);
            let mj = p.mj;
            let w = poly6(c, p.r2);
            acc[0] = _mm512_mask_add_ps(acc[0], p.live, acc[0], _mm512_mul_ps(mj, w));
            // (v_j − v_i) ((m_j/ρ0) W).
            let weight = _mm512_mul_ps(_mm512_mul_ps(mj, inv_rho0), w);
            // The neighbours' velocities, loaded as their positions (no gather).
            let vj = packed(vp, i, list, s);
            for a in 0..3 {
                let t = _mm512_mul_ps(_mm512_sub_ps(vj[a], vi[a]), weight);
                acc[1 + a] = _mm512_mask_add_ps(acc[1 + a], p.live, acc[1 + a], t);
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
    use sph_kernels::Kernel;
    use sph_solver::step::StepNeighbours;

    use super::{delta_sum, density_xsph, lambda_sums, pack_lambda, pack_velocities, LaneConsts};
    use crate::kernels::Consts;
    use crate::passes;
    use crate::PbfParams;
    use sph_solver::pair_lanes::Packed;

    /// `|a − b| ≤ 2 γ_n Σ|t_k|` (`abs_sum`; see the module docs).
    fn within(what: &str, a: f32, b: f32, n: usize, abs_sum: f64) -> Result<(), TestCaseError> {
        sph_solver::testing::reordered_sums_agree(what, a, b, n, abs_sum)
            .map_err(TestCaseError::fail)
    }

    /// Positions, masses, `λ` and velocities of a cloud.
    type Cloud = (Vec<Vec3<f32>>, Vec<f32>, Vec<f32>, Vec<Vec3<f32>>);

    /// A cloud of particles at spacing 0.025 m (PBF's default `h` = 0.05 m): `n` random
    /// positions in a cube of side `0.025 n^(1/3)` (so about 30 neighbours each, as in the
    /// dam break, with coincident and near-`h` pairs possible), masses, `λ` and velocities.
    fn cloud() -> impl Strategy<Value = Cloud> {
        (20usize..400).prop_flat_map(|n| {
            let side = 0.025 * (n as f32).cbrt();
            let p = (0.0..side, 0.0..side, 0.0..side).prop_map(|(a, b, c)| Vec3::new(a, b, c));
            let v = (-1f32..1.0, -1f32..1.0, -1f32..1.0).prop_map(|(a, b, c)| Vec3::new(a, b, c));
            (
                prop::collection::vec(p, n),
                prop::collection::vec(0.008f32..0.02, n),
                prop::collection::vec(-1e-5f32..1e-5, n),
                prop::collection::vec(v, n),
            )
        })
    }

    /// The constants of the defaults (`s_corr` on, `n = 4`) or without `s_corr`.
    fn consts(scorr: bool) -> Consts<f32> {
        let mut p = PbfParams::<f32>::default();
        if !scorr {
            p.scorr_k = 0.0;
        }
        Consts::new(&p).unwrap()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// The `λ` pass's lane kernel against the scalar loop: the pair cache bit for bit
        /// (same operations, same order), the sums within `2 γ_n Σ|t_k|` (only their order
        /// differs), with `s_corr` on and off. Skipped (nothing to compare) without AVX-512.
        #[test]
        fn lambda_lanes_match_the_scalar_loop((x, m, lambda, _v) in cloud(), scorr in any::<bool>()) {
            let c = consts(scorr);
            let mut nb = StepNeighbours::new(Method::CellStartGrid);
            nb.find(&x, c.h).unwrap();
            let nb = nb.lists();
            let Some(l) = LaneConsts::new(&c, x.len(), nb) else {
                return Ok(());
            };
            let unit = crate::PbfParams::<f32>::default().scorr_unit().unwrap();
            let mut packed = Packed::default();
            packed.fill(&x, &m);
            let mut packed_lambda = packed.clone();
            pack_lambda(&mut packed_lambda, &lambda);
            for i in 0..x.len() {
                let len = nb.neighbours(i).len();
                let (mut gf, mut sc) = (vec![0f32; len], vec![0f32; len]);
                let (mut gf_l, mut sc_l) = (vec![1f32; len], vec![1f32; len]);
                let want = passes::lambda_sums(&c, &x, &m, nb, i, &mut gf, &mut sc);
                let got = lambda_sums(&l, (&x, &m, &packed), nb, i, &mut gf_l, &mut sc_l);
                for (k, &j) in nb.neighbours(i).iter().enumerate() {
                    prop_assert_eq!(gf[k].to_bits(), gf_l[k].to_bits(), "W'/r of pair {} of {}", k, i);
                    // The lanes' second slot: s_corr, or m_j without it.
                    let slot = if c.scorr_on { sc[k] } else { m[j as usize] };
                    prop_assert_eq!(slot.to_bits(), sc_l[k].to_bits(), "s_corr or m_j of pair {} of {}", k, i);
                }
                // Σ|t_k| of each sum, from the scalar terms.
                let mut abs = [f64::from(m[i] * c.w0), 0.0, 0.0, 0.0, 0.0];
                for (k, &j) in nb.neighbours(i).iter().enumerate() {
                    let j = j as usize;
                    let r = x[i] - x[j];
                    abs[0] += f64::from(m[j] * c.poly6.value_r2(r.norm_squared()));
                    let g = (r * gf[k]) * (m[j] * c.inv_rho0);
                    for a in 0..3 {
                        abs[1 + a] += f64::from(g[a].abs());
                    }
                    abs[4] += f64::from(g.norm_squared());
                }
                within("density", got.density, want.density, len, abs[0])?;
                for a in 0..3 {
                    within("gradient", got.grad[a], want.grad[a], len, abs[1 + a])?;
                }
                within("|gradient|²", got.grad_sq, want.grad_sq, len, abs[4])?;

                let half_unit = 0.5 * unit;
                let cache = (&gf[..], &sc[..]);
                let want = passes::delta_sum(&c, &x, &m, &lambda, nb, i, cache, half_unit);
                let got = delta_sum(&l, (&m, &packed_lambda), &lambda, nb, i, (&gf_l[..], &sc_l[..]), half_unit);
                let mut abs = [0f64; 3];
                for (k, &j) in nb.neighbours(i).iter().enumerate() {
                    let j = j as usize;
                    let mut coeff = lambda[i] * m[j] + lambda[j] * m[i];
                    if c.scorr_on {
                        coeff += sc[k] * (m[i] + m[j]) * half_unit;
                    }
                    let t = ((x[i] - x[j]) * gf[k]) * coeff;
                    for a in 0..3 {
                        abs[a] += f64::from(t[a].abs());
                    }
                }
                for a in 0..3 {
                    within("Δp sum", got[a], want[a], len, abs[a])?;
                }
            }
        }

        /// The final density and XSPH lane kernel against a scalar sum in list order
        /// written here from `Poly6::value_r2` (eqs. 2 and 17), within `2 γ_n Σ|t_k|`.
        #[test]
        fn density_xsph_lanes_match_a_scalar_sum((x, m, _lambda, v) in cloud()) {
            let c = consts(false);
            let mut nb = StepNeighbours::new(Method::CellStartGrid);
            nb.find(&x, c.h).unwrap();
            let nb = nb.lists();
            let Some(l) = LaneConsts::new(&c, x.len(), nb) else {
                return Ok(());
            };
            let mut packed = Packed::default();
            packed.fill(&x, &m);
            let mut packed_v = Packed::default();
            pack_velocities(&mut packed_v, &v);
            for i in 0..x.len() {
                let (mut rho, mut xsph) = (0f32, Vec3::<f32>::zeros());
                let (mut abs_rho, mut abs_xsph) = (0f64, [0f64; 3]);
                for &j in nb.neighbours(i) {
                    let j = j as usize;
                    let w = c.poly6.value_r2((x[i] - x[j]).norm_squared());
                    rho += m[j] * w;
                    abs_rho += f64::from(m[j] * w);
                    let t = (v[j] - v[i]) * (m[j] * c.inv_rho0 * w);
                    xsph += t;
                    for a in 0..3 {
                        abs_xsph[a] += f64::from(t[a].abs());
                    }
                }
                let len = nb.neighbours(i).len();
                let (got_rho, got_xsph) = density_xsph(&l, (&packed, &packed_v), &v, nb, i);
                within("density", got_rho, rho, len, abs_rho)?;
                for a in 0..3 {
                    within("XSPH", got_xsph[a], xsph[a], len, abs_xsph[a])?;
                }
            }
        }
    }

    /// The lanes run wherever the processor has AVX-512 (so the property tests above compare
    /// something there), and never for `f64`.
    #[test]
    fn lanes_run_on_avx512_for_f32_only() {
        let c = consts(true);
        let x = vec![Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(0.01, 0.0, 0.0)];
        let mut nb = StepNeighbours::new(Method::CellStartGrid);
        nb.find(&x, c.h).unwrap();
        #[cfg(target_arch = "x86_64")]
        assert_eq!(
            LaneConsts::new(&c, 2, nb.lists()).is_some(),
            std::arch::is_x86_feature_detected!("avx512f")
        );
        let c64 = Consts::new(&PbfParams::<f64>::default()).unwrap();
        let x64: Vec<Vec3<f64>> = x.iter().map(|p| p.cast()).collect();
        let mut nb64 = StepNeighbours::new(Method::CellStartGrid);
        nb64.find(&x64, c64.h).unwrap();
        assert!(LaneConsts::new(&c64, 2, nb64.lists()).is_none());
        assert_eq!(c.poly6.support_radius(), c.h);
    }
}
