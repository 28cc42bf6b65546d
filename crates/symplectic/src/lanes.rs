//! The barycentric particle step for several particles at once, one per lane.
//!
//! A particle step is about 850 flops but about 2200 scalar instructions (interpolation,
//! kicks, Kepler drift, removal tests, loads and checks), retired at nearly four per cycle:
//! one particle at a time is bound by the instruction count. Here
//! [`LANES`] independent particles, each on its own clock, go through the same operations
//! side by side in `[f64; LANES]` values ([`V`]), which the compiler turns into packed
//! instructions (`mulpd`, `addpd`, `divpd`, `sqrtpd`): pairs of SSE2 ones in portable code,
//! single AVX ones where the population's window compiles the lanes for AVX after detecting
//! it at run time.
//!
//! **Bit for bit the scalar path.** Each lane performs exactly the IEEE operations of
//! [`ParticleIntegrator::advance`](crate::ParticleIntegrator) in the same order (packed
//! `+ − × ÷ √` round like their scalar forms; Rust never contracts to FMA), written out
//! below next to their scalar originals: the same association of every sum and product as
//! nalgebra's `Vector3` (`dot = (a₀b₀ + a₁b₁) + a₂b₂`), the same Stumpff series and
//! quadruple-argument reductions (a per-lane count), the same Halley iteration (a lane stops
//! when its own test passes and keeps its own result; the others go on). What the lanes do
//! not handle — a non-positive `F₀` or `F₁`, a drift longer than the orbital period, a
//! Halley iteration that fails, a non-finite state — they report, and the caller redoes that
//! particle's step with the scalar path from its unchanged state, so the outcome (including
//! the error) is the scalar one.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// Particles stepped side by side.
pub(crate) const LANES: usize = 4;

/// One `f64` per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(align(32))]
pub(crate) struct V(pub(crate) [f64; LANES]);

/// A `Vec3` per lane, component-major.
pub(crate) type V3 = [V; 3];

/// A per-lane flag.
pub(crate) type Mask = [bool; LANES];

impl V {
    #[inline(always)]
    pub(crate) fn splat(x: f64) -> Self {
        Self([x; LANES])
    }

    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        let mut out = self.0;
        for x in &mut out {
            *x = f(*x);
        }
        Self(out)
    }

    #[inline(always)]
    fn zip(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let mut out = self.0;
        for (x, y) in out.iter_mut().zip(other.0) {
            *x = f(*x, y);
        }
        Self(out)
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }

    /// `f64::max` per lane.
    #[inline(always)]
    pub(crate) fn max(self, other: f64) -> Self {
        self.map(|a| a.max(other))
    }

    /// `mask ? a : b` per lane.
    #[inline(always)]
    pub(crate) fn select(mask: Mask, a: Self, b: Self) -> Self {
        let mut out = b.0;
        for ((o, m), x) in out.iter_mut().zip(mask).zip(a.0) {
            if m {
                *o = x;
            }
        }
        Self(out)
    }
}

macro_rules! lane_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for V {
            type Output = V;
            #[inline(always)]
            fn $method(self, rhs: V) -> V {
                self.zip(rhs, |a, b| a $op b)
            }
        }
        impl $trait<f64> for V {
            type Output = V;
            #[inline(always)]
            fn $method(self, rhs: f64) -> V {
                self.map(|a| a $op rhs)
            }
        }
        impl $trait<V> for f64 {
            type Output = V;
            #[inline(always)]
            fn $method(self, rhs: V) -> V {
                rhs.map(|b| self $op b)
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        self.map(|a| -a)
    }
}

/// nalgebra's `a.dot(b)` for 3-vectors: `(a₀b₀ + a₁b₁) + a₂b₂`.
#[inline(always)]
pub(crate) fn dot(a: &V3, b: &V3) -> V {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// nalgebra's `a.norm_squared()` (`0 + a·a`, the zero changing nothing: `a·a ≥ +0`).
#[inline(always)]
pub(crate) fn norm_squared(a: &V3) -> V {
    dot(a, a)
}

/// nalgebra's `a.norm()`.
#[inline(always)]
pub(crate) fn norm(a: &V3) -> V {
    norm_squared(a).sqrt()
}

/// Lane `l` of `x`.
#[inline(always)]
pub(crate) fn lane(x: &V3, l: usize) -> crate::Vec3 {
    crate::Vec3::new(x[0].0[l], x[1].0[l], x[2].0[l])
}

/// Whether every lane of `x` is finite, per lane.
#[inline(always)]
pub(crate) fn finite(x: V) -> Mask {
    x.0.map(f64::is_finite)
}

/// The barycentric `E₁` terms per lane: `ParticleIntegrator::barycentric_kick_terms`, for the
/// bodies `positions[j]`, `velocities[j]` (one [`V3`] per body, each lane at its own time)
/// and `gm[j]`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct KickLanes {
    pub(crate) f1: V,
    pub(crate) gradient: V3,
    pub(crate) dt_part: V,
}

impl KickLanes {
    #[inline(always)]
    pub(crate) fn zero() -> Self {
        Self {
            f1: V::splat(0.0),
            gradient: [V::splat(0.0); 3],
            dt_part: V::splat(0.0),
        }
    }

    /// The terms at positions `q`.
    #[inline(always)]
    pub(crate) fn at(
        b0: f64,
        b1: f64,
        q: &V3,
        gm: &[f64],
        positions: &[V3],
        velocities: &[V3],
    ) -> Self {
        let inv_r = 1.0 / norm(q);
        let s = inv_r * inv_r * inv_r;
        let q_r3 = [q[0] * s, q[1] * s, q[2] * s];
        let mut f1 = b0 + b1 * inv_r;
        let neg = |x: V| x.map(|a| -a);
        let mut gradient = [neg(q_r3[0]) * b1, neg(q_r3[1]) * b1, neg(q_r3[2]) * b1];
        let mut dt_part = V::splat(0.0);
        for ((&gm, qj), vj) in gm.iter().zip(positions).zip(velocities) {
            let d = [q[0] - qj[0], q[1] - qj[1], q[2] - qj[2]];
            let inv_d = 1.0 / norm(&d);
            let inv_d3 = inv_d * inv_d * inv_d;
            f1 = f1 + gm * (inv_d - inv_r);
            for i in 0..3 {
                gradient[i] = gradient[i] + (q_r3[i] - d[i] * inv_d3) * gm;
            }
            dt_part = dt_part + gm * dot(&d, vj) * inv_d3;
        }
        Self {
            f1,
            gradient,
            dt_part,
        }
    }

    /// `mask ? a : b` per lane.
    #[inline(always)]
    pub(crate) fn select(mask: Mask, a: &Self, b: &Self) -> Self {
        Self {
            f1: V::select(mask, a.f1, b.f1),
            gradient: [0, 1, 2].map(|i| V::select(mask, a.gradient[i], b.gradient[i])),
            dt_part: V::select(mask, a.dt_part, b.dt_part),
        }
    }
}

/// [`kepler::stumpff`](crate::kepler::stumpff) per lane, for the lanes in `mask` (the others
/// get unspecified values); a lane with a non-finite `z` gets `NaN`, as the scalar form.
#[inline(always)]
fn stumpff(z: V, mask: Mask) -> [V; 4] {
    let ok: Mask = std::array::from_fn(|l| mask[l] && z.0[l].is_finite());
    // Reduce |z| below 0.1 by quarter steps, each lane its own number of times.
    let mut n = [0u32; LANES];
    let mut x = z;
    loop {
        let mut any = false;
        for l in 0..LANES {
            if ok[l] && x.0[l].abs() > 0.1 {
                x.0[l] *= 0.25;
                n[l] += 1;
                any = true;
            }
        }
        if !any {
            break;
        }
    }
    let c3 = (1.0
        - x * (1.0 / 20.0)
            * (1.0
                - x * (1.0 / 42.0)
                    * (1.0
                        - x * (1.0 / 72.0)
                            * (1.0
                                - x * (1.0 / 110.0)
                                    * (1.0 - x * (1.0 / 156.0) * (1.0 - x * (1.0 / 210.0)))))))
        * (1.0 / 6.0);
    let c2 = (1.0
        - x * (1.0 / 12.0)
            * (1.0
                - x * (1.0 / 30.0)
                    * (1.0
                        - x * (1.0 / 56.0)
                            * (1.0
                                - x * (1.0 / 90.0)
                                    * (1.0 - x * (1.0 / 132.0) * (1.0 - x * (1.0 / 182.0)))))))
        * 0.5;
    let mut c = [1.0 - x * c2, 1.0 - x * c3, c2, c3];
    let rounds = n.iter().copied().max().unwrap_or(0);
    for k in 0..rounds {
        let [c0, c1, c2, c3] = c;
        let next = [
            2.0 * c0 * c0 - 1.0,
            c1 * c0,
            0.5 * c1 * c1,
            0.25 * (c2 + c0 * c3),
        ];
        let apply: Mask = std::array::from_fn(|l| k < n[l]);
        c = [0, 1, 2, 3].map(|i| V::select(apply, next[i], c[i]));
    }
    for l in 0..LANES {
        if !z.0[l].is_finite() {
            for ck in &mut c {
                ck.0[l] = f64::NAN;
            }
        }
    }
    c
}

/// [`kepler::drift_from_distance`](crate::kepler) per lane for the lanes in `live`, with each
/// lane's `mu` valid (finite, `> 0`). Returns the Halley iterations of each lane and sets `redo` for the
/// lanes the scalar path must take over (its checks, the period reduction, its fallback, a
/// non-finite result); those lanes' `r`, `v` are unspecified.
#[inline(always)]
pub(crate) fn drift(
    r: &mut V3,
    v: &mut V3,
    r0: V,
    mu: V,
    dt: V,
    live: Mask,
    redo: &mut Mask,
) -> [u32; LANES] {
    let eta = dot(r, v);
    let beta = 2.0 * mu / r0 - norm_squared(v);
    let two_pi_mu = 2.0 * std::f64::consts::PI * mu;
    let long = dt * dt * beta * beta * beta;
    let (r_ok, v_ok, dt_ok) = (finite(r0), [0, 1, 2].map(|i| finite(v[i])), finite(dt));
    let mut todo = [false; LANES];
    for l in 0..LANES {
        if !live[l] || redo[l] {
            continue;
        }
        let checks = r_ok[l]
            && r0.0[l] > 0.0
            && v_ok.iter().all(|f| f[l])
            && dt_ok[l]
            && dt.0[l] != 0.0
            && !(beta.0[l] > 0.0 && long.0[l] > two_pi_mu.0[l] * two_pi_mu.0[l]);
        if checks {
            todo[l] = true;
        } else {
            redo[l] = true;
        }
    }
    let x = dt / r0;
    let a2 = eta / (2.0 * r0);
    let a3 = (mu - beta * r0) / (6.0 * r0);
    let neg_a2 = a2.map(|a| -a);
    let correction = neg_a2 * x * x + (2.0 * a2 * a2 - a3) * x * x * x;
    let small: Mask = std::array::from_fn(|l| correction.0[l].abs() < 0.1 * x.0[l].abs());
    let mut s = V::select(small, x + correction, x);
    const HALLEY_ACCEPT: f64 = 1e-6;
    let mut iterations = [0u32; LANES];
    let zero = V::splat(0.0);
    let (mut sg0, mut sg1, mut sg2) = (zero, zero, zero);
    for _ in 0..40 {
        if !todo.iter().any(|&t| t) {
            break;
        }
        for l in 0..LANES {
            iterations[l] += u32::from(todo[l]);
        }
        let c = stumpff(beta * s * s, todo);
        let (g0, g1, g2, g3) = (c[0], s * c[1], s * s * c[2], s * s * s * c[3]);
        let f = r0 * g1 + eta * g2 + mu * g3 - dt;
        let fp = r0 * g0 + eta * g1 + mu * g2;
        let fpp = eta * g0 + (mu - beta * r0) * g1;
        let denominator = 2.0 * fp * fp - f * fpp;
        let (fp2, fp2_3) = (fp * fp, 3.0 * fp * fp);
        let halley = 2.0 * f * fp / denominator;
        let newton = f / fp;
        let use_halley: Mask =
            std::array::from_fn(|l| denominator.0[l] > fp2.0[l] && denominator.0[l] < fp2_3.0[l]);
        let ds = V::select(use_halley, halley, newton);
        let s_new = s - ds;
        let mut done = [false; LANES];
        for l in 0..LANES {
            if !todo[l] {
                continue;
            }
            if !s_new.0[l].is_finite() {
                todo[l] = false;
                redo[l] = true;
            } else if ds.0[l].abs() <= HALLEY_ACCEPT * s_new.0[l].abs() || ds.0[l] == 0.0 {
                todo[l] = false;
                done[l] = true;
            }
        }
        if done.iter().any(|&d| d) {
            let d = ds.map(|a| -a);
            let half_d2 = 0.5 * d * d;
            sg0 = V::select(done, g0 - beta * (g1 * d + g0 * half_d2), sg0);
            sg1 = V::select(done, g1 + g0 * d - beta * g1 * half_d2, sg1);
            sg2 = V::select(done, g2 + g1 * d + g0 * half_d2, sg2);
        }
        s = V::select(todo, s_new, s);
    }
    for l in 0..LANES {
        // Not converged in 40 iterations: the scalar path's bracketed fallback.
        redo[l] |= todo[l];
    }
    let (g0, g1, g2) = (sg0, sg1, sg2);
    let rr = r0 * g0 + eta * g1 + mu * g2;
    let (inv_r0, inv_rr) = (1.0 / r0, 1.0 / rr);
    let f = 1.0 - mu * g2 * inv_r0;
    let g = r0 * g1 + eta * g2;
    let fdot = -mu * g1 * (inv_rr * inv_r0);
    let gdot = 1.0 - mu * g2 * inv_rr;
    let (r_old, v_old) = (*r, *v);
    for i in 0..3 {
        r[i] = r_old[i] * f + v_old[i] * g;
        v[i] = r_old[i] * fdot + v_old[i] * gdot;
    }
    let finite_out = [0, 1, 2].map(|i| (finite(r[i]), finite(v[i])));
    for l in 0..LANES {
        if live[l] && !finite_out.iter().all(|(a, b)| a[l] && b[l]) {
            redo[l] = true;
        }
    }
    iterations
}
