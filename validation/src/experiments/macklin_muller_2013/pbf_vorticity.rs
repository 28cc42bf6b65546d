//! `pbf-vorticity` (Macklin & Müller 2013, Fig. 5): the dam break with and without vorticity
//! confinement (eqs. 15–16), compared by splash height and kinetic energy; both final frames
//! are written as side-view images.
//!
//! The dam break (`scenes/dam_break.toml`; quick overrides in quick mode, the paper's
//! `t = 6.0 s` in full mode) is run with identical settings but the confinement strength `ε`
//! of eq. 16: 0 (off), [`VORTICITY_EPSILON`] (on), and `−`[`VORTICITY_EPSILON`] (the negative
//! control: the reversed force must lower what the confinement raises). Two more runs with
//! `ε = 0` start from positions perturbed by [`PERTURBATION_M`] (uniform in each coordinate,
//! fixed seeds): a dam break is chaotic, and the spread of their results against the
//! unperturbed run is the noise floor the on/off gap has to exceed.
//!
//! Per frame: the splash height, the `y` below which 99.9 % of the particles lie (so single
//! droplets do not count); the kinetic energy `Σ m v²/2` (the solver's); and the enstrophy
//! `½ Σ_i (m_i/ρ0) |ω_i|²` with the SPH vorticity `ω_i = Σ_j (m_j/ρ0) (v_j − v_i) × ∇W_ij`
//! (Spiky gradient over the neighbours within `h`, computed here, independently of the
//! solver), the quantity the confinement force exists to restore (§5, eqs. 15–16). Each is
//! compared over the second half of the run, after the first impact on the far wall.

use anyhow::Result;
use sph_core::Real;
use sph_scene::{Scene, SolverSpec};
use sph_sim::observe::OnFrame;
use sph_sim::{Flow, FrameRecord};

use crate::helpers::{
    plot_xy, side_view_png, write_csv_rows, Legend, PlotSpec, Series, SeriesStyle,
};
use crate::scene_runs::{advance_frames, scene_sim, shipped_scene, SceneSim};
use crate::{Check, Context, Experiment, Outcome};

/// The experiment.
pub struct PbfVorticity;

/// Confinement strength `ε` of eq. 16 in the "on" run (m/s: the acceleration is `ε N × ω`
/// with `ω` in 1/s). The paper gives no value; this one adds a visible amount of energy
/// at the scene's resolution without making the run unstable (chosen by this project).
pub const VORTICITY_EPSILON: f64 = 0.05;
/// Fraction of the particles allowed above the splash height.
const SPLASH_QUANTILE: f64 = 1e-3;
/// Amplitude of the initial-position perturbation of the noise-floor runs (m).
pub const PERTURBATION_M: f64 = 1e-6;
/// Seeds of the noise-floor runs.
const NOISE_SEEDS: [u64; 2] = [1, 2];
/// How many times the noise floor the on/off gap must exceed ("clearly": a gap of one noise
/// floor is what two unperturbed-equivalent runs already show).
const NOISE_MULTIPLE: f64 = 3.0;

/// Enstrophy `½ Σ_i (m_i/ρ0) |ω_i|²` (m³/s²) with the SPH vorticity
/// `ω_i = Σ_j (m_j/ρ0) (v_j − v_i) × ∇W_ij` (Spiky gradient, support `h`).
fn enstrophy<R: Real>(
    state: &pbf::ParticleSet<R>,
    h: f64,
    rho0: f64,
    lists: &mut neighbour_search::NeighbourLists,
) -> Result<f64> {
    use sph_kernels::{Kernel, KernelKind};
    let spiky = KernelKind::Spiky.build(h)?;
    let mut search = neighbour_search::Method::CellStartGrid.build::<R>();
    search.search(&state.positions, R::of_f64(h), lists)?;
    let (x, v, m) = (&state.positions, &state.velocities, &state.masses);
    let mut total = 0.0;
    for i in 0..state.len() {
        let mut w = [0.0f64; 3];
        for &j in lists.neighbours(i) {
            let j = j as usize;
            if j == i {
                continue;
            }
            let d = [
                (x[i].x - x[j].x).as_f64(),
                (x[i].y - x[j].y).as_f64(),
                (x[i].z - x[j].z).as_f64(),
            ];
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if r <= 0.0 || r >= h {
                continue;
            }
            let g = spiky.derivative(r).as_f64() / r;
            let grad = [g * d[0], g * d[1], g * d[2]];
            let dv = [
                (v[j].x - v[i].x).as_f64(),
                (v[j].y - v[i].y).as_f64(),
                (v[j].z - v[i].z).as_f64(),
            ];
            let vol = m[j].as_f64() / rho0;
            w[0] += vol * (dv[1] * grad[2] - dv[2] * grad[1]);
            w[1] += vol * (dv[2] * grad[0] - dv[0] * grad[2]);
            w[2] += vol * (dv[0] * grad[1] - dv[1] * grad[0]);
        }
        total += 0.5 * m[i].as_f64() / rho0 * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    }
    Ok(total)
}

fn quantile_y<R: Real>(positions: &[sph_core::Vec3<R>]) -> f64 {
    let mut ys: Vec<f64> = positions.iter().map(|p| p.y.as_f64()).collect();
    if ys.is_empty() {
        return f64::NAN;
    }
    let k = ((ys.len() as f64 * SPLASH_QUANTILE) as usize).max(1);
    let idx = ys.len() - k;
    *ys.select_nth_unstable_by(idx, f64::total_cmp).1
}

/// One frame of a run: (t s, splash height m, kinetic energy J, enstrophy m³/s²).
type Frame = (f64, f64, f64, f64);
/// A column of [`Frame`].
type Column = fn(&Frame) -> f64;

/// Time series of one run and its final frame for the image.
struct Run {
    /// (t, splash height m, kinetic energy J, enstrophy m³/s²; the enstrophy is NaN in the
    /// first half, where it is not computed).
    series: Vec<Frame>,
    /// (x, y, speed) of the final frame.
    last_frame: Vec<(f64, f64, f64)>,
    /// Positions of the final frame (for the rendered view).
    last_positions: Vec<sph_core::Vec3<f32>>,
    particles: usize,
}

fn simulate<R: Real>(ctx: &Context, scene: &Scene, perturb_seed: Option<u64>) -> Result<Run> {
    let mut sim = scene_sim::<R>(scene)?;
    if let Some(seed) = perturb_seed {
        let mut rng = crate::helpers::SplitMix64::new(seed);
        for p in sim.state.positions.iter_mut() {
            for k in 0..3 {
                p[k] += R::of_f64(rng.range(-PERTURBATION_M, PERTURBATION_M));
            }
        }
    }
    let h = sim.solver().common().support_radius.as_f64();
    let rho0 = sim.solver().common().rest_density.as_f64();
    let mut lists = neighbour_search::NeighbourLists::new();
    let frames = scene.frame_count();
    let mut series = Vec::with_capacity(frames);
    let mut failed = None;
    let mut measure = OnFrame(|sim: &SceneSim<R>, r: &FrameRecord| {
        let k = r.frame - 1;
        let ens = if k >= frames / 2 {
            match enstrophy(&sim.state, h, rho0, &mut lists) {
                Ok(e) => e,
                Err(e) => {
                    failed = Some(e);
                    return Flow::Stop("the enstrophy could not be measured".into());
                }
            }
        } else {
            f64::NAN
        };
        series.push((
            sim.time_s,
            quantile_y(&sim.state.positions),
            r.kinetic_energy_j,
            ens,
        ));
        Flow::Continue
    });
    advance_frames(ctx, &mut sim, frames, &mut [&mut measure])?;
    if let Some(e) = failed {
        return Err(e);
    }
    let last_frame = sim
        .state
        .positions
        .iter()
        .zip(&sim.state.velocities)
        .map(|(p, v)| (p.x.as_f64(), p.y.as_f64(), v.norm().as_f64()))
        .collect();
    let last_positions = sim
        .state
        .positions
        .iter()
        .map(|p| p.map(|x| x.as_f64() as f32))
        .collect();
    Ok(Run {
        series,
        last_frame,
        last_positions,
        particles: sim.state.len(),
    })
}

fn run_with(ctx: &Context, scene: &Scene, epsilon: f64, perturb_seed: Option<u64>) -> Result<Run> {
    let mut scene = scene.clone();
    let SolverSpec::Pbf(pbf) = &mut scene.solver else {
        anyhow::bail!(
            "{}: the vorticity experiment needs a PBF scene, not kind = \"{}\"",
            scene.source.display(),
            scene.solver.kind_name()
        );
    };
    pbf.vorticity_epsilon = Some(epsilon);
    sph_sim::with_precision!(scene.precision, R => simulate::<R>(ctx, &scene, perturb_seed))
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    s / n as f64
}

/// The runs of the experiment: confinement off, on, reversed, and the perturbed "off" runs
/// that measure the noise floor.
struct Runs {
    off: Run,
    on: Run,
    negative: Run,
    noise: Vec<Run>,
}

impl Runs {
    fn simulate(ctx: &Context, scene: &Scene) -> Result<Self> {
        Ok(Self {
            off: run_with(ctx, scene, 0.0, None)?,
            on: run_with(ctx, scene, VORTICITY_EPSILON, None)?,
            negative: run_with(ctx, scene, -VORTICITY_EPSILON, None)?,
            noise: NOISE_SEEDS
                .iter()
                .map(|&seed| run_with(ctx, scene, 0.0, Some(seed)))
                .collect::<Result<Vec<_>>>()?,
        })
    }
}

fn write_series(ctx: &mut Context, runs: &Runs) -> Result<()> {
    let Runs {
        off, on, negative, ..
    } = runs;
    let rows = (0..off.series.len()).map(|k| {
        let mut row = vec![format!("{:.4}", off.series[k].0)];
        for run in [off, on, negative] {
            let r = run.series[k];
            row.push(format!("{:.5}", r.1));
            row.push(format!("{:.6e}", r.2));
            row.push(format!("{:.6e}", r.3));
        }
        row
    });
    write_csv_rows(
        &ctx.path("vorticity.csv"),
        &[
            "t_s",
            "splash_height_off_m",
            "kinetic_energy_off_j",
            "enstrophy_off_m3_per_s2",
            "splash_height_on_m",
            "kinetic_energy_on_j",
            "enstrophy_on_m3_per_s2",
            "splash_height_negative_m",
            "kinetic_energy_negative_j",
            "enstrophy_negative_m3_per_s2",
        ],
        rows,
    )?;
    ctx.add_file(
        "vorticity.csv",
        "splash height, kinetic energy and enstrophy per frame: confinement off, on, and reversed (negative control); enstrophy over the second half only",
    );
    Ok(())
}

/// A compared quantity: (name, metric key, column, max (else mean), origin of the check).
type Quantity = (&'static str, &'static str, Column, bool, &'static str);

const QUANTITIES: [Quantity; 3] = [
    (
        "kinetic energy",
        "mean_kinetic_energy_second_half",
        |r| r.2,
        false,
        "§5 of the paper: confinement is used \"to replace lost energy\"",
    ),
    (
        "max splash height",
        "max_splash_height_second_half",
        |r| r.1,
        true,
        "Fig. 5 of the paper: \"note the visibly higher splash\" with confinement",
    ),
    (
        "enstrophy",
        "mean_enstrophy_second_half",
        |r| r.3,
        false,
        "§5, eqs. 15–16: the confinement force adds rotational energy where numerical damping removed it, i.e. restores vorticity",
    ),
];

/// Maximum or mean of a column over the second half of a run: after the first impact on
/// the far wall.
fn second_half(run: &Run, col: Column, max: bool) -> f64 {
    let half = run.series.len() / 2;
    let v = run.series[half..].iter().map(col);
    if max {
        v.fold(f64::NEG_INFINITY, f64::max)
    } else {
        mean(v)
    }
}

/// On/off and negative/off ratios of `q` against the noise floor.
fn check_quantity(out: &mut Outcome, runs: &Runs, q: Quantity) {
    let (what, key, col, max, origin) = q;
    let second = |run: &Run| second_half(run, col, max);
    let base = second(&runs.off);
    let ratio_on = second(&runs.on) / base;
    let ratio_neg = second(&runs.negative) / base;
    let noise = runs
        .noise
        .iter()
        .map(|r| (second(r) / base - 1.0).abs())
        .fold(0.0, f64::max);
    out.metric(format!("{key}_off"), base);
    out.metric(format!("{key}_on"), second(&runs.on));
    out.metric(format!("{key}_negative"), second(&runs.negative));
    out.metric(format!("{what} ratio on/off"), ratio_on);
    out.metric(format!("{what} ratio negative/off"), ratio_neg);
    out.metric(format!("{what} noise floor |perturbed/off - 1|"), noise);
    out.check(Check::greater_than(
        format!("{what}: (ratio on/off - 1) over the noise floor"),
        (ratio_on - 1.0) / noise,
        NOISE_MULTIPLE,
        format!("{origin}; the gap must exceed {NOISE_MULTIPLE} times the spread of two runs with eps = 0 started {PERTURBATION_M} m apart (a dam break is chaotic)"),
    ));
    out.check(Check::less_than(
        format!("{what}: ratio negative/off (negative control)"),
        ratio_neg,
        1.0,
        "the reversed confinement force (eps < 0) takes rotational energy out: if the on/off gap comes from eq. 16 and not from noise, the reversed force lowers the quantity",
    ));
}

/// A time-series plot of one column, every run.
fn series_spec(runs: &Runs, title: &str, col: Column, y: &str) -> PlotSpec {
    let pts = |run: &Run| {
        run.series
            .iter()
            .map(|r| (r.0, col(r)))
            .filter(|p| p.1.is_finite())
            .collect::<Vec<_>>()
    };
    let mut series = vec![
        Series::line("confinement off", pts(&runs.off), 0),
        Series::line(
            format!("confinement on (ε = {VORTICITY_EPSILON} m/s)"),
            pts(&runs.on),
            3,
        ),
        Series::styled(
            format!("reversed (ε = −{VORTICITY_EPSILON} m/s)"),
            pts(&runs.negative),
            SeriesStyle::Dashed,
            2,
        ),
    ];
    for (k, r) in runs.noise.iter().enumerate() {
        series.push(Series::styled(
            format!(
                "off, start perturbed by {PERTURBATION_M} m (seed {})",
                NOISE_SEEDS[k]
            ),
            pts(r),
            SeriesStyle::Line,
            7 + k,
        ));
    }
    PlotSpec {
        legend: Legend::UpperRight,
        series,
        ..PlotSpec::new(title, "t (s)", y)
    }
}

fn plot_series(ctx: &mut Context, runs: &Runs) -> Result<()> {
    plot_xy(
        &ctx.path("splash_height.png"),
        &series_spec(
            runs,
            "Dam break: splash height",
            |r| r.1,
            "99.9 % quantile of y (m)",
        ),
    )?;
    ctx.add_plot(
        "splash_height.png",
        "splash height with and without vorticity confinement",
    );
    plot_xy(
        &ctx.path("kinetic_energy.png"),
        &series_spec(
            runs,
            "Dam break: kinetic energy",
            |r| r.2,
            "kinetic energy (J)",
        ),
    )?;
    ctx.add_plot(
        "kinetic_energy.png",
        "kinetic energy with and without vorticity confinement",
    );
    plot_xy(
        &ctx.path("enstrophy.png"),
        &series_spec(
            runs,
            "Dam break: enstrophy (second half)",
            |r| r.3,
            "enstrophy 1/2 sum (m/rho0) |omega|^2 (m^3/s^2)",
        ),
    )?;
    ctx.add_plot(
        "enstrophy.png",
        "enstrophy over the second half with and without vorticity confinement",
    );
    Ok(())
}

/// The final frames of the off and on runs: side views and renders.
fn plot_frames(ctx: &mut Context, scene: &Scene, runs: &Runs) -> Result<()> {
    let (off, on) = (&runs.off, &runs.on);
    let tank = scene.tank.map_or(((0.0, 1.0), (0.0, 1.0)), |t| {
        ((t.min.x, t.max.x), (t.min.y, t.max.y))
    });
    let t_end = off.series.last().map_or(0.0, |r| r.0);
    for (name, run, label) in [("frame_off.png", off, "off"), ("frame_on.png", on, "on")] {
        side_view_png(
            &ctx.path(name),
            &format!("Dam break at t = {t_end:.2} s, vorticity confinement {label}"),
            &run.last_frame,
            tank.0,
            tank.1,
            3.0,
            1000,
        )?;
        ctx.add_plot(
            name,
            format!("final frame, confinement {label} (side view, colour = speed up to 3 m/s)"),
        );
    }
    for (name, run, label) in [("render_off.png", off, "off"), ("render_on.png", on, "on")] {
        sph_sim::render::render_particles_png(scene, &run.last_positions, 1000, &ctx.path(name))?;
        ctx.add_plot(
            name,
            format!("final frame, confinement {label}, rendered (screen-space fluid rendering)"),
        );
    }
    Ok(())
}

impl Experiment for PbfVorticity {
    fn id(&self) -> &'static str {
        "pbf-vorticity"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["pbf", "ssfr-render"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &["dam_break"]
    }

    fn source(&self) -> &'static str {
        "Macklin & Müller (2013) Position Based Fluids, Fig. 5: dam break at t = 6.0 s with and without vorticity confinement"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let scene = shipped_scene("dam_break", ctx.mode)?;
        let frames = scene.frame_count() as u64;
        let n_runs = 3 + NOISE_SEEDS.len();
        ctx.progress.set_length(n_runs as u64 * frames);
        ctx.progress.set_message(format!("frames of {n_runs} runs"));
        let runs = Runs::simulate(ctx, &scene)?;
        write_series(ctx, &runs)?;

        let mut out = Outcome::new();
        out.metric("particles", runs.off.particles as f64);
        out.metric("vorticity_epsilon_m_per_s", VORTICITY_EPSILON);
        out.metric("perturbation_m", PERTURBATION_M);
        for q in QUANTITIES {
            check_quantity(&mut out, &runs, q);
        }
        out.metric(
            "final_splash_height_off_m",
            runs.off.series.last().map_or(f64::NAN, |r| r.1),
        );
        out.metric(
            "final_splash_height_on_m",
            runs.on.series.last().map_or(f64::NAN, |r| r.1),
        );
        plot_series(ctx, &runs)?;
        plot_frames(ctx, &scene, &runs)?;
        Ok(out)
    }
}
