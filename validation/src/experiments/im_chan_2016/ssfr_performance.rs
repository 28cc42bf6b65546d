//! `ssfr-performance`: time per frame and per stage of the screen-space renderer at
//! 1280 × 720, for 100k particles (quick and full) and 1M (full), on the threads rayon is
//! given (2 on the project's machine). The particles fill the dam break's water column
//! (0.4 × 0.8 × 0.6 m in the 1.6 × 1.0 × 0.6 m tank) on a cubic lattice, seen by the default
//! camera of `scenes/dam_break.toml`. Timings are metrics, not checks (the machine is
//! shared); the one check is that the pipeline draws every particle.

use std::time::Instant;

use anyhow::Result;
use sph_core::{sampling::cubic_lattice, Aabb, Vec3};
use ssfr_render::{FrameStats, ParticleView, Renderer};

use crate::helpers::stats::{median, spread};
use crate::helpers::write_csv_rows;
use crate::scene_runs::shipped_scene;
use crate::{Check, Context, Experiment, Outcome};
use sph_sim::render::render_params;

/// The experiment.
pub struct SsfrPerformance;

/// Frames rendered per size; the first also renders the background, the others are timed
/// (medians of the frame and of each stage are reported).
const REPEATS: usize = 11;

/// A lattice of about `n` particles filling the water column; returns positions and spacing.
pub fn column_particles(n: usize) -> Result<(Vec<Vec3<f32>>, f32)> {
    let s = (0.4f32 * 0.8 * 0.6 / n as f32).cbrt();
    let column = Aabb::new(Vec3::zeros(), Vec3::new(0.4, 0.8, 0.6))?;
    Ok((cubic_lattice(&column, s, 4 * n)?, s))
}

/// Renders `positions` `REPEATS` times at 1280x720; returns the renderer (holding the last
/// frame) and the wall time and statistics of each frame.
fn time_frames(
    ctx: &Context,
    scene: &sph_scene::Scene,
    positions: &[Vec3<f32>],
    s: f32,
) -> Result<(Renderer, Vec<(f64, FrameStats)>)> {
    let mut params = render_params(scene)?;
    params.camera.width = 1280;
    params.camera.height = 720;
    let r = ssfr_render::RADIUS_OVER_SPACING * s;
    params = ssfr_render::RenderParams {
        particle_radius_m: r,
        ..ssfr_render::RenderParams::new(params.camera, params.background, r)
    };
    let mut renderer = Renderer::default();
    let mut runs = Vec::new();
    for _ in 0..REPEATS {
        let t = Instant::now();
        let stats = renderer.render(&params, &ParticleView::spheres(positions, r))?;
        runs.push((t.elapsed().as_secs_f64(), stats));
        ctx.progress.inc(1);
    }
    Ok((renderer, runs))
}

/// Median frame and stage times (metrics; rows of `stages.csv`) and the framing check.
fn record_frames(
    out: &mut Outcome,
    label: &str,
    particles: usize,
    runs: &[(f64, FrameStats)],
    rows: &mut Vec<Vec<String>>,
) {
    // The first frame also renders the background; time the others.
    let timed = &runs[1..];
    let frame_s: Vec<f64> = timed.iter().map(|x| x.0).collect();
    out.metric(format!("{label}/frame_median_s"), median(&frame_s));
    out.metric(format!("{label}/frame_spread_s"), spread(&frame_s));
    let last = runs[runs.len() - 1].1;
    let background_s = runs[0].1.times.background_s;
    out.metric(format!("{label}/background_s"), background_s);
    for (k, (stage, _)) in last.times.stages().into_iter().enumerate() {
        let secs = if stage == "background" {
            background_s
        } else {
            let stage_s: Vec<f64> = timed.iter().map(|x| x.1.times.stages()[k].1).collect();
            let m = median(&stage_s);
            out.metric(format!("{label}/{stage}_s"), m);
            out.metric(format!("{label}/{stage}_spread_s"), spread(&stage_s));
            m
        };
        rows.push(vec![
            particles.to_string(),
            stage.to_string(),
            format!("{secs:.6}"),
        ]);
    }
    out.metric(
        format!("{label}/splat_pixel_tests"),
        last.splat_pixel_tests as f64,
    );
    out.metric(format!("{label}/liquid_pixels"), last.liquid_pixels as f64);
    out.check(Check::equals(
        format!("{label}: particles drawn"),
        last.particles_drawn as f64,
        particles as f64,
        "the default camera frames the whole tank (definition of the framing)",
    ));
}

impl Experiment for SsfrPerformance {
    fn id(&self) -> &'static str {
        "ssfr-performance"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["ssfr-render"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &["dam_break"]
    }

    fn source(&self) -> &'static str {
        "Im & Chan (2016) §V (real-time rendering): time per frame and per stage at 1280x720, 100k and 1M particles, CPU"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let sizes: Vec<usize> = ctx.mode.pick(vec![100_000], vec![100_000, 1_000_000]);
        ctx.progress.set_length((sizes.len() * REPEATS) as u64);
        let scene = shipped_scene("dam_break", crate::Mode::Full)?;
        let mut out = Outcome::new();
        let mut rows = Vec::new();
        out.metric("threads", rayon::current_num_threads() as f64);
        for &n in &sizes {
            let (positions, s) = column_particles(n)?;
            let (renderer, runs) = time_frames(ctx, &scene, &positions, s)?;
            let label = format!("{}k", positions.len() / 1000);
            record_frames(&mut out, &label, positions.len(), &runs, &mut rows);
            renderer
                .image()
                .write_png(&ctx.path(&format!("frame_{label}.png")))?;
            ctx.add_plot(
                &format!("frame_{label}.png"),
                format!("the timed frame, {} particles", positions.len()),
            );
        }
        write_csv_rows(
            &ctx.path("stages.csv"),
            &["particles", "stage", "seconds"],
            rows,
        )?;
        ctx.add_file(
            "stages.csv",
            "seconds per stage: median over the timed frames (background: the first frame)",
        );
        out.note(format!(
            "{} rayon threads; median of {} frames after the first (which also renders the background); the machine may be shared, timings are not asserted",
            rayon::current_num_threads(),
            REPEATS - 1
        ));
        Ok(out)
    }
}
