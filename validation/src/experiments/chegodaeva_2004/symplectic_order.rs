//! `symplectic-order`: error against step for the maps of Chegodaeva (2004) on a fixed span.
//!
//! (a) **Planets** (Hairer, Lubich & Wanner's outer Solar System, equatorial frame), 10 kyr:
//!     the largest relative energy error over the run and the largest heliocentric position
//!     error at 10 kyr against the IAS15 reference (`reference-data/symplectic-order/ias15_10kyr.csv`,
//!     REBOUND 5.2.2, accurate to 5e-11 AU), for S2 (eq. 13) and S6 (eq. 7) at steps
//!     τ = 730.5 … 45.66 d. Expected: S2 ∝ τ² (error `O(ε τ²)`); S6 `ε² τ² (13 − 5√5)/288 + O(ε τ⁶)`,
//!     i.e. about `ε ≈ 10⁻³` times S2's error at the same τ. The bounds, derived from these
//!     estimates (see `S6_OVER_S2_BOUND` and `wisdom_holman_estimate` below), are checked at the
//!     paper's step and, for the `ε` scaling, with the planet masses divided by 4.
//! (b) **Particle 1** (a = 60.91 AU, barycentric variant, B₀ = 0, B₁ = 0.21·10⁻⁶), 2 kyr, the
//!     planets fixed (S6, τ = 36.525 d): the largest |ΔH| = |H + p₄|/|H| against the initial
//!     step, S2 and S6 (eq. 27 and eq. 7 on the logarithmic Hamiltonian).

use anyhow::{bail, Result};
use symplectic::solar_system::{GIANT_PLANETS, SUN_MASS_WITH_INNER_PLANETS};
use symplectic::{
    kepler, outer_solar_system, CometRun, Ephemeris, Frame, Integrator, Limits, ParticleIntegrator,
    ParticleScratch, Planets, Scheme, Variant, Vec3, G_AU3_PER_MSUN_DAY2,
};

use crate::helpers::solar_system::{particles, to_barycentric, DAYS_PER_YEAR};
use crate::helpers::{
    load_reference_csv, plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle,
};
use crate::{Check, Context, Experiment, Outcome};

/// The experiment.
pub struct SymplecticOrder;

const PLANET_SPAN_DAY: f64 = 10_000.0 * DAYS_PER_YEAR;
const PLANET_STEPS_DAY: [f64; 5] = [730.5, 365.25, 182.625, 91.3125, 45.656_25];
const PARTICLE_SPAN_DAY: f64 = 2_000.0 * DAYS_PER_YEAR;
const PARTICLE_DT0_DAY: [f64; 5] = [1200.0, 600.0, 300.0, 150.0, 75.0];
const B1: f64 = 0.21e-6;
/// Step of the `ε`-scaling runs: in the regime where eq. 7's `ε²τ²` term leads S6's error
/// (S6's slope is 2 from 45.7 to 182.6 d; the `ετ⁶` term takes over above).
const SCALING_STEP_DAY: f64 = 91.3125;
/// Planet masses divided by this in the `ε`-scaling runs.
const MASS_DIVISOR: f64 = 4.0;

/// Bound on S6's error over S2's at the same step, as a multiple of `ε = Σ m_i / m₀`.
///
/// Eq. 7 (Laskar & Robutel 2001): S6 integrates `H + ε² τ² (13 − 5√5)/288 {{A,B},B} + O(ε τ⁶)`;
/// the Strang splitting S2 (eq. 13) integrates `H + ε τ²/12 {A,{A,B}} + O(ε² τ², ε τ⁴)`
/// (Baker–Campbell–Hausdorff; Yoshida 1990). For the same orbits both double brackets scale as
/// `G² m m₀²/r⁴` (`ε{A,{A,B}} ~ ω² εB` and `ε²{{A,B},B} ~ |ε∇B|²/m`), so their ratio `K` is
/// of order one and S6/S2 `≈ 12 (13 − 5√5)/288 · K · ε = 0.076 K ε`. The bound `ε` leaves
/// `K` up to 13, plus the `ε τ⁶` remainder at the paper's step.
const S6_OVER_S2_BOUND: f64 = 1.0;

/// `ε = Σ m_i / m₀` of the outer Solar System (1.34·10⁻³).
fn epsilon() -> f64 {
    GIANT_PLANETS.iter().map(|p| p.mass_msun).sum::<f64>() / SUN_MASS_WITH_INNER_PLANETS
}

/// The Wisdom–Holman estimate of S2's relative energy error at step `tau` (days): the map
/// integrates `H + ε τ²/12 {A,{A,B}}` (Wisdom & Holman 1991, the mapping Hamiltonian; the
/// coefficient from the Baker–Campbell–Hausdorff formula), whose size relative to `H` is
/// `ε_J (Ω_J τ)²/12` for the dominant planet (`ε_J = m_J/m₀`, `Ω_J` Jupiter's mean motion,
/// from its osculating semi-major axis). `max |ΔE/E|` over a run is at most twice that
/// amplitude (`H` swings on both sides of the conserved modified Hamiltonian).
pub(crate) fn wisdom_holman_estimate(planets: &Planets, tau: f64) -> Result<f64> {
    let m0 = planets.sun_mass();
    let m_j = planets.masses()[0];
    let mu = planets.g() * (m0 + m_j);
    let el = kepler::elements(
        &planets.positions()[0],
        &planets.heliocentric_velocities()[0],
        mu,
    )?;
    let omega = (mu / el.semi_major_axis.powi(3)).sqrt();
    Ok(m_j / m0 * (omega * tau).powi(2) / 12.0)
}

/// The outer Solar System (equatorial) with the planet masses divided by `divisor`.
fn scaled_planets(divisor: f64) -> Result<Planets> {
    let m: Vec<f64> = GIANT_PLANETS
        .iter()
        .map(|p| p.mass_msun / divisor)
        .collect();
    let q: Vec<Vec3> = GIANT_PLANETS.iter().map(|p| p.position_au.into()).collect();
    let v: Vec<Vec3> = GIANT_PLANETS
        .iter()
        .map(|p| p.velocity_au_per_day.into())
        .collect();
    Ok(Planets::from_heliocentric(
        G_AU3_PER_MSUN_DAY2,
        SUN_MASS_WITH_INNER_PLANETS,
        &m,
        &q,
        &v,
    )?)
}

/// Least-squares slope of log y against log x.
fn log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

fn ias15_positions(ctx: &Context, t_day: f64) -> Result<Vec<Vec3>> {
    let t = load_reference_csv(
        ctx,
        "symplectic-order/ias15_10kyr.csv",
        &["body", "t_day", "x_au", "y_au", "z_au"],
    )?;
    let mut out = Vec::new();
    for body in ["Jupiter", "Saturn", "Uranus", "Neptune"] {
        let rows: Vec<usize> = t
            .find_all(&[("body", body)])?
            .into_iter()
            .filter(|&r| t.number(r, "t_day").is_ok_and(|x| (x - t_day).abs() < 1e-6))
            .collect();
        let [r] = rows[..] else {
            bail!(
                "{}: expected one row for {body} at t = {t_day} d, found {}",
                t.path.display(),
                rows.len()
            );
        };
        out.push(Vec3::new(
            t.number(r, "x_au")?,
            t.number(r, "y_au")?,
            t.number(r, "z_au")?,
        ));
    }
    Ok(out)
}

/// Largest relative energy error over the run and the final positions.
fn planet_run(start: &Planets, integrator: Integrator) -> Result<(f64, Vec<Vec3>)> {
    let mut p = start.clone();
    let e0 = p.energy();
    let steps = (PLANET_SPAN_DAY / integrator.step_size()).round() as u64;
    let mut worst = 0.0f64;
    for _ in 0..steps {
        integrator.run(&mut p, 1)?;
        worst = worst.max(((p.energy() - e0) / e0).abs());
    }
    Ok((worst, p.positions().to_vec()))
}

fn particle_run(ctx: &Context, scheme: Scheme, dt0: f64) -> Result<f64> {
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let mut eph = Ephemeris::new(planets.clone(), Integrator::S6 { step: 36.525 })?;
    let pi = ParticleIntegrator::new(Variant::Barycentric, scheme, 0.0, B1)?;
    let p = &particles(ctx)?[0];
    let (q, v) = to_barycentric(&planets, p.position, p.velocity);
    let mut scratch = ParticleScratch::default();
    let particle = pi.particle(q, v, 0.0, dt0, &mut eph, &mut scratch)?;
    let mut run = CometRun::new(
        eph,
        pi,
        vec![particle],
        Limits {
            min_perihelion: 26.0,
            ejection_distance: 1e3,
        },
    );
    let mut worst = 0.0f64;
    run.advance_to(PARTICLE_SPAN_DAY, |_, _, info| {
        worst = worst.max(info.relative_error.abs())
    })?;
    Ok(worst)
}

/// Error against step, `[S2, S6]`, each a list of `(step_day, error)`.
type ErrorCurves = [Vec<(f64, f64)>; 2];

/// What the experiment measures.
struct Measured {
    /// Rows of `order.csv`.
    rows: Vec<Vec<String>>,
    /// Planets: largest relative energy error against step.
    energy: ErrorCurves,
    /// Planets: largest position error against IAS15 against step.
    position: ErrorCurves,
    /// Planets with the masses divided by `MASS_DIVISOR`: energy error at `SCALING_STEP_DAY`.
    light_energy: [f64; 2],
    /// Particle 1: largest |ΔH| against initial step.
    particle: ErrorCurves,
}

/// Runs the planets, S2 and S6, at each step of `PLANET_STEPS_DAY`, against IAS15.
fn measure_planets(ctx: &Context, start: &Planets, m: &mut Measured) -> Result<()> {
    let reference = ias15_positions(ctx, PLANET_SPAN_DAY)?;
    for (k, make) in [
        (|s| Integrator::S2 { step: s }) as fn(f64) -> Integrator,
        |s| Integrator::S6 { step: s },
    ]
    .iter()
    .enumerate()
    {
        for &tau in &PLANET_STEPS_DAY {
            let integ = make(tau);
            let (e, pos) = planet_run(start, integ)?;
            let dx = pos
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            m.energy[k].push((tau, e));
            m.position[k].push((tau, dx));
            m.rows.push(vec![
                integ.name().to_string(),
                "planets".into(),
                format!("{tau}"),
                format!("{e:e}"),
                format!("{dx:e}"),
            ]);
            ctx.progress.inc(1);
        }
    }
    Ok(())
}

/// ε scaling: the planet masses divided by `MASS_DIVISOR`, S2 and S6 at `SCALING_STEP_DAY`.
fn measure_scaling(ctx: &Context, m: &mut Measured) -> Result<()> {
    let light = scaled_planets(MASS_DIVISOR)?;
    for (k, integ) in [
        Integrator::S2 {
            step: SCALING_STEP_DAY,
        },
        Integrator::S6 {
            step: SCALING_STEP_DAY,
        },
    ]
    .into_iter()
    .enumerate()
    {
        let (e, _) = planet_run(&light, integ)?;
        m.light_energy[k] = e;
        m.rows.push(vec![
            integ.name().to_string(),
            format!("planets, masses / {MASS_DIVISOR}"),
            format!("{SCALING_STEP_DAY}"),
            format!("{e:e}"),
            String::new(),
        ]);
        ctx.progress.inc(1);
    }
    Ok(())
}

/// Particle 1, S2 and S6, at each initial step of `PARTICLE_DT0_DAY`.
fn measure_particle(ctx: &Context, m: &mut Measured) -> Result<()> {
    for (k, scheme) in [Scheme::S2, Scheme::S6].into_iter().enumerate() {
        for &dt0 in &PARTICLE_DT0_DAY {
            let e = particle_run(ctx, scheme, dt0)?;
            m.particle[k].push((dt0, e));
            m.rows.push(vec![
                format!("{scheme:?}"),
                "particle1".into(),
                format!("{dt0}"),
                format!("{e:e}"),
                String::new(),
            ]);
            ctx.progress.inc(1);
        }
    }
    Ok(())
}

fn write_order_csv(ctx: &mut Context, rows: &[Vec<String>]) -> Result<()> {
    write_csv_rows(
        &ctx.path("order.csv"),
        &[
            "map",
            "system",
            "step_day",
            "max_rel_energy_error",
            "max_position_error_vs_ias15_au",
        ],
        rows.iter().cloned(),
    )?;
    ctx.add_file("order.csv", "errors against step");
    Ok(())
}

const NAMES: [&str; 2] = ["S2", "S6"];

/// A log-log plot of `curves` (S2, S6) with the lower-right legend, before its references.
fn order_spec(
    title: &str,
    x: &str,
    y: &str,
    curves: &ErrorCurves,
    label: impl Fn(usize) -> String,
) -> PlotSpec {
    let mut spec = PlotSpec::new(title, x, y).log_log();
    spec.legend = Legend::LowerRight;
    for k in 0..2 {
        spec.series.push(Series::styled(
            label(k),
            curves[k].clone(),
            SeriesStyle::LineMarkers([Marker::Circle, Marker::Triangle][k]),
            k,
        ));
    }
    spec
}

/// Planets' energy error against step, with the Wisdom–Holman estimate and eq. 7's bound.
fn plot_planets_energy(ctx: &mut Context, start: &Planets, energy: &ErrorCurves) -> Result<()> {
    let eps = epsilon();
    let wh: Vec<(f64, f64)> = PLANET_STEPS_DAY
        .iter()
        .map(|&t| Ok((t, 2.0 * wisdom_holman_estimate(start, t)?)))
        .collect::<Result<_>>()?;
    let mut spec = order_spec(
        "Planets, 10 kyr: energy error against step",
        "step τ (days)",
        "max |ΔE/E| over the run (relative)",
        energy,
        |k| format!("{} (eq. {})", NAMES[k], [13, 7][k]),
    );
    spec.series.push(Series::styled(
        "S2 bound: Wisdom–Holman 2·ε_J(Ω_J τ)²/12",
        wh,
        SeriesStyle::Dashed,
        0,
    ));
    spec.series.push(Series::styled(
        format!("S6 bound: ε × S2 (eq. 7, ε = {eps:.2e})"),
        energy[0].iter().map(|&(t, e)| (t, eps * e)).collect(),
        SeriesStyle::Dashed,
        1,
    ));
    plot_xy(&ctx.path("planets_energy_order.png"), &spec)?;
    ctx.add_plot(
        "planets_energy_order.png",
        "Planets over 10 kyr: largest relative energy error against step, with the Wisdom–Holman estimate for S2 and eq. 7's bound for S6",
    );
    Ok(())
}

/// Planets' position error against IAS15 against step, with τ² and eq. 7's bound.
fn plot_planets_position(ctx: &mut Context, position: &ErrorCurves) -> Result<()> {
    let eps = epsilon();
    let mut spec = order_spec(
        "Planets at 10 kyr: position error against IAS15",
        "step τ (days)",
        "largest heliocentric position error (AU)",
        position,
        |k| format!("{} vs IAS15", NAMES[k]),
    );
    let (t0, p0) = position[0][1];
    spec.series.push(Series::styled(
        "τ² through S2 at 365.25 d (eq. 13)",
        PLANET_STEPS_DAY
            .iter()
            .map(|&t| (t, p0 * (t / t0).powi(2)))
            .collect(),
        SeriesStyle::Dashed,
        7,
    ));
    spec.series.push(Series::styled(
        "ε × S2 (eq. 7 bound for S6)",
        position[0].iter().map(|&(t, e)| (t, eps * e)).collect(),
        SeriesStyle::Dashed,
        1,
    ));
    plot_xy(&ctx.path("planets_position_order.png"), &spec)?;
    ctx.add_plot(
        "planets_position_order.png",
        "Planets at 10 kyr: position error against the IAS15 reference (accurate to 5e-11 AU) against step",
    );
    Ok(())
}

/// Particle 1's |ΔH| against initial step, with τ².
fn plot_particle(ctx: &mut Context, particle: &ErrorCurves) -> Result<()> {
    let mut spec = order_spec(
        "Particle 1, 2 kyr: extended-Hamiltonian error against initial step",
        "initial step (days)",
        "max |H + p4|/|H| (relative)",
        particle,
        |k| NAMES[k].to_string(),
    );
    let (d0, q0) = particle[0][0];
    spec.series.push(Series::styled(
        "τ² through S2's first point (eq. 27)",
        PARTICLE_DT0_DAY
            .iter()
            .map(|&t| (t, q0 * (t / d0).powi(2)))
            .collect(),
        SeriesStyle::Dashed,
        7,
    ));
    plot_xy(&ctx.path("particle_order.png"), &spec)?;
    ctx.add_plot(
        "particle_order.png",
        "Particle 1: |ΔH| against the initial step",
    );
    Ok(())
}

/// The error at step `tau` of a curve (NaN if not measured).
fn at(v: &[(f64, f64)], tau: f64) -> f64 {
    v.iter().find(|(t, _)| *t == tau).map_or(f64::NAN, |x| x.1)
}

/// Slopes (order) metrics; the S2 planets' slope checks.
fn check_slopes(out: &mut Outcome, m: &Measured) {
    let s2_energy_slope = log_slope(&m.energy[0]);
    // The position error is a phase error; at τ = 730.5 d (1/6 of Jupiter's period) it
    // is several AU, no longer small against the orbit (outside the asymptotic regime),
    // so the position slope is fitted over τ <= 365.25 d (the paper's step and below).
    let asymptotic: Vec<(f64, f64)> = m.position[0]
        .iter()
        .copied()
        .filter(|(t, _)| *t <= 365.25)
        .collect();
    let s2_position_slope = log_slope(&asymptotic);
    out.metric("S2_planets_energy_slope", s2_energy_slope);
    out.metric("S2_planets_position_slope", s2_position_slope);
    out.metric("S6_planets_energy_slope", log_slope(&m.energy[1]));
    out.metric("S2_particle_slope", log_slope(&m.particle[0]));
    out.metric("S6_particle_slope", log_slope(&m.particle[1]));
    out.metric("epsilon_planets_over_sun", epsilon());
    // Origin: eq. 13 is second order; ±0.2 on a fit over a factor 16 in τ allows the
    // higher-order terms still visible at the largest step.
    out.check(Check::within(
        "S2 planets: slope of energy error vs τ",
        s2_energy_slope,
        1.8,
        2.2,
        "eq. 13: O(ε τ²)",
    ));
    out.check(Check::within(
        "S2 planets: slope of position error vs IAS15 (τ <= 365.25 d)",
        s2_position_slope,
        1.8,
        2.2,
        "eq. 13: O(ε τ²) phase error",
    ));
}

/// S2 against the Wisdom–Holman estimate, and S6 against S2 at the paper's step.
fn check_365(out: &mut Outcome, start: &Planets, m: &Measured) -> Result<()> {
    let eps = epsilon();
    let at_365 = |v: &[(f64, f64)]| at(v, 365.25);
    let energy_ratio_365 = at_365(&m.energy[1]) / at_365(&m.energy[0]);
    // S2 against the Wisdom–Holman estimate at the paper's step.
    let wh_365 = wisdom_holman_estimate(start, 365.25)?;
    out.metric("S2_wisdom_holman_estimate_365d", wh_365);
    out.metric(
        "S2_energy_error_365d_over_estimate",
        at_365(&m.energy[0]) / wh_365,
    );
    out.check(Check::within(
        format!(
            "S2 max |ΔE/E| at τ = 365.25 d / Wisdom–Holman estimate ε_J(Ω_J τ)²/12 = {wh_365:.2e}"
        ),
        at_365(&m.energy[0]) / wh_365,
        0.25,
        2.0,
        "Wisdom & Holman 1991 mapping Hamiltonian, BCH coefficient 1/12: the error swings by at most twice the amplitude (upper bound 2); the bracket's geometric factor is of order one, not computed (lower bound 1/4)",
    ));
    // S6 against S2: eq. 7's ε²τ² against S2's ετ².
    out.check(Check::less_than(
        format!("S6 / S2 energy error at τ = 365.25 d, in units of ε = {eps:.3e}"),
        energy_ratio_365 / eps,
        S6_OVER_S2_BOUND,
        "eq. 7: S6's ε²τ²(13 − 5√5)/288 against S2's ετ²/12 gives 0.076·K·ε (K ~ 1, the ratio of the double brackets), plus O(ετ⁶)",
    ));
    Ok(())
}

/// The errors at 365.25 d and their S6/S2 ratios (metrics); returns (energy, position) ratio.
fn metrics_365(out: &mut Outcome, m: &Measured) -> (f64, f64) {
    let at_365 = |v: &[(f64, f64)]| at(v, 365.25);
    out.metric("S2_position_error_365d_au", at_365(&m.position[0]));
    out.metric("S6_position_error_365d_au", at_365(&m.position[1]));
    out.metric("S2_energy_error_365d", at_365(&m.energy[0]));
    out.metric("S6_energy_error_365d", at_365(&m.energy[1]));
    let energy_ratio_365 = at_365(&m.energy[1]) / at_365(&m.energy[0]);
    let position_ratio_365 = at_365(&m.position[1]) / at_365(&m.position[0]);
    out.metric("S6_over_S2_energy_365d", energy_ratio_365);
    out.metric("S6_over_S2_position_365d", position_ratio_365);
    (energy_ratio_365, position_ratio_365)
}

/// S6 against S2 at `SCALING_STEP_DAY`, and the ε scaling of their ratio; the particle's
/// order; the notes.
fn check_scaling(out: &mut Outcome, m: &Measured, ratios_365: (f64, f64)) {
    let eps = epsilon();
    let (energy_ratio_365, position_ratio_365) = ratios_365;
    let position_ratio_scaling =
        at(&m.position[1], SCALING_STEP_DAY) / at(&m.position[0], SCALING_STEP_DAY);
    out.metric("S6_over_S2_position_91d", position_ratio_scaling);
    out.check(Check::less_than(
        format!("S6 / S2 position error vs IAS15 at τ = {SCALING_STEP_DAY} d, in units of ε"),
        position_ratio_scaling / eps,
        S6_OVER_S2_BOUND,
        "eq. 7 as above, where its ε²τ² term leads (S6 slope 2 below 183 d); at 365.25 d the O(ετ⁶) term, which eq. 7 does not give, adds to it (reported as a metric)",
    ));
    // The ε dependence itself: S6/S2 ∝ ε, so dividing the masses by 4 divides the ratio by 4.
    let nominal = at(&m.energy[1], SCALING_STEP_DAY) / at(&m.energy[0], SCALING_STEP_DAY);
    let light_ratio = m.light_energy[1] / m.light_energy[0];
    let reduction = nominal / light_ratio;
    out.metric("S6_over_S2_energy_91d", nominal);
    out.metric("S6_over_S2_energy_91d_masses_div4", light_ratio);
    out.check(Check::within(
        format!(
            "S6/S2 energy error at τ = {SCALING_STEP_DAY} d: reduction when the planet masses are divided by {MASS_DIVISOR}"
        ),
        reduction,
        3.0,
        5.0,
        "eq. 7: S6 ∝ ε² against S2 ∝ ε, so the ratio ∝ ε (4); ±1 for S2's ε²τ² and S6's ετ⁶ terms",
    ));
    out.check(Check::within(
        "S2 particle: slope of |ΔH| vs initial step",
        log_slope(&m.particle[0]),
        1.8,
        2.2,
        "eq. 27: second order",
    ));
    out.note(format!(
        "S6/S2 at τ = 365.25 d: energy {energy_ratio_365:.2e} ({:.2} ε), position {position_ratio_365:.2e} ({:.2} ε); at {SCALING_STEP_DAY} d: position {position_ratio_scaling:.2e} ({:.2} ε); \
         energy {nominal:.2e}, and {light_ratio:.2e} with the masses / {MASS_DIVISOR}.",
        energy_ratio_365 / eps,
        position_ratio_365 / eps,
        position_ratio_scaling / eps,
    ));
    out.note(format!(
        "S6 on the particle's logarithmic Hamiltonian: slope {:.2}. Γ₀ and Γ₁ are both logarithms of O(1e-9) quantities, \
         not a Kepler part plus a small perturbation, so eq. 7's ε-expansion does not apply; reported, not checked.",
        log_slope(&m.particle[1])
    ));
}

impl Experiment for SymplecticOrder {
    fn id(&self) -> &'static str {
        "symplectic-order"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["symplectic"]
    }

    fn source(&self) -> &'static str {
        "Chegodaeva 2004, eqs. 7, 13, 27: error against step of S2 and S6 (planets 10 kyr vs IAS15; particle ΔH)"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let start = outer_solar_system(Frame::Equatorial);
        let mut m = Measured {
            rows: Vec::new(),
            energy: [Vec::new(), Vec::new()],
            position: [Vec::new(), Vec::new()],
            light_energy: [f64::NAN; 2],
            particle: [Vec::new(), Vec::new()],
        };
        ctx.progress
            .set_length((2 * PLANET_STEPS_DAY.len() + 2 * PARTICLE_DT0_DAY.len() + 2) as u64);
        measure_planets(ctx, &start, &mut m)?;
        measure_scaling(ctx, &mut m)?;
        measure_particle(ctx, &mut m)?;
        write_order_csv(ctx, &m.rows)?;
        plot_planets_energy(ctx, &start, &m.energy)?;
        plot_planets_position(ctx, &m.position)?;
        plot_particle(ctx, &m.particle)?;

        let mut out = Outcome::new();
        check_slopes(&mut out, &m);
        let ratios_365 = metrics_365(&mut out, &m);
        check_365(&mut out, &start, &m)?;
        check_scaling(&mut out, &m, ratios_365);
        Ok(out)
    }
}
