//! The integrals behind the volume maps: the exact half-space volume `Ψ_plane(d)` and
//! tabulated radial antiderivatives (Gauss–Legendre, `sph_kernels::quadrature`), and the spherical quadrature of the
//! difference between a solid and its tangent half-space at one grid node.

use std::f64::consts::PI;

use nalgebra::Matrix3;
use sph_core::{Real, Sdf, Vec3};
use sph_kernels::quadrature::gauss_legendre;
use sph_kernels::Kernel;

/// Points of the per-panel rule of the radial integrals (8 points: exact to degree 15,
/// enough for every polynomial kernel of `sph-kernels` times `r²` or `r (r − d)`).
const PANEL_POINTS: usize = 8;
/// Panels per smooth piece for a kernel whose name is not in [`breakpoints`] (composite rule:
/// for a piecewise polynomial of unknown breakpoints the error of a panel containing a kink in
/// the `k`-th derivative is `O(panel^{k+1})`; 256 panels reach 1e-12 for `C¹` kernels).
const UNKNOWN_KERNEL_PANELS: usize = 256;

/// Interior breakpoints (in units of `h`) where the kernel changes polynomial piece, and the
/// number of panels per piece: `cubic-spline` changes at `h/2`; the Müller and Wendland kernels
/// are one polynomial (the viscosity kernel a polynomial plus `h/(2r)`, which becomes a
/// polynomial in every integrand used here); unknown kernels get a composite rule.
fn breakpoints(name: &str) -> (&'static [f64], usize) {
    match name {
        "cubic-spline" | "cubic-spline-2d" => (&[0.5], 1),
        "poly6" | "spiky" | "viscosity" | "wendland-c2" | "wendland-c2-2d" => (&[], 1),
        _ => (&[], UNKNOWN_KERNEL_PANELS),
    }
}

/// `∫_a^b f(r) dr` for `0 ≤ a ≤ b ≤ h`, split at the kernel's breakpoints, Gauss–Legendre per
/// panel.
fn integrate_radial<K: Kernel<f64>>(
    kernel: &K,
    rule: &[(f64, f64)],
    a: f64,
    b: f64,
    f: impl Fn(f64) -> f64,
) -> f64 {
    let h = kernel.support_radius();
    let (bps, panels) = breakpoints(kernel.name());
    let mut cuts = vec![a];
    cuts.extend(bps.iter().map(|q| q * h).filter(|&r| r > a && r < b));
    cuts.push(b);
    let mut sum = 0.0;
    for w in cuts.windows(2) {
        let step = (w[1] - w[0]) / panels as f64;
        for p in 0..panels {
            let lo = w[0] + step * p as f64;
            let (m, hl) = (lo + 0.5 * step, 0.5 * step);
            sum += hl * rule.iter().map(|&(x, wt)| wt * f(m + hl * x)).sum::<f64>();
        }
    }
    sum
}

/// The kernel-weighted volume of a half-space at signed distance `d` (m) from the evaluation
/// point (`d > 0`: the solid is on the far side of a plane `d` away; `d < 0`: the point is
/// inside the solid), for a 3D kernel of support radius `h` (dimensionless, in `[0, 1]`):
///
/// `Ψ_plane(d) = 2π ∫_d^h W(r) r (r − d) dr` for `0 ≤ d < h` (`2π r (r − d)` is the area of
/// the spherical cap of radius `r` beyond the plane), `0` for `d ≥ h`, and
/// `Ψ_plane(−d) = 1 − Ψ_plane(d)` (so `Ψ_plane(0) = 1/2`, `Ψ_plane(−h) = 1` for a normalised
/// kernel).
///
/// Computed with 8-point Gauss–Legendre on `[d, h]` split at the kernel's interior
/// breakpoints (`h/2` for `cubic-spline`): exact up to rounding for the polynomial kernels of
/// `sph-kernels`; a kernel with an unknown name gets a 256-panel composite rule. NaN for a NaN
/// `d` or an invalid support radius; the value is meaningless for 2D kernels.
pub fn half_space_volume<K: Kernel<f64>>(kernel: &K, d: f64) -> f64 {
    let h = kernel.support_radius();
    if d.is_nan() || !(h.is_finite() && h > 0.0) {
        return f64::NAN;
    }
    if d >= h {
        0.0
    } else if d <= -h {
        1.0
    } else if d < 0.0 {
        1.0 - half_space_volume(kernel, -d)
    } else {
        let rule = gauss_legendre(PANEL_POINTS);
        2.0 * PI * integrate_radial(kernel, &rule, d, h, |r| kernel.value(r) * r * (r - d))
    }
}

/// `dΨ_plane/dd` (1/m) of [`half_space_volume`]: `−2π ∫_{|d|}^h W(r) r dr` for `|d| < h`
/// (even in `d`), 0 for `|d| ≥ h`; same quadrature. NaN for a NaN `d`.
pub fn half_space_volume_derivative<K: Kernel<f64>>(kernel: &K, d: f64) -> f64 {
    let h = kernel.support_radius();
    if d.is_nan() || !(h.is_finite() && h > 0.0) {
        return f64::NAN;
    }
    let a = d.abs();
    if a >= h {
        return 0.0;
    }
    let rule = gauss_legendre(PANEL_POINTS);
    -2.0 * PI * integrate_radial(kernel, &rule, a, h, |r| kernel.value(r) * r)
}

/// A function on `[0, h]` tabulated with its derivative at `n + 1` equidistant nodes and
/// evaluated by cubic Hermite interpolation (error `≤ Δ⁴/384 · max|f⁗|`, `Δ = h/n`), clamped
/// to the end values outside `[0, h]`.
#[derive(Debug, Clone)]
pub(crate) struct HermiteTable {
    dx: f64,
    /// `(value, slope from the left, slope to the right)` per node (one-sided slopes keep
    /// the table exact to the bound where the derivative jumps at a node, e.g. `W''` of the
    /// cubic spline at `h/2`).
    nodes: Vec<(f64, f64, f64)>,
}

impl HermiteTable {
    /// `f(k, t) = value`, `slope(t)` the derivative, evaluated `1e-9 Δ` left and right of
    /// each node.
    fn new(h: f64, n: usize, f: impl Fn(usize, f64) -> f64, slope: impl Fn(f64) -> f64) -> Self {
        let dx = h / n as f64;
        let e = 1e-9 * dx;
        Self {
            dx,
            nodes: (0..=n)
                .map(|k| {
                    let t = k as f64 * dx;
                    (f(k, t), slope((t - e).max(0.0)), slope(t + e))
                })
                .collect(),
        }
    }

    /// [`HermiteTable::eval`] of four tables on the same nodes at once (one index and one
    /// set of basis weights; each result bit-identical to its table's `eval`).
    #[inline]
    fn eval4(nodes: &[[(f64, f64, f64); 4]], dx: f64, t: f64) -> [f64; 4] {
        let n = nodes.len() - 1;
        let u = t / dx;
        if u.is_nan() || u <= 0.0 {
            return nodes[0].map(|v| v.0);
        }
        if u >= n as f64 {
            return nodes[n].map(|v| v.0);
        }
        let i = (u as usize).min(n - 1);
        let s = u - i as f64;
        let (a, b) = (&nodes[i], &nodes[i + 1]);
        let s2 = s * s;
        let h00 = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s);
        let h10 = s * (1.0 - s) * (1.0 - s);
        let h01 = s2 * (3.0 - 2.0 * s);
        let h11 = s2 * (s - 1.0);
        std::array::from_fn(|k| {
            let ((y0, _, m0), (y1, m1, _)) = (a[k], b[k]);
            h00 * y0 + h10 * dx * m0 + h01 * y1 + h11 * dx * m1
        })
    }

    #[inline]
    pub(crate) fn eval(&self, t: f64) -> f64 {
        let n = self.nodes.len() - 1;
        let u = t / self.dx;
        if u.is_nan() || u <= 0.0 {
            return self.nodes[0].0;
        }
        if u >= n as f64 {
            return self.nodes[n].0;
        }
        let i = (u as usize).min(n - 1);
        let s = u - i as f64;
        let ((y0, _, m0), (y1, m1, _)) = (self.nodes[i], self.nodes[i + 1]);
        let s2 = s * s;
        let h00 = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s);
        let h10 = s * (1.0 - s) * (1.0 - s);
        let h01 = s2 * (3.0 - 2.0 * s);
        let h11 = s2 * (s - 1.0);
        h00 * y0 + h10 * self.dx * m0 + h01 * y1 + h11 * self.dx * m1
    }

    /// The interpolant and its derivative at `t` (one table lookup for both).
    #[inline]
    pub(crate) fn eval_with_slope(&self, t: f64) -> (f64, f64) {
        let n = self.nodes.len() - 1;
        let u = t / self.dx;
        if u.is_nan() || u <= 0.0 {
            return (self.nodes[0].0, self.nodes[0].2);
        }
        if u >= n as f64 {
            return (self.nodes[n].0, self.nodes[n].1);
        }
        let i = (u as usize).min(n - 1);
        let s = u - i as f64;
        let ((y0, _, m0), (y1, m1, _)) = (self.nodes[i], self.nodes[i + 1]);
        let s2 = s * s;
        let h00 = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s);
        let h10 = s * (1.0 - s) * (1.0 - s);
        let h01 = s2 * (3.0 - 2.0 * s);
        let h11 = s2 * (s - 1.0);
        let value = h00 * y0 + h10 * self.dx * m0 + h01 * y1 + h11 * self.dx * m1;
        // d/dt of the Hermite basis (per unit s, then / dx).
        let d00 = 6.0 * s2 - 6.0 * s;
        let d10 = 3.0 * s2 - 4.0 * s + 1.0;
        let d01 = -d00;
        let d11 = 3.0 * s2 - 2.0 * s;
        let slope = (d00 * y0 + d01 * y1) / self.dx + d10 * m0 + d11 * m1;
        (value, slope)
    }
}

/// Intervals of each table (the Hermite error bound gives < 1e-13 for every kernel of
/// `sph-kernels`; the tests check the tables against [`half_space_volume`] to 1e-12).
pub(crate) const TABLE_INTERVALS: usize = 4096;

/// The per-kernel tables of a volume map: `G(t) = ∫_0^t W r² dr`, `G₁(t) = ∫_0^t W'(r) r² dr`,
/// `G₂(t) = ∫_0^t W''(r) r² dr`, `G₃(t) = ∫_0^t W'(r) r dr` (interleaved, [`KernelTables::radial`]),
/// `Ψ_plane` and `dΨ_plane/dd` on `[0, h]`.
#[derive(Debug, Clone)]
pub(crate) struct KernelTables {
    pub(crate) h: f64,
    plane: HermiteTable,
    plane_d: HermiteTable,
    /// The nodes of `g`, `g1`, `g2`, `g3` interleaved, for [`KernelTables::radial`].
    radial: Vec<[(f64, f64, f64); 4]>,
    /// [`KernelTables::radial`] at `h`.
    radial_h: [f64; 4],
}

impl KernelTables {
    pub(crate) fn new<K: Kernel<f64>>(kernel: &K) -> Self {
        let h = kernel.support_radius();
        let n = TABLE_INTERVALS;
        let rule = gauss_legendre(PANEL_POINTS);
        // Slopes at r = 0 are taken at 1e-12 h (limits; the viscosity kernel is rejected by
        // the volume maps, its W'' r² diverges).
        let at = |r: f64| r.max(1e-12 * h);
        let w = |r: f64| kernel.value(at(r));
        let dw = |r: f64| kernel.derivative(at(r));
        // W'' = ∇²W − 2W'/r (the 3D radial Laplacian).
        let ddw = |r: f64| {
            let r = at(r);
            kernel.laplacian(r).unwrap_or(f64::NAN) - 2.0 * kernel.derivative(r) / r
        };
        let dx = h / n as f64;
        let accumulate = |f: &dyn Fn(f64) -> f64| {
            let mut acc = vec![0.0; n + 1];
            for k in 0..n {
                let (a, b) = (k as f64 * dx, (k + 1) as f64 * dx);
                acc[k + 1] = acc[k] + integrate_radial(kernel, &rule, a, b, f);
            }
            acc
        };
        let gv = accumulate(&|r| kernel.value(r) * r * r);
        let g1v = accumulate(&|r| kernel.derivative(r) * r * r);
        let g2v = accumulate(&|r| ddw(r) * r * r);
        let g3v = accumulate(&|r| kernel.derivative(r) * r);
        let sq = |r: f64| at(r) * at(r);
        let g = HermiteTable::new(h, n, |k, _| gv[k], |r| w(r) * sq(r));
        let g1 = HermiteTable::new(h, n, |k, _| g1v[k], |r| dw(r) * sq(r));
        let g2 = HermiteTable::new(h, n, |k, _| g2v[k], |r| ddw(r) * sq(r));
        let g3 = HermiteTable::new(h, n, |k, _| g3v[k], |r| dw(r) * at(r));
        let radial: Vec<_> = (0..=n)
            .map(|k| [g.nodes[k], g1.nodes[k], g2.nodes[k], g3.nodes[k]])
            .collect();
        Self {
            h,
            radial_h: HermiteTable::eval4(&radial, dx, h),
            radial,
            plane: HermiteTable::new(
                h,
                n,
                |_, d| half_space_volume(kernel, d),
                |d| half_space_volume_derivative(kernel, d),
            ),
            plane_d: HermiteTable::new(
                h,
                n,
                |_, d| half_space_volume_derivative(kernel, d),
                |d| 2.0 * PI * w(d) * at(d),
            ),
        }
    }

    /// `[G(t), G₁(t), G₂(t), G₃(t)]` in one lookup (`t = h`, the end of most rays, from
    /// the value stored at construction: bit-identical to the lookup).
    #[inline]
    pub(crate) fn radial(&self, t: f64) -> [f64; 4] {
        if t == self.h {
            self.radial_h
        } else {
            HermiteTable::eval4(&self.radial, self.plane.dx, t)
        }
    }

    /// `Ψ_plane(d)` from the table.
    #[inline]
    pub(crate) fn psi_plane(&self, d: f64) -> f64 {
        if d >= self.h {
            0.0
        } else if d <= -self.h {
            1.0
        } else if d < 0.0 {
            1.0 - self.plane.eval(-d)
        } else {
            self.plane.eval(d)
        }
    }

    /// `Ψ_plane(d)` and `dΨ_plane/dd` (1/m) in one lookup of the `Ψ_plane` table (the
    /// derivative is that of its cubic Hermite interpolant, whose node slopes are the exact
    /// derivative).
    #[inline]
    pub(crate) fn psi_plane_with_derivative(&self, d: f64) -> (f64, f64) {
        if d >= self.h {
            (0.0, 0.0)
        } else if d <= -self.h {
            (1.0, 0.0)
        } else if d < 0.0 {
            let (v, dv) = self.plane.eval_with_slope(-d);
            (1.0 - v, dv)
        } else {
            self.plane.eval_with_slope(d)
        }
    }

    /// `dΨ_plane/dd` from the table (1/m).
    #[inline]
    pub(crate) fn psi_plane_derivative(&self, d: f64) -> f64 {
        if d.abs() >= self.h {
            0.0
        } else {
            self.plane_d.eval(d.abs())
        }
    }
}

/// The direction set of the node quadrature.
#[derive(Debug, Clone)]
pub(crate) struct Directions {
    /// Gauss–Legendre rules on `[−1, 1]` with `1..=polar` points (index = count − 1).
    polar_rules: Vec<Vec<(f64, f64)>>,
    polar: usize,
    /// `(cos α, sin α)` of the azimuths, uniform with a half-step offset.
    azimuth: Vec<(f64, f64)>,
    ray_samples: usize,
}

impl Directions {
    pub(crate) fn new(polar: usize, azimuth: usize, ray_samples: usize) -> Self {
        Self {
            polar_rules: (1..=polar).map(gauss_legendre).collect(),
            polar,
            azimuth: (0..azimuth)
                .map(|k| {
                    let a = 2.0 * PI * (k as f64 + 0.5) / azimuth as f64;
                    (a.cos(), a.sin())
                })
                .collect(),
            ray_samples,
        }
    }
}

/// Lipschitz bound assumed for the signed distance along a ray when looking for thin
/// slivers between samples of equal sign, for solids that declare none
/// ([`Sdf::lipschitz_bound`]; 2 leaves room for the trilinear `GridSdf`, whose gradient norm
/// is at most `√3`).
const LIPSCHITZ: f64 = 2.0;
/// Slivers thinner than this (relative to `h`) are not looked for.
const MIN_SLIVER: f64 = 1e-6;
/// Root tolerance along a ray (relative to `h`).
const ROOT_TOL: f64 = 1e-10;

/// The solid's signed distance along the ray `x + t ω`, evaluated in the solid's precision.
struct Ray<'a, R: Real> {
    sdf: &'a dyn Sdf<R>,
    x: Vec3<f64>,
    dir: Vec3<f64>,
    h: f64,
    /// Lipschitz bound of the sliver search.
    lipschitz: f64,
}

impl<R: Real> Ray<'_, R> {
    fn phi(&self, t: f64) -> f64 {
        let p = self.x + self.dir * t;
        self.sdf
            .signed_distance(&Vec3::new(R::of_f64(p.x), R::of_f64(p.y), R::of_f64(p.z)))
            .as_f64()
    }

    /// Appends the sign changes of `φ` in `(a, b)`, in order.
    fn scan(&self, a: f64, fa: f64, b: f64, fb: f64, out: &mut Vec<f64>) {
        if (fa < 0.0) != (fb < 0.0) {
            out.push(self.root(a, fa, b, fb));
            return;
        }
        if fa.is_nan() || fb.is_nan() || fa.abs() + fb.abs() >= self.lipschitz * (b - a) {
            return;
        }
        if b - a < MIN_SLIVER * self.h {
            return;
        }
        let m = 0.5 * (a + b);
        let fm = self.phi(m);
        self.scan(a, fa, m, fm, out);
        self.scan(m, fm, b, fb, out);
    }

    /// A sign change of `φ` in `[a, b]` (Illinois regula falsi, bisection fallback).
    fn root(&self, mut a: f64, mut fa: f64, mut b: f64, mut fb: f64) -> f64 {
        let tol = ROOT_TOL * self.h;
        let mut side = 0i8;
        for _ in 0..100 {
            if b - a <= tol {
                break;
            }
            let mut c = (a * fb - b * fa) / (fb - fa);
            if !(c > a && c < b) {
                c = 0.5 * (a + b);
            }
            let fc = self.phi(c);
            if fc.abs() <= tol {
                return c;
            }
            if (fc < 0.0) == (fa < 0.0) {
                a = c;
                fa = fc;
                if side == -1 {
                    fb *= 0.5;
                }
                side = -1;
            } else {
                b = c;
                fb = fc;
                if side == 1 {
                    fa *= 0.5;
                }
                side = 1;
            }
        }
        0.5 * (a + b)
    }
}

/// `(∫ W t² dt, ∫ W' t² dt)` over the parts of `[0, h]` where the list of crossings (sign
/// changes, in order) says the ray is inside, starting inside when `inside0`.
#[inline]
fn radial_sums(tables: &KernelTables, inside0: bool, crossings: &[f64]) -> [f64; 4] {
    let (mut inside, mut prev, mut s) = (inside0, 0.0, [0.0; 4]);
    for &t in crossings.iter().chain(std::iter::once(&tables.h)) {
        if inside {
            let d = interval_sums(tables, prev, t);
            for (a, b) in s.iter_mut().zip(d) {
                *a += b;
            }
        }
        inside = !inside;
        prev = t;
    }
    s
}

/// `[∫ W t², ∫ W' t², ∫ W'' t², ∫ W' t]` over `[a, b]`.
#[inline]
fn interval_sums(tables: &KernelTables, a: f64, b: f64) -> [f64; 4] {
    if a == 0.0 {
        // G(0) = 0 for all four tables (their first nodes are exact zeros).
        return tables.radial(b);
    }
    let (gb, ga) = (tables.radial(b), tables.radial(a));
    [gb[0] - ga[0], gb[1] - ga[1], gb[2] - ga[2], gb[3] - ga[3]]
}

/// The same sums for the tangent half-space `{y : φ₀ + n·(y − x) < 0}` along a direction
/// with `μ = n·ω`.
#[inline]
fn plane_sums(tables: &KernelTables, phi0: f64, mu: f64) -> [f64; 4] {
    let h = tables.h;
    let (a, b) = if mu == 0.0 {
        if phi0 < 0.0 {
            (0.0, h)
        } else {
            (0.0, 0.0)
        }
    } else {
        let t = (-phi0 / mu).clamp(0.0, h);
        if mu > 0.0 {
            (0.0, t)
        } else {
            (t, h)
        }
    };
    interval_sums(tables, a, b)
}

/// `(C, ∇D, ∇∇D)` at a node `x` with signed distance `phi0` and unit normal `n`:
/// `C = Ψ_exact(x) − Ψ_plane(phi0)`, `∇D = ∇Ψ_exact(x) − Ψ_plane'(phi0) n` and
/// `∇∇D = ∇∇Ψ_exact(x) − Ψ_plane''(phi0) n nᵀ`, by the
/// spherical quadrature `∫_{S²} [f_solid(ω) − f_plane(ω)] dω` with
/// `f(ω) = ∫_{inside, t<h} W(t) t² dt` (and `−∫ ω ∫ W'(t) t² dt dω` for the gradient, since
/// `∇_x W(|x − y|) = −W'(t) ω` for `y = x + t ω`; and
/// `∫ [ω ωᵀ ∫ W'' t² dt + (I − ω ωᵀ) ∫ W' t dt] dω` for the Hessian, from
/// `∇∇W = W'' ω ωᵀ + (W'/t)(I − ω ωᵀ)`). Directions: Gauss–Legendre in `μ = cos θ`
/// about `n`, split at `μ* = −phi0/h` where the tangent plane's `f_plane` has its kink,
/// times uniform azimuths.
pub(crate) fn node_correction<R: Real>(
    sdf: &dyn Sdf<R>,
    x: Vec3<f64>,
    phi0: f64,
    n: Vec3<f64>,
    tables: &KernelTables,
    dirs: &Directions,
) -> NodeCorrection {
    let h = tables.h;
    let helper = if n.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    let t1 = (helper - n * helper.dot(&n)).normalize();
    let t2 = n.cross(&t1);
    let mu_star = (-phi0 / h).clamp(-1.0, 1.0);
    let pieces: [(f64, f64, usize); 2] = if dirs.polar >= 2 {
        let n1 =
            ((dirs.polar as f64 * (mu_star + 1.0) / 2.0).round() as usize).clamp(1, dirs.polar - 1);
        [(-1.0, mu_star, n1), (mu_star, 1.0, dirs.polar - n1)]
    } else {
        [(-1.0, 1.0, 1), (1.0, 1.0, 0)]
    };
    let w_az = 2.0 * PI / dirs.azimuth.len() as f64;
    let search = RaySearch::new(sdf, x, phi0, h, dirs.ray_samples);
    let (mut intervals, mut crossings) = (Vec::with_capacity(4), Vec::with_capacity(8));
    let (mut c, mut grad, mut hess) = (0.0, Vec3::zeros(), Matrix3::zeros());
    for &(lo, hi, count) in &pieces {
        if count == 0 || hi <= lo {
            continue;
        }
        let (m, hl) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        for &(xi, wi) in &dirs.polar_rules[count - 1] {
            let mu = m + hl * xi;
            let s = (1.0 - mu * mu).max(0.0).sqrt();
            let fp = plane_sums(tables, phi0, mu);
            for &(ca, sa) in &dirs.azimuth {
                let dir = n * mu + (t1 * ca + t2 * sa) * s;
                intervals.clear();
                let fs = if sdf.ray_inside_intervals(&x, &dir, h, &mut intervals) {
                    intervals
                        .iter()
                        .map(|&(a, b)| interval_sums(tables, a, b))
                        .fold([0.0; 4], |acc, d| std::array::from_fn(|k| acc[k] + d[k]))
                } else {
                    crossings.clear();
                    search.crossings(dir, &mut crossings);
                    radial_sums(tables, phi0 < 0.0, &crossings)
                };
                let w = wi * hl * w_az;
                c += w * (fs[0] - fp[0]);
                grad -= dir * (w * (fs[1] - fp[1]));
                let (s2, s3) = (w * (fs[2] - fp[2]), w * (fs[3] - fp[3]));
                let oo = dir * dir.transpose();
                hess += oo * (s2 - s3) + Matrix3::identity() * s3;
            }
        }
    }
    NodeCorrection { c, grad, hess }
}

/// The sampled search for the sign changes of a solid's distance along rays from one node,
/// for solids without closed-form ray intervals ([`Sdf::ray_inside_intervals`]).
struct RaySearch<'a, R: Real> {
    sdf: &'a dyn Sdf<R>,
    x: Vec3<f64>,
    phi0: f64,
    h: f64,
    samples: usize,
    lipschitz: f64,
    declared: bool,
    /// Rounding of the solid's distance at `x + t ω` (`|x| + h` bounds the coordinates),
    /// with a factor 64 of room, plus the sliver floor.
    margin: f64,
    /// The node lies on the surface (to rounding) of a solid with a declared bound.
    on_surface: bool,
}

impl<'a, R: Real> RaySearch<'a, R> {
    fn new(sdf: &'a dyn Sdf<R>, x: Vec3<f64>, phi0: f64, h: f64, samples: usize) -> Self {
        let declared = sdf.lipschitz_bound();
        let margin = 64.0 * R::MACHINE_EPSILON.as_f64() * (x.amax() + h) + MIN_SLIVER * h;
        Self {
            sdf,
            x,
            phi0,
            h,
            samples,
            lipschitz: declared.unwrap_or(LIPSCHITZ),
            declared: declared.is_some(),
            margin,
            on_surface: declared.is_some() && phi0.abs() <= margin,
        }
    }

    /// The end of the stretch from `a` on which a declared bound keeps `φ`'s sign; `-∞`
    /// without a declared bound.
    fn certified(&self, a: f64, fa: f64) -> f64 {
        if self.declared && fa.abs() > self.margin {
            a + (fa.abs() - self.margin) / self.lipschitz
        } else {
            f64::NEG_INFINITY
        }
    }

    fn sample(&self, k: usize) -> f64 {
        if k == self.samples {
            self.h
        } else {
            k as f64 * (self.h / self.samples as f64)
        }
    }

    /// Appends the sign changes of `φ` along `x + t ω`, `0 < t < h`, in order.
    fn crossings(&self, dir: Vec3<f64>, out: &mut Vec<f64>) {
        let ray = Ray {
            sdf: self.sdf,
            x: self.x,
            dir,
            h: self.h,
            lipschitz: self.lipschitz,
        };
        let (mut a, mut fa) = (0.0, self.phi0);
        // With a known Lipschitz bound `L`, `φ` keeps the sign of `φ(a)` on `[a, reach)`,
        // `reach = a + (|φ(a)| − margin)/L`: samples there are skipped when the next sample
        // is also within reach (neither adjacent interval can hold a crossing), and an
        // interval ending within reach is not searched. The crossings, and the brackets they
        // are refined from, are those of searching every interval.
        let mut reach = self.certified(a, fa);
        for k in 1..=self.samples {
            let b = self.sample(k);
            if self.sample((k + 1).min(self.samples)) < reach {
                continue;
            }
            let fb = ray.phi(b);
            // A node on the surface (to rounding) of a solid with a declared bound: the
            // "sliver" touching the ray's start is the surface the node lies on, so the first
            // interval is only checked for a sign change (the sliver search there would
            // bisect towards `t = 0` down to `1e-6 h`).
            let skip_sliver = k == 1 && self.on_surface && (fa < 0.0) == (fb < 0.0);
            if b >= reach && !skip_sliver {
                ray.scan(a, fa, b, fb, out);
            }
            (a, fa) = (b, fb);
            reach = self.certified(a, fa);
        }
    }
}

/// The correction at one node relative to its tangent half-space `P`:
/// `C = Ψ_exact − Ψ_P`, `∇(Ψ_exact − Ψ_P)` (1/m) and `∇∇(Ψ_exact − Ψ_P)` (1/m²).
#[derive(Debug, Clone, Copy)]
pub(crate) struct NodeCorrection {
    pub(crate) c: f64,
    pub(crate) grad: Vec3<f64>,
    pub(crate) hess: Matrix3<f64>,
}

/// Probe directions of the planarity test: the 26 neighbour directions of a cube, unit.
fn probe_directions() -> impl Iterator<Item = Vec3<f64>> {
    (0..27).filter(|&k| k != 13).map(|k| {
        let v = Vec3::new(
            (k % 3) as f64 - 1.0,
            ((k / 3) % 3) as f64 - 1.0,
            (k / 9) as f64 - 1.0,
        );
        v.normalize()
    })
}

/// Whether the solid agrees with its tangent half-space at `x` on the probe points
/// `x + r e` (26 directions `e`, `r ∈ {h/3, 2h/3, h}`), to `tol` (m).
pub(crate) fn looks_planar<R: Real>(
    sdf: &dyn Sdf<R>,
    x: Vec3<f64>,
    phi0: f64,
    n: Vec3<f64>,
    h: f64,
    tol: f64,
) -> bool {
    probe_directions().all(|e| {
        (1..=3).all(|k| {
            let r = h * k as f64 / 3.0;
            let p = x + e * r;
            let phi = sdf
                .signed_distance(&Vec3::new(R::of_f64(p.x), R::of_f64(p.y), R::of_f64(p.z)))
                .as_f64();
            (phi - (phi0 + r * n.dot(&e))).abs() <= tol
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use sph_kernels::{CubicSpline, Poly6, Spiky, WendlandC2};

    fn tables_match<K: Kernel<f64>>(k: K) {
        let t = KernelTables::new(&k);
        let h = k.support_radius();
        for i in 0..=997 {
            // Off-node points: 997 does not divide 4096.
            let d = -h + 2.0 * h * i as f64 / 997.0;
            let (a, b) = (t.psi_plane(d), half_space_volume(&k, d));
            // Hermite bound Δ⁴/384·max|f⁗| < 1e-13 (module docs) plus GL rounding.
            assert!((a - b).abs() < 1e-12, "{} d {d}: {a} vs {b}", k.name());
            let (a, b) = (
                t.psi_plane_derivative(d),
                half_space_volume_derivative(&k, d),
            );
            assert!((a - b).abs() * h < 1e-11, "{} d' {d}: {a} vs {b}", k.name());
        }
        // G(h) = ∫ W r² dr = 1/(4π) for a normalised 3D kernel: independent of the table.
        assert!((t.radial(h)[0] * 4.0 * PI - 1.0).abs() < 1e-12);
        // G₁(h) = ∫ W' r² dr = −2 ∫ W r dr (by parts, W(h) = 0) = Ψ_plane'(0)/π.
        let ref_g1 = half_space_volume_derivative(&k, 0.0) / PI;
        assert!((t.radial(h)[1] - ref_g1).abs() * h < 1e-11, "{}", k.name());
    }

    /// The solid without its Lipschitz bound: the full ray search (the oracle of the skips).
    struct NoBound<'a, R: Real>(&'a dyn Sdf<R>);

    impl<R: Real> Sdf<R> for NoBound<'_, R> {
        fn signed_distance(&self, p: &Vec3<R>) -> R {
            self.0.signed_distance(p)
        }
        fn gradient(&self, p: &Vec3<R>) -> Vec3<R> {
            self.0.gradient(p)
        }
    }

    /// The solid with its Lipschitz bound but without closed-form ray intervals: the
    /// sampled search with its skips.
    struct SearchOnly<'a, R: Real>(&'a dyn Sdf<R>);

    impl<R: Real> Sdf<R> for SearchOnly<'_, R> {
        fn signed_distance(&self, p: &Vec3<R>) -> R {
            self.0.signed_distance(p)
        }
        fn gradient(&self, p: &Vec3<R>) -> Vec3<R> {
            self.0.gradient(p)
        }
        fn lipschitz_bound(&self) -> Option<f64> {
            self.0.lipschitz_bound()
        }
    }

    fn node_frame<R: Real>(solid: &dyn Sdf<R>, x: Vec3<f64>) -> (f64, Vec3<f64>) {
        let xr = Vec3::new(R::of_f64(x.x), R::of_f64(x.y), R::of_f64(x.z));
        let g = solid.gradient(&xr);
        let n = Vec3::new(g.x.as_f64(), g.y.as_f64(), g.z.as_f64()).normalize();
        (solid.signed_distance(&xr).as_f64(), n)
    }

    fn same_correction<R: Real>(solid: &dyn Sdf<R>, x: Vec3<f64>, tables: &KernelTables) {
        assert_eq!(solid.lipschitz_bound(), Some(1.0));
        let (phi0, n) = node_frame(solid, x);
        let dirs = Directions::new(6, 12, 8);
        let fast = node_correction(&SearchOnly(solid), x, phi0, n, tables, &dirs);
        let full = node_correction(&NoBound(solid), x, phi0, n, tables, &dirs);
        let bits = |c: &NodeCorrection| {
            let mut v = vec![c.c.to_bits()];
            v.extend(c.grad.iter().map(|x| x.to_bits()));
            v.extend(c.hess.iter().map(|x| x.to_bits()));
            v
        };
        assert_eq!(bits(&fast), bits(&full), "at {x:?}");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 64, ..Default::default() })]
        /// Skipping ray samples and sliver searches by the Lipschitz bound gives the node
        /// corrections of the full search bit for bit (tank corner in f32 and f64, sphere),
        /// also at nodes on the surface and on grid-aligned walls.
        #[test]
        fn lipschitz_skips_are_bit_identical_to_the_full_search(
            u in proptest::array::uniform3(-0.12..0.12f64),
            snap in 0..4usize,
        ) {
            let h = 0.1;
            let tables = KernelTables::new(&CubicSpline::new(h).unwrap());
            // Tank corner at the origin; `snap` puts the node on a grid of h/4 (walls and
            // edges through nodes, as in a tank whose walls lie on grid lines).
            let u = if snap == 0 { u.map(|v| (v / (h / 4.0)).round() * (h / 4.0)) } else { u };
            let x = Vec3::new(u[0], u[1], u[2]);
            let b = sph_core::Aabb::new(Vec3::zeros(), Vec3::new(1.0, 0.8, 0.6)).unwrap();
            let tank64 = sph_core::Inverted(sph_core::BoxSdf::new(b).unwrap());
            same_correction::<f64>(&tank64, x, &tables);
            let b32 = sph_core::Aabb::new(Vec3::zeros(), Vec3::new(1.0f32, 0.8, 0.6)).unwrap();
            let tank32 = sph_core::Inverted(sph_core::BoxSdf::new(b32).unwrap());
            same_correction::<f32>(&tank32, x, &tables);
            let ball = sph_core::Sphere::new(Vec3::new(0.0, 0.0, 0.0), 0.15).unwrap();
            same_correction::<f64>(&ball, x + Vec3::new(0.15, 0.0, 0.0), &tables);
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 64, ..Default::default() })]
        /// Closed-form ray intervals give the node corrections of the sampled search (the
        /// oracle) in f64 (tank corner and ball). The search stops at `|φ| ≤ 1e-10 h`, so a
        /// crossing is off by at most `1e-10 h / |μ|` along a ray meeting the surface at
        /// `μ = cos` of its angle to the normal (≥ 1e-2 on the rules used here away from
        /// grazing); each moves `f = ∫ W t² dt` by `W t² δt ≤ (2/h) δt` (cubic spline), and
        /// the directions' weights sum to `4π`: `|ΔC| ≤ 4π · 3 crossings · (2/h) · 1e-8 h
        /// ≈ 1e-6`; the gradient and Hessian scale as `1/h` and `1/h²`.
        #[test]
        fn closed_form_intervals_agree_with_the_search(
            u in proptest::array::uniform3(-0.12..0.12f64),
        ) {
            let h = 0.1;
            let tables = KernelTables::new(&CubicSpline::new(h).unwrap());
            let dirs = Directions::new(6, 12, 8);
            let b = sph_core::Aabb::new(Vec3::zeros(), Vec3::new(1.0, 0.8, 0.6)).unwrap();
            let tank = sph_core::Inverted(sph_core::BoxSdf::new(b).unwrap());
            let ball = sph_core::Sphere::new(Vec3::new(0.0, 0.0, 0.0), 0.15).unwrap();
            let x = Vec3::new(u[0], u[1], u[2]);
            let cases: [(&dyn Sdf<f64>, Vec3<f64>); 2] =
                [(&tank, x), (&ball, x + Vec3::new(0.15, 0.0, 0.0))];
            for (solid, x) in cases {
                let (phi0, n) = node_frame(solid, x);
                let closed = node_correction(solid, x, phi0, n, &tables, &dirs);
                let search = node_correction(&SearchOnly(solid), x, phi0, n, &tables, &dirs);
                proptest::prop_assert!((closed.c - search.c).abs() <= 1e-6, "C {} vs {}", closed.c, search.c);
                proptest::prop_assert!((closed.grad - search.grad).amax() * h <= 1e-6);
                proptest::prop_assert!((closed.hess - search.hess).amax() * h * h <= 1e-6);
            }
        }
    }

    #[test]
    fn tables_agree_with_direct_quadrature() {
        tables_match(Poly6::new(0.7).unwrap());
        tables_match(Spiky::new(0.7).unwrap());
        tables_match(CubicSpline::new(0.7).unwrap());
        tables_match(WendlandC2::new(0.7).unwrap());
    }
}
