//! `comet-population`: a population of test particles between and beyond the giant planets,
//! removed at Hill-sphere entry, against the same initial conditions and rule integrated by
//! an independent code.
//!
//! Initially near-circular orbits, `a` 20–50 AU, `e < 0.01`, `i < 1°`, random angles
//! (`symplectic::samples::NEAR_CIRCULAR`, seed 2021; the set-up of Holman & Wisdom 1993,
//! AJ 105, 1987, and Gladman & Duncan 1990, AJ 100, 1680), among the Sun and four giants
//! (`outer_solar_system`, ecliptic J2000), integrated by [`symplectic::Population`]
//! (barycentric variant, S2, `B₀ = 0`, `B₁ = 0.21·10⁻⁶`, first step 365.25 d; planets S2 at
//! τ = 365.25 d) for 10 kyr: 10⁴ particles (quick) or 10⁶ (`--full`). A particle is removed
//! inside one Hill radius of a planet or unbound beyond 1000 AU.
//!
//! Reference: `reference-data/comet-population/rebound_removals.csv`, REBOUND 5.2.2 WHFast
//! (democratic heliocentric, τ = 365.25 d, test particles) on the same 10⁴ initial
//! conditions with the same rule checked at every step (script and provenance beside it).
//! Individual orbits are chaotic, so the check compares statistics: in each bin of initial
//! semi-major axis and at each time, the surviving fractions of the two codes must agree
//! within a two-proportion z-test, `|z| < 3.5` (binomial errors; the two samples share
//! their initial conditions, which only makes the test conservative; 3.5 keeps the
//! family-wise false alarm of the 24 comparisons near 1 %).

use anyhow::{bail, Result};
use symplectic::kepler::state_from_elements;
use symplectic::samples::{sample_elements, NEAR_CIRCULAR};
use symplectic::{
    outer_solar_system, Ephemeris, Frame, Integrator, ParticleIntegrator, ParticleStatus,
    Population, RemovalRules, Scheme, Variant,
};

use crate::helpers::solar_system::DAYS_PER_YEAR;
use crate::helpers::{
    load_reference_csv, plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle,
};
use crate::{Check, Context, Experiment, Outcome};

/// The experiment.
pub struct CometPopulation;

const SEED: u64 = 2021;
const SPAN_YEARS: f64 = 10_000.0;
const B1: f64 = 0.21e-6;
/// Edges of the initial semi-major-axis bins (AU).
const BIN_EDGES: [f64; 7] = [20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0];
/// Times at which the surviving fractions are compared (years).
const CHECK_YEARS: [f64; 4] = [1_000.0, 2_500.0, 5_000.0, 10_000.0];
/// Largest |z| of the two-proportion test (see the module docs).
const Z_MAX: f64 = 3.5;

/// `(a₀, removal time in years or ∞)` per particle.
type Removals = Vec<(f64, f64)>;

fn run_ours(ctx: &Context, n: usize) -> Result<(Removals, Vec<(usize, u64)>)> {
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let g = planets.g();
    let mu = g * (planets.sun_mass() + planets.masses().iter().sum::<f64>());
    let elements = sample_elements(&NEAR_CIRCULAR, n, SEED);
    let states = elements
        .iter()
        .map(|el| state_from_elements(el, mu))
        .collect::<Result<Vec<_>, _>>()?;
    let ids: Vec<u64> = (0..n as u64).collect();
    let ephemeris = Ephemeris::new(
        planets,
        Integrator::S2 {
            step: DAYS_PER_YEAR,
        },
    )?;
    let integrator = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, B1)?;
    let rules = RemovalRules {
        hill_factor: Some(1.0),
        min_perihelion: None,
        ejection_distance: Some(1000.0),
        ..RemovalRules::default()
    };
    let mut pop = Population::new(
        ephemeris,
        integrator,
        rules,
        0.0,
        DAYS_PER_YEAR,
        &states,
        &ids,
    )?;
    ctx.progress.set_length(SPAN_YEARS as u64);
    pop.advance_to(SPAN_YEARS * DAYS_PER_YEAR, |p| {
        ctx.progress.set_position((p.time / DAYS_PER_YEAR) as u64)
    })?;
    let mut reasons: Vec<(usize, u64)> = Vec::new();
    let mut removals = Vec::with_capacity(n);
    for (m, el) in pop.members().iter().zip(&elements) {
        let a0 = el.perihelion / (1.0 - el.eccentricity);
        let (code, t) = match &m.status {
            ParticleStatus::Active => (0, f64::INFINITY),
            ParticleStatus::HillSphereEntry { planet, time, .. } => (*planet, *time),
            ParticleStatus::Ejected { time, .. } => (5, *time),
            ParticleStatus::RegularisationLost { time, .. } => (6, *time),
            ParticleStatus::IntegrationFailed { time, .. } => (7, *time),
            ParticleStatus::PerihelionBelowLimit { time, .. } => (8, *time),
            other => bail!("unexpected status {other:?}"),
        };
        match reasons.iter_mut().find(|r| r.0 == code) {
            Some(r) => r.1 += 1,
            None => reasons.push((code, 1)),
        }
        removals.push((a0, t / DAYS_PER_YEAR));
    }
    reasons.sort_unstable();
    Ok((removals, reasons))
}

fn reference(ctx: &Context) -> Result<Removals> {
    let table = load_reference_csv(
        ctx,
        "comet-population/rebound_removals.csv",
        &["id", "a0_au", "removal_time_years", "reason"],
    )?;
    (0..table.len())
        .map(|i| {
            let a0 = table.number(i, "a0_au")?;
            let t = match table.text(i, "removal_time_years")? {
                "" => f64::INFINITY,
                _ => table.number(i, "removal_time_years")?,
            };
            Ok((a0, t))
        })
        .collect()
}

/// `(surviving, total)` in bin `b` at `t` years.
fn survivors(removals: &Removals, b: usize, t: f64) -> (usize, usize) {
    let in_bin = removals
        .iter()
        .filter(|(a, _)| (BIN_EDGES[b]..BIN_EDGES[b + 1]).contains(a));
    in_bin.fold((0, 0), |(s, n), &(_, tr)| (s + usize::from(tr > t), n + 1))
}

/// Two-proportion z statistic (pooled variance); 0 when both fractions are 0 or 1.
pub(crate) fn z_two_proportions((s1, n1): (usize, usize), (s2, n2): (usize, usize)) -> f64 {
    let (p1, p2) = (s1 as f64 / n1 as f64, s2 as f64 / n2 as f64);
    let p = (s1 + s2) as f64 / (n1 + n2) as f64;
    let var = p * (1.0 - p) * (1.0 / n1 as f64 + 1.0 / n2 as f64);
    if var == 0.0 {
        0.0
    } else {
        (p1 - p2) / var.sqrt()
    }
}

fn plot_fractions(ctx: &mut Context, ours: &Removals, reference: &Removals) -> Result<()> {
    let times: Vec<f64> = (1..=50).map(|k| k as f64 * SPAN_YEARS / 50.0).collect();
    let mut spec = PlotSpec::new(
        "Surviving fraction per bin of initial a (removal at Hill-sphere entry)",
        "time (years)",
        "surviving fraction",
    );
    spec.legend = Legend::LowerLeft;
    for b in 0..BIN_EDGES.len() - 1 {
        let curve = |r: &Removals| -> Vec<(f64, f64)> {
            times
                .iter()
                .map(|&t| {
                    let (s, n) = survivors(r, b, t);
                    (t, s as f64 / n.max(1) as f64)
                })
                .collect()
        };
        let label = format!("{}–{} AU", BIN_EDGES[b], BIN_EDGES[b + 1]);
        spec.series
            .push(Series::line(format!("{label} ours"), curve(ours), b));
        spec.series.push(Series::styled(
            format!("{label} REBOUND"),
            curve(reference),
            SeriesStyle::DashedMarkers(Marker::Ring),
            b,
        ));
    }
    plot_xy(&ctx.path("surviving_fraction.png"), &spec)?;
    ctx.add_plot(
        "surviving_fraction.png",
        "Surviving fraction against time per bin of initial semi-major axis: ours (solid) and REBOUND WHFast (dashed, same initial conditions and rule)",
    );
    Ok(())
}

fn plot_throughput(ctx: &mut Context) -> Result<()> {
    let table = load_reference_csv(
        ctx,
        "comet-population/throughput.csv",
        &["n", "ours_1t", "ours_2t", "rebound_1t"],
    )?;
    let mut spec = PlotSpec::new(
        "Throughput against population size (one script, both codes)",
        "particles N",
        "particle-years per second",
    )
    .log_log();
    spec.legend = Legend::LowerRight;
    for (k, (col, name)) in [
        ("ours_1t", "Population, 1 thread"),
        ("ours_2t", "Population, 2 threads"),
        ("rebound_1t", "REBOUND 5.2.2 WHFast, 1 thread"),
    ]
    .into_iter()
    .enumerate()
    {
        let points = (0..table.len())
            .map(|i| Ok((table.number(i, "n")?, table.number(i, col)?)))
            .collect::<Result<Vec<_>>>()?;
        spec.series.push(Series::styled(
            name,
            points,
            SeriesStyle::LineMarkers([Marker::Circle, Marker::Triangle, Marker::Cross][k]),
            k,
        ));
    }
    plot_xy(&ctx.path("throughput.png"), &spec)?;
    ctx.add_plot(
        "throughput.png",
        "Particle-years per second against N, measured by benches/scripts/comets_vs_rebound.py (stored in reference-data/comet-population/throughput.csv; shared machine)",
    );
    Ok(())
}

impl Experiment for CometPopulation {
    fn id(&self) -> &'static str {
        "comet-population"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["symplectic"]
    }

    fn source(&self) -> &'static str {
        "Holman & Wisdom 1993 / Gladman & Duncan 1990 set-up: surviving fraction per initial a against REBOUND WHFast"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let n = ctx.mode.pick(10_000, 1_000_000);
        let (ours, reasons) = run_ours(ctx, n)?;
        let reference = reference(ctx)?;
        let mut out = Outcome::new();
        let mut rows = Vec::new();
        let mut worst = 0.0f64;
        for b in 0..BIN_EDGES.len() - 1 {
            for &t in &CHECK_YEARS {
                let (so, no) = survivors(&ours, b, t);
                let (sr, nr) = survivors(&reference, b, t);
                let z = z_two_proportions((so, no), (sr, nr));
                worst = worst.max(z.abs());
                rows.push(vec![
                    format!("{}", BIN_EDGES[b]),
                    format!("{}", BIN_EDGES[b + 1]),
                    format!("{t}"),
                    format!("{so}"),
                    format!("{no}"),
                    format!("{sr}"),
                    format!("{nr}"),
                    format!("{z:.3}"),
                ]);
                out.check(Check::less_than(
                    format!(
                        "|z| surviving fraction, a0 {}–{} AU, {t} yr",
                        BIN_EDGES[b],
                        BIN_EDGES[b + 1]
                    ),
                    z.abs(),
                    Z_MAX,
                    "two-proportion z-test against REBOUND WHFast, binomial errors (module docs)",
                ));
            }
        }
        write_csv_rows(
            &ctx.path("surviving_fraction.csv"),
            &[
                "a0_min_au",
                "a0_max_au",
                "time_years",
                "ours_surviving",
                "ours_total",
                "rebound_surviving",
                "rebound_total",
                "z",
            ],
            rows,
        )?;
        ctx.add_file(
            "surviving_fraction.csv",
            "surviving fractions per bin and time, both codes, z statistic",
        );
        out.metric("largest |z|", worst);
        out.metric("particles", n as f64);
        let names = [
            "active",
            "Jupiter Hill",
            "Saturn Hill",
            "Uranus Hill",
            "Neptune Hill",
            "ejected",
            "regularisation lost",
            "failed",
            "perihelion",
        ];
        for (code, count) in reasons {
            out.metric(format!("final: {}", names[code.min(8)]), count as f64);
        }
        plot_fractions(ctx, &ours, &reference)?;
        plot_throughput(ctx)?;
        Ok(out)
    }
}
