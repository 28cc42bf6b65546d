//! Property tests of every kernel, in `f32` and `f64`, against an independent `f64` reference.
//!
//! One generic function, [`check_kernel`], is instantiated for every kernel and both
//! precisions by `kernel_tests!`. The reference kernels below are written as expanded
//! (Laurent) polynomials in `q = r/h` with their normalisations typed in again, so they share
//! no code and no formula layout with the crate (which uses factored forms).
//!
//! Tolerances are derived, not fitted; each is explained where it is computed. `eps` is the
//! machine epsilon of the precision under test, `C_EVAL = 16` the number of roundings (in units
//! of `eps`) allowed for one evaluation of a kernel formula (the longest formula has about 8
//! roundings; the factor 2 covers the rounding of the argument and of the stored constants).

use std::f64::consts::PI;

use nalgebra::SVector;
use proptest::collection::vec;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use sph_kernels::quadrature::gauss_legendre;
use sph_kernels::{
    CubicSpline, CubicSpline2D, Kernel, KernelError, Poly6, Real, Spiky, ViscosityKernel,
    WendlandC2, WendlandC2Planar,
};

/// Roundings allowed per kernel evaluation, in units of `eps` (see the file docs).
const C_EVAL: f64 = 16.0;

// ---------------------------------------------------------------------------------------------
// Quadrature
// ---------------------------------------------------------------------------------------------

/// `∫_a^b f` with `panels` equal panels of the Gauss–Legendre rule `gl`.
fn integrate(gl: &[(f64, f64)], a: f64, b: f64, panels: usize, f: impl Fn(f64) -> f64) -> f64 {
    let w = (b - a) / panels as f64;
    (0..panels)
        .map(|p| {
            let mid = a + (p as f64 + 0.5) * w;
            gl.iter()
                .map(|&(x, wt)| wt * f(mid + 0.5 * w * x))
                .sum::<f64>()
                * 0.5
                * w
        })
        .sum()
}

/// `J0(x)`, to ~1e-15: for `x < 25` the trapezoidal rule with 64 points on the periodic
/// integrand of `J0(x) = (1/π) ∫_0^π cos(x sin θ) dθ` (error `2 Σ_m J_{128m}(x)`, negligible);
/// above, Hankel's asymptotic expansion truncated at its smallest term (error `< e^{-2x}`).
fn bessel_j0(x: f64) -> f64 {
    let x = x.abs();
    if x < 25.0 {
        let n = 64;
        (0..n)
            .map(|j| (x * (PI * j as f64 / n as f64).sin()).cos())
            .sum::<f64>()
            / n as f64
    } else {
        let (mut p, mut q, mut a) = (1.0, 0.0, 1.0);
        for k in 1..200 {
            let kf = k as f64;
            let next = a * -((2.0 * kf - 1.0).powi(2)) / (8.0 * kf * x);
            if next.abs() >= a.abs() || next.abs() < 1e-18 {
                break;
            }
            a = next;
            match k % 4 {
                1 => q += a,
                2 => p -= a,
                3 => q -= a,
                _ => p += a,
            }
        }
        let chi = x - PI / 4.0;
        (2.0 / (PI * x)).sqrt() * (p * chi.cos() - q * chi.sin())
    }
}

#[test]
fn bessel_j0_matches_mpmath() {
    // Values from mpmath.besselj(0, x) at 25 digits.
    for (x, j0) in [
        (0.5, 0.938_469_807_240_812_9),
        (3.0, -0.260_051_954_901_933_44),
        (10.0, -0.245_935_764_451_348_34),
        (24.9, 0.083_245_968_353_015_5),
        (25.1, 0.108_275_671_499_949_45),
        (30.0, -0.086_367_983_581_040_21),
        (100.0, 0.019_985_850_304_223_122),
        (1000.0, 0.024_786_686_152_420_175),
    ] {
        assert!(
            (bessel_j0(x) - j0).abs() < 1e-14,
            "J0({x}) = {} != {j0}",
            bessel_j0(x)
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Independent reference kernels: W(r) = σ/h^D · f(r/h), f a piecewise Laurent polynomial.
// ---------------------------------------------------------------------------------------------

/// `f(q) = Σ_i c[i] q^(p0 + i)` on `lo <= q < hi`.
struct Piece {
    lo: f64,
    hi: f64,
    p0: i32,
    c: &'static [f64],
}

struct Reference {
    name: &'static str,
    dim: usize,
    sigma: f64,
    pieces: &'static [Piece],
}

// (1 − q²)³ = 1 − 3q² + 3q⁴ − q⁶
static POLY6: Reference = Reference {
    name: "poly6",
    dim: 3,
    sigma: 315.0 / (64.0 * PI),
    pieces: &[Piece {
        lo: 0.0,
        hi: 1.0,
        p0: 0,
        c: &[1.0, 0.0, -3.0, 0.0, 3.0, 0.0, -1.0],
    }],
};
// (1 − q)³ = 1 − 3q + 3q² − q³
static SPIKY: Reference = Reference {
    name: "spiky",
    dim: 3,
    sigma: 15.0 / PI,
    pieces: &[Piece {
        lo: 0.0,
        hi: 1.0,
        p0: 0,
        c: &[1.0, -3.0, 3.0, -1.0],
    }],
};
// −q³/2 + q² + 1/(2q) − 1, the paper's expanded form
static VISCOSITY: Reference = Reference {
    name: "viscosity",
    dim: 3,
    sigma: 15.0 / (2.0 * PI),
    pieces: &[Piece {
        lo: 0.0,
        hi: 1.0,
        p0: -1,
        c: &[0.5, -1.0, 0.0, 1.0, -0.5],
    }],
};
// 6q³ − 6q² + 1 on [0, 1/2), 2(1 − q)³ = 2 − 6q + 6q² − 2q³ on [1/2, 1)
const CUBIC_PIECES: &[Piece] = &[
    Piece {
        lo: 0.0,
        hi: 0.5,
        p0: 0,
        c: &[1.0, 0.0, -6.0, 6.0],
    },
    Piece {
        lo: 0.5,
        hi: 1.0,
        p0: 0,
        c: &[2.0, -6.0, 6.0, -2.0],
    },
];
static CUBIC: Reference = Reference {
    name: "cubic-spline",
    dim: 3,
    sigma: 8.0 / PI,
    pieces: CUBIC_PIECES,
};
static CUBIC_2D: Reference = Reference {
    name: "cubic-spline-2d",
    dim: 2,
    sigma: 40.0 / (7.0 * PI),
    pieces: CUBIC_PIECES,
};
// (1 − q)⁴(1 + 4q) = 1 − 10q² + 20q³ − 15q⁴ + 4q⁵
const WENDLAND_PIECES: &[Piece] = &[Piece {
    lo: 0.0,
    hi: 1.0,
    p0: 0,
    c: &[1.0, 0.0, -10.0, 20.0, -15.0, 4.0],
}];
static WENDLAND: Reference = Reference {
    name: "wendland-c2",
    dim: 3,
    sigma: 21.0 / (2.0 * PI),
    pieces: WENDLAND_PIECES,
};
static WENDLAND_2D: Reference = Reference {
    name: "wendland-c2-2d",
    dim: 2,
    sigma: 7.0 / PI,
    pieces: WENDLAND_PIECES,
};

impl Piece {
    /// `d^n f / dq^n` of this piece's polynomial at `q` (without σ).
    fn d(&self, q: f64, n: u32) -> f64 {
        self.c
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                let p = self.p0 + i as i32;
                let falling: f64 = (0..n as i32).map(|j| (p - j) as f64).product();
                if c == 0.0 || falling == 0.0 {
                    0.0
                } else {
                    c * falling * q.powi(p - n as i32)
                }
            })
            .sum()
    }
}

impl Piece {
    /// `Σ |term|` of `d^n f / dq^n` at `q`: the scale of the rounding error of [`Piece::d`]
    /// (the expanded form cancels heavily near `q = 1`).
    fn d_abs(&self, q: f64, n: u32) -> f64 {
        self.c
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                let p = self.p0 + i as i32;
                let falling: f64 = (0..n as i32).map(|j| (p - j) as f64).product();
                if c == 0.0 || falling == 0.0 {
                    0.0
                } else {
                    (c * falling * q.powi(p - n as i32)).abs()
                }
            })
            .sum()
    }
}

impl Reference {
    /// Rounding-error bound of [`Reference::w`]: `C_EVAL · eps_f64 · Σ|terms|` (each term
    /// takes at most ~8 roundings: `powi`, products, the sum).
    fn w_err(&self, r: f64, h: f64, n: u32) -> f64 {
        let q = r / h;
        self.piece(q).map_or(0.0, |p| {
            C_EVAL * f64::EPSILON * self.sigma * p.d_abs(q, n) / h.powi(self.dim as i32 + n as i32)
        })
    }

    /// Rounding-error bound of [`Reference::lap`].
    fn lap_err(&self, r: f64, h: f64) -> f64 {
        self.w_err(r, h, 2) + (self.dim as f64 - 1.0) / r * self.w_err(r, h, 1)
    }

    fn piece(&self, q: f64) -> Option<&Piece> {
        self.pieces.iter().find(|p| p.lo <= q && q < p.hi)
    }

    /// `σ f^(n)(q)` (0 for `q >= 1`).
    fn f(&self, q: f64, n: u32) -> f64 {
        self.piece(q).map_or(0.0, |p| self.sigma * p.d(q, n))
    }

    /// `d^n W / dr^n` at distance `r` for support radius `h`.
    fn w(&self, r: f64, h: f64, n: u32) -> f64 {
        self.f(r / h, n) / h.powi(self.dim as i32 + n as i32)
    }

    /// `∇²W = W'' + (D−1)/r W'`.
    fn lap(&self, r: f64, h: f64) -> f64 {
        self.w(r, h, 2) + (self.dim as f64 - 1.0) / r * self.w(r, h, 1)
    }

    /// Interior piece boundaries (kinks of a derivative), in units of `h`.
    fn kinks(&self) -> Vec<f64> {
        self.pieces.iter().skip(1).map(|p| p.lo).collect()
    }

    /// `true` if `f` has negative powers (diverges at the origin).
    fn singular(&self) -> bool {
        self.pieces[0].p0 < 0
    }

    /// Surface measure of the unit sphere: 4π in 3D, 2π in 2D.
    fn sphere(&self) -> f64 {
        if self.dim == 3 {
            4.0 * PI
        } else {
            2.0 * PI
        }
    }
}

/// Sanity of the reference itself: exact normalisation (term by term) and `f(1) = 0`.
#[test]
fn references_are_normalised() {
    for re in [
        &POLY6,
        &SPIKY,
        &VISCOSITY,
        &CUBIC,
        &CUBIC_2D,
        &WENDLAND,
        &WENDLAND_2D,
    ] {
        let d = re.dim as i32;
        let integral: f64 = re
            .pieces
            .iter()
            .map(|p| {
                p.c.iter()
                    .enumerate()
                    .map(|(i, &c)| {
                        let e = p.p0 + i as i32 + d; // ∫ q^(p+D−1) dq
                        c * (p.hi.powi(e) - p.lo.powi(e)) / e as f64
                    })
                    .sum::<f64>()
            })
            .sum();
        let total = re.sigma * re.sphere() * integral;
        assert!((total - 1.0).abs() < 1e-14, "{}: ∫W = {total}", re.name);
        let last = re.pieces.last().unwrap();
        assert!(last.d(1.0, 0).abs() < 1e-14, "{}: f(1) != 0", re.name);
    }
}

// ---------------------------------------------------------------------------------------------
// Lattice sums in reciprocal space (Poisson summation), computed once per kernel and h/s.
// ---------------------------------------------------------------------------------------------

/// `Σ' |n|^-4` over `Z³` (Epstein zeta; computed with mpmath by Ewald's theta splitting to 30
/// digits: 16.5323159597616696…; also Borwein et al., "Lattice Sums Then and Now", CUP 2013).
const Z3_4: f64 = 16.532_315_959_761_67;

/// Reciprocal-lattice cut-off: `|k| <= K_RECIP`.
const K_RECIP: i64 = 40;

struct LatticeRef {
    ratio: usize,
    /// Real-space `f64` deviation `s^D Σ_n W(s n) − 1` (h = 1).
    dev_real: f64,
    /// Reciprocal-space value of the same deviation, `Σ_{0<|k|<=K} Ŵ(2πk/s)` (+ the exactly
    /// summed `|k|⁻⁴` origin term in 3D).
    dev_recip: f64,
    /// Rigorous bound on the neglected `|k| > K` terms.
    tail: f64,
}

/// Multiplicities of `|k|²` for `k ∈ Z^D`, `0 < |k| <= K`.
fn shell_counts(dim: usize) -> Vec<u64> {
    let k2max = (K_RECIP * K_RECIP) as usize;
    let mut counts = vec![0u64; k2max + 1];
    let r = -K_RECIP..=K_RECIP;
    for a in r.clone() {
        for b in r.clone() {
            if dim == 2 {
                let m = (a * a + b * b) as usize;
                if m > 0 && m <= k2max {
                    counts[m] += 1;
                }
            } else {
                for c in r.clone() {
                    let m = (a * a + b * b + c * c) as usize;
                    if m > 0 && m <= k2max {
                        counts[m] += 1;
                    }
                }
            }
        }
    }
    counts
}

/// Checks `F`, `F'`, `F''` are continuous at the kinks and vanish at `q = 1` (the smoothness
/// the Fourier bounds below rely on).
fn assert_c2(re: &Reference) {
    let eps = 1e-12;
    for c in re.kinks() {
        for n in 0..=2 {
            let left = re.pieces.iter().find(|p| p.hi == c).unwrap().d(c, n);
            let right = re.pieces.iter().find(|p| p.lo == c).unwrap().d(c, n);
            assert!(
                (left - right).abs() < eps,
                "{}: f^({n}) jumps at {c}",
                re.name
            );
        }
    }
    let last = re.pieces.last().unwrap();
    for n in 0..=2 {
        assert!(last.d(1.0, n).abs() < eps, "{}: f^({n})(1) != 0", re.name);
    }
}

/// The lattice-sum deviation at `h = ratio · s` in reciprocal space.
///
/// Poisson summation: `s^D Σ_{n∈Z^D} W(s n) = Σ_{k∈Z^D} Ŵ(2πk/s)` with `Ŵ(0) = ∫W = 1`, so the
/// deviation is `ε = Σ_{k≠0} Ŵ(2πk/s)`; with `h = 1`, `κ_k = 2π |k| ratio`.
///
/// 3D: `Ŵ(κ) = (4π/κ) ∫_0^1 g(q) sin(κq) dq`, `g = q F`. Integrating by parts three times
/// (valid because `F ∈ C²`, `g(0) = 0` and `g = g' = g'' = 0` at `q = 1`, see [`assert_c2`]):
/// `Ŵ(κ) = −4π g''(0)/κ⁴ + R(κ)` with `|R(κ)| <= 4π V/κ⁵`,
/// `V = |g'''(1⁻)| + Σ_kinks |[g''']| + ∫_0^1 |g''''|`. The `|k|⁻⁴` term is summed exactly with
/// `Z3_4`; `R` is summed for `|k| <= K` and its tail is bounded by
/// `4πV (2π ratio)⁻⁵ Σ_{|k|>K} |k|⁻⁵`, and `Σ_{|k|>K} |k|⁻⁵ <= ∫_{|x|>K−a} (|x|−a)⁻⁵ dx`
/// (`a = √3/2`, each lattice point owns its unit cube).
///
/// 2D: `Ŵ(κ) = 2π ∫_0^1 q F(q) J0(κq) dq`, summed for `|k| <= K`. The tail uses
/// `|Ŵ(κ)| <= ‖Δ²W‖_TV / κ⁴` (`Δ²W` is a finite measure because `F ∈ C²`: its absolutely
/// continuous part `L²F` plus single layers `|[(LF)']|` on the kink circles and on `q = 1`,
/// with `LF = F'' + F'/q`), and `Σ_{|k|>K} |k|⁻⁴ <= ∫_{|x|>K−a} (|x|−a)⁻⁴ dx`, `a = √2/2`.
fn lattice_reference(re: &Reference, ratio: usize, gl: &[(f64, f64)]) -> LatticeRef {
    assert!(!re.singular());
    assert_c2(re);
    let d = re.dim;
    let s = 1.0 / ratio as f64;

    // Real space, f64, h = 1.
    let side = 2 * ratio + 1;
    let mut sum = 0.0;
    for idx in 0..side.pow(d as u32) {
        let mut r2 = 0.0;
        let mut rest = idx;
        for _ in 0..d {
            let n = (rest % side) as f64 - ratio as f64;
            rest /= side;
            r2 += (n * s).powi(2);
        }
        sum += re.w(r2.sqrt(), 1.0, 0);
    }
    let dev_real = sum * s.powi(d as i32) - 1.0;

    // Quadrature of a radial transform over the pieces, with enough panels per oscillation.
    let transform = |kappa: f64, weight: &dyn Fn(f64) -> f64| -> f64 {
        re.pieces
            .iter()
            .map(|p| {
                let panels = (kappa * (p.hi - p.lo) / 2.0).ceil() as usize + 2;
                integrate(gl, p.lo, p.hi, panels, |q| {
                    q * re.sigma * p.d(q, 0) * weight(q)
                })
            })
            .sum()
    };

    let counts = shell_counts(d);
    let kk = K_RECIP as f64;
    let two_pi_ratio = 2.0 * PI * ratio as f64;
    let (dev_recip, tail) = if d == 3 {
        // g = qF: g'' = 2F' + qF'', g''' = 3F'' + qF''', g'''' = 4F''' + qF''''.
        let g2_0 = 2.0 * re.f(0.0, 1);
        let g3 = |p: &Piece, q: f64| re.sigma * (3.0 * p.d(q, 2) + q * p.d(q, 3));
        let g4 = |p: &Piece, q: f64| re.sigma * (4.0 * p.d(q, 3) + q * p.d(q, 4));
        let last = re.pieces.last().unwrap();
        let mut v = g3(last, 1.0).abs();
        for w in re.pieces.windows(2) {
            v += (g3(&w[0], w[0].hi) - g3(&w[1], w[1].lo)).abs();
        }
        for p in re.pieces {
            // |g''''| of a polynomial: fine panels; +1 % covers the quadrature error at its roots.
            v += 1.01 * integrate(gl, p.lo, p.hi, 400, |q| g4(p, q).abs());
        }
        let origin = |kappa: f64| -4.0 * PI * g2_0 / kappa.powi(4);
        let mut rsum = 0.0;
        for (m, &c) in counts.iter().enumerate().filter(|(_, &c)| c > 0) {
            let kappa = two_pi_ratio * (m as f64).sqrt();
            let w_hat = 4.0 * PI / kappa * transform(kappa, &|q| (kappa * q).sin());
            rsum += c as f64 * (w_hat - origin(kappa));
        }
        let origin_total = -4.0 * PI * g2_0 * Z3_4 / two_pi_ratio.powi(4);
        let a = 3f64.sqrt() / 2.0;
        let l = kk - 2.0 * a;
        let t5 = 4.0
            * PI
            * (1.0 / (2.0 * l * l) + 2.0 * a / (3.0 * l.powi(3)) + a * a / (4.0 * l.powi(4)));
        (
            origin_total + rsum,
            4.0 * PI * v / two_pi_ratio.powi(5) * t5,
        )
    } else {
        assert!(
            re.f(0.0, 1).abs() < 1e-14,
            "{}: F'(0) != 0 (Δ²W not a measure)",
            re.name
        );
        // L F = F'' + F'/q; (LF)' = F''' + F''/q − F'/q²; L²F = F'''' + 2F'''/q − F''/q² + F'/q³.
        let lf1 = |p: &Piece, q: f64| re.sigma * (p.d(q, 3) + p.d(q, 2) / q - p.d(q, 1) / (q * q));
        let l2f = |p: &Piece, q: f64| {
            re.sigma
                * (p.d(q, 4) + 2.0 * p.d(q, 3) / q - p.d(q, 2) / (q * q) + p.d(q, 1) / q.powi(3))
        };
        // LF must be continuous (no double layers); F ∈ C² implies it, check anyway.
        for w in re.pieces.windows(2) {
            let c = w[0].hi;
            let jump = (w[0].d(c, 2) + w[0].d(c, 1) / c) - (w[1].d(c, 2) + w[1].d(c, 1) / c);
            assert!(jump.abs() < 1e-12, "{}: LF jumps at {c}", re.name);
        }
        let last = re.pieces.last().unwrap();
        let mut tv = 2.0 * PI * lf1(last, 1.0).abs();
        for w in re.pieces.windows(2) {
            let c = w[0].hi;
            tv += 2.0 * PI * c * (lf1(&w[0], c) - lf1(&w[1], c)).abs();
        }
        for p in re.pieces {
            tv += 1.01 * integrate(gl, p.lo, p.hi, 400, |q| 2.0 * PI * q * l2f(p, q).abs());
        }
        let mut sum = 0.0;
        for (m, &c) in counts.iter().enumerate().filter(|(_, &c)| c > 0) {
            let kappa = two_pi_ratio * (m as f64).sqrt();
            sum += c as f64 * 2.0 * PI * transform(kappa, &|q| bessel_j0(kappa * q));
        }
        let a = 2f64.sqrt() / 2.0;
        let l = kk - 2.0 * a;
        let t4 = 2.0 * PI * (1.0 / (2.0 * l * l) + a / (3.0 * l.powi(3)));
        (sum, tv / two_pi_ratio.powi(4) * t4)
    };
    LatticeRef {
        ratio,
        dev_real,
        dev_recip,
        tail,
    }
}

// ---------------------------------------------------------------------------------------------
// The generic property test
// ---------------------------------------------------------------------------------------------

fn to_vec<R: Real, const D: usize>(v: &[f64]) -> SVector<R, D> {
    SVector::from_fn(|i, _| R::of_f64(v[i]))
}

fn widen<R: Real, const D: usize>(v: &SVector<R, D>) -> [f64; D] {
    std::array::from_fn(|i| v[i].as_f64())
}

fn unit(v: &[f64]) -> Vec<f64> {
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if n < 1e-3 {
        let mut e = vec![0.0; v.len()];
        e[0] = 1.0;
        e
    } else {
        v.iter().map(|x| x / n).collect()
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

macro_rules! check {
    ($cond:expr, $($fmt:tt)*) => {{
        // (NaN compares false, so it fails.)
        let ok: bool = $cond;
        if !ok {
            return Err(TestCaseError::fail(format!($($fmt)*)));
        }
    }};
}

/// `check!(err <= tol)` that also records the worst `err/tol` per label (printed at the end,
/// to show how much of each tolerance is used).
macro_rules! within {
    ($worst:expr, $label:literal, $err:expr, $tol:expr, $($fmt:tt)*) => {{
        let (err, tol): (f64, f64) = ($err, $tol);
        let mut worst = $worst.borrow_mut();
        let entry = worst.entry($label).or_insert(0.0f64);
        *entry = entry.max(err / tol);
        drop(worst);
        check!(err <= tol, $($fmt)*);
    }};
}

/// All properties of one kernel type in one precision.
fn check_kernel<R: Real, K: Kernel<R>, const D: usize>(
    new: fn(R) -> Result<K, KernelError>,
    re: &'static Reference,
) {
    assert_eq!(K::DIM, D);
    assert_eq!(re.dim, D);
    let name = new(R::one()).unwrap().name();
    assert_eq!(name, re.name);
    let eps = R::MACHINE_EPSILON.as_f64();

    // --- Constructors reject h <= 0, NaN, ±∞ with the kernel's name. ---
    for bad in [
        0.0,
        -0.0,
        -1.0,
        -1e-30,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ] {
        match new(R::of_f64(bad)) {
            Err(e @ KernelError::InvalidSupportRadius { kernel, value }) => {
                assert_eq!(kernel, name);
                let bad_r = R::of_f64(bad).as_f64();
                assert!(value.to_bits() == bad_r.to_bits() || (value.is_nan() && bad.is_nan()));
                assert!(e.to_string().contains(name), "{e}");
            }
            other => panic!("{name}: h = {bad} gave {other:?}"),
        }
    }
    // Finite positive h whose constants over/underflow (k/h² ∝ h^-(D+2), h² ...).
    let (tiny, huge) = if R::NAME == "f32" {
        (1e-12, 1e12)
    } else {
        (1e-80, 1e80)
    };
    for extreme in [tiny, huge] {
        match new(R::of_f64(extreme)) {
            Err(e @ KernelError::SupportRadiusOutOfRange { .. }) => {
                assert!(e.to_string().contains(name), "{e}")
            }
            other => panic!("{name}: h = {extreme} gave {other:?}"),
        }
    }

    // --- Reciprocal-space lattice references (once; independent of h and of R). ---
    let gl = gauss_legendre(10);
    let lattice: Vec<LatticeRef> = if re.singular() {
        Vec::new()
    } else {
        [2, 3, 4]
            .into_iter()
            .map(|ratio| {
                let l = lattice_reference(re, ratio, &gl);
                // The two independent f64 evaluations of the same deviation must agree.
                assert!(
                    (l.dev_real - l.dev_recip).abs() <= l.tail + 1e-9,
                    "{name} h/s = {ratio}: real {:e} vs reciprocal {:e} ± {:e}",
                    l.dev_real,
                    l.dev_recip,
                    l.tail
                );
                eprintln!(
                    "{name} [{}] h/s = {ratio}: lattice deviation real-space {:+.4e}, \
                     reciprocal {:+.4e} ± {:.1e}",
                    R::NAME,
                    l.dev_real,
                    l.dev_recip,
                    l.tail
                );
                l
            })
            .collect()
    };

    let kinks = re.kinks();
    let strategy = (
        0.01f64..10.0,        // h
        vec(-1.0f64..1.0, D), // direction of the evaluation point
        vec(-1.0f64..1.0, D), // finite-difference direction
        0.05f64..0.95,        // q = r/h
        1.0f64..2000.0,       // ρ0
        0.0f64..2.0,          // beyond the support: r = h (1 + t)
    );
    let mut runner = TestRunner::new(Config {
        cases: 256,
        failure_persistence: None,
        ..Config::default()
    });
    let worst = std::cell::RefCell::new(std::collections::BTreeMap::<&str, f64>::new());
    let result = runner.run(&strategy, |(h, u, e, q, rho0, t_out)| {
        let kernel = new(R::of_f64(h)).unwrap();
        let h_r = kernel.support_radius();
        let h = h_r.as_f64(); // the radius the kernel really has
        let (u, e) = (unit(&u), unit(&e));
        // Keep q away from the kinks (cubic spline: q = 1/2) by 0.02.
        let q = kinks.iter().fold(q, |q, &c| {
            if (q - c).abs() < 0.02 {
                c + 0.02f64.copysign(q - c)
            } else {
                q
            }
        });

        // --- Normalisation: ∫ W dV = 1 (Gauss–Legendre in r, split at the kinks). ---
        // The rule (10 nodes × 4 panels per piece) is exact for these integrands (polynomials
        // of degree <= 9 in r, including the viscosity kernel's r²·h/(2r)), so the error is
        // rounding only: ~C_EVAL eps per node, i.e. ~1e-6 in f32, ~1e-14 in f64. The bound is
        // the required 1e-4, tightened to 1000 eps where that is smaller (f64).
        let mut bounds = vec![0.0];
        bounds.extend(kinks.iter().map(|c| c * h));
        bounds.push(h);
        let mut integral = 0.0;
        let min_w = std::cell::Cell::new(f64::INFINITY);
        for b in bounds.windows(2) {
            integral += integrate(&gl, b[0], b[1], 4, |r| {
                let w = kernel.value(R::of_f64(r)).as_f64();
                min_w.set(min_w.get().min(w));
                re.sphere() * r.powi(D as i32 - 1) * w
            });
        }
        let norm_tol = 1e-4f64.min(1e3 * eps);
        within!(worst, "normalisation", (integral - 1.0).abs(), norm_tol, "{name}: ∫W dV = {integral} (h = {h})");
        check!(min_w.get() >= 0.0, "{name}: W < 0 at a quadrature node (h = {h})");

        // --- Point values against the reference (value, derivative, Laplacian, W >= 0). ---
        let r_r = R::of_f64(q * h);
        let r = r_r.as_f64();
        let wr = |n: u32| re.w(r, h, n).abs();
        let w = kernel.value(r_r).as_f64();
        check!(w >= 0.0, "{name}: W({r}) = {w} < 0");
        // Tolerances: the kernel's rounding (C_EVAL eps on the value and on the argument, which
        // enters through |W'| r) plus the reference's own rounding (w_err).
        let tol_w = C_EVAL * eps * (wr(0) + wr(1) * r) + re.w_err(r, h, 0);
        within!(worst, "value", (w - re.w(r, h, 0)).abs(), tol_w, "{name}: W({r}) = {w} vs {}", re.w(r, h, 0));
        let w_r2 = kernel.value_r2(r_r * r_r).as_f64();
        within!(worst, "value_r2", (w_r2 - re.w(r, h, 0)).abs(), tol_w, "{name}: W_r2({r}) = {w_r2}");
        let dw = kernel.derivative(r_r).as_f64();
        let tol_dw = C_EVAL * eps * (wr(1) + wr(2) * r) + re.w_err(r, h, 1);
        within!(worst, "derivative", (dw - re.w(r, h, 1)).abs(), tol_dw, "{name}: W'({r}) = {dw} vs {}", re.w(r, h, 1));
        let lap = kernel.laplacian(r_r);
        check!(lap.is_some(), "{name}: no Laplacian at r = {r}");
        let lap = lap.unwrap().as_f64();
        // The Laplacian sums W'' and (D−1)W'/r (which may cancel): error relative to both.
        let tol_lap =
            C_EVAL * eps * (wr(2) + (D as f64 - 1.0) * wr(1) / r + wr(3) * r) + re.lap_err(r, h);
        within!(worst, "laplacian", (lap - re.lap(r, h)).abs(), tol_lap, "{name}: ∇²W({r}) = {lap} vs {}", re.lap(r, h));

        // --- Gradient vs central differences of value_vec along a random direction e. ---
        // g(s) = W(|x + s e|): (g(δ) − g(−δ))/(2δ) = g'(0) + δ²/6 g'''(ξ), and
        // |g'''| <= |W'''| + 3|W''|/ρ + 3|W'|/ρ² (derivatives of ρ(s) = |x + s e|), taken from
        // the reference at ρ = r − δ, r, r + δ (×1.1: the stencil is ~eps^(1/3) of the local
        // length ℓ wide, so the max over it differs from these samples by far less than 10 %).
        // Rounding: each W carries C_EVAL eps (M0 + M1 ρ) (value and rounded position), the
        // quotient divides it by δ; the gradient itself carries C_EVAL eps M1. The step
        // δ = eps^(1/3) ℓ balances the two; ℓ = distance to 0, to h and to the kinks (where
        // W''' jumps), so the stencil stays inside one smooth piece. Factor 2 of safety.
        let ell = kinks
            .iter()
            .fold(r.min(h - r), |l, &c| l.min((r - c * h).abs()));
        let delta = eps.cbrt() * ell;
        let x: Vec<f64> = u.iter().map(|c| c * r).collect();
        let xr = to_vec::<R, D>(&x);
        let xp: Vec<f64> = x.iter().zip(&e).map(|(a, b)| a + delta * b).collect();
        let xm: Vec<f64> = x.iter().zip(&e).map(|(a, b)| a - delta * b).collect();
        let fd = (kernel.value_vec(&to_vec::<R, D>(&xp)).as_f64()
            - kernel.value_vec(&to_vec::<R, D>(&xm)).as_f64())
            / (2.0 * delta);
        let grad = widen(&kernel.gradient(&xr));
        let analytic: f64 = grad.iter().zip(&e).map(|(g, b)| g * b).sum();
        let rx = norm(&widen(&xr));
        let stencil = [rx - delta, rx, rx + delta];
        let max_of = |f: &dyn Fn(f64) -> f64| stencil.iter().map(|&p| f(p)).fold(0.0, f64::max);
        let m0 = max_of(&|p| re.w(p, h, 0).abs());
        let m1 = max_of(&|p| re.w(p, h, 1).abs());
        let m2 = max_of(&|p| re.w(p, h, 2).abs());
        let m3 = max_of(&|p| re.w(p, h, 3).abs());
        let m4 = max_of(&|p| re.w(p, h, 4).abs());
        let g3 = max_of(&|p| {
            re.w(p, h, 3).abs() + 3.0 * re.w(p, h, 2).abs() / p + 3.0 * re.w(p, h, 1).abs() / (p * p)
        });
        let trunc = delta * delta / 6.0 * g3 * 1.1;
        let eval_err = C_EVAL * eps * (m0 + m1 * (rx + delta));
        let tol_grad = 2.0 * (trunc + eval_err / delta + C_EVAL * eps * m1);
        within!(
            worst,
            "gradient vs FD",
            (fd - analytic).abs(),
            tol_grad,
            "{name}: ∇W·e = {analytic} vs FD {fd} (tol {tol_grad:e}, r = {rx}, h = {h})"
        );
        // value_vec agrees with value(|x|).
        let wv = kernel.value_vec(&xr).as_f64();
        let tol_wv = C_EVAL * eps * (m0 + m1 * rx) + re.w_err(rx, h, 0);
        within!(worst, "value_vec", (wv - re.w(rx, h, 0)).abs(), tol_wv, "{name}: value_vec");

        // --- Laplacian vs central differences of the radial derivative. ---
        // (W'(a+) − W'(a−))/(a+ − a−) = W''(mid) + δ²/6 W''''(ξ) with the rounded arguments
        // a± = r ± δ (their exact difference is used) and mid = (a+ + a−)/2 (≠ r by
        // rounding: |W'''| |mid − r| more). Rounding: each W' carries C_EVAL eps (M1 + M2 ρ),
        // divided by the step; the (D−1)/r W' term carries (D−1)/r of the same; the Laplacian
        // formula C_EVAL eps (M2 + (D−1) M1/r + M3 r). Factor 2 of safety.
        let a_p = R::of_f64(r + delta);
        let a_m = R::of_f64(r - delta);
        let step = a_p.as_f64() - a_m.as_f64();
        let mid = 0.5 * (a_p.as_f64() + a_m.as_f64());
        let d2 = (kernel.derivative(a_p).as_f64() - kernel.derivative(a_m).as_f64()) / step;
        let lap_fd = d2 + (D as f64 - 1.0) / r * dw;
        let e1 = C_EVAL * eps * (m1 + m2 * (r + delta));
        let trunc2 = step * step / 24.0 * m4 * 1.1 + m3 * (mid - r).abs();
        let tol_lap_fd = 2.0
            * (trunc2 + 2.0 * e1 / step + (D as f64 - 1.0) / r * e1
                + C_EVAL * eps * (m2 + (D as f64 - 1.0) * m1 / r + m3 * r));
        within!(
            worst,
            "laplacian vs FD",
            (lap_fd - lap).abs(),
            tol_lap_fd,
            "{name}: ∇²W = {lap} vs FD {lap_fd} (tol {tol_lap_fd:e}, r = {r}, h = {h})"
        );

        // --- Exactly zero at r = h and beyond. ---
        let zero = R::zero();
        check!(kernel.value(h_r) == zero, "{name}: W(h) != 0");
        check!(kernel.value_r2(h_r * h_r) == zero, "{name}: W_r2(h²) != 0");
        check!(kernel.derivative(h_r) == zero, "{name}: W'(h) != 0");
        check!(kernel.laplacian(h_r) == Some(zero), "{name}: ∇²W(h) != 0");
        let r_out = R::of_f64(h * (1.0 + t_out));
        check!(kernel.value(r_out) == zero, "{name}: W(r > h) != 0");
        check!(kernel.derivative(r_out) == zero, "{name}: W'(r > h) != 0");
        check!(kernel.laplacian(r_out) == Some(zero), "{name}: ∇²W(r > h) != 0");
        // A vector of length >= h (as computed in R: grow it by ulps until |v|² >= h²).
        let mut v = to_vec::<R, D>(&u.iter().map(|c| c * h * (1.0 + t_out)).collect::<Vec<_>>());
        while v.norm_squared() < h_r * h_r || v.norm() < h_r {
            v *= R::one() + R::MACHINE_EPSILON;
        }
        check!(kernel.value_vec(&v) == zero, "{name}: W(|v| >= h) != 0");
        check!(kernel.gradient(&v) == SVector::<R, D>::zeros(), "{name}: ∇W(|v| >= h) != 0");

        // --- Symmetry (exact: negation is exact) and ∇W(0) = 0. ---
        let xm = -xr;
        check!(kernel.value_vec(&xm) == kernel.value_vec(&xr), "{name}: W(−x) != W(x)");
        check!(kernel.gradient(&xm) == -kernel.gradient(&xr), "{name}: ∇W(−x) != −∇W(x)");
        check!(kernel.gradient(&SVector::<R, D>::zeros()) == SVector::<R, D>::zeros(), "{name}: ∇W(0) != 0");

        // --- The origin: W(0) and the Laplacian limit. ---
        let w0 = kernel.value(zero);
        if re.singular() {
            check!(w0.as_f64() == f64::INFINITY, "{name}: W(0) = {w0}, expected +∞");
        } else {
            let tol0 = C_EVAL * eps * re.w(0.0, h, 0);
            check!((w0.as_f64() - re.w(0.0, h, 0)).abs() <= tol0, "{name}: W(0) = {w0}");
            check!(kernel.value_vec(&SVector::<R, D>::zeros()) == w0, "{name}: value_vec(0)");
        }
        match kernel.laplacian(zero) {
            Some(l0) => {
                // Finite, and the limit of the reference Laplacian (taken at q = 1e-4, where it
                // differs from the limit by O(1e-4) relative; reference rounding there is
                // < 1e-8 relative even for the viscosity kernel's cancelling 1/q³ terms).
                let l0 = l0.as_f64();
                let near = re.lap(1e-4 * h, h);
                check!(l0.is_finite(), "{name}: ∇²W(0) = {l0}");
                check!((l0 - near).abs() <= 1e-3 * near.abs(), "{name}: ∇²W(0) = {l0} vs {near}");
            }
            // Only where the Laplacian really diverges: a cusp (F'(0) != 0) in 3D.
            None => check!(
                D == 3 && !re.singular() && re.f(0.0, 1) != 0.0,
                "{name}: ∇²W(0) is None but the limit is finite"
            ),
        }

        // --- Lattice sums: Σ_j m W(x_i − x_j), m = ρ0 s^D, h = ratio·s. ---
        for l in lattice.iter().map(Some).chain(re.singular().then_some(None)) {
            let ratio = l.map_or(3, |l| l.ratio);
            let s_r = R::of_f64(h / ratio as f64);
            let s = s_r.as_f64();
            let m_r = R::of_f64(rho0 * s.powi(D as i32));
            let m = m_r.as_f64();
            let side = 2 * ratio + 1;
            let (mut sum_r, mut sum_ref, mut abs_sum, mut der_sum) = (zero, 0.0, 0.0, 0.0);
            let mut ref_err = 0.0;
            let mut self_term = zero;
            for idx in 0..side.pow(D as u32) {
                let mut rest = idx;
                let xj = SVector::<R, D>::from_fn(|_, _| {
                    let n = (rest % side) as f64 - ratio as f64;
                    rest /= side;
                    R::of_f64(n) * s_r
                });
                let wj = kernel.value_vec(&(-xj)); // x_i = 0
                if xj == SVector::<R, D>::zeros() {
                    self_term = m_r * wj;
                    if re.singular() {
                        continue;
                    }
                }
                sum_r += m_r * wj;
                let rj = norm(&widen(&xj));
                sum_ref += m * re.w(rj, h, 0);
                abs_sum += m * re.w(rj, h, 0).abs();
                ref_err += m * re.w_err(rj, h, 0);
                der_sum += m * re.w(rj, h, 1).abs() * rj;
            }
            let n_terms = side.pow(D as u32) as f64;
            // Rounding of the R sum: (N−1) eps Σ|terms| for the summation, C_EVAL eps per term
            // (value and rounded positions, the latter ∝ |W'| r), eps for m.
            // The reference sum carries its own w_err per term (f64 summation error is below
            // that).
            let tol_sum = eps * ((n_terms + C_EVAL) * abs_sum + C_EVAL * der_sum) + ref_err;
            let sum = sum_r.as_f64();
            within!(
                worst,
                "lattice sum vs f64 reference",
                (sum - sum_ref).abs(),
                tol_sum,
                "{name}: lattice sum {sum} vs reference {sum_ref} (h/s = {ratio}, h = {h})"
            );
            match l {
                Some(l) => {
                    // Against Poisson: ρ/ρ0 − 1 = dev_recip ± tail. Extra slack: the rounded
                    // h/s differs from `ratio` by <= 2 eps relative, which moves the sum by
                    // <= 2 eps (D Σ m W + Σ m |W'| r) (scaling W(x; h) = h^-D F(|x|/h)); m by eps.
                    let slack = l.tail + 1e-9 + tol_sum / rho0
                        + 2.0 * eps * (D as f64 * abs_sum + der_sum) / rho0
                        + eps * sum / rho0;
                    let dev = sum / rho0 - 1.0;
                    within!(
                        worst,
                        "lattice deviation vs Poisson",
                        (dev - l.dev_recip).abs(),
                        slack,
                        "{name}: lattice deviation {dev:e}, Poisson {:e} ± {slack:e} (h/s = {ratio})",
                        l.dev_recip
                    );
                    check!(dev.abs() <= l.dev_recip.abs() + slack, "{name}: |deviation| bound");
                }
                None => {
                    // The viscosity kernel: the self term W(0) = +∞ makes the density infinite;
                    // only the neighbour part (checked above) is finite.
                    check!(self_term.as_f64() == f64::INFINITY, "{name}: self term is finite");
                }
            }
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{name} [{}]: {e}", R::NAME);
    }
    for (label, ratio) in worst.borrow().iter() {
        eprintln!(
            "{name} [{}]: worst error/tolerance for {label}: {ratio:.3}",
            R::NAME
        );
    }
}

macro_rules! kernel_tests {
    ($($test:ident: $ty:ident<$r:ty>, $d:literal, $re:ident;)*) => {
        $(
            #[test]
            fn $test() {
                check_kernel::<$r, $ty<$r>, $d>($ty::<$r>::new, &$re);
            }
        )*
    };
}

kernel_tests! {
    poly6_f32: Poly6<f32>, 3, POLY6;
    poly6_f64: Poly6<f64>, 3, POLY6;
    spiky_f32: Spiky<f32>, 3, SPIKY;
    spiky_f64: Spiky<f64>, 3, SPIKY;
    viscosity_f32: ViscosityKernel<f32>, 3, VISCOSITY;
    viscosity_f64: ViscosityKernel<f64>, 3, VISCOSITY;
    cubic_spline_f32: CubicSpline<f32>, 3, CUBIC;
    cubic_spline_f64: CubicSpline<f64>, 3, CUBIC;
    cubic_spline_2d_f32: CubicSpline2D<f32>, 2, CUBIC_2D;
    cubic_spline_2d_f64: CubicSpline2D<f64>, 2, CUBIC_2D;
    wendland_c2_f32: WendlandC2<f32>, 3, WENDLAND;
    wendland_c2_f64: WendlandC2<f64>, 3, WENDLAND;
    wendland_c2_2d_f32: WendlandC2Planar<f32>, 2, WENDLAND_2D;
    wendland_c2_2d_f64: WendlandC2Planar<f64>, 2, WENDLAND_2D;
}
