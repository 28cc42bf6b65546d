//! `granular-repose`: the angle of repose of a slumped heap against the friction angle θ of
//! the IISPH granular solver (Neder 2024: Drucker–Prager yield `‖s‖ ≤ √2 sin θ · p`, after
//! Alduán & Otaduy 2011).
//!
//! The shipped scenes `scenes/granular_repose_{20,30,40}.toml`: a planar block of granular
//! material, 0.3 m × 0.3 m in a 0.05 m deep slab, released in the middle of a 1.6 m long tank,
//! slumps into a heap. θ = 0 (the 20° scene with the friction angle set to 0) must flow flat
//! like a liquid. The settled heap's angle is measured with
//! [`iisph_granular::measure::angle_of_repose`] (planar heap, bins of one spacing, least-squares
//! fit of each flank between 20 % and 80 % of the heap height, mean of the two flanks).
//!
//! Checks, for θ = 20°, 30°, 40°:
//! - **physics**: a cohesionless Drucker–Prager slope is stable up to slope angle θ and fails
//!   beyond it, so a flank that slumped comes to rest at θ: `|measured − θ|` within the
//!   measurement's resolution (the bound [`iisph_granular::measure::ReposeMeasurement::resolution_deg`]
//!   derives from the spacing, the bin width and the fitted run);
//! - the measured angle increases with θ;
//! - validity: the heap is at rest at the end (kinetic energy below 10⁻³ of the initial
//!   potential energy) and clear of the tank's end walls (else it was not free to spread).
//!
//! For θ = 0 (no yield stress: a liquid): the material covers the whole floor (it reaches both
//! end walls) and its free surface is flat: the relief of the surface profile (highest minus
//! lowest surface particle) below half the thickness of the layer the volume would make spread
//! over the floor (a-priori bound of this project, set before the run; it leaves room for the
//! sloshing left after the run, while a heap at 20° of the same volume has a relief of several
//! layer thicknesses).

use anyhow::Result;
use iisph_granular::measure::{angle_of_repose, surface_profile, PileShape, ReposeOptions};
use sph_core::Vec3;
use sph_scene::{Scene, SolverSpec};

use super::scene_edit::shipped;
use super::{run_scene, solver_error_check, SceneRun};
use crate::helpers::{plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle};
use crate::{Check, Context, Experiment, Outcome};

/// The experiment.
pub struct GranularRepose;

/// The friction angles run (degrees) and the shipped scene each comes from (θ = 0 is the 20°
/// scene with the friction angle set to 0).
const CASES: [(f64, &str); 4] = [
    (0.0, "granular_repose_20"),
    (20.0, "granular_repose_20"),
    (30.0, "granular_repose_30"),
    (40.0, "granular_repose_40"),
];
/// Kinetic energy at the end, relative to the initial potential energy, below which the heap
/// counts as at rest.
const REST_KE_FRACTION: f64 = 1e-3;
/// Largest relief of the θ = 0 surface, as a fraction of the spread layer's thickness.
const FLAT_RELIEF_FRACTION: f64 = 0.5;

struct Case {
    theta_deg: f64,
    scene: Scene,
    run: SceneRun,
}

fn scene_for(theta_deg: f64, name: &str, ctx: &Context) -> Result<Scene> {
    let mut scene = shipped(name, ctx.mode)?;
    let SolverSpec::Granular(granular) = &mut scene.solver else {
        anyhow::bail!(
            "{}: the repose sweep needs kind = \"granular\", not \"{}\"",
            scene.source.display(),
            scene.solver.kind_name()
        );
    };
    granular.friction_angle_deg = theta_deg;
    scene.check()?;
    Ok(scene)
}

impl Experiment for GranularRepose {
    fn id(&self) -> &'static str {
        "granular-repose"
    }

    fn source(&self) -> &'static str {
        "Neder (2024) Drucker-Prager granular IISPH: a cohesionless slope is stable up to the friction angle (angle of repose = θ)"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let scenes: Vec<(f64, Scene)> = CASES
            .iter()
            .map(|&(theta, name)| Ok((theta, scene_for(theta, name, ctx)?)))
            .collect::<Result<_>>()?;
        ctx.progress
            .set_length(scenes.iter().map(|(_, s)| s.frame_count() as u64).sum());
        let mut cases = Vec::new();
        for (theta_deg, scene) in scenes {
            let run = run_scene(ctx, &scene, &[])?;
            cases.push(Case {
                theta_deg,
                scene,
                run,
            });
        }

        let mut out = Outcome::new();
        let mut rows = Vec::new();
        let mut measured_points = Vec::new();
        let mut profiles = Vec::new();
        for case in &cases {
            let theta = case.theta_deg;
            let s = case.scene.particle_spacing;
            let tank = case.scene.tank.expect("the repose scenes have a tank");
            let tag = format!("theta={theta:.0}");
            out.metric(format!("{tag}/particles"), case.run.particles as f64);
            if let Some(e) = &case.run.blow_up {
                out.check(solver_error_check(&tag, e));
                continue;
            }
            let pos = &case.run.final_positions;
            let ke_end = case
                .run
                .frames
                .last()
                .map_or(f64::NAN, |f| f.kinetic_energy_j);
            let ke_fraction = ke_end / case.run.initial_potential_energy_j;
            out.metric(format!("{tag}/final_ke_over_initial_pe"), ke_fraction);
            let x_min = pos.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
            let x_max = pos.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max);
            if let Ok(profile) = surface_profile(pos, PileShape::Planar, s) {
                profiles.push((
                    theta,
                    profile
                        .iter()
                        .map(|p| (p.d_m, p.y_m - tank.min.y))
                        .collect::<Vec<_>>(),
                ));
            }
            if theta == 0.0 {
                check_flat(&mut out, &tag, pos, &case.scene, x_min, x_max)?;
                continue;
            }
            out.check(Check::less_than(
                format!("{tag}/at rest: final KE / initial PE"),
                ke_fraction,
                REST_KE_FRACTION,
                "validity of the measurement: the heap must have stopped (10^-3 of the released potential energy, the rest bound of the solver-layer tests)",
            ));
            let clearance = (x_min - tank.min.x).min(tank.max.x - x_max);
            out.check(Check::greater_than(
                format!("{tag}/heap clear of the end walls (m)"),
                clearance,
                s,
                "validity: a heap touching the end walls was not free to spread",
            ));
            let opts = ReposeOptions::planar(tank.min.y, s).with_spacing(s);
            match angle_of_repose(pos, &opts) {
                Ok(m) => {
                    let res = m.resolution_deg.unwrap_or(f64::NAN);
                    out.metric(format!("{tag}/angle_deg"), m.angle_deg);
                    out.metric(format!("{tag}/resolution_deg"), res);
                    out.metric(format!("{tag}/heap_height_m"), m.pile_height_m);
                    out.check(Check::within(
                        format!("{tag}/measured angle of repose (deg)"),
                        m.angle_deg,
                        theta - res,
                        theta + res,
                        "physics: a cohesionless Drucker-Prager slope is stable up to slope angle = theta, \
                         so a slumped flank rests at theta; band = the measurement's resolution \
                         (1.5 delta / run of the fit, delta = spacing + bin width * tan theta)",
                    ));
                    let flank = |side: i8| {
                        m.flanks
                            .iter()
                            .find(|f| f.side == side)
                            .map_or(f64::NAN, |f| f.angle_deg)
                    };
                    rows.push(vec![
                        format!("{theta}"),
                        format!("{:.3}", m.angle_deg),
                        format!("{res:.3}"),
                        format!("{:.3}", flank(-1)),
                        format!("{:.3}", flank(1)),
                        format!("{:.4}", m.pile_height_m),
                        case.run.particles.to_string(),
                        format!("{ke_fraction:.3e}"),
                    ]);
                    measured_points.push((theta, m.angle_deg, res));
                }
                Err(e) => out.check(Check::equals(
                    format!("{tag}/heap measurable"),
                    0.0,
                    1.0,
                    format!("the measurement failed: {e}"),
                )),
            }
        }
        if measured_points.len() == 3 {
            let increasing = measured_points.windows(2).all(|w| w[1].1 > w[0].1);
            out.check(Check::equals(
                "measured angle increases with theta (20 < 30 < 40)",
                f64::from(u8::from(increasing)),
                1.0,
                "physics: a larger friction angle holds a steeper slope",
            ));
        }
        write_csv_rows(
            &ctx.path("repose.csv"),
            &[
                "theta_deg",
                "measured_deg",
                "resolution_deg",
                "left_flank_deg",
                "right_flank_deg",
                "heap_height_m",
                "particles",
                "final_ke_over_initial_pe",
            ],
            rows,
        )?;
        ctx.add_file(
            "repose.csv",
            "measured angle of repose per friction angle, with the measurement's resolution",
        );
        plot_angles(ctx, &measured_points)?;
        plot_profiles(ctx, &profiles)?;
        out.note(format!(
            "angle = mean of both flanks' least-squares slopes of the surface profile (highest particle per bin of one spacing) between 20 % and 80 % of the heap height; {} in quick mode",
            if ctx.mode == crate::Mode::Quick { "spacing 10 mm" } else { "spacing 5 mm (full)" }
        ));
        Ok(out)
    }
}

fn check_flat(
    out: &mut Outcome,
    tag: &str,
    pos: &[Vec3<f64>],
    scene: &Scene,
    x_min: f64,
    x_max: f64,
) -> Result<()> {
    let s = scene.particle_spacing;
    let tank = scene.tank.expect("the repose scenes have a tank");
    let reach = (x_min - tank.min.x).max(tank.max.x - x_max);
    out.check(Check::less_than(
        format!("{tag}/spreads over the whole floor: largest gap to an end wall (m)"),
        reach,
        2.0 * s,
        "physics: without friction there is no yield stress; the material flows until it covers the floor, like a liquid",
    ));
    let profile = surface_profile(pos, PileShape::Planar, s)?;
    let y_hi = profile
        .iter()
        .map(|p| p.y_m)
        .fold(f64::NEG_INFINITY, f64::max);
    let y_lo = profile.iter().map(|p| p.y_m).fold(f64::INFINITY, f64::min);
    let footprint = (tank.max.x - tank.min.x) * (tank.max.z - tank.min.z);
    let layer = pos.len() as f64 * s.powi(3) / footprint;
    out.metric(format!("{tag}/surface_relief_m"), y_hi - y_lo);
    out.metric(format!("{tag}/layer_thickness_m"), layer);
    out.check(Check::less_than(
        format!("{tag}/flat: surface relief / layer thickness"),
        (y_hi - y_lo) / layer,
        FLAT_RELIEF_FRACTION,
        "a-priori bound of this project: a liquid at rest is flat; half the layer thickness allows the sloshing left after the run",
    ));
    Ok(())
}

fn plot_angles(ctx: &mut Context, points: &[(f64, f64, f64)]) -> Result<()> {
    let mut series = vec![Series::styled(
        "measured = θ (Drucker–Prager: stable up to θ)",
        vec![(0.0, 0.0), (50.0, 50.0)],
        SeriesStyle::Dashed,
        7,
    )];
    series.push(Series::markers(
        "IISPH granular, settled heap",
        points.iter().map(|&(t, m, _)| (t, m)).collect(),
        Marker::Circle,
        0,
    ));
    for &(t, m, r) in points {
        series.push(Series::line("", vec![(t, m - r), (t, m + r)], 0));
    }
    let spec = PlotSpec {
        legend: Legend::UpperLeft,
        series,
        x_range: Some((0.0, 50.0)),
        y_range: Some((0.0, 50.0)),
        ..PlotSpec::new(
            "Angle of repose against friction angle (bars: measurement resolution)",
            "friction angle θ (deg)",
            "measured angle of repose (deg)",
        )
    };
    plot_xy(&ctx.path("repose.png"), &spec)?;
    ctx.add_plot(
        "repose.png",
        "measured angle of repose against the friction angle, with the identity line",
    );
    Ok(())
}

fn plot_profiles(ctx: &mut Context, profiles: &[(f64, Vec<(f64, f64)>)]) -> Result<()> {
    if profiles.is_empty() {
        return Ok(());
    }
    let series = profiles
        .iter()
        .enumerate()
        .map(|(i, (theta, pts))| Series::line(format!("θ = {theta:.0}°"), pts.clone(), i))
        .collect();
    let spec = PlotSpec {
        legend: Legend::UpperRight,
        series,
        ..PlotSpec::new(
            "Settled surface profiles",
            "x (m)",
            "height of the highest particle above the floor (m)",
        )
    };
    plot_xy(&ctx.path("profiles.png"), &spec)?;
    ctx.add_plot(
        "profiles.png",
        "free-surface profile (highest particle per bin of one spacing) of each settled run",
    );
    Ok(())
}
