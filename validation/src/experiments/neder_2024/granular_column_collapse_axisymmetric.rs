//! `granular-column-collapse-axisymmetric`: axisymmetric collapse of granular cylinders of
//! aspect ratio `a = H0/R0 ∈ {0.5, 1, 2, 4}` with the IISPH granular solver, the normalised
//! runout `(R∞ − R0)/R0` against the law of Lube, Huppert, Sparks & Hallworth (2004,
//! J. Fluid Mech. 508, 175–199): `1.24 a` for `a ≲ 1.7`, `1.6 a^(1/2)` above
//! (`reference-data/granular-column-collapse-axisymmetric/lube_2004_axisymmetric_runout_law.csv`), and the slope angles
//! of the deposits.
//!
//! The columns are built from the shipped template
//! `scenes/granular_column_collapse_axisymmetric.toml` (the `a = 1` column; its spacing,
//! friction angle 30° and boundary): a full cylinder (`[[fluid]] kind = "cylinder"`) standing
//! on the floor in the middle of a square tank, its smaller dimension `min(R0, H0)` the
//! template's radius (so that the flat and the tall columns are both resolved: Lube et al.
//! report the law as independent of the column's size); the tank's half-width
//! `R0 (1 + 1.6 r(a)) + 4 s` (`r(a)` the law's runout, so the deposit has room, as in the
//! planar experiment) and its height `H0 + 4 s`; the duration `0.5 s + 6 √(H0/g)`; the step
//! scaled so that a particle at the free-fall speed `√(2 g H0)` moves the template's fraction
//! of a spacing per step. A full cylinder rather than a quarter in a corner: a quarter needs
//! frictionless symmetry walls, and the tank's walls are no-slip.
//!
//! The runout `R∞` is the mean radius of the connected deposit's outline
//! ([`granular_measure::radial_runout`]: the largest set of particles connected by
//! steps shorter than two spacings, the outermost particle of each of 16 azimuthal sectors
//! around the column's axis, plus the particle radius, averaged), so grains thrown ahead do
//! not count. The deposit's slope is [`granular_measure::angle_of_repose`] on the
//! deposit around the same axis (the surface profile `y(r)` in bins of one spacing, fitted
//! between 20 % and 80 % of the deposit's height).
//!
//! Checks, per column: the run completes; the deposit has stopped (`R∞` moved less than one
//! spacing over the last 10 % of the run); it did not reach the tank's walls; and the
//! normalised runout lies within ±30 % of the law of its regime. The ±30 % band is this
//! project's, set before the run, the planar experiment's (see
//! [`super::granular_column_collapse`]: the material-dependent prefactor of Balmforth & Kerswell 2005,
//! one friction angle in a continuum model); Warnett et al. (2014, Granular Matter 16, 115)
//! add a dependence on `R0/d` that a continuum model does not have. The slope angles are
//! reported (metrics, `deposits.csv`, `angles.png` against the friction angle and the
//! static slope of the yield cone), not checked: the paper gives no law for them here.
//!
//! **The elastic–plastic model** (crate `elastoplastic-granular`, Bui et al. 2008) runs the
//! same columns (`elastoplastic/…` metrics, the same checks and band) as the planar
//! experiment builds them (`granular_column_collapse::elastoplastic_column`: the
//! template's friction angle with the thesis's cone, `E` = 0.584 MPa, a geostatic start,
//! walls of no-slip boundary particles; nothing periodic). Quick mode runs the `a` = 1
//! column (`ELASTOPLASTIC_QUICK`: 1,600 grains at 10 mm; the `a` = 0.5 column is four
//! times as many, its radius twice the template's), full mode all four. Its deposits' slopes
//! are metrics (`elastoplastic/a=…/deposit_slope_deg`), not in the plots, which are the
//! thesis model's.

use anyhow::{bail, Result};
use granular_measure::{
    angle_of_repose, normalised_runout, radial_runout, surface_profile, PileShape,
    RadialRunoutOptions, ReposeOptions, SurfacePoint,
};
use sph_core::Vec3;
use sph_scene::{FluidSpec, Scene, SolverSpec};

use super::granular_column_collapse::{
    band, elastoplastic_column, load_laws, plot_runout, Model, Regime, RunoutPlot, BAND,
};
use crate::helpers::{plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle};
use crate::scene_runs::{run_scene, shipped_scene, solver_error_check};
use crate::{Check, Context, Experiment, Mode, Outcome};

/// The experiment.
pub struct GranularColumnCollapseAxisymmetric;

/// The aspect ratios `a = H0/R0` run.
const ASPECT_RATIOS: [f64; 4] = [0.5, 1.0, 2.0, 4.0];
/// The shipped template scene.
const TEMPLATE: &str = "granular_column_collapse_axisymmetric";
/// The aspect ratios the elastic–plastic model runs in quick mode (full mode: all).
const ELASTOPLASTIC_QUICK: [f64; 1] = [1.0];
/// The reference law.
const LAW_FILE: &str =
    "granular-column-collapse-axisymmetric/lube_2004_axisymmetric_runout_law.csv";

/// One column: its model, its geometry and its scene.
struct Column {
    model: Model,
    a: f64,
    r0: f64,
    h0: f64,
    /// The column's axis `[x, z]` (m): the tank's centre.
    axis_xz: [f64; 2],
    /// Half the tank's width (m): the distance from the axis to the side walls.
    half_width: f64,
    scene: Scene,
}

/// What one column's run gave.
struct ColumnResult {
    runout_m: f64,
    normalised: f64,
    front_change_m: f64,
    sector_min_m: f64,
    sector_max_m: f64,
    slope_deg: Option<f64>,
    deposit_height_m: f64,
    profile: Vec<SurfacePoint>,
}

fn column(base: &Scene, a: f64, laws: &[Regime; 2]) -> Result<Column> {
    let Some(FluidSpec::Cylinder { radius, .. }) = base.fluids.first() else {
        bail!("{TEMPLATE}: the template's first fluid must be a cylinder");
    };
    let size = *radius;
    let s = base.particle_spacing;
    let g = base.gravity.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (r0, h0) = if a >= 1.0 {
        (size, a * size)
    } else {
        (size / a, size)
    };
    let (_, hi, _) = band(laws, a);
    let predicted = hi / (1.0 + BAND);
    let half_width = r0 * (1.0 + 1.6 * predicted) + 4.0 * s;
    // the template's step in spacings travelled at the free-fall speed
    let Some(h_template) = base.fluids.first().map(|f| f.bounds().extent().y) else {
        bail!("{TEMPLATE}: no fluid");
    };
    let dt_template = base.frame_dt_s / base.solver.substeps() as f64;
    let courant = (2.0 * g * h_template).sqrt() * dt_template / s;
    let substeps = (base.frame_dt_s * (2.0 * g * h0).sqrt() / (courant * s)).ceil() as i64;
    let mut scene = base.clone();
    scene.fluids = vec![FluidSpec::Cylinder {
        base_center: [half_width, 0.0, half_width],
        radius: r0,
        height: h0,
        velocity: [0.0; 3],
    }];
    scene.tank = Some(sph_core::Aabb {
        min: Vec3::zeros(),
        max: Vec3::new(2.0 * half_width, h0 + 4.0 * s, 2.0 * half_width),
    });
    scene.solver.common_mut().substeps = substeps.max(1) as usize;
    scene.duration_s = 0.5 + 6.0 * (h0 / g).sqrt();
    scene.name = format!("{TEMPLATE}_a{a}");
    scene.check()?;
    Ok(Column {
        model: Model::Thesis,
        a,
        r0,
        h0,
        axis_xz: [half_width, half_width],
        half_width,
        scene,
    })
}

/// Runout, stop and slope of one column's run (`late` = the positions at 90 % of the run).
fn measure(col: &Column, last: &[Vec3<f64>], late: Option<&[Vec3<f64>]>) -> Result<ColumnResult> {
    let s = col.scene.particle_spacing;
    let opts = RadialRunoutOptions::connected(col.axis_xz, s);
    let fin = radial_runout(last, &opts)?;
    let r_late = match late {
        Some(p) => radial_runout(p, &opts)?.radius_m,
        None => f64::NAN,
    };
    let deposit: Vec<Vec3<f64>> = fin.deposit.iter().map(|&i| last[i]).collect();
    let shape = PileShape::Conical {
        axis_xz: Some(col.axis_xz),
    };
    let repose = ReposeOptions {
        shape,
        ..ReposeOptions::conical(0.0, s)
    }
    .with_spacing(s);
    let (slope_deg, profile) = match angle_of_repose(&deposit, &repose) {
        Ok(m) => (Some(m.angle_deg), m.profile),
        Err(_) => (None, surface_profile(&deposit, shape, s)?),
    };
    let deposit_height_m = deposit.iter().map(|p| p.y).fold(0.0, f64::max) + 0.5 * s;
    let fronts = &fin.sector_fronts_m;
    Ok(ColumnResult {
        runout_m: fin.radius_m,
        normalised: normalised_runout(fin.radius_m, col.r0)?,
        front_change_m: (fin.radius_m - r_late).abs(),
        sector_min_m: fronts.iter().copied().fold(f64::INFINITY, f64::min),
        sector_max_m: fronts.iter().copied().fold(0.0, f64::max),
        slope_deg,
        deposit_height_m,
        profile,
    })
}

/// `col` with the elastic–plastic solver.
fn elastoplastic(col: &Column) -> Result<Column> {
    Ok(Column {
        model: Model::Elastoplastic,
        scene: elastoplastic_column(&col.scene, &[])?,
        ..*col
    })
}

/// The metrics' prefix of a column: `a=…`, `elastoplastic/a=…`.
fn tag(col: &Column) -> String {
    format!("{}a={}", col.model.prefix(), col.a)
}

fn checks(out: &mut Outcome, col: &Column, res: &ColumnResult, laws: &[Regime; 2]) {
    let tag = tag(col);
    let s = col.scene.particle_spacing;
    let (lo, hi, regime) = band(laws, col.a);
    out.metric(format!("{tag}/normalised_runout"), res.normalised);
    out.metric(
        format!("{tag}/deposit_slope_deg"),
        res.slope_deg.unwrap_or(f64::NAN),
    );
    out.check(Check::less_than(
        format!("{tag}/settled: R_inf change over the last 10 % (m)"),
        res.front_change_m,
        s,
        "validity: the runout is that of the deposit at rest (one spacing, the front's resolution)",
    ));
    out.check(Check::greater_than(
        format!("{tag}/front clear of the side walls (m)"),
        col.half_width - res.sector_max_m,
        2.0 * s,
        "validity: a front at a wall was stopped by it",
    ));
    out.check(Check::within(
        format!("{tag}/(R_inf - R0)/R0, {regime} regime"),
        res.normalised,
        lo,
        hi,
        "Lube et al. (2004): 1.24 a (a < 1.7), 1.6 a^(1/2) (a > 1.7); band +-30 % set a priori by this project, \
         as for the planar collapse (material-dependent prefactor, Balmforth & Kerswell 2005)",
    ));
}

fn csv_row(col: &Column, res: &ColumnResult, laws: &[Regime; 2], particles: usize) -> Vec<String> {
    let (lo, hi, regime) = band(laws, col.a);
    let slope = res.slope_deg.map_or("nan".into(), |d| format!("{d:.2}"));
    vec![
        col.model.name().to_string(),
        format!("{}", col.a),
        format!("{:.4}", col.r0),
        format!("{:.4}", col.h0),
        format!("{:.4}", res.runout_m),
        format!("{:.4}", res.normalised),
        format!("{lo:.4}"),
        format!("{hi:.4}"),
        regime.to_string(),
        format!("{:.4}", res.sector_min_m),
        format!("{:.4}", res.sector_max_m),
        format!("{:.5}", res.front_change_m),
        format!("{:.4}", res.deposit_height_m),
        slope,
        particles.to_string(),
    ]
}

/// The friction angle θ of the template and the static slope of its yield cone (degrees,
/// [`iisph_granular::ConeMatch::predicted_repose_angle_deg`]).
fn friction_and_static_slope(base: &Scene) -> (f64, f64) {
    match &base.solver {
        SolverSpec::Granular(g) => {
            let theta = g.friction_angle_deg;
            let cone = g.cone_match.unwrap_or(iisph_granular::DEFAULT_CONE_MATCH);
            (theta, cone.predicted_repose_angle_deg(theta))
        }
        _ => (f64::NAN, f64::NAN),
    }
}

impl Experiment for GranularColumnCollapseAxisymmetric {
    fn id(&self) -> &'static str {
        "granular-column-collapse-axisymmetric"
    }
    fn crates(&self) -> &'static [&'static str] {
        &[
            "iisph-granular",
            "elastoplastic-granular",
            "granular-measure",
        ]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &["granular_column_collapse_axisymmetric"]
    }

    fn source(&self) -> &'static str {
        "Lube, Huppert, Sparks & Hallworth (2004) J. Fluid Mech. 508, 175-199: runout of axisymmetric granular column collapse"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let laws = load_laws(ctx, LAW_FILE)?;
        let base = shipped_scene(TEMPLATE, ctx.mode)?;
        let mut columns: Vec<Column> = ASPECT_RATIOS
            .iter()
            .map(|&a| column(&base, a, &laws))
            .collect::<Result<_>>()?;
        let elastoplastic_columns: Vec<Column> = columns
            .iter()
            .filter(|c| ctx.mode == Mode::Full || ELASTOPLASTIC_QUICK.contains(&c.a))
            .map(elastoplastic)
            .collect::<Result<_>>()?;
        columns.extend(elastoplastic_columns);
        ctx.progress
            .set_length(columns.iter().map(|c| c.scene.frame_count() as u64).sum());
        let mut out = Outcome::new();
        let (mut rows, mut deposits) = (Vec::new(), Vec::new());
        let (mut simulated, mut simulated_elastoplastic) = (Vec::new(), Vec::new());
        for col in &columns {
            let tag = tag(col);
            let late = (col.scene.frame_count() as f64 * 0.9).round() as usize;
            let run = run_scene(ctx, &col.scene, &[late])?;
            out.metric(format!("{tag}/particles"), run.particles as f64);
            if let Some(e) = &run.blow_up {
                out.check(solver_error_check(&tag, e));
                continue;
            }
            let late_positions = run.snapshots.first().map(|(_, p)| p.as_slice());
            let res = measure(col, &run.final_positions, late_positions)?;
            checks(&mut out, col, &res, &laws);
            rows.push(csv_row(col, &res, &laws, run.particles));
            match col.model {
                Model::Thesis => {
                    simulated.push((col.a, res.normalised));
                    deposits.push((col.a, col.r0, res));
                }
                Model::Elastoplastic => simulated_elastoplastic.push((col.a, res.normalised)),
            }
        }
        write_outputs(ctx, &rows, &deposits)?;
        plot_runout(
            ctx,
            &laws,
            &[
                ("IISPH granular (θ = 30°)", &simulated),
                ("elastic–plastic (θ = 30°)", &simulated_elastoplastic),
            ],
            &RunoutPlot {
                title: "Axisymmetric granular column collapse: runout",
                x_label: "aspect ratio a = H0/R0",
                y_label: "normalised runout (R∞ − R0)/R0",
                laws: [
                    "Lube et al. 2004: 1.24 a (a < 1.7)",
                    "Lube et al. 2004: 1.6 a^(1/2) (a > 1.7)",
                ],
                caption: "normalised runout against aspect ratio, IISPH and the elastic–plastic model against both regimes of Lube et al. (2004)",
            },
        )?;
        let (theta, static_slope) = friction_and_static_slope(&base);
        plot_profiles(ctx, &deposits, static_slope)?;
        plot_angles(ctx, &deposits, theta, static_slope)?;
        out.note(format!(
            "R_inf = mean over 16 azimuthal sectors of the connected deposit's outermost particle (gaps up to 2 spacings) plus the particle radius; \
             min(R0, H0) = {} m; friction angle {theta}° (static slope of the yield cone {static_slope:.1}°) and spacing from scenes/{TEMPLATE}.toml",
            columns.first().map_or(f64::NAN, |c| c.r0.min(c.h0))
        ));
        Ok(out)
    }
}

fn write_outputs(
    ctx: &mut Context,
    rows: &[Vec<String>],
    deposits: &[(f64, f64, ColumnResult)],
) -> Result<()> {
    write_csv_rows(
        &ctx.path("runout.csv"),
        &[
            "model",
            "a",
            "R0_m",
            "H0_m",
            "runout_m",
            "normalised_runout",
            "band_lo",
            "band_hi",
            "regime",
            "sector_front_min_m",
            "sector_front_max_m",
            "runout_change_last_10pct_m",
            "deposit_height_m",
            "deposit_slope_deg",
            "particles",
        ],
        rows.to_vec(),
    )?;
    ctx.add_file(
        "runout.csv",
        "runout, deposit height and slope of each column against the band of Lube et al. (2004)",
    );
    let profile_rows = deposits.iter().flat_map(|(a, r0, res)| {
        res.profile.iter().map(move |p| {
            vec![
                format!("{a}"),
                format!("{:.5}", p.d_m),
                format!("{:.5}", p.y_m),
                format!("{:.4}", p.d_m / r0),
                format!("{:.4}", p.y_m / r0),
            ]
        })
    });
    write_csv_rows(
        &ctx.path("profiles.csv"),
        &["a", "r_m", "y_m", "r_over_R0", "y_over_R0"],
        profile_rows,
    )?;
    ctx.add_file(
        "profiles.csv",
        "free-surface profile of each deposit: the highest particle centre per radial bin of one spacing",
    );
    Ok(())
}

fn plot_profiles(
    ctx: &mut Context,
    deposits: &[(f64, f64, ColumnResult)],
    static_slope_deg: f64,
) -> Result<()> {
    let markers = [
        Marker::Circle,
        Marker::Ring,
        Marker::Cross,
        Marker::Triangle,
    ];
    let mut series: Vec<Series> = deposits
        .iter()
        .enumerate()
        .map(|(i, (a, r0, res))| {
            let pts = res
                .profile
                .iter()
                .map(|p| (p.d_m / r0, p.y_m / r0))
                .collect();
            Series::styled(
                format!("a = {a}"),
                pts,
                SeriesStyle::LineMarkers(markers[i % markers.len()]),
                i,
            )
        })
        .collect();
    // a slope of the static angle, for the eye, from the tallest deposit's outer edge
    if let Some((_, r0, res)) = deposits.last() {
        let edge = res.runout_m / r0;
        let tan = static_slope_deg.to_radians().tan();
        let top = res.deposit_height_m / r0;
        series.push(Series::styled(
            format!("slope {static_slope_deg:.1}° (static slope of the yield cone)"),
            vec![(edge - top / tan, top), (edge, 0.0)],
            SeriesStyle::Dashed,
            7,
        ));
    }
    let spec = PlotSpec {
        legend: Legend::UpperRight,
        series,
        ..PlotSpec::new(
            "Axisymmetric collapse: deposit profiles",
            "radius r/R0",
            "surface height y/R0 (particle centres)",
        )
    };
    plot_xy(&ctx.path("profiles.png"), &spec)?;
    ctx.add_plot(
        "profiles.png",
        "radial free-surface profiles of the deposits, scaled by the initial radius",
    );
    Ok(())
}

fn plot_angles(
    ctx: &mut Context,
    deposits: &[(f64, f64, ColumnResult)],
    theta_deg: f64,
    static_slope_deg: f64,
) -> Result<()> {
    let measured: Vec<(f64, f64)> = deposits
        .iter()
        .filter_map(|(a, _, r)| r.slope_deg.map(|d| (*a, d)))
        .collect();
    let series = vec![
        Series::markers("deposit slope (20–80 % fit)", measured, Marker::Circle, 0),
        Series::styled(
            format!("friction angle θ = {theta_deg}°"),
            vec![(0.5, theta_deg)],
            SeriesStyle::HorizontalLine,
            3,
        ),
        Series::styled(
            format!("static slope of the yield cone, {static_slope_deg:.1}°"),
            vec![(0.5, static_slope_deg)],
            SeriesStyle::HorizontalLine,
            2,
        ),
    ];
    let spec = PlotSpec {
        legend: Legend::LowerRight,
        series,
        x_range: Some((0.3, 6.0)),
        y_range: Some((0.0, 40.0)),
        ..PlotSpec::new(
            "Axisymmetric collapse: deposit slope angles",
            "aspect ratio a = H0/R0",
            "slope angle (degrees)",
        )
    };
    plot_xy(&ctx.path("angles.png"), &spec)?;
    ctx.add_plot(
        "angles.png",
        "slope angle of each deposit against the friction angle and the static slope of the yield cone",
    );
    Ok(())
}
