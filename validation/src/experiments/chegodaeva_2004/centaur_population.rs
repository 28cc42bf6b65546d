//! `centaur-population`: Centaurs integrated through their close encounters with the giant
//! planets, against the same initial conditions and end rules integrated by REBOUND's
//! MERCURIUS.
//!
//! The population study `populations/centaurs.toml` (300 comets, barycentric `a` 5.5–30 AU,
//! `e` 0–0.2, `i` 0–10°, random angles; S2 barycentric map with `B₁ = 4·10⁻⁶`, planets S6 at
//! 91.3125 d, whose trajectory the map and the encounter mode both read; encounters inside 3
//! Hill radii by Bulirsch–Stoer at 10⁻¹², handed back to the map beyond 3.5) run through [`symplectic::io::PopulationSpec`] for 200 kyr (quick) or 1 Myr
//! (`--full`). A comet ends at a
//! collision with a planet (its equatorial radius), when its barycentric perihelion falls
//! below 2.5 AU, or when it is unbound beyond 100 AU.
//!
//! Reference: `reference-data/centaur-population/mercurius_ends.csv`, REBOUND 5.2.0 MERCURIUS
//! (H. Rein, D. M. Hernandez, D. Tamayo et al., "Hybrid symplectic integrators for planetary
//! dynamics", *MNRAS* 485, 5490–5497 (2019), doi:10.1093/mnras/stz769; `r_crit_hill = 3`,
//! `dt = 0.1 yr`) on the same 300 initial states with the same end rules over 1 Myr (script
//! and provenance beside it); quick mode compares both codes censored at its span.
//!
//! Single trajectories diverge within a few encounters, so the codes are compared as two
//! samples of the same distribution: the surviving fraction at a quarter, half, three
//! quarters and the whole span, and the fractions ended by each rule, by a two-proportion
//! z-test (pooled binomial standard error of the difference), and the end times of the comets
//! that ended (their dynamical lifetimes) by the two-sample Kolmogorov–Smirnov test.
//! Sharing initial conditions correlates the samples only early (before the first
//! encounters), which narrows the true scatter of the difference: the unpaired tests are
//! conservative. Each test is two-sided at 0.27 % (`|z| < 3`, KS `p > 0.0027`); over the
//! eight tests the chance of a false alarm is about 2 %.
//!
//! **Power of the q < 2.5 AU test.** For two binomial samples of `n` comets each, fractions
//! `p` and `p′ = p (1 ± 0.25)` (a 25 % change), the test fails with probability
//! `Φ(|p′ − p|/σ − 3) + Φ(−|p′ − p|/σ − 3)`, `σ = √((p(1 − p) + p′(1 − p′))/n)` (the unpooled
//! standard error of the difference under the change; the smaller of the two directions is
//! quoted). With MERCURIUS's fractions (`p` = 43/300 = 0.143 at 200 kyr, 78/300 = 0.26 at 1 Myr
//! in `mercurius_ends.csv`; 57/1000 = 0.057 at 20 kyr and 92/1000 = 0.092 at 50 kyr in the
//! 1,000-comet run of the same script, `mercurius_ends_1000.csv`): the quick check (n = 300, 200 kyr) catches a 25 %
//! change with probability 0.036 and `--full` (n = 300, 1 Myr) with 0.11; n = 1,000 over 1 Myr
//! gives 0.58 (0.49 at the 1,000-comet run's own 234/1000 = 0.234, `mercurius_ends_1000.csv`,
//! whose 0.8 needs 1,668 comets). A power of 0.8 (0.9) needs n = 3,102 (3,863) comets over 200 kyr, 1,449
//! (1,808) over 1 Myr, 5,210 (6,485) over 50 kyr or 8,738 (10,870) over 20 kyr; in comet-years
//! (each counted until it ends) the shortest of these spans is the cheapest, 1.7·10⁸ at 20 kyr
//! against 5.3·10⁷ for today's quick check (3.2×). Neither check has that power today: a
//! change of the fraction by less than about 67 % (quick) or 44 % (`--full`) passes more often
//! than not.

use anyhow::{bail, Result};
use symplectic::io::{status_label, PopulationSpec};

use super::comet_population::z_two_proportions;
use crate::helpers::solar_system::DAYS_PER_YEAR;
use crate::helpers::{
    load_reference_csv, plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle,
};
use crate::{workspace_root, Check, Context, Experiment, Outcome};

/// The experiment.
pub struct CentaurPopulation;

/// Largest |z| of a two-proportion test (two-sided 0.27 %; module docs).
const Z_MAX: f64 = 3.0;
/// Smallest p-value of the Kolmogorov–Smirnov test (the same two-sided 0.27 %).
const P_MIN: f64 = 0.0027;

/// How a comet ended: the label (`active`, `perihelion`, `ejected`, `collision_<planet>`,
/// anything else from our code) and the time in years (∞ if active at the span's end).
type Ends = Vec<(String, f64)>;

/// A named end rule: which labels it counts.
type Rule = (&'static str, fn(&str) -> bool);

/// Our ends, and the switches to the encounter integrator of all comets
/// (`PopulationProgress::encounters_begun`).
fn run_ours(ctx: &Context, span_years: f64) -> Result<(Ends, u64)> {
    let path = workspace_root().join("populations/centaurs.toml");
    let spec = PopulationSpec::from_file(&path)?;
    let mut population = spec.population(&path)?;
    ctx.progress.set_length(span_years as u64);
    let progress = population.advance_to(span_years * DAYS_PER_YEAR, |p| {
        ctx.progress.set_position((p.time / DAYS_PER_YEAR) as u64)
    })?;
    let planets = population.ephemeris().planets().clone();
    let ends = population
        .members()
        .iter()
        .map(|m| {
            let (label, t) = status_label(&m.status, &planets);
            censor(label, t / DAYS_PER_YEAR, span_years)
        })
        .collect();
    Ok((ends, progress.encounters_begun))
}

/// An end after `span` years counts as active (both codes are compared over the same span).
fn censor(label: String, years: f64, span: f64) -> (String, f64) {
    if label == "active" || years > span {
        ("active".into(), f64::INFINITY)
    } else {
        (label, years)
    }
}

fn reference(ctx: &Context, span_years: f64) -> Result<Ends> {
    let table = load_reference_csv(
        ctx,
        "centaur-population/mercurius_ends.csv",
        &["id", "end", "end_time_days", "planet"],
    )?;
    (0..table.len())
        .map(|i| {
            let label = table.text(i, "end")?.to_string();
            let t = match label.as_str() {
                "active" => f64::INFINITY,
                _ => table.number(i, "end_time_days")? / DAYS_PER_YEAR,
            };
            Ok(censor(label, t, span_years))
        })
        .collect()
}

/// `(count, total)` of the ends whose label satisfies `which`.
fn count(ends: &Ends, which: impl Fn(&str) -> bool) -> (usize, usize) {
    (ends.iter().filter(|(l, _)| which(l)).count(), ends.len())
}

fn surviving(ends: &Ends, t: f64) -> (usize, usize) {
    (ends.iter().filter(|(_, e)| *e > t).count(), ends.len())
}

/// Two-sample Kolmogorov–Smirnov statistic `D = sup |F₁ − F₂|` of two samples.
fn ks_statistic(a: &[f64], b: &[f64]) -> f64 {
    let mut a = a.to_vec();
    let mut b = b.to_vec();
    a.sort_unstable_by(f64::total_cmp);
    b.sort_unstable_by(f64::total_cmp);
    let (mut i, mut j, mut d) = (0, 0, 0.0f64);
    while i < a.len() && j < b.len() {
        let x = a[i].min(b[j]);
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
        d = d.max((i as f64 / a.len() as f64 - j as f64 / b.len() as f64).abs());
    }
    d
}

/// The p-value of the two-sample KS statistic `d` for sample sizes `n1`, `n2`: the
/// Kolmogorov distribution `Q(λ) = 2 Σ_{k≥1} (−1)^{k−1} e^{−2k²λ²}` at `λ = (√nₑ + 0.12 +
/// 0.11/√nₑ) d`, `nₑ = n₁n₂/(n₁ + n₂)` (M. A. Stephens, "Use of the Kolmogorov–Smirnov,
/// Cramér–von Mises and related statistics without extensive tables", *J. R. Stat. Soc. B*
/// 32, 115–122 (1970); W. H. Press et al., *Numerical Recipes*, 3rd ed., Cambridge 2007,
/// §14.3.3).
fn ks_p_value(d: f64, n1: usize, n2: usize) -> f64 {
    let ne = (n1 * n2) as f64 / (n1 + n2) as f64;
    let lambda = (ne.sqrt() + 0.12 + 0.11 / ne.sqrt()) * d;
    if lambda < 0.2 {
        return 1.0;
    }
    let sum: f64 = (1..=100)
        .map(|k| {
            let k = k as f64;
            let sign = if k as u64 % 2 == 1 { 1.0 } else { -1.0 };
            sign * (-2.0 * k * k * lambda * lambda).exp()
        })
        .sum();
    (2.0 * sum).clamp(0.0, 1.0)
}

fn plot_survival(ctx: &mut Context, ours: &Ends, reference: &Ends, span: f64) -> Result<()> {
    let times: Vec<f64> = (0..=100).map(|k| k as f64 * span / 100.0).collect();
    let curve = |e: &Ends| -> Vec<(f64, f64)> {
        times
            .iter()
            .map(|&t| {
                let (s, n) = surviving(e, t);
                (t / 1e3, s as f64 / n as f64)
            })
            .collect()
    };
    let mut spec = PlotSpec::new(
        "Centaurs: fraction not yet ended (collision, q < 2.5 AU, ejection)",
        "time (kyr)",
        "surviving fraction",
    );
    spec.legend = Legend::LowerLeft;
    spec.series.push(Series::line("ours", curve(ours), 0));
    spec.series.push(Series::styled(
        "REBOUND 5.2 MERCURIUS",
        curve(reference),
        SeriesStyle::DashedMarkers(Marker::Ring),
        1,
    ));
    plot_xy(&ctx.path("surviving_fraction.png"), &spec)?;
    ctx.add_plot(
        "surviving_fraction.png",
        "Surviving fraction against time: ours (solid) and REBOUND MERCURIUS (dashed), same initial conditions and end rules",
    );
    Ok(())
}

impl Experiment for CentaurPopulation {
    fn id(&self) -> &'static str {
        "centaur-population"
    }

    fn crates(&self) -> &'static [&'static str] {
        &["symplectic"]
    }

    fn source(&self) -> &'static str {
        "Centaurs among the giant planets through close encounters: survival, lifetimes and ends against REBOUND MERCURIUS"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let span = ctx.mode.pick(200_000.0, 1_000_000.0);
        let (ours, encounters_begun) = run_ours(ctx, span)?;
        let reference = reference(ctx, span)?;
        if ours.len() != reference.len() {
            bail!(
                "{} comets here, {} in the reference: not the same population",
                ours.len(),
                reference.len()
            );
        }
        let mut out = Outcome::new();
        let mut rows = Vec::new();
        let mut z_check = |out: &mut Outcome,
                           name: String,
                           a: (usize, usize),
                           b: (usize, usize)| {
            let z = z_two_proportions(a, b);
            rows.push(vec![
                name.clone(),
                a.0.to_string(),
                b.0.to_string(),
                a.1.to_string(),
                format!("{z:.3}"),
            ]);
            out.check(Check::less_than(
                format!("|z| {name}"),
                z.abs(),
                Z_MAX,
                "two-proportion z-test against REBOUND MERCURIUS, pooled binomial standard error, two-sided 0.27 % (module docs)",
            ));
        };
        for quarter in 1..=4 {
            let t = span * quarter as f64 / 4.0;
            z_check(
                &mut out,
                format!("surviving at {} kyr", t / 1e3),
                surviving(&ours, t),
                surviving(&reference, t),
            );
        }
        let rules: [Rule; 3] = [
            ("ended by q < 2.5 AU", |l| l == "perihelion"),
            ("ejected", |l| l == "ejected"),
            ("collided with a planet", |l| l.starts_with("collision_")),
        ];
        for (name, which) in rules {
            z_check(
                &mut out,
                name.to_string(),
                count(&ours, which),
                count(&reference, which),
            );
        }
        write_csv_rows(
            &ctx.path("fractions.csv"),
            &["statistic", "ours", "mercurius", "comets", "z"],
            rows,
        )?;
        ctx.add_file(
            "fractions.csv",
            "surviving and end fractions of both codes with the z statistic",
        );
        let lifetimes = |e: &Ends| -> Vec<f64> {
            e.iter()
                .map(|(_, t)| *t)
                .filter(|t| t.is_finite())
                .collect()
        };
        let (lo, lr) = (lifetimes(&ours), lifetimes(&reference));
        let d = ks_statistic(&lo, &lr);
        let p = if lo.is_empty() || lr.is_empty() {
            f64::NAN
        } else {
            ks_p_value(d, lo.len(), lr.len())
        };
        out.metric("KS D, lifetimes of the comets that ended", d);
        out.check(Check::greater_than(
            "KS p-value, lifetimes of the comets that ended",
            p,
            P_MIN,
            "two-sample Kolmogorov–Smirnov test against REBOUND MERCURIUS (Stephens 1970), two-sided 0.27 % (module docs)",
        ));
        let other = count(&ours, |l| {
            !(l == "active" || l == "perihelion" || l == "ejected" || l.starts_with("collision_"))
        });
        out.check(Check::equals(
            "comets ended for another reason (failed, regularisation lost)",
            other.0 as f64,
            0.0,
            "the end rules are the reference's: no other end may occur",
        ));
        let mut labels: Vec<&str> = ours
            .iter()
            .chain(&reference)
            .map(|(l, _)| l.as_str())
            .collect();
        labels.sort_unstable();
        labels.dedup();
        for label in labels {
            out.metric(
                format!("ours: {label}"),
                count(&ours, |l| l == label).0 as f64,
            );
            out.metric(
                format!("MERCURIUS: {label}"),
                count(&reference, |l| l == label).0 as f64,
            );
        }
        out.metric("comets", ours.len() as f64);
        out.metric(
            "ours: switches to the encounter integrator (all comets)",
            encounters_begun as f64,
        );
        out.metric("span (years)", span);
        write_csv_rows(
            &ctx.path("ours_ends.csv"),
            &["id", "end", "end_time_years"],
            ours.iter()
                .enumerate()
                .map(|(i, (l, t))| vec![i.to_string(), l.clone(), format!("{t}")]),
        )?;
        ctx.add_file("ours_ends.csv", "each comet's end here (row = id)");
        plot_survival(ctx, &ours, &reference, span)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ks_p_value_matches_the_kolmogorov_table() {
        // Q(1.358) = 0.050 and Q(1.628) = 0.010 (the 5 % and 1 % points of the Kolmogorov
        // distribution); with n₁ = n₂ = 2·10⁸ the Stephens factor is √nₑ to 10⁻⁵.
        let n = 200_000_000;
        let ne_sqrt = (n as f64 / 2.0).sqrt();
        assert!((ks_p_value(1.358 / ne_sqrt, n, n) - 0.050).abs() < 1e-3);
        assert!((ks_p_value(1.628 / ne_sqrt, n, n) - 0.010).abs() < 3e-4);
    }

    #[test]
    fn ks_statistic_is_the_largest_cdf_gap() {
        // By hand: after 1 and 2, F_a = 2/3 and F_b = 0; after 3, 1 and 1/2.
        assert_eq!(ks_statistic(&[1.0, 2.0, 3.0], &[3.0, 4.0]), 2.0 / 3.0);
        assert_eq!(ks_statistic(&[1.0, 2.0], &[1.0, 2.0]), 0.0);
    }
}
