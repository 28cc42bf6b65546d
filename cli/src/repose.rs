//! `particles repose DIR`: the angle of repose of the last (or a given) frame of a scene
//! run, measured with [`granular_measure::angle_of_repose`] (`--shape funnel`: a conical heap
//! on the scene's circular base, per azimuthal sector,
//! [`granular_measure::cone_angle_by_sector`]), and whether the heap is at rest by
//! [`granular_measure::rest`]'s criterion judged over the run's frames up to it (the last
//! second of them and the speeds' hold under way), with by how much it misses; any granular
//! scene's output can be measured, not only the experiment's.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use granular_measure::{
    angle_of_repose, cone_angle_by_sector, flank_layer_stress, ConeBase, ConeOptions, FlankLayers,
    PileShape, ReposeMeasurement, ReposeOptions,
};
use sph_core::Vec3;
use sph_sim::observe::RestCriterion;
use sph_sim::vtk::FrameRead;
use sph_sim::{RunDir, Scene};

use crate::render::scene_of_run;

/// The shape of the heap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Shape {
    /// A planar (2.5D) heap, its profile taken along x.
    Planar,
    /// An axisymmetric pile around the particles' centroid.
    Conical,
    /// A conical heap on a circular base, the scene's first solid cylinder (the funnel
    /// method's fixed base): the generatrix per azimuthal sector, its mean and spread
    /// (`granular_measure::cone_angle_by_sector`). As a rest shape (`run --until-rest`):
    /// a conical pile around the centroid.
    Funnel,
}

impl Shape {
    /// The pile shape of `granular-measure` (a conical pile around the particles' centroid).
    pub fn pile(self) -> PileShape {
        match self {
            Shape::Planar => PileShape::Planar,
            Shape::Conical | Shape::Funnel => PileShape::Conical { axis_xz: None },
        }
    }
}

/// Arguments of `particles repose`.
#[derive(Debug, clap::Args)]
pub struct ReposeArgs {
    /// The run's output directory.
    dir: PathBuf,
    /// The frame to measure [default: the last `frame_*.vtk` in DIR].
    #[arg(long, value_name = "FILE")]
    frame: Option<PathBuf>,
    /// Planar heap (profile along x), conical pile, or a conical heap on the scene's
    /// circular base measured per azimuthal sector.
    #[arg(long, value_enum, default_value = "planar")]
    shape: Shape,
    /// The scene file [default: the one recorded by `run` in DIR].
    #[arg(long, value_name = "PATH")]
    scene: Option<PathBuf>,
    /// With --scene: apply its `[quick]` overrides.
    #[arg(long)]
    quick: bool,
    /// Also print the stress of the flanks' layers in the slope's axes (a planar heap of a
    /// solver that writes a `stress` field, e.g. the elastic–plastic one): for the surface
    /// layer and the layer 2–5 spacings deep, between 20 % and 80 % of the heap's height,
    /// the medians of the normal-stress difference along the slope, the mobilised friction
    /// on the slope-parallel plane, √J2/p, the speed down the slope and the pressure
    /// (`granular_measure::flank`).
    #[arg(long)]
    layers: bool,
}

/// Measures the frame and prints the angle, the flanks and the resolution, then the rest
/// verdict. The floor is the scene tank's bottom (or y = 0 without a tank); the bins are
/// one particle spacing wide.
pub fn run(a: &ReposeArgs) -> Result<()> {
    let run = RunDir::new(&a.dir);
    let scene = scene_of_run(&run, a.scene.as_deref(), a.quick)?;
    let frames = run.frames()?;
    let file = match &a.frame {
        Some(f) => f.clone(),
        None => frames
            .last()
            .map(|(_, p)| p.clone())
            .with_context(|| format!("{}: no frame_*.vtk to measure", a.dir.display()))?,
    };
    let frame = sph_sim::vtk::read_particle_frame(&file)?;
    let positions = &frame.positions;
    let s = scene.particle_spacing;
    let floor = scene.tank.map_or(0.0, |t| t.min.y);
    let shape = a.shape.pile();
    if a.shape == Shape::Funnel {
        anyhow::ensure!(
            !a.layers,
            "--layers measures a planar heap's flanks (give --shape planar)"
        );
        print_funnel(&scene, positions, &file)?;
    } else {
        print_pile(a, &frame, &file, floor, s)?;
    }
    // The frames of DIR up to the measured one.
    let upto = frames.iter().position(|(_, p)| same_file(p, &file));
    match upto {
        Some(i) => {
            print_rest(&scene, shape, &frames[..=i])?;
            let verdict = a.dir.join(sph_sim::rest_log::REST_VERDICT_FILE);
            if i + 1 == frames.len() && verdict.is_file() {
                let text = std::fs::read_to_string(&verdict)
                    .with_context(|| format!("reading {}", verdict.display()))?;
                let summary = text
                    .lines()
                    .find_map(|l| l.trim().strip_prefix("\"summary\": "))
                    .map(|l| l.trim_end_matches(',').trim_matches('"').to_string())
                    .unwrap_or_else(|| "unreadable".into());
                println!(
                    "the run's own verdict (run --until-rest, judged every frame, {}): {summary}",
                    verdict.display()
                );
            }
        }
        None => println!(
            "rest: not judged ({} is not one of {}'s frames)",
            file.display(),
            a.dir.display()
        ),
    }
    Ok(())
}

/// The planar or conical measure of the frame: the angle, the flanks and the resolution,
/// and with `--layers` the flanks' layers.
fn print_pile(a: &ReposeArgs, frame: &FrameRead, file: &Path, floor: f64, s: f64) -> Result<()> {
    let positions = &frame.positions;
    let opts = match a.shape {
        Shape::Planar => ReposeOptions::planar(floor, s),
        _ => ReposeOptions::conical(floor, s),
    }
    .with_spacing(s);
    let m = angle_of_repose(positions, &opts)
        .with_context(|| format!("measuring {}", file.display()))?;
    println!(
        "{}: angle of repose {:.2}° (resolution ±{:.2}°), pile height {:.4} m, {} particles",
        file.display(),
        m.angle_deg,
        m.resolution_deg.unwrap_or(f64::NAN),
        m.pile_height_m,
        positions.len()
    );
    for f in &m.flanks {
        println!(
            "  flank {}: {:.2}° over {:.4} m ({} surface points, rms residual {:.4} m)",
            if f.side < 0 { "left " } else { "right" },
            f.angle_deg,
            f.run_m,
            f.points,
            f.rms_residual_m
        );
    }
    if a.layers {
        anyhow::ensure!(
            a.shape == Shape::Planar,
            "--layers measures a planar heap's flanks (give --shape planar)"
        );
        print_layers(frame, file, s, floor, &m)?;
    }
    Ok(())
}

/// Azimuthal sectors of `--shape funnel`.
const FUNNEL_SECTORS: usize = 12;

/// `--shape funnel`: the heap on the scene's first solid cylinder, per azimuthal sector.
fn print_funnel(scene: &Scene, positions: &[Vec3<f32>], file: &Path) -> Result<()> {
    let (centre, radius_m) = scene
        .solids
        .iter()
        .find_map(sph_scene::SolidSpec::cylinder_top)
        .with_context(|| {
            format!(
                "--shape funnel: {} has no solid cylinder (the heap's base)",
                scene.source.display()
            )
        })?;
    let base = ConeBase::on_disc(centre, radius_m);
    let opts = ConeOptions::new(base, FUNNEL_SECTORS, scene.particle_spacing);
    let m = cone_angle_by_sector(positions, &opts)
        .with_context(|| format!("measuring {}", file.display()))?;
    println!(
        "{}: angle of repose {:.2}° (mean over {} of {FUNNEL_SECTORS} sectors; std {:.2}°, {:.2}–{:.2}°), height {:.4} m on the base of radius {} m, {} of {} particles on it",
        file.display(),
        m.mean_deg,
        m.fitted,
        m.std_deg,
        m.min_deg,
        m.max_deg,
        m.height_m,
        base.radius_m,
        m.grains_on_base,
        positions.len()
    );
    for s in &m.sectors {
        let angle = s
            .angle_deg
            .map_or_else(|| "not fitted".into(), |a| format!("{a:.2}°"));
        println!(
            "  sector {:.0}–{:.0}°: {angle} ({} surface points over {:.4} m)",
            s.azimuth_deg[0], s.azimuth_deg[1], s.points, s.run_m
        );
    }
    Ok(())
}

/// Prints the flanks' layers' stress ([`flank_layer_stress`]) at the measured slope.
fn print_layers(
    frame: &FrameRead,
    file: &Path,
    spacing_m: f64,
    floor_y: f64,
    m: &ReposeMeasurement,
) -> Result<()> {
    let stress = frame.stress.as_ref().with_context(|| {
        format!(
            "{}: the frame has no stress field (--layers needs a solver that carries one, kind = \"elastoplastic\")",
            file.display()
        )
    })?;
    let velocities = frame
        .velocities
        .as_ref()
        .with_context(|| format!("{}: the frame has no velocities", file.display()))?;
    let f64s = |v: &[Vec3<f32>]| -> Vec<Vec3<f64>> { v.iter().map(|p| p.cast()).collect() };
    let stress: Vec<[f64; 6]> = stress.iter().map(|t| t.map(f64::from)).collect();
    let mut opts = FlankLayers::new(spacing_m, m.angle_deg, floor_y);
    opts.apex_x_m = Some(m.apex_d_m);
    let layers = flank_layer_stress(&f64s(&frame.positions), &f64s(velocities), &stress, &opts)?;
    for l in layers {
        println!(
            "  layer {:.0}-{:.0} spacings deep: {} grains, dN {:+.3}, tau/sigma_n {:.3}, sqrt(J2)/p {:.3}, v_down {:.4} m/s, p {:.0} Pa",
            l.depth_spacings.0.max(0.0),
            l.depth_spacings.1.floor(),
            l.grains,
            l.normal_stress_difference,
            l.shear_over_normal,
            l.sqrt_j2_over_pressure,
            l.downslope_speed_m_s,
            l.pressure_pa
        );
    }
    Ok(())
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// Judges the rest criterion over `frames` (the last one the measured frame): the frames of
/// the criterion's windows and of the speeds' hold under way, read from the last back, and
/// prints the verdict with each quantity's bound and miss.
fn print_rest(scene: &Scene, shape: PileShape, frames: &[(usize, PathBuf)]) -> Result<()> {
    let criterion = RestCriterion {
        shape,
        ..RestCriterion::default()
    };
    let settings = criterion.settings;
    let window = settings.speed_hold_s.max(settings.angle_window_s);
    let tank_floor = scene.tank.as_ref().map(|t| t.min.y);
    let bound = criterion.speed_bound_m_s(scene.gravity, scene.particle_spacing)?;
    // Read back from the last frame: every frame of the windows and one before (which says
    // they are covered), then on while the speeds stay below the bound (the hold under way).
    let mut samples = Vec::new();
    let mut t_last = None;
    for (n, path) in frames.iter().rev() {
        let f = sph_sim::vtk::read_particle_frame(path)?;
        let velocities = f.velocities.with_context(|| {
            format!(
                "{}: the frame has no velocities, so the rest criterion cannot be judged",
                path.display()
            )
        })?;
        let t = f.time_s.unwrap_or(*n as f64 * scene.frame_dt_s);
        let sample = criterion.sample(
            &f.positions,
            &velocities,
            scene.particle_spacing,
            tank_floor,
            t,
        )?;
        let t_end = *t_last.get_or_insert(t);
        let in_window = t >= t_end - window - 1e-9;
        let slow = sample.percentile_speed_m_s < bound && sample.deep_max_speed_m_s < bound;
        samples.push(sample);
        if !in_window && !slow {
            break;
        }
    }
    samples.reverse();
    let v = granular_measure::judge_rest(&samples, bound, &settings)?;
    println!(
        "rest: {} (judged over {} frames from t = {:.3} s)",
        v.summary(&settings),
        samples.len(),
        samples.first().map_or(f64::NAN, |s| s.time_s)
    );
    for (name, unit, margin) in v.margins() {
        println!(
            "  {name}: {:.4} {unit} against {:.4} {unit}: {}",
            margin.value,
            margin.bound,
            if margin.passes() {
                "passes".to_string()
            } else {
                format!("misses by {:.4} {unit}", margin.misses_by())
            }
        );
    }
    println!(
        "  speeds held {:.3} s of {} s; angle window covered {:.3} s of {} s",
        v.speeds_held_s, settings.speed_hold_s, v.angle_window_covered_s, settings.angle_window_s
    );
    Ok(())
}
