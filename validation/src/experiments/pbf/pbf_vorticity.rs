//! `pbf-vorticity` (Macklin & Müller 2013, Fig. 5): the dam break with and without vorticity
//! confinement (eqs. 15–16), compared by splash height and kinetic energy; both final frames
//! are written as side-view images.
//!
//! The dam break (`scenes/dam_break.toml`; quick overrides in quick mode, the paper's
//! `t = 6.0 s` in full mode) is run twice with identical settings but the confinement
//! strength `ε` of eq. 16: 0 (off) and [`VORTICITY_EPSILON`]. The splash height of a frame
//! is the `y` below which 99.9 % of the particles lie (so single droplets do not count);
//! the kinetic energy is the solver's `Σ m v²/2`.

use anyhow::Result;
use sph_core::Real;
use sph_scene::{Precision, Scene, SolverSpec};

use crate::helpers::{plot_xy, side_view_png, write_csv_rows, Legend, PlotSpec, Series};
use crate::sim::{shipped_scene, SceneSim};
use crate::{Check, Context, Experiment, Outcome};

/// The experiment.
pub struct PbfVorticity;

/// Confinement strength `ε` of eq. 16 in the "on" run (m/s: the acceleration is `ε N × ω`
/// with `ω` in 1/s). The paper gives no value; this one adds a visible amount of energy
/// at the scene's resolution without making the run unstable (chosen by this project).
pub const VORTICITY_EPSILON: f64 = 0.05;
/// Fraction of the particles allowed above the splash height.
const SPLASH_QUANTILE: f64 = 1e-3;

fn quantile_y<R: Real>(positions: &[sph_core::Vec3<R>]) -> f64 {
    let mut ys: Vec<f64> = positions.iter().map(|p| p.y.as_f64()).collect();
    if ys.is_empty() {
        return f64::NAN;
    }
    let k = ((ys.len() as f64 * SPLASH_QUANTILE) as usize).max(1);
    let idx = ys.len() - k;
    *ys.select_nth_unstable_by(idx, f64::total_cmp).1
}

/// Time series of one run and its final frame for the image.
struct Run {
    /// (t, splash height m, kinetic energy J).
    series: Vec<(f64, f64, f64)>,
    /// (x, y, speed) of the final frame.
    last_frame: Vec<(f64, f64, f64)>,
    /// Positions of the final frame (for the rendered view).
    last_positions: Vec<sph_core::Vec3<f32>>,
    particles: usize,
}

fn simulate<R: Real>(ctx: &Context, scene: &Scene) -> Result<Run> {
    let mut sim = SceneSim::<R>::new(scene)?;
    let frames = scene.frame_count();
    let mut series = Vec::with_capacity(frames);
    for _ in 0..frames {
        let stats = sim.advance()?;
        series.push((
            sim.time_s,
            quantile_y(&sim.state.positions),
            stats.kinetic_energy,
        ));
        ctx.progress.inc(1);
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

fn run_with(ctx: &Context, scene: &Scene, epsilon: f64) -> Result<Run> {
    let mut scene = scene.clone();
    let SolverSpec::Pbf(pbf) = &mut scene.solver else {
        anyhow::bail!(
            "{}: the vorticity experiment needs a PBF scene, not kind = \"{}\"",
            scene.source.display(),
            scene.solver.kind_name()
        );
    };
    pbf.vorticity_epsilon = Some(epsilon);
    match scene.precision {
        Precision::F32 => simulate::<f32>(ctx, &scene),
        Precision::F64 => simulate::<f64>(ctx, &scene),
    }
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    s / n as f64
}

impl Experiment for PbfVorticity {
    fn id(&self) -> &'static str {
        "pbf-vorticity"
    }

    fn source(&self) -> &'static str {
        "Macklin & Müller (2013) Position Based Fluids, Fig. 5: dam break at t = 6.0 s with and without vorticity confinement"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let scene = shipped_scene("dam_break", ctx.mode)?;
        let frames = scene.frame_count() as u64;
        ctx.progress.set_length(2 * frames);
        let off = run_with(ctx, &scene, 0.0)?;
        let on = run_with(ctx, &scene, VORTICITY_EPSILON)?;

        let rows = off.series.iter().zip(&on.series).map(|(a, b)| {
            vec![
                format!("{:.4}", a.0),
                format!("{:.5}", a.1),
                format!("{:.5}", b.1),
                format!("{:.6e}", a.2),
                format!("{:.6e}", b.2),
            ]
        });
        write_csv_rows(
            &ctx.path("vorticity.csv"),
            &[
                "t_s",
                "splash_height_off_m",
                "splash_height_on_m",
                "kinetic_energy_off_j",
                "kinetic_energy_on_j",
            ],
            rows,
        )?;
        ctx.add_file(
            "vorticity.csv",
            "splash height and kinetic energy per frame, confinement off and on",
        );

        // The second half of the run: after the first impact on the far wall.
        let half = off.series.len() / 2;
        let ke_off = mean(off.series[half..].iter().map(|r| r.2));
        let ke_on = mean(on.series[half..].iter().map(|r| r.2));
        let splash_off = off.series[half..]
            .iter()
            .map(|r| r.1)
            .fold(f64::NEG_INFINITY, f64::max);
        let splash_on = on.series[half..]
            .iter()
            .map(|r| r.1)
            .fold(f64::NEG_INFINITY, f64::max);
        let mut out = Outcome::new();
        out.metric("particles", off.particles as f64);
        out.metric("vorticity_epsilon_m_per_s", VORTICITY_EPSILON);
        out.metric("mean_kinetic_energy_second_half_off_j", ke_off);
        out.metric("mean_kinetic_energy_second_half_on_j", ke_on);
        out.metric("max_splash_height_second_half_off_m", splash_off);
        out.metric("max_splash_height_second_half_on_m", splash_on);
        out.metric(
            "final_splash_height_off_m",
            off.series.last().map_or(f64::NAN, |r| r.1),
        );
        out.metric(
            "final_splash_height_on_m",
            on.series.last().map_or(f64::NAN, |r| r.1),
        );
        out.check(Check::greater_than(
            "kinetic energy ratio on/off (second half)",
            ke_on / ke_off,
            1.0,
            "§5 of the paper: confinement is used \"to replace lost energy\"",
        ));
        out.check(Check::greater_than(
            "max splash height ratio on/off (second half)",
            splash_on / splash_off,
            1.0,
            "Fig. 5 of the paper: \"note the visibly higher splash\" with confinement",
        ));

        let spec = |title: &str, col: fn(&(f64, f64, f64)) -> f64, y: &str| PlotSpec {
            legend: Legend::UpperRight,
            series: vec![
                Series::line(
                    "confinement off",
                    off.series.iter().map(|r| (r.0, col(r))).collect(),
                    0,
                ),
                Series::line(
                    format!("confinement on (ε = {VORTICITY_EPSILON} m/s)"),
                    on.series.iter().map(|r| (r.0, col(r))).collect(),
                    3,
                ),
            ],
            ..PlotSpec::new(title, "t (s)", y)
        };
        plot_xy(
            &ctx.path("splash_height.png"),
            &spec(
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
            &spec("Dam break: kinetic energy", |r| r.2, "kinetic energy (J)"),
        )?;
        ctx.add_plot(
            "kinetic_energy.png",
            "kinetic energy with and without vorticity confinement",
        );
        let tank = scene.tank.map_or(((0.0, 1.0), (0.0, 1.0)), |t| {
            ((t.min.x, t.max.x), (t.min.y, t.max.y))
        });
        let t_end = off.series.last().map_or(0.0, |r| r.0);
        for (name, run, label) in [("frame_off.png", &off, "off"), ("frame_on.png", &on, "on")] {
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
        for (name, run, label) in [
            ("render_off.png", &off, "off"),
            ("render_on.png", &on, "on"),
        ] {
            crate::render::render_particles_png(
                &scene,
                &run.last_positions,
                1000,
                &ctx.path(name),
            )?;
            ctx.add_plot(
                name,
                format!(
                    "final frame, confinement {label}, rendered (screen-space fluid rendering)"
                ),
            );
        }
        Ok(out)
    }
}
