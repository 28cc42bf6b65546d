//! The ensembles of `granular-repose`: each case's pours (seeds 1, 2, …) summarised by their
//! mean and standard error, the mean and each flank's mean checked against the prediction,
//! the modulus and spacing independences judged by two-sample tests (statistics in
//! [`crate::helpers::stats`]).
//!
//! **Bands.** Full mode: ±[`BAND_FULL_DEG`] on the mean of [`POURS_FULL`](super::plan::POURS_FULL)
//! pours. Quick mode: `t_{0.975, ν} × SE + `[`MEASURE_RESOLUTION_QUICK_DEG`], the mean's
//! two-sided 95 % band from the pour-to-pour scatter plus the measure's own resolution at 20 mm
//! (a systematic error the mean does not average away). The scatter is pooled over the cases
//! run at one spacing (one pour-to-pour variance for one model at one spacing: the avalanches
//! that build a heap branch on small differences whatever the case; each case's own standard
//! deviation is reported beside it), so that `ν = Σ (n − 1)` is large enough for the band to
//! mean something with few pours per case. Each check states its power: the offset it catches
//! with probability 80 %, `band + 0.84 SE`.
//!
//! **Two-sample tests.** The modulus check (10 E against E, both at 20 mm) compares the two
//! ensembles' means with the pooled scatter of their spacing, `SE_d = s_p √(1/n₁ + 1/n₂)`; the
//! spacing check (full mode: 10 mm against 20 mm) with Welch's `SE_d = √(s₁²/n₁ + s₂²/n₂)` and
//! Welch–Satterthwaite's degrees of freedom (two spacings need not share a variance). Either
//! passes when `|d| ≤ t_{0.975, ν} SE_d` (no difference at the 5 % level) and states the
//! difference it would catch with probability 80 %, `(t_{0.975, ν} + 0.84) SE_d`.

use elastoplastic_granular::ConeMatch;

use super::plan::{case_of, Plan, COARSE_TAG, PLAIN_30_TAG, STIFF_TAG};
use crate::helpers::repose::{HeapRun, Measured};
use crate::helpers::stats::{mean, pooled_sd, sample_sd, shift_caught_80, t_quantile, Z_80};
use crate::{Check, Mode, Outcome};

/// Band on the full-mode mean (degrees): the band a full-mode ensemble of eight pours is
/// held to.
pub const BAND_FULL_DEG: f64 = 1.0;
/// The measure's resolution at 20 mm (degrees): its error on lattice heaps of known slope
/// (≤ 0.8°, `granular-measure/tests/measure.rs`), added to quick mode's statistical band.
pub const MEASURE_RESOLUTION_QUICK_DEG: f64 = 0.8;

/// One case's pours that could be measured.
#[derive(Debug, Clone)]
pub struct CaseEnsemble {
    /// The case (a run's tag without `/pour=K`).
    pub case: String,
    /// The friction angle (degrees).
    pub theta_deg: f64,
    /// The cone's match.
    pub cone: ConeMatch,
    /// The particle spacing (m): the pooling key.
    pub spacing_m: f64,
    /// Each measured pour.
    pub pours: Vec<Measured>,
}

impl CaseEnsemble {
    /// The angles (mean of both flanks) of the pours.
    pub fn angles(&self) -> Vec<f64> {
        self.pours.iter().map(|m| m.angle_deg).collect()
    }
    /// One flank's angles (0: facing −x, 1: facing +x).
    pub fn flank(&self, side: usize) -> Vec<f64> {
        self.pours.iter().map(|m| m.flank_deg[side]).collect()
    }
    /// The ensemble's mean heap, for the order check and the plot.
    pub fn mean_heap(&self) -> Measured {
        let field = |f: fn(&Measured) -> f64| mean(&self.pours.iter().map(f).collect::<Vec<_>>());
        Measured {
            angle_deg: field(|m| m.angle_deg),
            steepest_deg: field(|m| m.steepest_deg),
            flank_difference_deg: field(|m| m.flank_difference_deg),
            flank_deg: [field(|m| m.flank_deg[0]), field(|m| m.flank_deg[1])],
            height_m: field(|m| m.height_m),
        }
    }
}

/// Groups the measured pours `measured` (plan, run, measure) by case, in plan order.
pub fn group(measured: &[(&Plan, &HeapRun, Measured)]) -> Vec<CaseEnsemble> {
    let mut cases: Vec<CaseEnsemble> = Vec::new();
    for (p, run, m) in measured {
        let case = case_of(&p.tag);
        match cases.iter_mut().find(|c| c.case == case) {
            Some(c) => c.pours.push(*m),
            None => cases.push(CaseEnsemble {
                case: case.to_string(),
                theta_deg: p.theta_deg,
                cone: p.cone,
                spacing_m: run.scene.particle_spacing,
                pours: vec![*m],
            }),
        }
    }
    cases
}

/// The pooled standard deviation (and its degrees of freedom) of `values` of the cases at
/// `spacing_m`.
fn pooled_at(
    cases: &[CaseEnsemble],
    spacing_m: f64,
    values: impl Fn(&CaseEnsemble) -> Vec<Vec<f64>>,
) -> (f64, usize) {
    let groups: Vec<Vec<f64>> = cases
        .iter()
        .filter(|c| c.spacing_m == spacing_m)
        .flat_map(values)
        .collect();
    pooled_sd(groups.iter().map(Vec::as_slice))
}

/// The band of a mean of `n` pours with pooled scatter `(sd, dof)` in `mode` and its
/// standard error.
fn band(mode: Mode, (sd, dof): (f64, usize), n: usize) -> (f64, f64) {
    let se = sd / (n as f64).sqrt();
    let band = match mode {
        Mode::Quick => t_quantile(0.975, dof) * se + MEASURE_RESOLUTION_QUICK_DEG,
        Mode::Full => BAND_FULL_DEG,
    };
    (band, se)
}

/// Checks one mean of `values` (a case's angle or one flank's) against `predicted`.
fn check_mean(
    out: &mut Outcome,
    mode: Mode,
    name: String,
    values: &[f64],
    scatter: (f64, usize),
    predicted: f64,
    what: &str,
) {
    let n = values.iter().filter(|x| x.is_finite()).count();
    let m = mean(values);
    let (b, se) = band(mode, scatter, n);
    out.metric(format!("{name}/mean_deg"), m);
    out.metric(format!("{name}/standard_error_deg"), se);
    out.metric(format!("{name}/own_sd_deg"), sample_sd(values));
    out.metric(format!("{name}/pours"), n as f64);
    let origin = match mode {
        Mode::Quick => format!(
            "physics: a flank formed by flowing at zero dilatancy comes to rest at tan(beta) = 3 alpha_phi (docs/elastoplastic-granular.md); band = t(0.975, {}) x SE {se:.2}° (pooled pour-to-pour s = {:.2}° over the cases at this spacing, {n} pours) + the measure's resolution {MEASURE_RESOLUTION_QUICK_DEG}° at 20 mm (granular-measure/tests/measure.rs); power: catches an offset of {:.2}° with 80 %",
            scatter.1, scatter.0, shift_caught_80(b, se)
        ),
        Mode::Full => format!(
            "physics: tan(beta) = 3 alpha_phi (docs/elastoplastic-granular.md); band ±{BAND_FULL_DEG}° on the mean of {n} pours (SE {se:.2}°, pooled s = {:.2}°); power: catches an offset of {:.2}° with 80 %",
            scatter.0, shift_caught_80(b, se)
        ),
    };
    out.check(Check::within(
        format!("{name}/{what} (deg), mean of {n} pours, against {predicted:.2}"),
        m,
        predicted - b,
        predicted + b,
        origin,
    ));
}

/// Each case's mean angle and each flank's mean against the case's prediction.
pub fn check_cases(out: &mut Outcome, mode: Mode, cases: &[CaseEnsemble]) {
    for c in cases {
        let predicted = c.cone.predicted_repose_angle_deg(c.theta_deg);
        out.metric(format!("{}/predicted_deg", c.case), predicted);
        let angle_scatter = pooled_at(cases, c.spacing_m, |k| vec![k.angles()]);
        check_mean(
            out,
            mode,
            c.case.clone(),
            &c.angles(),
            angle_scatter,
            predicted,
            "angle of repose",
        );
        let flank_scatter = pooled_at(cases, c.spacing_m, |k| vec![k.flank(0), k.flank(1)]);
        for (side, name) in [(0, "left flank"), (1, "right flank")] {
            let tag = format!("{}/{}", c.case, name.replace(' ', "_"));
            check_mean(
                out,
                mode,
                tag,
                &c.flank(side),
                flank_scatter,
                predicted,
                name,
            );
        }
    }
}

/// A two-sample test of the means of `a` and `b`: `Some((d, SE_d, dof))`, with the pooled
/// scatter `pooled` when given and Welch's otherwise; `None` with fewer than two pours on
/// either side.
fn two_sample(a: &[f64], b: &[f64], pooled: Option<(f64, usize)>) -> Option<(f64, f64, f64)> {
    let (na, nb) = (a.len() as f64, b.len() as f64);
    if na < 2.0 || nb < 2.0 {
        return None;
    }
    let d = mean(a) - mean(b);
    Some(match pooled {
        Some((sd, dof)) => (d, sd * (1.0 / na + 1.0 / nb).sqrt(), dof as f64),
        None => {
            let (va, vb) = (sample_sd(a).powi(2) / na, sample_sd(b).powi(2) / nb);
            let dof = (va + vb).powi(2) / (va * va / (na - 1.0) + vb * vb / (nb - 1.0));
            (d, (va + vb).sqrt(), dof)
        }
    })
}

/// Checks that `a` and `b` do not differ at the 5 % level (`what`: the independence).
fn check_same(
    out: &mut Outcome,
    name: &str,
    a: &CaseEnsemble,
    b: &CaseEnsemble,
    pooled: Option<(f64, usize)>,
    what: &str,
) {
    let Some((d, se, dof)) = two_sample(&a.angles(), &b.angles(), pooled) else {
        out.check(Check::equals(
            format!("{name}: two pours or more on each side"),
            0.0,
            1.0,
            "a two-sample test needs two measured pours on each side",
        ));
        return;
    };
    // Student's t with a fractional dof (Welch): the quantile of the next lower integer, the
    // conservative side.
    let t = t_quantile(0.975, dof.floor().max(1.0) as usize);
    out.metric(format!("{name}/difference_deg"), d);
    out.metric(format!("{name}/difference_se_deg"), se);
    out.check(Check::at_most(
        format!("{name}: |mean({}) - mean({})| (deg), two-sample test at 5 %", a.case, b.case),
        d.abs(),
        t * se,
        format!(
            "{what}: no difference at the 5 % level, |d| <= t(0.975, {dof:.1}) x SE_d {se:.2}° ({} test, {} and {} pours); power: catches a difference of {:.2}° with 80 %",
            if pooled.is_some() { "pooled-variance" } else { "Welch" },
            a.pours.len(),
            b.pours.len(),
            (t + Z_80) * se
        ),
    ));
}

/// The modulus check (both modes) and the spacing check (full mode) on the ensembles.
pub fn check_pairs(out: &mut Outcome, mode: Mode, cases: &[CaseEnsemble]) {
    let find = |case: &str| cases.iter().find(|c| c.case == case);
    let coarse = match mode {
        Mode::Quick => find(PLAIN_30_TAG),
        Mode::Full => find(COARSE_TAG),
    };
    if let (Some(stiff), Some(coarse)) = (find(STIFF_TAG), coarse) {
        let pooled = pooled_at(cases, coarse.spacing_m, |k| vec![k.angles()]);
        check_same(out, "simple-shear/theta=30/modulus", stiff, coarse, Some(pooled), "a heap of a rigid-enough material does not depend on its stiffness (10 E against E, the viscosity's velocity scale held at the sound speed of E)");
    }
    if let (Mode::Full, Some(fine), Some(coarse)) = (mode, find(PLAIN_30_TAG), coarse) {
        check_same(out, "simple-shear/theta=30/spacing", fine, coarse, None, "a result converged in the spacing does not move when the spacing halves (10 mm against 20 mm)");
    }
}
