//! `centaur-population`: Centaurs integrated through their close encounters with the giant
//! planets, against the same initial conditions and end rules integrated by REBOUND's
//! MERCURIUS.
//!
//! Centaurs drawn by `symplectic::samples::CENTAURS` (seed 2027: barycentric `a` 5.5–30 AU,
//! `e` 0–0.2, `i` 0–10°, random angles, as barycentric states at the planets' epoch) run with
//! the settings of `populations/centaurs.toml` (S2 barycentric map with `B₁ = 4·10⁻⁶`,
//! planets S6 at 91.3125 d, whose trajectory the map and the encounter mode both read;
//! encounters inside 3 Hill radii by Bulirsch–Stoer at 10⁻¹², handed back to the map beyond
//! 3.5). Quick: the first 16,000 draws (`reference-data/centaur-population/initial_20000.csv`)
//! over 5 kyr, the design below that catches a 25 % change of the q < 2.5 AU fraction.
//! `--full`: the first 1,000 draws (`initial_1000.csv`, the same states as the first 1,000
//! rows of `initial_20000.csv`) over 1 Myr, checkpointed every 100 kyr into the output
//! directory and resumed from there by a run of the same build (`centaur_sample`). A comet
//! ends at a collision with a planet (its equatorial radius), when its barycentric perihelion
//! falls below 2.5 AU, or when it is unbound beyond 100 AU.
//!
//! References (`reference-data/centaur-population/`, script and provenance in `SOURCE.md`):
//! REBOUND 5.2.2 MERCURIUS (H. Rein, D. M. Hernandez, D. Tamayo et al., "Hybrid symplectic
//! integrators for planetary dynamics", *MNRAS* 485, 5490–5497 (2019),
//! doi:10.1093/mnras/stz769; `r_crit_hill = 3`, `dt = 0.1 yr`) on the same initial states with
//! the same end rules: `mercurius_ends_20000.csv` (20,000 comets over 10 kyr; quick reads the
//! first 16,000) and `mercurius_ends_1000.csv` (1,000 comets over 1 Myr; `--full`). Both
//! codes are censored at the span.
//!
//! **Unpaired tests.** Single trajectories diverge within a few encounters, so the codes are
//! first compared as two samples of the same distribution: the surviving fraction at a
//! quarter, half, three quarters and the whole span, and the fractions ended by each rule, by
//! a two-proportion z-test (pooled binomial standard error of the difference), and the end
//! times of the comets that ended (their dynamical lifetimes) by the two-sample
//! Kolmogorov–Smirnov test. Each test is two-sided at 0.27 % (`|z| < 3`, KS `p > 0.0027`);
//! over the nine tests the chance of a false alarm is about 2.4 %.
//!
//! **Power of the unpaired q < 2.5 AU test.** For two binomial samples of `n` comets each,
//! fractions `p` and `p′ = p (1 ± 0.25)` (a 25 % change), the test fails with probability
//! `Φ(|p′ − p|/σ − 3) + Φ(−|p′ − p|/σ − 3)`, `σ = √((p(1 − p) + p′(1 − p′))/n)` (the unpooled
//! standard error of the difference under the change; the smaller of the two directions is
//! quoted). With MERCURIUS's fractions in `mercurius_ends_1000.csv` (57/1000 at 20 kyr,
//! 92/1000 at 50 kyr, 234/1000 at 1 Myr): 0.8 needs n = 8,738 comets over 20 kyr, 5,210 over
//! 50 kyr, 1,668 over 1 Myr; the 1,000 comets have power 0.095 over 50 kyr and 0.49
//! over 1 Myr.
//!
//! **The paired test.** Both codes start the same comet from the same state, so early on a
//! comet that one code sends below 2.5 AU the other tends to send too: the outcomes are
//! correlated comet by comet, and McNemar's test on the discordant comets (`b`: only ours
//! ended by q < 2.5 AU within the span, `c`: only MERCURIUS; `z = (b − c)/√(b + c)`,
//! two-sided 0.27 %) sees a change of the fraction against the scatter of the discordant
//! comets only, not of all. A change that adds (removes) `Δ = 0.25 p n` comets at random
//! moves `b − c` by `Δ` and `b + c` by at most `Δ`, so the check fails with probability at
//! least `Φ(Δ/√(b + c + Δ) − 3)` (metric "power of the McNemar check", computed from each
//! run's own `b + c` and MERCURIUS's count; the unit test
//! `a_25_percent_change_fails_the_mcnemar_check_as_often_as_its_power_says` draws 2,000
//! changed populations of that model, ±25 %, and finds them failing at least that often), and
//! the change caught with 80 % probability solves `Δ/√(b + c + Δ) = 3 + Φ⁻¹(0.8)` (metric
//! "change … the McNemar check catches with 80 % probability").
//!
//! **The correlation, measured** (the `--full` run of 2026-12-05 below, each code's ends
//! censored at the span; `φ` the correlation of the two codes' outcomes comet by comet;
//! powers against a 25 % change; the comets a paired check at that span would need for 0.8,
//! from that span's `p` and `(b + c)/n`, and their cost in comet-years, each comet counted
//! until it ends, and in our wall time at the `--full` run's 1.1·10⁶ comet-years per second
//! on 2 threads):
//!
//! | span | ours | MERCURIUS | both | b | c | φ | paired power | unpaired | comets for 0.8 | comet-years | ours (s) |
//! | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |
//! | 5 kyr | 29 | 28 | 8 | 21 | 20 | 0.26 | 0.023 | 0.018 | 14,457 | 7.1·10⁷ | 65 |
//! | 10 kyr | 39 | 40 | 10 | 29 | 30 | 0.22 | 0.036 | 0.027 | 10,183 | 9.9·10⁷ | 90 |
//! | 20 kyr | 58 | 57 | 20 | 38 | 37 | 0.31 | 0.068 | 0.045 | 6,486 | 1.3·10⁸ | 113 |
//! | 50 kyr | 94 | 92 | 40 | 54 | 52 | 0.37 | 0.165 | 0.095 | 3,599 | 1.7·10⁸ | 153 |
//! | 100 kyr | 117 | 122 | 56 | 61 | 66 | 0.40 | 0.284 | 0.155 | 2,499 | 2.3·10⁸ | 207 |
//! | 200 kyr | 145 | 147 | 71 | 74 | 76 | 0.40 | 0.378 | 0.216 | 2,041 | 3.6·10⁸ | 326 |
//! | **1 Myr** | 239 | 234 | 118 | 121 | 116 | 0.34 | **0.657** | 0.491 | 1,274 | 9.8·10⁸ | 893 |
//!
//! The outcomes are correlated (`φ` 0.2–0.4), not enough to make 1,000 comets decisive: the
//! paired test needs a third to a half of the unpaired test's comets, and the shortest spans
//! are the cheapest per unit of power (7.1·10⁷ comet-years at 5 kyr against 9.8·10⁸ at 1 Myr).
//! `--full` (1 Myr, 1,000 comets) catches about 29 % with 80 % probability (power 0.66
//! against 25 %).
//!
//! **The quick design, measured.** The 1,000-comet estimates at short spans rest on 28 to 59
//! events, so the design was chosen on a larger sample: MERCURIUS on 20,000 comets over 10 kyr
//! (`mercurius_ends_20000.csv`) and this experiment on the same 20,000 over 10 kyr
//! (2026-12-05, 21:43–21:46 UTC, 2 threads, 211.7 s, 1.95·10⁸ comet-years, 9.2·10⁵ per second;
//! its ends censored at each span and cut to the first `n` comets; MERCURIUS's fraction at 5
//! kyr 512/20,000 = 2.56 %, at 10 kyr 4.06 %):
//!
//! | comets | span | MERCURIUS | ours | b | c | φ | paired power | unpaired | comet-years |
//! | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |
//! | 20,000 | 2.5 kyr | 317 | 310 | 193 | 200 | 0.36 | 0.741 | 0.498 | 5.0·10⁷ |
//! | 14,000 | 5 kyr | 348 | 341 | 219 | 226 | 0.34 | 0.780 | 0.561 | 6.9·10⁷ |
//! | 15,000 | 5 kyr | 376 | 369 | 235 | 242 | 0.34 | 0.825 | 0.610 | 7.4·10⁷ |
//! | **16,000** | **5 kyr** | 403 | 403 | 258 | 258 | 0.34 | **0.855** | 0.654 | 7.9·10⁷ |
//! | 18,000 | 5 kyr | 450 | 444 | 284 | 290 | 0.34 | 0.902 | 0.721 | 8.9·10⁷ |
//! | 14,000 | 6 kyr | 390 | 391 | 252 | 251 | 0.34 | 0.836 | 0.635 | 8.3·10⁷ |
//! | 12,000 | 7.5 kyr | 397 | 403 | 259 | 253 | 0.34 | 0.845 | 0.650 | 8.8·10⁷ |
//! | 10,000 | 10 kyr | 401 | 395 | 247 | 253 | 0.35 | 0.863 | 0.661 | 9.8·10⁷ |
//! | 20,000 | 10 kyr | 812 | 790 | 504 | 526 | 0.33 | 0.997 | 0.969 | 2.0·10⁸ |
//!
//! The quick mode runs the cheapest row above 0.8 with some margin: **16,000 comets over 5
//! kyr, power 0.855 against a 25 % change** (the paired check; 0.654 for the unpaired one),
//! and checks that its own power, from its own `b + c`, stays at least 0.8 (a run whose
//! discordance grows so far that a 25 % change could pass fails that check). The 1,000 × 50
//! kyr survival and lifetime tests of the quick mode before are now those of `--full` (1 Myr,
//! the same tests); quick runs every test on its own 16,000 comets. It judges the earliest
//! q < 2.5 AU ends, those of comets that start on or near Jupiter-crossing orbits.
//!
//! **`--full`, measured** (2026-12-05, 18:36–18:48 UTC, `validation run --full --only
//! centaur-population`, 2 rayon threads, under the build lock on the shared 2-core machine:
//! 700.9 s of wall time, 1,349 s of CPU; 230,332 switches to the encounter integrator, 230
//! per comet): passes 10/10. Surviving at 250, 500, 750 kyr and 1 Myr: 820/821, 752/770,
//! 713/729, 685/696 (ours/MERCURIUS; z = −0.06, −0.94, −0.80, −0.53); ended by q < 2.5 AU
//! 239/234 (z = 0.26), ejected 73/62 (0.98), collided with a planet 3/8 (−1.51: ours 3 with
//! Jupiter; MERCURIUS 4 with Jupiter, 2 with Neptune, 1 with Saturn and with Uranus);
//! McNemar `b` = 121, `c` = 116, z = 0.32; KS of the lifetimes D = 0.052, p = 0.79; no other
//! end.
//!
//! **Quick, measured** (2026-12-05, 21:48 UTC, `validation run --only centaur-population`, 2
//! rayon threads, under the build lock on the shared 2-core machine): **82.5 s** of wall time
//! (161 s of CPU; the 1,000 comets over 50 kyr before: 47.3 s), passes 11/11. Surviving at
//! 1.25, 2.5, 3.75 and 5 kyr: 15,827/15,833, 15,733/15,739, 15,645/15,648, 15,580/15,579
//! (ours/MERCURIUS; z = −0.33, −0.26, −0.11, 0.03); q < 2.5 AU 403/403 (0), ejected 0/0,
//! collided 17/18 (−0.17: ours 12 with Jupiter, 3 with Saturn, 2 with Uranus; MERCURIUS 11,
//! 5, 2); McNemar `b` = 258, `c` = 258, z = 0; KS D = 0.031, p = 0.99; 67,512 switches.
//! Power of the McNemar check against a 25 % change 0.855 (checked ≥ 0.8); it catches 23.6 %
//! with 80 % probability. Its ends equal those of the 20,000-comet, 10 kyr run above censored
//! at 5 kyr and cut to 16,000 comets (0 of 16,000 differ).
//!
//! **Switches per close encounter** (metrics): the close encounters with a planet and the
//! switches to the encounter integrator in them, mean and most
//! (`symplectic::Population::switches_per_encounter`; an encounter runs from a switch inside
//! 3 Hill radii until the comet is beyond twice that, as `symplectic::EncounterTally`
//! defines it). With the hand-back at 3.5 Hill radii a comet skimming 3 Hill radii switches
//! once per encounter.
//!
//! **On Dask**: `benches/scripts/centaurs_dask.py` runs the `--full` comets with
//! `partisim.dask.run_population_dask` (chunks of comets, each checkpointed atomically and
//! resumed). Over 50 kyr on 2 workers it took 53.0 s and its ends equal the in-process run's,
//! all 1,000, bit for bit. **Over 1 Myr on 2 workers** (2026-12-05, `LocalCluster`, one
//! thread each, 8 chunks of 125 comets, a checkpoint every 100 kyr; `python
//! benches/scripts/centaurs_dask.py CKPT ENDS.csv 1e6 2 8 1e5`, under the build lock on the
//! shared 2-core machine): started 22:09:43 UTC, killed (SIGKILL to the whole process group)
//! at 22:15:36 after 353 s with two chunks done and two part-way, started again with the same
//! arguments at 22:21:22 and finished at 22:28:32 (430.5 s, 795 s of CPU): **783 s of wall
//! time in all** (the in-process `--full` run: 700.9 s). The resumed run ends 685 active, 239
//! by q < 2.5 AU, 73 ejected, 3 collided with Jupiter; surviving at 250, 500, 750 kyr 820,
//! 752, 713; McNemar `b` = 121, `c` = 116; KS D = 0.052: every count of the in-process
//! `--full` run above, and row by row, bit for bit (label and end time, 0 of 1,000 differ),
//! those of this experiment's `--full` run of this build uninterrupted (2026-12-05,
//! 22:33:43–22:45:24 UTC, 2 threads, 700.8 s, 10/10, the same counts again).
use anyhow::{bail, Result};

use super::centaur_sample::{censor, run_ours, Ends, Sample};
use super::comet_population::z_two_proportions;
use crate::helpers::solar_system::DAYS_PER_YEAR;
use crate::helpers::{
    load_reference_csv, plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle,
};
use crate::{Check, Context, Experiment, Mode, Outcome};

/// The experiment.
pub struct CentaurPopulation;

/// Largest |z| of a two-proportion test (two-sided 0.27 %; module docs).
const Z_MAX: f64 = 3.0;
/// Smallest p-value of the Kolmogorov–Smirnov test (the same two-sided 0.27 %).
const P_MIN: f64 = 0.0027;
/// The quick mode's comets (module docs: the paired test's power against its cost).
const QUICK: Sample = Sample {
    initial: "centaur-population/initial_20000.csv",
    comets: QUICK_COMETS,
};
/// How many comets the quick mode runs (module docs).
const QUICK_COMETS: usize = 16_000;
/// MERCURIUS's ends of the comets of `QUICK.initial` over 10 kyr.
const QUICK_REFERENCE: &str = "centaur-population/mercurius_ends_20000.csv";
/// The quick mode's span (years; module docs).
const QUICK_SPAN_YEARS: f64 = 5_000.0;
/// The smallest power against a 25 % change of the q < 2.5 AU fraction the quick design
/// must have (module docs): the conventional 0.8 (J. Cohen, *Statistical Power Analysis for
/// the Behavioral Sciences*, 2nd ed., Erlbaum 1988, §2.4).
const QUICK_MIN_POWER: f64 = 0.8;
/// The full mode's comets.
const FULL: Sample = Sample {
    initial: "centaur-population/initial_1000.csv",
    comets: 1_000,
};
/// MERCURIUS's ends of the comets of `FULL.initial` over 1 Myr.
const FULL_REFERENCE: &str = "centaur-population/mercurius_ends_1000.csv";
/// The full mode's span (years).
const FULL_SPAN_YEARS: f64 = 1_000_000.0;
/// The full mode's checkpoint cadence (years of simulated time).
const FULL_CHECKPOINT_YEARS: f64 = 100_000.0;

/// McNemar's statistic for paired binary outcomes, `z = (b − c)/√(b + c)` with `b` the
/// comets where only `ours` holds, `c` those where only `theirs` does (Q. McNemar, "Note on
/// the sampling error of the difference between correlated proportions or percentages",
/// *Psychometrika* 12, 153–157 (1947)); 0 without discordant pairs. Also `(b, c)`.
fn mcnemar_z(ours: &[bool], theirs: &[bool]) -> (f64, usize, usize) {
    let b = ours.iter().zip(theirs).filter(|(o, t)| **o && !**t).count();
    let c = ours.iter().zip(theirs).filter(|(o, t)| !**o && **t).count();
    let z = if b + c == 0 {
        0.0
    } else {
        (b as f64 - c as f64) / ((b + c) as f64).sqrt()
    };
    (z, b, c)
}

/// The standard normal distribution function `Φ(x) = erfc(−x/√2)/2`, with `erfc` by the
/// Chebyshev fit of W. H. Press et al., *Numerical Recipes*, 3rd ed., Cambridge 2007, §6.2
/// (`erfccheb`'s predecessor `erfcc`: fractional error below 1.2·10⁻⁷ everywhere).
fn normal_cdf(x: f64) -> f64 {
    let z = x.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = [
        -1.265_512_23,
        1.000_023_68,
        0.374_091_96,
        0.096_784_18,
        -0.186_288_06,
        0.278_868_07,
        -1.135_203_98,
        1.488_515_87,
        -0.822_152_23,
        0.170_872_77,
    ];
    let series = poly.iter().rev().fold(0.0, |acc, c| acc * t + c);
    let erfc = t * (-z * z + series).exp();
    if x >= 0.0 {
        1.0 - 0.5 * erfc
    } else {
        0.5 * erfc
    }
}

/// The probability that McNemar's check (`|z| < Z_MAX`) fails when our code ends
/// `shift` more (or fewer) comets by q < 2.5 AU than it does, the added or lost comets
/// drawn at random among the others: `b − c` moves by `shift`, `b + c` to at most
/// `discordant + shift`, so the power is at least `Φ(shift/√(discordant + shift) − Z_MAX)`
/// (the far tail, below 10⁻³, left out).
fn mcnemar_power(discordant: usize, shift: f64) -> f64 {
    normal_cdf(shift / (discordant as f64 + shift).sqrt() - Z_MAX)
}

/// `Φ⁻¹(0.8)`, the standard normal quantile of 80 % (Abramowitz & Stegun, Table 26.5).
const Z_POWER_80: f64 = 0.841_621;

/// The relative change of a count `reference` that McNemar's check catches with 80 %
/// probability ([`mcnemar_power`] = 0.8): the shift `Δ` solving `Δ/√(d + Δ) = Z_MAX + z₀.₈`,
/// `Δ = (k² + √(k⁴ + 4k²d))/2` with `k = Z_MAX + z₀.₈`, over `reference`.
fn mcnemar_change_at_80(discordant: usize, reference: usize) -> f64 {
    let k2 = (Z_MAX + Z_POWER_80).powi(2);
    let shift = (k2 + (k2 * k2 + 4.0 * k2 * discordant as f64).sqrt()) / 2.0;
    shift / reference as f64
}

/// A named end rule: which labels it counts.
type Rule = (&'static str, fn(&str) -> bool);

/// The first `comets` rows of MERCURIUS's ends in `file`, censored at `span_years`.
fn reference(ctx: &Context, file: &str, comets: usize, span_years: f64) -> Result<Ends> {
    let table = load_reference_csv(ctx, file, &["id", "end", "end_time_days", "planet"])?;
    if table.len() < comets {
        bail!("{file}: {} comets, {comets} expected", table.len());
    }
    (0..comets)
        .map(|i| {
            let label = table.text(i, "end")?.to_string();
            let t = match label.as_str() {
                "active" => f64::INFINITY,
                _ => table.number(i, "end_time_days")? / DAYS_PER_YEAR,
            };
            if table.number(i, "id")? != i as f64 {
                bail!(
                    "{file}: row {} is not comet {i} (rows in id order expected)",
                    i + 2
                );
            }
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
        let span = ctx.mode.pick(QUICK_SPAN_YEARS, FULL_SPAN_YEARS);
        let sample = ctx.mode.pick(QUICK, FULL);
        let reference_file = ctx.mode.pick(QUICK_REFERENCE, FULL_REFERENCE);
        let checkpoints = ctx.mode.pick(None, Some(FULL_CHECKPOINT_YEARS));
        let run = run_ours(ctx, sample, span, checkpoints)?;
        let (ours, encounters_begun) = (run.ends, run.encounters_begun);
        let reference = reference(ctx, reference_file, sample.comets, span)?;
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
        // The same comets from the same states: paired, comet by comet (module docs).
        let flags = |e: &Ends| -> Vec<bool> { e.iter().map(|(l, _)| l == "perihelion").collect() };
        let (z, b, c) = mcnemar_z(&flags(&ours), &flags(&reference));
        out.metric("q < 2.5 AU: comets only ours ended so (b)", b as f64);
        out.metric("q < 2.5 AU: comets only MERCURIUS ended so (c)", c as f64);
        // A 25 % change of the fraction MERCURIUS finds, at this run's discordance.
        let theirs = count(&reference, |l| l == "perihelion").0;
        let power = mcnemar_power(b + c, 0.25 * theirs as f64);
        out.metric(
            "power of the McNemar check against a 25 % change of the q < 2.5 AU fraction",
            power,
        );
        if ctx.mode == Mode::Quick {
            out.check(Check::greater_than(
                "power of the McNemar check against a 25 % change of the q < 2.5 AU fraction",
                power,
                QUICK_MIN_POWER,
                "the quick design's target: a 25 % change fails with at least 80 % probability (Cohen 1988; module docs)",
            ));
        }
        out.metric(
            "change of the q < 2.5 AU fraction the McNemar check catches with 80 % probability",
            mcnemar_change_at_80(b + c, theirs),
        );
        out.check(Check::less_than(
            "|z| McNemar, ended by q < 2.5 AU, paired by comet",
            z.abs(),
            Z_MAX,
            "McNemar's test on the discordant comets against REBOUND MERCURIUS from the same initial states, two-sided 0.27 % (module docs: its power)",
        ));
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
        let per_encounter = run.switches_per_encounter;
        out.metric(
            "ours: close encounters with a planet (inside 3 Hill radii)",
            per_encounter.encounters as f64,
        );
        out.metric(
            "ours: switches per close encounter, mean",
            per_encounter.mean(),
        );
        out.metric(
            "ours: switches per close encounter, most",
            f64::from(per_encounter.max),
        );
        out.metric("span (years)", span);
        if let Some(t) = run.resumed_from_years {
            out.metric("resumed from a checkpoint at (years)", t);
        }
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
    use symplectic::samples::SplitMix64;

    /// The quick run's (comets, MERCURIUS's q < 2.5 AU ends, discordant comets `b + c`), from
    /// its metrics (module docs, "Quick, measured").
    const QUICK_RUN_COUNTS: (usize, usize, usize) = (16_000, 403, 516);

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
    fn normal_cdf_matches_the_table() {
        // Φ(1.959964) = 0.975, Φ(−3) = 0.0013499, Φ(0) = 0.5 (Abramowitz & Stegun, Table
        // 26.1); the fit's fractional error of 1.2e-7 (Numerical Recipes) sets the tolerance.
        assert!((normal_cdf(1.959_964) - 0.975).abs() < 1e-6);
        assert!((normal_cdf(-3.0) - 0.001_349_9).abs() < 1e-7);
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-7);
    }

    #[test]
    fn mcnemar_counts_only_the_discordant_pairs() {
        // By hand: pairs (T,T), (T,F), (T,F), (F,T), (F,F): b = 2, c = 1, z = 1/√3.
        let ours = [true, true, true, false, false];
        let theirs = [true, false, false, true, false];
        let (z, b, c) = mcnemar_z(&ours, &theirs);
        assert_eq!((b, c), (2, 1));
        assert!((z - 1.0 / 3f64.sqrt()).abs() < 1e-15);
        assert_eq!(mcnemar_z(&ours, &ours).0, 0.0);
    }

    #[test]
    fn the_change_caught_at_80_percent_has_that_power() {
        // The inverse of mcnemar_power: at the shift it returns, the power is 0.8 (to the
        // 1e-6 of the quantile's six digits and the fit of normal_cdf).
        for (d, m) in [(106, 92), (237, 234), (0, 10)] {
            let x = mcnemar_change_at_80(d, m);
            assert!(
                (mcnemar_power(d, x * m as f64) - 0.8).abs() < 1e-5,
                "{d} {m}"
            );
        }
    }

    /// Uniform in `0..k` (`k ≥ 1`).
    fn below(rng: &mut SplitMix64, k: usize) -> usize {
        ((rng.uniform() * k as f64) as usize).min(k - 1)
    }

    /// `v` in a uniformly random order (Fisher–Yates).
    fn shuffled(rng: &mut SplitMix64, mut v: Vec<usize>) -> Vec<usize> {
        for i in (1..v.len()).rev() {
            v.swap(i, below(rng, i + 1));
        }
        v
    }

    /// Paired outcomes drawn from the model of [`mcnemar_power`]: `n` comets, the reference
    /// ending the first `m` by q < 2.5 AU; without a change, `d` comets discordant, each
    /// ours-only or reference-only with probability 1/2; then ours gains (`grow`) or loses
    /// `shift` comets so ended, drawn at random among its others (its own). Returns the flags
    /// (ours, reference).
    fn changed_pairs(
        rng: &mut SplitMix64,
        (n, m, d): (usize, usize, usize),
        shift: usize,
        grow: bool,
    ) -> (Vec<bool>, Vec<bool>) {
        let reference: Vec<bool> = (0..n).map(|i| i < m).collect();
        let mut ours = reference.clone();
        let pos = shuffled(rng, (0..m).collect());
        let neg = shuffled(rng, (m..n).collect());
        let only_ours = (0..d).filter(|_| below(rng, 2) == 0).count();
        neg[..only_ours].iter().for_each(|&i| ours[i] = true);
        pos[..d - only_ours].iter().for_each(|&i| ours[i] = false);
        let candidates = shuffled(rng, (0..n).filter(|&i| ours[i] != grow).collect());
        candidates[..shift].iter().for_each(|&i| ours[i] = grow);
        (ours, reference)
    }

    #[test]
    fn a_25_percent_change_fails_the_mcnemar_check_as_often_as_its_power_says() {
        // The quick run's counts (module docs: comets, MERCURIUS's q < 2.5 AU ends, b + c) and
        // the 1 Myr run's. The fraction of 2,000 draws whose McNemar |z| reaches Z_MAX is at
        // least the power mcnemar_power states (a lower bound) less three binomial standard
        // errors of that fraction (the draws' own scatter), in both directions; at the quick
        // run's counts it is at least QUICK_MIN_POWER.
        let draws = 2_000;
        let mut rng = SplitMix64::new(2027);
        for (counts, quick) in [(QUICK_RUN_COUNTS, true), ((1_000, 234, 237), false)] {
            let shift = (0.25 * counts.1 as f64).round() as usize;
            let power = mcnemar_power(counts.2, shift as f64);
            for grow in [true, false] {
                let failed = (0..draws)
                    .filter(|_| {
                        let (ours, reference) = changed_pairs(&mut rng, counts, shift, grow);
                        mcnemar_z(&ours, &reference).0.abs() >= Z_MAX
                    })
                    .count() as f64
                    / draws as f64;
                let se = (power * (1.0 - power) / draws as f64).sqrt();
                eprintln!("{counts:?} grow {grow}: fails {failed}, power at least {power:.4}");
                assert!(
                    failed >= power - 3.0 * se,
                    "{counts:?} grow {grow}: fails {failed}, power {power}"
                );
                if quick {
                    assert!(
                        failed >= QUICK_MIN_POWER,
                        "{counts:?} grow {grow}: {failed}"
                    );
                }
            }
        }
    }

    #[test]
    fn ks_statistic_is_the_largest_cdf_gap() {
        // By hand: after 1 and 2, F_a = 2/3 and F_b = 0; after 3, 1 and 1/2.
        assert_eq!(ks_statistic(&[1.0, 2.0, 3.0], &[3.0, 4.0]), 2.0 / 3.0);
        assert_eq!(ks_statistic(&[1.0, 2.0], &[1.0, 2.0]), 0.0);
    }
}
