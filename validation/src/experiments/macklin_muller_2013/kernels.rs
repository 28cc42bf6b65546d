//! `kernels`: normalisation, derivatives and closed-form constants of every kernel of
//! `sph-kernels`, in f32 and f64.
//!
//! For each kernel and precision, over several support radii `h`:
//!
//! (a) **normalisation** `∫W dV = ∫₀ʰ W(r) S_D r^(D−1) dr` (`S_3 = 4π`, `S_2 = 2π`) by
//!     16-point Gauss–Legendre quadrature on the panels `[0, ¼, ½, ¾, 1]·h` (the cubic
//!     spline's kink at `q = ½` is a panel boundary; every kernel is a polynomial in `r` on
//!     each panel — the viscosity kernel's `h/(2r)` term times `r²` included — so the rule is
//!     exact up to rounding). Check `|∫W dV − 1| < 1e-4`.
//! (b) **gradient** `dW/dr` against the central difference `(W(r+δ) − W(r−δ)) / (2δ)` on
//!     `r ∈ [0.05h, 0.95h]`, with `δ = η·d`, `d = min(r, h − r, |r − h/2|)` (distance to the
//!     ends and to the cubic spline's kink, where d³W/dr³ jumps; samples with d < 10⁻³h skipped) and `η = ε^(1/3)` (ε the
//!     machine epsilon of the precision). The error is scaled by `|dW/dr| + |W|/d` (the
//!     derivative's magnitude, floored by the size the kernel's value imposes, so that zeros
//!     of `dW/dr` do not divide by zero). Truncation contributes `η²·d²|W'''|/6 / scale` and
//!     rounding `≈ c·ε/η` (c ≈ a few roundings of W); both are `O(ε^(2/3))`. Bound:
//!     `50·ε^(2/3)` = 1.8e-9 (f64), 1.2e-3 (f32). The same test is applied to the Laplacian
//!     (`W'' + (D−1)/r·W'`, central difference of `dW/dr`) where the kernel defines one.
//!     The vector API (`gradient`, `value_r2`) is checked against `derivative`/`value`
//!     (`< 32ε`, a few roundings).
//! (c) **constants**: `W(0)·h^D` (and, where the paper gives them, `dW/dr(0⁺)·h^(D+1)` and
//!     `∇²W(0)·h^(D+2)`) against `reference-data/kernels/normalisation_constants.csv`,
//!     relative error `< 64ε`.

use std::f64::consts::PI;

use anyhow::{Context as _, Result};
use sph_core::{Vec2, Vec3};
use sph_kernels::quadrature::gauss_legendre;
use sph_kernels::{
    CubicSpline, CubicSpline2D, Kernel, KernelError, Poly6, Real, Spiky, ViscosityKernel,
    WendlandC2, WendlandC2Planar,
};

use crate::helpers::{
    load_reference_csv, plot_xy, write_csv_columns, write_csv_rows, Legend, Marker, PlotSpec,
    ReferenceTable, Series,
};
use crate::{fmt_num, Check, Context, Experiment, Mode, Outcome};

/// The `kernels` experiment.
pub struct Kernels;

const REFERENCE: &str = "kernels/normalisation_constants.csv";
const NORMALISATION_BOUND: f64 = 1e-4;
/// Gauss–Legendre points per panel.
const GL_POINTS: usize = 16;
/// Panel boundaries in `q = r/h`.
const PANELS: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];
/// The cubic spline's kink (jump of d³W/dr³); differences are kept from straddling it.
const KINK: f64 = 0.5;
const Q_MIN: f64 = 0.05;
const Q_MAX: f64 = 0.95;

impl Experiment for Kernels {
    fn id(&self) -> &'static str {
        "kernels"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["sph-kernels"]
    }

    fn source(&self) -> &'static str {
        "Müller et al. 2003 eqs. 20–22; Monaghan 1992; Wendland 1995 / Dehnen & Aly 2012 Table 1"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let settings = Settings::for_mode(ctx.mode);
        let reference =
            load_reference_csv(ctx, REFERENCE, &["kernel", "dim", "quantity", "sigma"])?;
        let analyses = analyse_all(ctx, &settings)?;

        let mut out = Outcome::new();
        out.metric("h_values", settings.h.len() as f64);
        out.metric("fd_samples", settings.samples as f64);
        for a in &analyses {
            check_derivatives(&mut out, a);
            check_constants(&mut out, a, &reference)?;
        }

        write_outputs(ctx, &analyses, &reference)?;
        out.note(format!(
            "Support radii h = {:?} (absolute lengths; W = 0 for r ≥ h); f32 and f64 instances of each kernel.",
            settings.h
        ));
        out.note(
            "Normalisation: 16-point Gauss–Legendre per panel on [0, ¼, ½, ¾, 1]·h, in f64 over kernel values \
             computed in the kernel's precision.",
        );
        out.note(
            "Gradient check: scaled error |dW/dr − FD| / (|dW/dr| + |W|/d), central \
             difference with δ = ε^(1/3)·d, d = min(r, h − r, |r − h/2|) so that no difference straddles the \
             cubic spline's kink at q = ½ (where the third derivative jumps); the Laplacian is checked the same way against the difference of dW/dr.",
        );
        out.note(
            "The viscosity kernel has no finite W(0) (W ~ h/(2r) → ∞): its constant check uses Müller et al.'s \
             Laplacian ∇²W(0)·h⁵ = 45/π instead, and its W(0) marker is absent from the plot.",
        );
        Ok(out)
    }
}

/// Analyses every kernel, f64 and f32.
fn analyse_all(ctx: &Context, settings: &Settings) -> Result<Vec<Analysis>> {
    let gl = gauss_legendre(GL_POINTS);
    type Case = Box<dyn Fn(&Settings, &[(f64, f64)]) -> Result<Analysis>>;
    macro_rules! both {
        ($($ty:ident),*) => {
            vec![$(
                Box::new(|s: &Settings, gl: &[(f64, f64)]| analyse(<$ty<f64>>::new, s, gl)) as Case,
                Box::new(|s: &Settings, gl: &[(f64, f64)]| analyse(<$ty<f32>>::new, s, gl)) as Case,
            )*]
        };
    }
    let cases = both!(
        Poly6,
        Spiky,
        ViscosityKernel,
        CubicSpline,
        WendlandC2,
        CubicSpline2D,
        WendlandC2Planar
    );
    ctx.progress.set_length(cases.len() as u64);
    let mut analyses = Vec::new();
    for case in &cases {
        let a = case(settings, &gl)?;
        ctx.progress
            .set_message(format!("kernel cases (last: {} {})", a.name, a.precision));
        ctx.progress.inc(1);
        analyses.push(a);
    }
    Ok(analyses)
}

/// (a) normalisation, (b) the derivatives against finite differences and the vector API.
fn check_derivatives(out: &mut Outcome, a: &Analysis) {
    let key = format!("{}/{}", a.name, a.precision);
    let eps = a.eps;
    out.metric(format!("normalisation_error/{key}"), a.norm_err);
    out.check(Check::less_than(
        format!("normalisation/{key}"),
        a.norm_err,
        NORMALISATION_BOUND,
        "a normalised kernel has ∫W dV = 1 (definition); 1e-4 is above the radial quadrature's error and f32 round-off, and far below any wrong constant (a factor error in the normalisation)",
    ));
    let fd_bound = 50.0 * eps.powf(2.0 / 3.0);
    let fd_origin = format!(
        "central-difference error analysis: δ = ε^(1/3)·d, d = min(r, h−r, |r−h/2|), truncation + rounding = O(ε^(2/3)); bound 50·ε^(2/3), ε = {}",
        fmt_num(eps)
    );
    out.metric(format!("gradient_fd_error/{key}"), a.grad_err);
    out.metric(format!("gradient_fd_error_at_q/{key}"), a.grad_err_q);
    out.check(Check::less_than(
        format!("gradient-fd/{key}"),
        a.grad_err,
        fd_bound,
        fd_origin.clone(),
    ));
    if let Some((e, q)) = a.lap_err {
        out.metric(format!("laplacian_fd_error/{key}"), e);
        out.metric(format!("laplacian_fd_error_at_q/{key}"), q);
        out.check(Check::less_than(
            format!("laplacian-fd/{key}"),
            e,
            fd_bound,
            fd_origin,
        ));
    }
    out.metric(format!("api_consistency_error/{key}"), a.api_err);
    out.check(Check::less_than(
        format!("vector-api/{key}"),
        a.api_err,
        32.0 * eps,
        format!(
            "same formula up to a few roundings: 32ε, ε = {}",
            fmt_num(eps)
        ),
    ));
}

/// (c) closed-form constants against the reference table.
fn check_constants(out: &mut Outcome, a: &Analysis, reference: &ReferenceTable) -> Result<()> {
    let key = format!("{}/{}", a.name, a.precision);
    let eps = a.eps;
    let rows = reference.find_all(&[("kernel", a.name), ("dim", &a.dim.to_string())])?;
    if rows.is_empty() {
        out.check(Check::less_than(
            format!("constant/{key}"),
            f64::NAN,
            64.0 * eps,
            format!("no row for this kernel in reference-data/{REFERENCE}"),
        ));
    }
    for row in rows {
        let quantity = reference.text(row, "quantity")?;
        let sigma = reference.number(row, "sigma")?;
        let measured = measured_constant(a, &key, quantity, reference, row)?;
        let rel = measured
            .iter()
            .map(|m| ((m - sigma) / sigma).abs())
            .fold(0.0, |acc: f64, e| {
                if e.is_nan() || acc.is_nan() {
                    f64::NAN
                } else {
                    acc.max(e)
                }
            });
        out.metric(format!("{quantity}_scaled/{key}"), measured[0]);
        out.metric(format!("{quantity}_relative_error/{key}"), rel);
        let source = reference
            .text(row, "source")
            .unwrap_or("reference")
            .to_string();
        out.check(Check::less_than(
            format!("constant-{quantity}/{key}"),
            rel,
            64.0 * eps,
            format!(
                "{} = {} ({source}, reference-data/{REFERENCE} line {}); rounding bound 64ε",
                quantity_label(quantity, a.dim),
                fmt_num(sigma),
                reference.rows[row].line
            ),
        ));
    }
    Ok(())
}

/// The measured `quantity` (W0, dW0 or lap0) at each support radius.
fn measured_constant(
    a: &Analysis,
    key: &str,
    quantity: &str,
    reference: &ReferenceTable,
    row: usize,
) -> Result<Vec<f64>> {
    a.constants
        .iter()
        .map(|c| match quantity {
            "W0" => Ok(c.w0),
            "dW0" => Ok(c.dw0),
            "lap0" => c
                .lap0
                .with_context(|| format!("{key}: laplacian(0) is None")),
            other => anyhow::bail!(
                "reference file {}, line {}: unknown quantity {other:?} (expected W0, dW0 or lap0)",
                reference.path.display(),
                reference.rows[row].line
            ),
        })
        .collect()
}

fn quantity_label(q: &str, dim: usize) -> String {
    match q {
        "W0" => format!("W(0)·h^{dim}"),
        "dW0" => format!("dW/dr(0⁺)·h^{}", dim + 1),
        "lap0" => format!("∇²W(0)·h^{}", dim + 2),
        other => other.to_string(),
    }
}

struct Settings {
    h: Vec<f64>,
    samples: usize,
    /// Points of the plotted curves on [0, 1].
    curve_points: usize,
}

impl Settings {
    fn for_mode(mode: Mode) -> Self {
        match mode {
            Mode::Quick => Self {
                h: vec![0.1, 1.7],
                samples: 400,
                curve_points: 401,
            },
            Mode::Full => Self {
                h: vec![0.1, 1.7, 0.0125, 40.0],
                samples: 4000,
                curve_points: 1001,
            },
        }
    }
}

/// Scaled closed-form quantities at the origin for one `h`.
struct Constants {
    w0: f64,
    dw0: f64,
    lap0: Option<f64>,
}

struct Analysis {
    name: &'static str,
    dim: usize,
    precision: &'static str,
    eps: f64,
    norm_err: f64,
    grad_err: f64,
    grad_err_q: f64,
    lap_err: Option<(f64, f64)>,
    api_err: f64,
    constants: Vec<Constants>,
    /// `(q, W·h^D, dW/dr·h^(D+1))` for the first `h`.
    curve: Vec<(f64, f64, f64)>,
}

/// Worst scaled error, propagating NaN.
fn worst(acc: (f64, f64), e: f64, q: f64) -> (f64, f64) {
    if acc.0.is_nan() {
        acc
    } else if e.is_nan() || e > acc.0 {
        (e, q)
    } else {
        acc
    }
}

/// The worst errors over every support radius: finite-difference gradient and Laplacian
/// `(error, q)`, and the vector API.
struct WorstErrors {
    grad: (f64, f64),
    lap: Option<(f64, f64)>,
    api: f64,
}

fn analyse<R: Real, K: Kernel<R>>(
    make: impl Fn(R) -> Result<K, KernelError>,
    s: &Settings,
    gl: &[(f64, f64)],
) -> Result<Analysis> {
    let eps = R::MACHINE_EPSILON.as_f64();
    let dim = K::DIM;
    if dim != 3 && dim != 2 {
        anyhow::bail!("unsupported kernel dimension {dim}");
    }
    let mut norm_err: f64 = 0.0;
    let mut worst_errors = WorstErrors {
        grad: (0.0, 0.0),
        lap: None,
        api: 0.0,
    };
    let mut constants = Vec::new();
    let mut name = "";
    let mut curve = Vec::new();
    for (hi, &h_req) in s.h.iter().enumerate() {
        let k = make(R::of_f64(h_req))?;
        name = k.name();
        // (a) normalisation.
        let e = normalisation_error(&k, gl);
        norm_err = if e.is_nan() {
            f64::NAN
        } else {
            norm_err.max(e)
        };
        // (b) derivatives against central differences, and the vector API.
        derivative_errors(&k, s, &mut worst_errors);
        // (c) constants at the origin.
        constants.push(constants_at_origin(&k));
        if hi == 0 {
            curve = scaled_curve(&k, s.curve_points);
        }
    }
    Ok(Analysis {
        name,
        dim,
        precision: R::NAME,
        eps,
        norm_err,
        grad_err: worst_errors.grad.0,
        grad_err_q: worst_errors.grad.1,
        lap_err: worst_errors.lap,
        api_err: worst_errors.api,
        constants,
        curve,
    })
}

/// `|∫W dV − 1|` by Gauss–Legendre quadrature over the radial panels.
fn normalisation_error<R: Real, K: Kernel<R>>(k: &K, gl: &[(f64, f64)]) -> f64 {
    let dim = K::DIM;
    let sphere = if dim == 3 { 4.0 * PI } else { 2.0 * PI };
    let h = k.support_radius().as_f64();
    let w = |r: f64| k.value(R::of_f64(r)).as_f64();
    let mut integral = 0.0;
    for p in PANELS.windows(2) {
        let (a, b) = (p[0] * h, p[1] * h);
        for &(x, wt) in gl {
            let r = 0.5 * (a + b) + 0.5 * (b - a) * x;
            integral += 0.5 * (b - a) * wt * w(r) * sphere * r.powi(dim as i32 - 1);
        }
    }
    (integral - 1.0).abs()
}

/// dW/dr and ∇²W against central differences, and the vector API against the scalar one,
/// at `s.samples` radii in `[Q_MIN, Q_MAX]·h`; accumulates the worst errors.
fn derivative_errors<R: Real, K: Kernel<R>>(k: &K, s: &Settings, acc: &mut WorstErrors) {
    let eta = R::MACHINE_EPSILON.as_f64().cbrt();
    let dim = K::DIM;
    let h = k.support_radius().as_f64();
    for i in 0..s.samples {
        let q = Q_MIN + (Q_MAX - Q_MIN) * i as f64 / (s.samples - 1) as f64;
        let r = R::of_f64(q * h);
        let r64 = r.as_f64();
        // distance to the nearest end or kink: the difference never straddles q = ½
        let d = r64.min(h - r64).min((r64 - KINK * h).abs());
        if d < 1e-3 * h {
            continue;
        }
        let delta = eta * d;
        let (rp, rm) = (R::of_f64(r64 + delta), R::of_f64(r64 - delta));
        let step = rp.as_f64() - rm.as_f64();
        let wr = k.value(r).as_f64();
        let g = k.derivative(r).as_f64();
        let fd = (k.value(rp).as_f64() - k.value(rm).as_f64()) / step;
        let scale = g.abs() + wr.abs() / d;
        acc.grad = worst(acc.grad, (g - fd).abs() / scale, q);
        if let Some(l) = k.laplacian(r) {
            let l = l.as_f64();
            let fd2 = (k.derivative(rp).as_f64() - k.derivative(rm).as_f64()) / step
                + (dim as f64 - 1.0) / r64 * g;
            let scale = l.abs() + g.abs() / d;
            acc.lap = Some(worst(
                acc.lap.unwrap_or((0.0, 0.0)),
                (l - fd2).abs() / scale,
                q,
            ));
        }
        let e = api_error(k, r, d, wr, g);
        acc.api = if e.is_nan() { f64::NAN } else { acc.api.max(e) };
    }
}

/// Scaled error of the vector API at `r`: the gradient along a fixed direction against
/// dW/dr, and `value_r2` against `value`.
fn api_error<R: Real, K: Kernel<R>>(k: &K, r: R, d: f64, wr: f64, g: f64) -> f64 {
    let r64 = r.as_f64();
    let (gv_err, r_len) = if K::DIM == 3 {
        let n = Vec3::<R>::new(
            R::of_f64(1.0 / 3.0),
            R::of_f64(2.0 / 3.0),
            R::of_f64(2.0 / 3.0),
        );
        let x = n * r;
        let len = x.norm();
        let expect = x * (k.derivative(len) / len);
        ((k.gradient(&x) - expect).norm().as_f64(), len)
    } else {
        let n = Vec2::<R>::new(R::of_f64(0.6), R::of_f64(0.8));
        let x = n * r;
        let len = x.norm();
        let expect = x * (k.derivative(len) / len);
        ((k.gradient(&x) - expect).norm().as_f64(), len)
    };
    let gl_len = k.derivative(r_len).as_f64().abs() + k.value(r_len).as_f64().abs() / d;
    let r2_err = (k.value_r2(r * r).as_f64() - wr).abs() / (wr.abs() + g.abs() * r64);
    (gv_err / gl_len).max(r2_err)
}

/// W(0)·h^D, dW/dr(0⁺)·h^(D+1) (the limit, evaluated at r = 0) and ∇²W(0)·h^(D+2).
fn constants_at_origin<R: Real, K: Kernel<R>>(k: &K) -> Constants {
    let h = k.support_radius().as_f64();
    let hd = h.powi(K::DIM as i32);
    let zero = R::zero();
    Constants {
        w0: k.value(zero).as_f64() * hd,
        dw0: k.derivative(zero).as_f64() * hd * h,
        lap0: k.laplacian(zero).map(|l| l.as_f64() * hd * h * h),
    }
}

/// `(q, W·h^D, dW/dr·h^(D+1))` at `points` values of `q` on [0, 1].
fn scaled_curve<R: Real, K: Kernel<R>>(k: &K, points: usize) -> Vec<(f64, f64, f64)> {
    let h = k.support_radius().as_f64();
    let hd = h.powi(K::DIM as i32);
    (0..points)
        .map(|i| {
            let q = i as f64 / (points - 1) as f64;
            let r = R::of_f64(q * h);
            (
                q,
                k.value(r).as_f64() * hd,
                k.derivative(r).as_f64() * hd * h,
            )
        })
        .collect()
}

fn label(a: &Analysis) -> String {
    format!("{} ({}D)", a.name, a.dim)
}

fn write_outputs(
    ctx: &mut Context,
    analyses: &[Analysis],
    reference: &ReferenceTable,
) -> Result<()> {
    write_curves(ctx, analyses)?;
    write_errors(ctx, analyses)?;
    plot_curves(ctx, analyses, reference)
}

/// `kernel_values.csv` and `kernel_derivatives.csv`: one column per kernel and precision.
fn write_curves(ctx: &mut Context, analyses: &[Analysis]) -> Result<()> {
    let q: Vec<f64> = analyses[0].curve.iter().map(|c| c.0).collect();
    let names: Vec<String> = analyses
        .iter()
        .map(|a| format!("{}_{}", a.name, a.precision))
        .collect();
    let files = [
        (
            "kernel_values.csv",
            "W(r)·h^D against r/h, every kernel in f64 and f32 (h = 0.1)",
            (|c| c.1) as fn(&(f64, f64, f64)) -> f64,
        ),
        (
            "kernel_derivatives.csv",
            "dW/dr·h^(D+1) against r/h, every kernel in f64 and f32 (h = 0.1)",
            |c| c.2,
        ),
    ];
    for (file, what, pick) in files {
        let columns: Vec<Vec<f64>> = analyses
            .iter()
            .map(|a| a.curve.iter().map(pick).collect())
            .collect();
        let mut cols: Vec<(&str, &[f64])> = vec![("r_over_h", &q)];
        cols.extend(
            names
                .iter()
                .map(String::as_str)
                .zip(columns.iter().map(Vec::as_slice)),
        );
        write_csv_columns(&ctx.path(file), &cols)?;
        ctx.add_file(file, what);
    }
    Ok(())
}

fn write_errors(ctx: &mut Context, analyses: &[Analysis]) -> Result<()> {
    write_csv_rows(
        &ctx.path("kernel_errors.csv"),
        &[
            "kernel",
            "dim",
            "precision",
            "normalisation_error",
            "gradient_fd_error",
            "laplacian_fd_error",
            "api_error",
            "W0_scaled",
        ],
        analyses.iter().map(|a| {
            vec![
                a.name.to_string(),
                a.dim.to_string(),
                a.precision.to_string(),
                format!("{:e}", a.norm_err),
                format!("{:e}", a.grad_err),
                a.lap_err.map_or("".into(), |l| format!("{:e}", l.0)),
                format!("{:e}", a.api_err),
                format!("{}", a.constants[0].w0),
            ]
        }),
    )?;
    ctx.add_file(
        "kernel_errors.csv",
        "per kernel and precision: the measured errors of the checks",
    );
    Ok(())
}

/// Plots of the f64 curves with the reference constants as markers at r = 0.
fn plot_curves(ctx: &mut Context, analyses: &[Analysis], reference: &ReferenceTable) -> Result<()> {
    let f64s: Vec<&Analysis> = analyses.iter().filter(|a| a.precision == "f64").collect();
    let (mut values_plot, mut deriv_plot) = curve_specs(&f64s);
    for (i, a) in f64s.iter().enumerate() {
        for (quantity, plot) in [("W0", &mut values_plot), ("dW0", &mut deriv_plot)] {
            if let Ok(row) = reference.find(&[
                ("kernel", a.name),
                ("dim", &a.dim.to_string()),
                ("quantity", quantity),
            ]) {
                let sigma = reference.number(row, "sigma")?;
                let formula = reference.text(row, "formula").unwrap_or("");
                plot.series.push(Series::markers(
                    format!("{} reference {formula}", a.name),
                    vec![(0.0, sigma)],
                    Marker::Ring,
                    i,
                ));
            }
        }
    }
    plot_xy(&ctx.path("kernel_values.png"), &values_plot)?;
    ctx.add_plot(
        "kernel_values.png",
        "W(r)·h^D against r/h for every kernel (lines, f64; dashed: 2D kernels) with the closed-form \
         W(0)·h^D of reference-data/kernels/normalisation_constants.csv as rings at r = 0",
    );
    plot_xy(&ctx.path("kernel_derivatives.png"), &deriv_plot)?;
    ctx.add_plot(
        "kernel_derivatives.png",
        "dW/dr·h^(D+1) against r/h for every kernel (f64; dashed: 2D kernels); ring: Müller et al.'s \
         spiky gradient constant −45/π at r = 0⁺",
    );
    Ok(())
}

/// The value and derivative plots with one curve per kernel (dashed: 2D kernels).
fn curve_specs(f64s: &[&Analysis]) -> (PlotSpec, PlotSpec) {
    let mut values_plot = PlotSpec::new(
        "SPH kernels: W(r)·h^D (f64), reference W(0)·h^D at r = 0",
        "r / h  (dimensionless)",
        "W · h^D  (dimensionless; W in 1/length^D)",
    );
    values_plot.y_range = Some((-0.25, 5.25));
    values_plot.x_range = Some((-0.03, 1.03));
    let mut deriv_plot = PlotSpec::new(
        "SPH kernels: dW/dr·h^(D+1) (f64), reference dW/dr(0⁺)·h^(D+1) at r = 0",
        "r / h  (dimensionless)",
        "dW/dr · h^(D+1)  (dimensionless; dW/dr in 1/length^(D+1))",
    );
    deriv_plot.y_range = Some((-15.5, 1.0));
    deriv_plot.x_range = Some((-0.03, 1.03));
    deriv_plot.legend = Legend::LowerRight;
    for (i, a) in f64s.iter().enumerate() {
        let style = if a.dim == 2 {
            crate::helpers::SeriesStyle::Dashed
        } else {
            crate::helpers::SeriesStyle::Line
        };
        values_plot.series.push(Series::styled(
            label(a),
            a.curve.iter().map(|c| (c.0, c.1)).collect(),
            style,
            i,
        ));
        deriv_plot.series.push(Series::styled(
            label(a),
            a.curve.iter().map(|c| (c.0, c.2)).collect(),
            style,
            i,
        ));
    }
    (values_plot, deriv_plot)
}
