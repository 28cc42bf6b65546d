//! `granular-column-collapse`: planar collapse of granular columns of aspect ratio
//! `a = H0/L0 ∈ {0.5, 1, 2, 4, 7}` with the IISPH granular solver, the normalised runout
//! `(L∞ − L0)/L0` against the law of Lube, Huppert, Sparks & Freundt (2005, Phys. Rev. E 72,
//! 041301): `1.2 a` for `a < 1.8`, `1.9 a^(2/3)` for `a > 2.8`
//! (`reference-data/granular-column-collapse/lube_2005_runout_law.csv`).
//!
//! The columns are built from the shipped template `scenes/granular_column_collapse.toml`
//! (the `a = 2` column; its spacing, friction angle 30°, slab depth and boundary): a block
//! `[0, L0] × [0, a L0]` against the end wall `x = 0`; the tank `L0 (1 + 1.6 r(a)) + 4 s` long
//! (`r(a)` the law's runout, so the deposit has room) and `a L0 + 4 s` high; the duration
//! `0.5 s + 6 √(H0/g)` (the collapse takes a few free-fall times `√(H0/g)`); the step scaled so
//! that a particle at the free-fall speed `√(2 g H0)` moves the template's fraction of a
//! spacing per step.
//!
//! The runout `L∞` is the front of the connected deposit
//! ([`granular_measure::runout()`], `FrontMethod::ConnectedBulk` with gaps up to two
//! spacings, plus the particle radius), so grains thrown ahead do not count.
//!
//! Checks, per column: the run completes; the deposit has stopped (the front moved less than
//! one spacing over the last 10 % of the run); it did not reach the far wall; and the
//! normalised runout lies within ±30 % of the law of its regime (for `1.8 < a < 2.8`, between
//! 70 % of the linear law and 130 % of the power law). The ±30 % band is this project's,
//! set before the run: Lube et al.'s scatter is not tabulated here, and Balmforth & Kerswell
//! (2005) find the prefactor material dependent; a continuum Drucker–Prager model with one
//! friction angle is not expected to do better than that spread.
//!
//! **The elastic–plastic model** (crate `elastoplastic-granular`, Bui et al. 2008) runs the
//! same columns (`elastoplastic/…` metrics, the same checks and band): the template's
//! friction angle with the thesis's cone (`cone_match = "plane-strain"`, `α_φ = sin θ/3`, the
//! cone of `‖s‖_F ≤ √2 sin θ p`), `E` = 0.584 MPa (a tenth of Bui's aluminium bars, as the
//! repose heaps), a geostatic start, no-slip walls of boundary particles (a base at least as
//! rough as the grains: the deposit slides on a layer of grains, its basal friction the
//! internal one), periodic across the slab (plane strain without side walls). Quick mode
//! runs the `a` = 0.5 column only (its cost: explicit steps of `0.46 h/c_p`, `c_p` the P-wave speed), full
//! mode all five. Measured once in quick mode at `a` = 2 (10 mm): the normalised runout is
//! 4.55 with no-slip walls and 4.20 with Coulomb walls `μ_w = tan θ`, above the band's
//! 3.92 (docs/elastoplastic-granular.md).

use anyhow::{bail, Result};
use elastoplastic_granular::{
    Axis, ConeMatch, ElastoplasticSettings, InitialStress, PeriodicSetting,
};
use granular_measure::{normalised_runout, runout, RunoutOptions};
use sph_scene::{BoundaryModel, FluidSpec, InitialMasses, Scene, SolverSpec, WallModel};

use crate::helpers::{
    load_reference_csv, plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle,
};
use crate::scene_runs::{run_scene, set_block_and_tank, shipped_scene, solver_error_check};
use crate::{Check, Context, Experiment, Mode, Outcome};

/// The experiment.
pub struct GranularColumnCollapse;

/// The aspect ratios `a = H0/L0` run.
const ASPECT_RATIOS: [f64; 5] = [0.5, 1.0, 2.0, 4.0, 7.0];
/// Relative band around the law of each regime (this project's, set a priori; see the module
/// documentation). Shared with the axisymmetric collapse.
pub(super) const BAND: f64 = 0.3;
/// The shipped template scene.
const TEMPLATE: &str = "granular_column_collapse";
/// The aspect ratios the elastic–plastic model runs in quick mode (full mode: all).
const ELASTOPLASTIC_QUICK: [f64; 1] = [0.5];
/// Young's modulus of the elastic–plastic columns (Pa): the repose heaps' (a tenth of Bui
/// et al. 2008's aluminium bars, so that the explicit step is √10 longer; the elastic
/// settlement of a 0.7 m column, `ρ0 g H0 / E`, stays below 2.5 %).
const ELASTOPLASTIC_YOUNGS_MODULUS_PA: f64 = 5.84e5;

/// One regime of a runout law: `coefficient · a^exponent` for `a_min ≤ a ≤ a_max`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Regime {
    pub(super) a_min: f64,
    pub(super) a_max: f64,
    pub(super) coefficient: f64,
    pub(super) exponent: f64,
}

impl Regime {
    pub(super) fn at(&self, a: f64) -> f64 {
        self.coefficient * a.powf(self.exponent)
    }
}

/// The band `[lo, hi]` of the normalised runout at `a`, and the regime's name.
pub(super) fn band(laws: &[Regime; 2], a: f64) -> (f64, f64, &'static str) {
    let [linear, power] = laws;
    if a <= linear.a_max {
        let v = linear.at(a);
        (v * (1.0 - BAND), v * (1.0 + BAND), "linear")
    } else if a >= power.a_min {
        let v = power.at(a);
        (v * (1.0 - BAND), v * (1.0 + BAND), "power")
    } else {
        (
            linear.at(a) * (1.0 - BAND),
            power.at(a) * (1.0 + BAND),
            "transition",
        )
    }
}

fn column_scene(base: &Scene, a: f64, laws: &[Regime; 2]) -> Result<Scene> {
    let Some(FluidSpec::Block { min, max, .. }) = base.fluids.first() else {
        bail!("{TEMPLATE}: the template's first fluid must be a block");
    };
    let s = base.particle_spacing;
    let l0 = max[0] - min[0];
    let depth = max[2] - min[2];
    let h0_template = max[1] - min[1];
    let g = base.gravity.iter().map(|x| x * x).sum::<f64>().sqrt();
    let h0 = a * l0;
    let (_, hi, _) = band(laws, a);
    let predicted = hi / (1.0 + BAND);
    let length = l0 * (1.0 + 1.6 * predicted) + 4.0 * s;
    // the template's step in spacings travelled at the free-fall speed
    let dt_template = base.frame_dt_s / base.solver.substeps() as f64;
    let courant = (2.0 * g * h0_template).sqrt() * dt_template / s;
    let substeps = (base.frame_dt_s * (2.0 * g * h0).sqrt() / (courant * s)).ceil() as i64;
    let duration = 0.5 + 6.0 * (h0 / g).sqrt();
    let mut scene = base.clone();
    set_block_and_tank(
        &mut scene,
        [0.0, 0.0, 0.0],
        [l0, h0, depth],
        [0.0, 0.0, 0.0],
        [length, h0 + 4.0 * s, depth],
    );
    scene.solver.common_mut().substeps = substeps.max(1) as usize;
    scene.duration_s = duration;
    scene.name = format!("{TEMPLATE}_a{a}");
    scene.check()?;
    Ok(scene)
}

/// `column` with the elastic–plastic solver (see the module docs): the template's friction
/// angle, the thesis's cone, walls of no-slip boundary particles, a geostatic start, and
/// periodic across the tank along each of `periodic_axes` (`[Axis::Z]`: plane strain).
pub(super) fn elastoplastic_column(column: &Scene, periodic_axes: &[Axis]) -> Result<Scene> {
    let SolverSpec::Granular(granular) = &column.solver else {
        bail!("{TEMPLATE}: the template must be a granular scene");
    };
    let Some(tank) = column.tank else {
        bail!("{TEMPLATE}: the template needs a tank");
    };
    let theta = granular.friction_angle_deg;
    let mut common = granular.common.clone();
    common.substeps = 1;
    let mut settings =
        <ElastoplasticSettings as sph_solver::SolverSettings>::with_common(common, 1);
    settings.friction_angle_deg = theta;
    settings.cone_match = Some(ConeMatch::PlaneStrain);
    settings.youngs_modulus = Some(ELASTOPLASTIC_YOUNGS_MODULUS_PA);
    settings.initial_stress = Some(InitialStress::Geostatic);
    let mut scene = column.clone();
    scene.solver = SolverSpec::Elastoplastic(settings);
    scene.boundary.periodic = periodic_axes
        .iter()
        .map(|&axis| {
            let k = axis.index();
            PeriodicSetting {
                axis,
                lo: tank.min[k],
                hi: tank.max[k],
            }
        })
        .collect();
    scene.boundary.model = BoundaryModel::Particles;
    scene.boundary.initial_masses = InitialMasses::Lattice;
    scene.walls.tank = Some(WallModel::NoSlip);
    scene.name = format!("{}_elastoplastic", column.name);
    scene.check()?;
    Ok(scene)
}

/// The two regimes (`linear`, `power`) of the runout law in the reference file `file`
/// (columns `regime, a_min, a_max, coefficient, exponent`).
pub(super) fn load_laws(ctx: &Context, file: &str) -> Result<[Regime; 2]> {
    let table = load_reference_csv(
        ctx,
        file,
        &["regime", "a_min", "a_max", "coefficient", "exponent"],
    )?;
    let get = |name: &str| -> Result<Regime> {
        let row = table.find(&[("regime", name)])?;
        Ok(Regime {
            a_min: table.number(row, "a_min")?,
            a_max: table.number(row, "a_max")?,
            coefficient: table.number(row, "coefficient")?,
            exponent: table.number(row, "exponent")?,
        })
    };
    Ok([get("linear")?, get("power")?])
}

impl Experiment for GranularColumnCollapse {
    fn id(&self) -> &'static str {
        "granular-column-collapse"
    }
    fn crates(&self) -> &'static [&'static str] {
        &[
            "iisph-granular",
            "elastoplastic-granular",
            "granular-measure",
        ]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &["granular_column_collapse"]
    }

    fn source(&self) -> &'static str {
        "Lube, Huppert, Sparks & Freundt (2005) Phys. Rev. E 72, 041301: runout of 2D granular column collapse"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let laws = load_laws(ctx, "granular-column-collapse/lube_2005_runout_law.csv")?;
        let base = shipped_scene(TEMPLATE, ctx.mode)?;
        let mut scenes: Vec<(Model, f64, Scene)> = ASPECT_RATIOS
            .iter()
            .map(|&a| Ok((Model::Thesis, a, column_scene(&base, a, &laws)?)))
            .collect::<Result<_>>()?;
        let elastoplastic: Vec<(Model, f64, Scene)> = scenes
            .iter()
            .filter(|(_, a, _)| ctx.mode == Mode::Full || ELASTOPLASTIC_QUICK.contains(a))
            .map(|(_, a, s)| {
                Ok((
                    Model::Elastoplastic,
                    *a,
                    elastoplastic_column(s, &[Axis::Z])?,
                ))
            })
            .collect::<Result<_>>()?;
        scenes.extend(elastoplastic);
        ctx.progress
            .set_length(scenes.iter().map(|(_, _, s)| s.frame_count() as u64).sum());
        let mut out = Outcome::new();
        let mut rows = Vec::new();
        let mut simulated = Vec::new();
        let mut simulated_elastoplastic = Vec::new();
        for (model, a, scene) in &scenes {
            let a = *a;
            let s = scene.particle_spacing;
            let Some(FluidSpec::Block { max, .. }) = scene.fluids.first() else {
                bail!("column scene without its block");
            };
            let l0 = max[0];
            let tank_length = scene.tank.map_or(f64::NAN, |t| t.max.x);
            let frames = scene.frame_count();
            let late = (frames as f64 * 0.9).round() as usize;
            let run = run_scene(ctx, scene, &[late])?;
            let tag = format!("{}a={a}", model.prefix());
            out.metric(format!("{tag}/particles"), run.particles as f64);
            if let Some(e) = &run.blow_up {
                out.check(solver_error_check(&tag, e));
                continue;
            }
            let opts = RunoutOptions::connected(0.0, s);
            let l_inf = runout(&run.final_positions, &opts)?;
            let l_late = match run.snapshots.first() {
                Some((_, p)) => runout(p, &opts)?,
                None => f64::NAN,
            };
            let r = normalised_runout(l_inf, l0)?;
            let (lo, hi, regime) = band(&laws, a);
            out.metric(format!("{tag}/normalised_runout"), r);
            out.check(Check::less_than(
                format!("{tag}/settled: front change over the last 10 % (m)"),
                (l_inf - l_late).abs(),
                s,
                "validity: the runout is that of the deposit at rest (one spacing, the front's resolution)",
            ));
            out.check(Check::greater_than(
                format!("{tag}/front clear of the far wall (m)"),
                tank_length - l_inf,
                2.0 * s,
                "validity: a front at the far wall was stopped by it",
            ));
            out.check(Check::within(
                format!("{tag}/(L_inf - L0)/L0, {regime} regime"),
                r,
                lo,
                hi,
                "Lube et al. (2005): 1.2 a (a < 1.8), 1.9 a^(2/3) (a > 2.8); band +-30 % set a priori by this project \
                 (material-dependent prefactor, Balmforth & Kerswell 2005); transition: between the two laws' bands",
            ));
            rows.push(vec![
                model.name().to_string(),
                format!("{a}"),
                format!("{l0}"),
                format!("{:.4}", a * l0),
                format!("{l_inf:.4}"),
                format!("{r:.4}"),
                format!("{lo:.4}"),
                format!("{hi:.4}"),
                regime.to_string(),
                run.particles.to_string(),
                format!("{:.5}", (l_inf - l_late).abs()),
            ]);
            match model {
                Model::Thesis => simulated.push((a, r)),
                Model::Elastoplastic => simulated_elastoplastic.push((a, r)),
            }
        }
        write_csv_rows(
            &ctx.path("runout.csv"),
            &[
                "model",
                "a",
                "L0_m",
                "H0_m",
                "runout_m",
                "normalised_runout",
                "band_lo",
                "band_hi",
                "regime",
                "particles",
                "front_change_last_10pct_m",
            ],
            rows,
        )?;
        ctx.add_file(
            "runout.csv",
            "runout of each column against the band of Lube et al. (2005)",
        );
        plot_runout(
            ctx,
            &laws,
            &[
                ("IISPH granular (θ = 30°)", &simulated),
                ("elastic–plastic (θ = 30°)", &simulated_elastoplastic),
            ],
            &RunoutPlot {
                title: "Granular column collapse: runout",
                x_label: "aspect ratio a = H0/L0",
                y_label: "normalised runout (L∞ − L0)/L0",
                laws: [
                    "Lube et al. 2005: 1.2 a (a < 1.8)",
                    "Lube et al. 2005: 1.9 a^(2/3) (a > 2.8)",
                ],
                caption: "normalised runout against aspect ratio, IISPH and the elastic–plastic model against both regimes of Lube et al. (2005)",
            },
        )?;
        out.note(format!(
            "front = connected deposit (gaps up to 2 spacings) plus the particle radius; L0 = {} m; friction angle and spacing from scenes/{TEMPLATE}.toml",
            match base.fluids.first() {
                Some(FluidSpec::Block { min, max, .. }) => max[0] - min[0],
                _ => f64::NAN,
            }
        ));
        Ok(out)
    }
}

/// Which model ran a column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Model {
    /// The thesis's IISPH granular solver (the shipped template).
    Thesis,
    /// The elastic–plastic solver ([`elastoplastic_column`]).
    Elastoplastic,
}

impl Model {
    pub(super) fn name(self) -> &'static str {
        match self {
            Model::Thesis => "iisph-granular",
            Model::Elastoplastic => "elastoplastic",
        }
    }
    /// The prefix of its metrics (none for the thesis's, as before).
    pub(super) fn prefix(self) -> &'static str {
        match self {
            Model::Thesis => "",
            Model::Elastoplastic => "elastoplastic/",
        }
    }
}

/// The labels of a runout plot.
pub(super) struct RunoutPlot {
    pub(super) title: &'static str,
    pub(super) x_label: &'static str,
    pub(super) y_label: &'static str,
    /// The legend of the linear and the power regime.
    pub(super) laws: [&'static str; 2],
    pub(super) caption: &'static str,
}

/// `runout.png`: the simulated normalised runouts `(a, r)` of each model `(label, points)`
/// over both regimes of `laws` and their ±[`BAND`] bands, log–log.
pub(super) fn plot_runout(
    ctx: &mut Context,
    laws: &[Regime; 2],
    models: &[(&str, &[(f64, f64)])],
    labels: &RunoutPlot,
) -> Result<()> {
    let [linear, power] = *laws;
    let curve = |law: Regime, lo: f64, hi: f64, scale: f64| -> Vec<(f64, f64)> {
        (0..=40)
            .map(|i| {
                let a = lo * (hi / lo).powf(i as f64 / 40.0);
                (a, scale * law.at(a))
            })
            .collect()
    };
    let (a_lo, a_hi) = (0.3, 10.0);
    let lin_hi = linear.a_max.min(a_hi);
    let pow_lo = power.a_min.max(a_lo);
    let series = vec![
        Series::line(labels.laws[0], curve(linear, a_lo, lin_hi, 1.0), 3),
        Series::line(labels.laws[1], curve(power, pow_lo, a_hi, 1.0), 2),
        Series::styled(
            "±30 % band",
            curve(linear, a_lo, lin_hi, 1.0 + BAND),
            SeriesStyle::Dashed,
            3,
        ),
        Series::styled(
            "",
            curve(linear, a_lo, lin_hi, 1.0 - BAND),
            SeriesStyle::Dashed,
            3,
        ),
        Series::styled(
            "",
            curve(power, pow_lo, a_hi, 1.0 + BAND),
            SeriesStyle::Dashed,
            2,
        ),
        Series::styled(
            "",
            curve(power, pow_lo, a_hi, 1.0 - BAND),
            SeriesStyle::Dashed,
            2,
        ),
    ];
    let markers = [Marker::Circle, Marker::Triangle];
    let mut series = series;
    for (k, (label, points)) in models
        .iter()
        .enumerate()
        .filter(|(_, (_, p))| !p.is_empty())
    {
        series.push(Series::markers(
            *label,
            points.to_vec(),
            markers[k % markers.len()],
            k,
        ));
    }
    let spec = PlotSpec {
        legend: Legend::UpperLeft,
        series,
        ..PlotSpec::new(labels.title, labels.x_label, labels.y_label).log_log()
    };
    plot_xy(&ctx.path("runout.png"), &spec)?;
    ctx.add_plot("runout.png", labels.caption);
    Ok(())
}
