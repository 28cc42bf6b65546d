//! `granular-funnel-heap`: the angle of repose as a laboratory measures it, on a conical heap
//! of the elastic–plastic granular model of Bui, H. H., Fukagawa, R., Sako, K. & Ohno, S.
//! (2008), *Int. J. Numer. Anal. Meth. Geomech.* 32(12), 1537–1570, doi:10.1002/nag.688
//! (crate `elastoplastic-granular`), poured from a funnel onto a circular base (the
//! fixed-base funnel method of ISO 4324:1977 and ASTM C1444-00), in 3D with no slab and no
//! periodic axis, against the slope its yield cone predicts for a flank formed by flowing,
//! `tan β = 3 α_φ` (`ConeMatch::predicted_repose_angle_deg`: `β = θ` under the simple-shear
//! match).
//!
//! **Formation** (`scenes/granular_heap_funnel.toml`): the base is a pedestal, a solid
//! cylinder of radius `R` = 0.3 m standing on the tank's floor with a no-slip top, so that
//! grains reaching its rim fall off into the moat around it, as in the laboratory, and the
//! heap is bounded by the base, not by the volume poured. The funnel is a square box 0.1 m
//! wide centred over the axis, following the heap's top ([`sph_solver::Pour`]: each layer
//! one spacing above the highest landed grain under it, as the funnel is held just above the
//! growing heap). Each case pours [`POUR_OVER_CONE`] times the volume of the cone its
//! prediction stands on the base, `π R³ tan β / 3`, so that the base fills to its rim.
//!
//! **Rest** ([`granular_measure::rest`], judged on the frames after the last layer) on the
//! grains on the base only (at or above its top, within a spacing of its radius): the moat's
//! grains are not the heap's. The heap's drift is taken on the conical angle about the axis.
//!
//! **Measure** ([`granular_measure::cone_angle_by_sector`]): the generatrix fitted from the
//! crest outward between 20 % and 80 % of the heap's height in each of [`SECTORS`] azimuthal
//! sectors; the mean over azimuth against the prediction within [`TOLERANCE_DEG`] (the band
//! of the issue that asked for the experiment), the standard deviation and range over
//! azimuth reported.
//!
//! **Cases**: θ = 20°, 30° and 40°, in full mode only ([`thetas`]), at the scene's spacing
//! (12.5 mm, `R` = 24 spacings, 6,848–15,808 grains poured). Quick mode runs none: at the
//! scene's quick spacing (25 mm, `R` = 12 spacings) the base is not resolved — the 20° heap
//! (4.4 spacings high as predicted) collapses to a mound at 8.47°, the 40° one stands at
//! 43.2° still moving at the 20 s cap, and the 30° ones at 28.5–29.4° scatter by 2.8–3.5°
//! over azimuth (2026-12-06, `docs/elastoplastic-granular.md`, "The funnel heap"): a quick
//! 30° case alone would pass or fail by the resolution, not by the model. At 12.5 mm the 30°
//! heap stood at 26.94° with the funnel's feed at 0.4 m/s per area, and at 28.72° with the
//! slab heaps' 0.12 m/s, the 40° one at 37.45° and 32.89° (one pour each: the feed is not
//! the cause); the hoop strain of the cone's outward flow lowers
//! the prediction by 0.3–1° (`docs/notebooks/elastoplastic-granular.md`, "A conical flank
//! under radial outflow"), which the band does not absorb: a miss is reported as it is.
//! The issue asks for 2·10⁴ grains in quick mode and 10⁵ in full; those sizes wait for the
//! solver's speed. One pour each: the pour-to-pour scatter of the slab heaps (±1.2–1.5°,
//! `docs/elastoplastic-granular.md`) is not measured here for the cone.

use std::f64::consts::PI;

use anyhow::{Context as _, Result};
use elastoplastic_granular::ConeMatch;
use granular_measure::{cone_angle_by_sector, ConeBase, ConeMeasurement, ConeOptions};
use sph_core::{Aabb, Vec3};
use sph_scene::{Scene, SolidSpec, SolverSpec};

use crate::helpers::repose::{check_completed, check_rest, rest_settings, run_heap, HeapRun};
use crate::helpers::{plot_xy, write_csv_rows, Legend, PlotSpec, Series, SeriesStyle};
use crate::scene_runs::{shipped_scene, RestCriterion};
use crate::{Check, Context, Experiment, Mode, Outcome};

/// The shipped scene.
pub const SCENE: &str = "granular_heap_funnel";
/// Band on the azimuth-mean angle (degrees): the ±1.5° the issue asks of the 3D heap.
pub const TOLERANCE_DEG: f64 = 1.5;
/// Azimuthal sectors of the measure.
pub const SECTORS: usize = 12;
/// The volume poured over the volume of the predicted cone on the base.
pub const POUR_OVER_CONE: f64 = 1.3;
/// The match of every case: its predicted angle is θ.
const CONE: ConeMatch = ConeMatch::SimpleShear;

/// The experiment.
pub struct GranularFunnelHeap;

impl Experiment for GranularFunnelHeap {
    fn id(&self) -> &'static str {
        "granular-funnel-heap"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["elastoplastic-granular", "granular-measure"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &[SCENE]
    }
    fn source(&self) -> &'static str {
        "Bui, Fukagawa, Sako & Ohno (2008) elastic-plastic SPH: a conical heap poured from a funnel onto a circular base (ISO 4324, ASTM C1444), its generatrix per azimuthal sector against the cone's repose slope tan(beta) = 3 alpha_phi = tan(theta) (simple-shear match)"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let thetas = thetas(ctx.mode);
        let scenes = thetas
            .iter()
            .map(|&t| scene_for(t, ctx.mode))
            .collect::<Result<Vec<_>>>()?;
        ctx.progress
            .set_length(scenes.iter().map(|s| s.frame_count() as u64).sum());
        let mut out = Outcome::new();
        let mut rows = Vec::new();
        let mut profiles = Vec::new();
        for (&theta, scene) in thetas.iter().zip(scenes) {
            let base = base_of(&scene)?;
            let tag = format!("theta={theta:.0}");
            let criterion = rest_criterion(&scene, base, theta);
            let case = run_heap(ctx, tag, theta, scene, criterion, None, |_| Vec::new())?;
            if let Some(m) = judge(&mut out, &case, base, &criterion) {
                rows.extend(sector_rows(theta, &m));
                profiles.push((theta, m));
            }
        }
        write_csv_rows(
            &ctx.path("sectors.csv"),
            &[
                "theta_deg",
                "sector_from_deg",
                "sector_to_deg",
                "angle_deg",
                "points",
                "run_m",
                "rms_residual_m",
            ],
            rows,
        )?;
        ctx.add_file(
            "sectors.csv",
            "per case and azimuthal sector: the generatrix angle fitted from the crest outward between 20 % and 80 % of the heap's height (empty when not fitted), its points, radial run and residual",
        );
        for (theta, m) in &profiles {
            plot_profiles(ctx, *theta, m)?;
        }
        out.note(format!(
            "conical heaps of the elastic-plastic model poured from a funnel 0.1 m wide following the heap's top onto a pedestal of radius 0.3 m (no-slip top, grains fall off its rim), {POUR_OVER_CONE} x the predicted cone's volume; rest on the grains on the base; angle = mean over {SECTORS} azimuthal sectors of the generatrix fitted from the crest outward between 20 % and 80 % of the height; {}",
            match ctx.mode {
                Mode::Quick => "quick: no case (25 mm does not resolve the base; module docs)",
                Mode::Full => "full: spacing 12.5 mm (R = 24 spacings)",
            }
        ));
        Ok(out)
    }
}

/// The friction angles (degrees) `mode` runs: none in quick mode (module documentation).
pub fn thetas(mode: Mode) -> &'static [f64] {
    mode.pick(&[], &[20.0, 30.0, 40.0])
}

/// The shipped scene for `mode` with the friction angle `theta_deg` and the pour's volume
/// [`POUR_OVER_CONE`] times the predicted cone's on the base.
pub fn scene_for(theta_deg: f64, mode: Mode) -> Result<Scene> {
    let mut scene = shipped_scene(SCENE, mode)?;
    let radius = base_of(&scene)?.radius_m;
    let SolverSpec::Elastoplastic(e) = &mut scene.solver else {
        anyhow::bail!("{}: not the elastoplastic solver", scene.source.display());
    };
    e.friction_angle_deg = theta_deg;
    e.cone_match = Some(CONE);
    let predicted = CONE.predicted_repose_angle_deg(theta_deg);
    let pour = scene
        .pour
        .as_mut()
        .with_context(|| format!("{}: no [pour]", scene.source.display()))?;
    pour.volume_m3 = POUR_OVER_CONE * PI * radius.powi(3) * predicted.to_radians().tan() / 3.0;
    scene.check()?;
    Ok(scene)
}

/// The base: the scene's first solid cylinder (its top disc).
pub fn base_of(scene: &Scene) -> Result<ConeBase> {
    scene
        .solids
        .iter()
        .find_map(SolidSpec::cylinder_top)
        .map(|(centre, radius_m)| ConeBase::on_disc(centre, radius_m))
        .with_context(|| {
            format!(
                "{}: a funnel heap stands on a solid cylinder (the base)",
                scene.source.display()
            )
        })
}

/// The rest criterion on the grains on the base: at or above its top, within a spacing of
/// its radius; the angle's drift on the conical angle about its axis.
fn rest_criterion(scene: &Scene, base: ConeBase, theta_deg: f64) -> RestCriterion {
    let reach = base.radius_m + scene.particle_spacing;
    let [cx, cz] = base.centre_xz;
    RestCriterion {
        settings: rest_settings(theta_deg),
        region: Some(Aabb {
            min: Vec3::new(cx - reach, base.top_y, cz - reach),
            max: Vec3::new(cx + reach, f64::MAX, cz + reach),
        }),
        shape: granular_measure::PileShape::Conical {
            axis_xz: Some(base.centre_xz),
        },
        floor_y: Some(base.top_y),
    }
}

/// The checks of one case; its measurement when it can be measured.
fn judge(
    out: &mut Outcome,
    case: &HeapRun,
    base: ConeBase,
    criterion: &RestCriterion,
) -> Option<ConeMeasurement> {
    check_completed(out, case)?;
    let tag = &case.tag;
    out.check(Check::equals(
        format!("{tag}/every layer poured before the cap"),
        f64::from(u8::from(case.run.pour_finished)),
        1.0,
        format!(
            "definition of the heap: the whole pour ({} grains at this spacing) in {} s",
            case.scene.poured_grains(),
            case.scene.duration_s
        ),
    ));
    check_rest(out, case, criterion);
    let s = case.scene.particle_spacing;
    let m = match cone_angle_by_sector(
        &case.run.final_positions,
        &ConeOptions::new(base, SECTORS, s),
    ) {
        Ok(m) => m,
        Err(e) => {
            out.check(Check::equals(
                format!("{tag}/heap measurable"),
                0.0,
                1.0,
                format!("the measurement failed: {e}"),
            ));
            return None;
        }
    };
    let spilled = case.run.final_positions.len() - m.grains_on_base;
    out.metric(format!("{tag}/grains_on_base"), m.grains_on_base as f64);
    out.metric(format!("{tag}/grains_fallen_off"), spilled as f64);
    out.metric(format!("{tag}/height_m"), m.height_m);
    out.metric(format!("{tag}/sectors_fitted"), m.fitted as f64);
    out.metric(format!("{tag}/angle_std_over_azimuth_deg"), m.std_deg);
    out.metric(format!("{tag}/angle_min_over_azimuth_deg"), m.min_deg);
    out.metric(format!("{tag}/angle_max_over_azimuth_deg"), m.max_deg);
    out.check(Check::greater_than(
        format!("{tag}/the heap filled its base: grains fallen over the rim"),
        spilled as f64,
        0.0,
        "definition of the fixed-base method (ISO 4324, ASTM C1444): the heap grows until grains fall off the base's rim, so that it is bounded by the base and not by the volume poured",
    ));
    let predicted = CONE.predicted_repose_angle_deg(case.theta_deg);
    out.metric(format!("{tag}/predicted_deg"), predicted);
    out.metric(format!("{tag}/angle_deg"), m.mean_deg);
    out.check(Check::within(
        format!("{tag}/azimuth-mean angle of repose (deg) against atan(3 alpha_phi) = {predicted:.1}"),
        m.mean_deg,
        predicted - TOLERANCE_DEG,
        predicted + TOLERANCE_DEG,
        format!(
            "physics: a flank formed by flowing at zero dilatancy comes to rest at tan(beta) = 3 alpha_phi ({} match; docs/elastoplastic-granular.md); band ±{TOLERANCE_DEG}° the issue's for the 3D heap; over azimuth: std {:.2}°, {:.2}–{:.2}° ({} of {SECTORS} sectors fitted)",
            CONE.name(),
            m.std_deg,
            m.min_deg,
            m.max_deg,
            m.fitted
        ),
    ));
    Some(m)
}

/// The rows of `sectors.csv` for one case.
fn sector_rows(theta: f64, m: &ConeMeasurement) -> Vec<Vec<String>> {
    m.sectors
        .iter()
        .map(|s| {
            vec![
                format!("{theta:.0}"),
                format!("{:.1}", s.azimuth_deg[0]),
                format!("{:.1}", s.azimuth_deg[1]),
                s.angle_deg.map_or_else(String::new, |a| format!("{a:.3}")),
                s.points.to_string(),
                format!("{:.4}", s.run_m),
                format!("{:.5}", s.rms_residual_m),
            ]
        })
        .collect()
}

/// `profiles_theta=N.png`: each sector's surface profile (height above the base against the
/// radius) and the predicted generatrix through the rim.
fn plot_profiles(ctx: &mut Context, theta: f64, m: &ConeMeasurement) -> Result<()> {
    let top = m
        .sectors
        .iter()
        .flat_map(|s| s.profile.iter())
        .map(|p| p.y_m)
        .fold(f64::NEG_INFINITY, f64::max);
    let base_y = top - m.height_m;
    let mut series: Vec<Series> = m
        .sectors
        .iter()
        .enumerate()
        .map(|(k, s)| {
            Series::line(
                format!(
                    "{:.0}–{:.0}°: {}",
                    s.azimuth_deg[0],
                    s.azimuth_deg[1],
                    s.angle_deg
                        .map_or_else(|| "not fitted".into(), |a| format!("{a:.1}°"))
                ),
                s.profile.iter().map(|p| (p.d_m, p.y_m - base_y)).collect(),
                k % 8,
            )
        })
        .collect();
    let predicted = CONE.predicted_repose_angle_deg(theta);
    let r_max = m
        .sectors
        .iter()
        .flat_map(|s| s.profile.iter())
        .map(|p| p.d_m)
        .fold(0.0, f64::max);
    series.push(Series::styled(
        format!(
            "predicted {predicted:.1}° (mean measured {:.1}° ± {:.1}°)",
            m.mean_deg, m.std_deg
        ),
        vec![(0.0, r_max * predicted.to_radians().tan()), (r_max, 0.0)],
        SeriesStyle::Dashed,
        0,
    ));
    let file = format!("profiles_theta={theta:.0}.png");
    let spec = PlotSpec {
        legend: Legend::UpperRight,
        series,
        ..PlotSpec::new(
            format!("Funnel heap, theta = {theta:.0}°: surface profile per azimuthal sector"),
            "radius from the axis (m)",
            "height above the base (m)",
        )
    };
    plot_xy(&ctx.path(&file), &spec)?;
    ctx.add_plot(
        &file,
        "the highest grain per radial bin in each azimuthal sector, and the predicted generatrix",
    );
    Ok(())
}
