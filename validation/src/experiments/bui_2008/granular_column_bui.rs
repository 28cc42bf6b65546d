//! `granular-column-bui`: the collapse of a column of aluminium bars of Bui, Fukagawa, Sako &
//! Ohno (2008, "Lagrangian meshfree particles method (SPH) for large deformation and failure
//! flows of geomaterial using elastic–plastic soil constitutive model", *Int. J. Numer. Anal.
//! Meth. Geomech.* 32:1537–1570, §6) with the elastic–plastic model of crate
//! `elastoplastic-granular`, against Rankine's active wedge.
//!
//! **Set-up** (`scenes/granular_column_bui.toml`): a column `L0 × H0` = 0.2 m × 0.1 m on the
//! floor of a tank 0.8 m long, a fixed wall behind it (`x = 0`), released at `t = 0` (the
//! plate in front removed) from its geostatic stress; plane strain as a slab three spacings
//! deep, periodic across `z` (the experiment sets the tank's depth, the block's and the
//! period to `3 s` in either mode); the material whole from one transcription, SPHinXsys's
//! `test_2d_column_collapse`: `E` = 5.84 MPa, `ν` = 0.3, `ρ0` = 2040 kg/m³, `c` = 0, `ψ` = 0,
//! φ = 21.9° (other sources quote 19.8° for the bars, `reference-data/granular-column-bui/
//! SOURCE.md`), the cone matched as Bui matched it (`ConeMatch::PlaneStrainAssociated`); the
//! geostatic start with Jaky's `K0 = 1 − sin φ` (inside the cone: the column starts
//! elastic). Walls of no-slip boundary particles.
//!
//! **Rest** ([`granular_measure::rest`], default figures, all grains): the run stops once the
//! 99th-percentile speed and the fastest grain two spacings deep have stayed below
//! `0.05 √(g s)` for 0.5 s and the deposit's angle has moved less than 0.3° over 1 s; the
//! scene's duration (2 s) is a cap.
//!
//! **Measures**, on the grains followed from their initial lattice position (`x0, y0`) to
//! the deposit:
//!
//! - *First slip surface* (the failure line Rankine's theory describes): at
//!   [`SLIP_TIMES_S`] after the release, a grain has failed when its equivalent plastic shear
//!   strain exceeds [`SLIP_PLASTIC_STRAIN`] (Rankine's active wedge is plastic throughout,
//!   the ground behind it elastic: the plastic zone's edge is the slip line); the same with
//!   "has moved more than [`SLIP_THRESHOLD_SPACINGS`] of a spacing" is reported beside it. In
//!   each initial row (height `y` of one spacing), the boundary between the grains left in
//!   place (behind) and those that failed (in front) lies at
//!   `x_b = L0 · (grains of the row that did not move) / (grains of the row)`. The line through
//!   the column's toe `(L0, 0)` is fitted to the rows, `L0 − x_b = y cot β` by least squares
//!   (`cot β = Σ y (L0 − x_b) / Σ y²`); `β` is its angle from the horizontal. The line at
//!   [`SLIP_CHECK_S`] is checked; the others are reported.
//! - *Final moved zone*: the same fit on the deposit, a grain moved when it travelled more
//!   than one spacing by the end: the edge of everything that moved, which on a spreading
//!   deposit follows the final surface rather than the first slip surface; reported.
//! - *Back of the column*: the highest grain among those that started within
//!   [`BACK_SPACINGS`] spacings of the back wall, before and after.
//! - *Deposit slope*: [`granular_measure::angle_of_repose`] on the deposit (planar, floor
//!   `y = 0`, bins of one spacing, the flank's least-squares slope between 20 % and 80 % of
//!   the deposit's height), next to the model's angle of repose `atan(3 α_φ)` (a heap formed
//!   by flowing, ψ = 0) and its largest stable slope `asin(3 α_φ)` (a wedge that has not
//!   flowed), `ConeMatch::predicted_repose_angle_deg` and `max_stable_slope_deg`.
//! - *Runout*: [`granular_measure::runout()`] (the connected deposit's front plus the grain's
//!   radius, from the back wall).
//! - *Potential energy kept*: `Σ y_final / Σ y_initial` over the grains (equal masses).
//! - *Against the experiment* (Bui et al.'s measured final surface and failure line, as
//!   MaterialPointSolver.jl digitised them, `reference-data/granular-column-bui/SOURCE.md`):
//!   the runout against the surface's last point; the deposit's height (the top of the
//!   highest grain within half a spacing) at each measured surface point, RMS of the
//!   differences; per initial row, the boundary of the grains that moved by more than one
//!   bar ([`BAR_DIAMETER_M`]: the experiment's line delimits the bars that did not move)
//!   against the measured line at that height, RMS of the horizontal distances.
//!
//! **Checks**: the deposit's front clear of the far wall (validity); at rest by [`REST_BY_S`];
//! the back keeps its height within one spacing (the wall holds the material behind the
//! failure line, which does not move); the first slip surface at Rankine's `45° + φ/2`
//! within `1.5 sin²β s/H0` rad (see [`failure_line_tolerance_deg`]); the runout, the final
//! surface and the failure line against Bui et al.'s measurements, each within one spacing
//! (the deposit is resolved to a grain) plus the digitisation's error (read at the points
//! whose place is known); the energy kept against SPHinXsys's 0.690 (the same material,
//! φ = 21.9°) within [`ENERGY_BAND`]. The deposit's slope and the final moved zone are
//! reported.

use anyhow::{bail, Result};
use elastoplastic_granular::{Axis, ConeMatch};
use granular_measure::{angle_of_repose, normalised_runout, runout, ReposeOptions, RunoutOptions};
use sph_core::Vec3;
use sph_scene::{FluidSpec, Scene, SolverSpec};

use crate::helpers::{
    load_reference_csv, plot_xy, write_csv_rows, Legend, Marker, PlotSpec, Series, SeriesStyle,
};
use crate::scene_runs::{
    run_scene_until_rest_keeping, shipped_scene, solver_error_check, RestCriterion, SceneRun,
};
use crate::{Check, Context, Experiment, Mode, Outcome};

/// The experiment.
pub struct GranularColumnBui;

/// The shipped scene the checks run: the column in the plane (`[simulation] dimensions = 2`,
/// plane strain), as Bui et al. compute it.
const SCENE: &str = "granular_column_bui_planar";
/// The same column as a periodic slab in 3D (`scenes/granular_column_bui.toml`), run beside
/// the plane in full mode as a cross-check of the planar path (reported, not checked).
const SLAB_SCENE: &str = "granular_column_bui";
/// Depth of the periodic slab, in spacings (plane strain without side walls; the support,
/// 2.4 spacings, sees its periodic images).
const SLAB_SPACINGS: f64 = 3.0;
/// Time (s) by which the column must be at rest: SPHinXsys's column of the same material
/// (φ = 21.9°) keeps its mechanical energy within 0.1 % of its final value from about
/// 0.7 s on (`reference-data/granular-column-bui/SOURCE.md`); 1 s allows for the lower
/// friction angle and for the criterion's definition of rest (speeds below 0.05 √(g s)).
pub const REST_BY_S: f64 = 1.0;
/// The grains within this many spacings of the back wall are the back of the column.
pub const BACK_SPACINGS: f64 = 3.0;
/// The times (s after the release) of the first slip surface's measurements: the wedge in
/// front of Rankine's line starts to slide at once and has slid centimetres by 0.1 s
/// (`½ g (sin β − cos β tan φ) t²` = 3 cm on β = 56°, φ = 21.9°), long before the deposit
/// spreads.
pub const SLIP_TIMES_S: [f64; 3] = [0.05, 0.10, 0.15];
/// A grain has failed when its equivalent plastic shear strain exceeds this: about thirty times the
/// column's largest elastic strain (`ρ0 g H0/E` = 3.4·10⁻⁴), far below the strain of a slip
/// band that has slid centimetres by [`SLIP_CHECK_S`].
pub const SLIP_PLASTIC_STRAIN: f64 = 0.01;
/// The measurement of [`SLIP_TIMES_S`] that is checked.
pub const SLIP_CHECK_S: f64 = 0.10;
/// A grain has started to slip when it has moved this fraction of a spacing: far above the
/// elastic settlement of the column under its own weight (`ρ0 g H0²/(2E)` = 0.02 mm) and far
/// below the wedge's slide by [`SLIP_CHECK_S`].
pub const SLIP_THRESHOLD_SPACINGS: f64 = 0.25;
/// Band around SPHinXsys's fraction of the initial potential energy kept at rest: this
/// project's, set before the run (SPHinXsys is a peer code, not an experiment: the same
/// material and friction angle, but another wall condition, viscosity and stress
/// diffusion).
pub const ENERGY_BAND: f64 = 0.05;
/// SPHinXsys's regression figure (file in `reference-data/granular-column-bui/`).
const SPHINXSYS_FILE: &str = "granular-column-bui/sphinxsys_column_collapse_energy.csv";
/// The experiment's final surface, `(x, y)` from the back wall and the floor (m), as
/// MaterialPointSolver.jl digitised it (`reference-data/granular-column-bui/SOURCE.md`).
const MEASURED_SURFACE_FILE: &str = "granular-column-bui/bui2008_measured_surface.csv";
/// The experiment's failure line (the edge of the bars that did not move), the same axes.
const MEASURED_FAILURE_FILE: &str = "granular-column-bui/bui2008_measured_failure_line.csv";
/// The bars' larger diameter (m): Bui et al.'s aluminium bars are 1 mm and 1.5 mm across
/// (§6, as Ghaïtanellis et al. 2018, *Adv. Water Resour.* 111:156–173, Table 2, quote
/// them). The experiment's failure line delimits the bars that did not move; the grains
/// compared with it have moved when they travelled more than one bar (as Ghaïtanellis et al.
/// count them), far above the column's elastic settlement (`ρ0 g H0²/(2E)` = 0.02 mm).
pub const BAR_DIAMETER_M: f64 = 1.5e-3;

/// Bui et al.'s measured deposit, in the column's frame (`x` from the back wall, `y` above
/// the floor, m).
#[derive(Debug, Clone)]
struct Measured {
    /// The final surface, `(x, y)`, `x` increasing.
    surface: Vec<(f64, f64)>,
    /// The failure line, `(x, y)`, `y` decreasing.
    failure: Vec<(f64, f64)>,
}

impl Measured {
    /// Loads both files; `x` must increase along each.
    fn load(ctx: &Context) -> Result<Self> {
        let read = |file: &str| -> Result<Vec<(f64, f64)>> {
            let t = load_reference_csv(ctx, file, &["x_m", "y_m"])?;
            let points = (0..t.len())
                .map(|i| Ok((t.number(i, "x_m")?, t.number(i, "y_m")?)))
                .collect::<Result<Vec<_>>>()?;
            if points.len() < 2 || points.windows(2).any(|w| w[1].0 <= w[0].0) {
                bail!("{file}: needs two points or more, x increasing");
            }
            Ok(points)
        };
        Ok(Self {
            surface: read(MEASURED_SURFACE_FILE)?,
            failure: read(MEASURED_FAILURE_FILE)?,
        })
    }

    /// The measured runout from the back wall (m): the surface's last point, where the
    /// deposit thins to one bar on the floor.
    fn runout_m(&self) -> f64 {
        self.surface.last().map_or(f64::NAN, |p| p.0)
    }

    /// The digitisation's error (m), read at the three points whose true place is known: the
    /// surface's first point is the back wall's top, `(0, H0)` (the wall holds the material
    /// behind the failure line, which meets the top `0.02 m` from the wall), and the failure
    /// line's last point is on the floor, `y = 0`.
    fn transcription_error_m(&self, height: f64) -> f64 {
        let (x0, y0) = self.surface[0];
        let foot = self.failure.last().map_or(f64::NAN, |p| p.1);
        x0.abs().max((y0 - height).abs()).max(foot.abs())
    }

    /// The measured failure line's `x` at height `y` (linear between the points), `None`
    /// outside its span of heights.
    fn failure_x_at(&self, y: f64) -> Option<f64> {
        self.failure.windows(2).find_map(|w| {
            let ((xa, ya), (xb, yb)) = (w[0], w[1]);
            let (lo, hi) = (ya.min(yb), ya.max(yb));
            (lo..=hi)
                .contains(&y)
                .then(|| xa + (xb - xa) * (y - ya) / (yb - ya))
        })
    }
}

/// The column as the scene places it.
#[derive(Debug, Clone, Copy)]
struct Column {
    /// `x` of the back wall (the block's back face) (m).
    back_x: f64,
    /// The floor (the block's bottom) (m).
    floor_y: f64,
    /// Length `L0` (m).
    length: f64,
    /// Height `H0` (m).
    height: f64,
}

/// The shipped scene `name` in `ctx`'s mode (a 3D scene with its slab [`SLAB_SPACINGS`]
/// deep), its column and its friction angle and cone match.
fn column_scene(ctx: &Context, name: &str) -> Result<(Scene, Column, f64, ConeMatch)> {
    let mut scene = shipped_scene(name, ctx.mode)?;
    let planar = scene.is_planar();
    let depth = SLAB_SPACINGS * scene.particle_spacing;
    let Some(tank) = scene.tank.as_mut() else {
        bail!("{name}: the scene needs a tank (its floor and back wall)");
    };
    if !planar {
        tank.max.z = tank.min.z + depth;
    }
    let (z_lo, z_hi) = (tank.min.z, tank.max.z);
    let Some(FluidSpec::Block { min, max, .. }) = scene.fluids.first_mut() else {
        bail!("{name}: the scene's first fluid must be the column (a block)");
    };
    if !planar {
        min[2] = z_lo;
        max[2] = z_hi;
    }
    let column = Column {
        back_x: min[0],
        floor_y: min[1],
        length: max[0] - min[0],
        height: max[1] - min[1],
    };
    let SolverSpec::Elastoplastic(e) = &mut scene.solver else {
        bail!(
            "{name}: the experiment needs kind = \"elastoplastic\", not \"{}\"",
            scene.solver.kind_name()
        );
    };
    let (phi, cone) = (
        e.friction_angle_deg,
        e.cone_match
            .unwrap_or(elastoplastic_granular::DEFAULT_CONE_MATCH),
    );
    for p in scene.boundary.periodic.iter_mut() {
        if p.axis == Axis::Z {
            p.lo = z_lo;
            p.hi = z_hi;
        }
    }
    scene.check()?;
    Ok((scene, column, phi, cone))
}

/// The tolerance (degrees) of the failure line's angle `β` at spacing `s` and column height
/// `h`: the boundary of each row is located to one spacing (the displacement threshold is
/// one spacing, and the grains sit on a lattice of one spacing); a shift `δx = s` of every
/// row moves the least-squares `cot β` through the toe by `δx Σy/Σy² ≈ 1.5 s/h`, and `β` by
/// `sin²β` times that (radians).
pub fn failure_line_tolerance_deg(beta_deg: f64, s: f64, h: f64) -> f64 {
    (1.5 * beta_deg.to_radians().sin().powi(2) * s / h).to_degrees()
}

/// The failure line: per initial row, `(y above the floor, x_b)`, and the fitted angle
/// `β` (degrees) of the line through the toe.
fn failure_line(
    initial: &[Vec3<f64>],
    moved: &[bool],
    column: Column,
    s: f64,
) -> (Vec<(f64, f64)>, f64) {
    let rows = (column.height / s).round().max(1.0) as usize;
    let mut count = vec![0usize; rows];
    let mut still = vec![0usize; rows];
    for (p, &m) in initial.iter().zip(moved) {
        let j = (((p.y - column.floor_y) / s).floor().max(0.0) as usize).min(rows - 1);
        count[j] += 1;
        if !m {
            still[j] += 1;
        }
    }
    let points: Vec<(f64, f64)> = (0..rows)
        .filter(|&j| count[j] > 0)
        .map(|j| {
            let y = (j as f64 + 0.5) * s;
            (y, column.length * still[j] as f64 / count[j] as f64)
        })
        .collect();
    let beta = line_through_toe_deg(&points, column.length);
    (points, beta)
}

impl Experiment for GranularColumnBui {
    fn id(&self) -> &'static str {
        "granular-column-bui"
    }
    fn crates(&self) -> &'static [&'static str] {
        &["elastoplastic-granular", "granular-measure"]
    }
    fn scenes(&self) -> &'static [&'static str] {
        &[SCENE, SLAB_SCENE]
    }
    fn source(&self) -> &'static str {
        "Bui, Fukagawa, Sako & Ohno (2008) Int. J. Numer. Anal. Meth. Geomech. 32:1537-1570, section 6: collapse of a column of aluminium bars, against Rankine's active wedge (failure line at 45 deg + phi/2 through the toe)"
    }

    fn run(&self, ctx: &mut Context) -> Result<Outcome> {
        let peer = load_reference_csv(ctx, SPHINXSYS_FILE, &["quantity", "value"])?;
        let peer_kept = peer.number(peer.find(&[("quantity", "fraction_kept")])?, "value")?;
        let measured = Measured::load(ctx)?;
        let mut out = Outcome::new();
        let Some(m) = measure_column(ctx, SCENE, "", &measured, &mut out)? else {
            return Ok(out);
        };
        check_column(&mut out, &m, peer_kept);
        write_csv_rows(
            &ctx.path("failure_line.csv"),
            &["y_m", "boundary_x_m"],
            m.slip_rows
                .iter()
                .map(|(y, x)| vec![format!("{y:.5}"), format!("{x:.5}")]),
        )?;
        ctx.add_file(
            "failure_line.csv",
            "per initial row: the boundary between the grains that stayed (behind) and those whose plastic strain exceeded 0.01 at 0.1 s (the first slip surface)",
        );
        write_measured_comparison(ctx, &m, &measured)?;
        plot_deposit(ctx, &m, &measured)?;
        if ctx.mode == Mode::Full {
            // The 3D slab beside the plane: the planar path's cross-check (reported).
            if let Some(slab) = measure_column(ctx, SLAB_SCENE, "slab/", &measured, &mut out)? {
                out.metric(
                    "slab/slip_surface_minus_plane_deg",
                    slab.slip_deg - m.slip_deg,
                );
            }
        }
        out.note(format!(
            "phi = {} deg, cone {}, spacing {} m, in the plane (dimensions = 2, plane strain){}; first slip surface: the edge of the grains whose plastic strain exceeds {SLIP_PLASTIC_STRAIN} at {SLIP_CHECK_S} s; final moved zone: by more than one spacing at rest; the runout, final surface and failure line checked against Bui et al.'s measured ones (MaterialPointSolver.jl's digitisation, reference-data/granular-column-bui/SOURCE.md); rest by granular_measure::rest (default figures, all grains)",
            m.phi,
            m.cone.name(),
            m.spacing,
            if ctx.mode == Mode::Full {
                format!("; the same column as a 3D slab {SLAB_SPACINGS} spacings deep, periodic in z, reported as slab/*")
            } else {
                String::new()
            }
        ));
        Ok(out)
    }
}

/// One column's run and its measures.
struct ColumnMeasures {
    scene: Scene,
    column: Column,
    phi: f64,
    cone: ConeMatch,
    spacing: f64,
    run: SceneRun,
    /// The back's height lost (m).
    back_drop: f64,
    /// The first slip surface at [`SLIP_CHECK_S`]: per initial row `(y, x_b)`, and `β` (deg).
    slip_rows: Vec<(f64, f64)>,
    slip_deg: f64,
    runout_m: f64,
    kept: f64,
    /// Against Bui et al.'s measured deposit.
    fit: MeasuredFit,
}

/// The deposit against Bui et al.'s measured one.
#[derive(Debug, Clone)]
struct MeasuredFit {
    /// The measured runout from the back wall (m).
    measured_runout_m: f64,
    /// The digitisation's error (m), [`Measured::transcription_error_m`].
    transcription_m: f64,
    /// RMS and largest difference (m) of the deposit's height at the measured surface's
    /// points.
    profile_rms_m: f64,
    profile_max_m: f64,
    /// The measured surface's points.
    surface_points: usize,
    /// Per initial row `(y, x_b)`, the boundary of the grains that moved by more than
    /// [`BAR_DIAMETER_M`] by the end, and its line through the toe (deg).
    bar_rows: Vec<(f64, f64)>,
    bar_zone_deg: f64,
    /// RMS horizontal distance (m) between those boundaries and the measured failure line,
    /// over the rows within its span of heights, and their number.
    failure_rms_m: f64,
    failure_rows: usize,
    /// The measured failure line's angle (deg), fitted through the toe as the model's rows.
    measured_line_deg: f64,
}

/// The deposit's height above the floor at `x` (from the back wall, m): the top of the
/// highest grain whose centre lies within half a spacing of `x` (its centre plus its radius
/// `s/2`), 0 where there is none.
fn deposit_height(positions: &[Vec3<f64>], column: Column, s: f64, x: f64) -> f64 {
    positions
        .iter()
        .filter(|p| (p.x - column.back_x - x).abs() <= 0.5 * s)
        .map(|p| p.y - column.floor_y + 0.5 * s)
        .fold(0.0, f64::max)
}

/// Root mean square of `values` (NaN if empty).
fn rms(values: &[f64]) -> f64 {
    (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
}

/// The line through the toe `(L0, 0)` fitted to boundary points `(y, x_b)` (`x_b` from the
/// back wall) by least squares, `L0 − x_b = y cot β`; `β` in degrees.
fn line_through_toe_deg(points: &[(f64, f64)], length: f64) -> f64 {
    let (num, den) = points.iter().fold((0.0, 0.0), |(n, d), &(y, xb)| {
        (n + y * (length - xb), d + y * y)
    });
    90.0 - (num / den).atan().to_degrees()
}

/// The deposit at rest (`last`, each grain's final position beside its `initial` one) against
/// `measured`.
fn compare_with_measured(
    measured: &Measured,
    column: Column,
    s: f64,
    initial: &[Vec3<f64>],
    last: &[Vec3<f64>],
) -> MeasuredFit {
    let heights: Vec<f64> = measured
        .surface
        .iter()
        .map(|&(x, y)| deposit_height(last, column, s, x) - y)
        .collect();
    let moved: Vec<bool> = initial
        .iter()
        .zip(last)
        .map(|(a, b)| (b.x - a.x).hypot(b.y - a.y) > BAR_DIAMETER_M)
        .collect();
    let (bar_rows, bar_zone_deg) = failure_line(initial, &moved, column, s);
    let gaps: Vec<f64> = bar_rows
        .iter()
        .filter_map(|&(y, xb)| measured.failure_x_at(y).map(|x| xb - x))
        .collect();
    let measured_line: Vec<(f64, f64)> = measured.failure.iter().map(|&(x, y)| (y, x)).collect();
    MeasuredFit {
        measured_runout_m: measured.runout_m(),
        transcription_m: measured.transcription_error_m(column.height),
        profile_rms_m: rms(&heights),
        profile_max_m: heights.iter().fold(0.0, |m, d| m.max(d.abs())),
        surface_points: heights.len(),
        bar_rows,
        bar_zone_deg,
        failure_rms_m: rms(&gaps),
        failure_rows: gaps.len(),
        measured_line_deg: line_through_toe_deg(&measured_line, column.length),
    }
}

/// Runs shipped scene `name` to rest and records its measures as metrics named
/// `{prefix}…`; `None` if it blew up (the error is then a check).
fn measure_column(
    ctx: &mut Context,
    name: &str,
    prefix: &str,
    measured: &Measured,
    out: &mut Outcome,
) -> Result<Option<ColumnMeasures>> {
    let (scene, column, phi, cone) = column_scene(ctx, name)?;
    let s = scene.particle_spacing;
    ctx.progress.set_length(scene.frame_count() as u64);
    let t0 = std::time::Instant::now();
    let slip_frames: Vec<usize> = SLIP_TIMES_S
        .iter()
        .map(|t| (t / scene.frame_dt_s).round() as usize)
        .collect();
    let run = run_scene_until_rest_keeping(
        ctx,
        &scene,
        &slip_frames,
        &["plastic_strain"],
        RestCriterion::default(),
    )?;
    put(out, prefix, "particles", run.particles as f64);
    put(out, prefix, "wall_s", t0.elapsed().as_secs_f64());
    put(out, prefix, "spacing_m", s);
    if let Some(e) = &run.blow_up {
        out.check(solver_error_check(&format!("{prefix}column"), e));
        return Ok(None);
    }
    put(
        out,
        prefix,
        "end_time_s",
        run.frames.last().map_or(f64::NAN, |f| f.time_s),
    );
    put(
        out,
        prefix,
        "rest_from_s",
        run.rest_from_s.unwrap_or(f64::NAN),
    );

    let initial = scene.fluid_particles::<f64>()?.positions;
    let mut last = vec![Vec3::new(f64::NAN, f64::NAN, f64::NAN); initial.len()];
    for (&id, &p) in run.final_ids.iter().zip(&run.final_positions) {
        last[id as usize] = p;
    }
    let moved: Vec<bool> = initial
        .iter()
        .zip(&last)
        .map(|(a, b)| (b.x - a.x).hypot(b.y - a.y) > s)
        .collect();
    let back_top = |ps: &[Vec3<f64>]| {
        initial
            .iter()
            .zip(ps)
            .filter(|(a, _)| a.x - column.back_x < BACK_SPACINGS * s)
            .map(|(_, p)| p.y)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let back_drop = back_top(&initial) - back_top(&last);
    put(out, prefix, "back_height_drop_m", back_drop);
    let (_, final_zone) = failure_line(&initial, &moved, column, s);
    put(out, prefix, "final_moved_zone_deg", final_zone);
    put(
        out,
        prefix,
        "moved_fraction",
        moved.iter().filter(|&&m| m).count() as f64 / moved.len() as f64,
    );
    let mut slip = None;
    for (&t, &frame) in SLIP_TIMES_S.iter().zip(&slip_frames) {
        let at = run.snapshots.iter().find(|(f, _)| *f == frame);
        let strain = run
            .snapshot_fields
            .iter()
            .find(|(f, name, k, _)| *f == frame && name == "plastic_strain" && *k == 1);
        let (Some((_, at)), Some((_, _, _, strain))) = (at, strain) else {
            out.note(format!(
                "{prefix}no snapshot at t = {t} s (the run ended before)"
            ));
            continue;
        };
        let moved_early: Vec<bool> = initial
            .iter()
            .zip(at)
            .map(|(a, b)| (b.x - a.x).hypot(b.y - a.y) > SLIP_THRESHOLD_SPACINGS * s)
            .collect();
        let (_, beta_moved) = failure_line(&initial, &moved_early, column, s);
        put(
            out,
            prefix,
            &format!("moved_zone_{:.0}ms_deg", 1e3 * t),
            beta_moved,
        );
        let failed: Vec<bool> = strain.iter().map(|&e| e > SLIP_PLASTIC_STRAIN).collect();
        let (rows, beta) = failure_line(&initial, &failed, column, s);
        put(
            out,
            prefix,
            &format!("slip_surface_{:.0}ms_deg", 1e3 * t),
            beta,
        );
        if t == SLIP_CHECK_S {
            slip = Some((rows, beta));
        }
    }
    let Some((slip_rows, slip_deg)) = slip else {
        bail!("{name}: no snapshot at the slip surface's time {SLIP_CHECK_S} s");
    };

    let deposit = angle_of_repose(
        &run.final_positions,
        &ReposeOptions::planar(column.floor_y, s).with_spacing(s),
    );
    put(
        out,
        prefix,
        "deposit_slope_deg",
        deposit.as_ref().map_or(f64::NAN, |m| m.angle_deg),
    );
    if let Err(e) = &deposit {
        out.note(format!("{prefix}deposit slope not measured: {e}"));
    }
    let runout_m = runout(
        &run.final_positions,
        &RunoutOptions::connected(column.back_x, s),
    )?;
    let height_sum = |ps: &[Vec3<f64>]| ps.iter().map(|p| p.y - column.floor_y).sum::<f64>();
    let kept = height_sum(&run.final_positions) / height_sum(&initial);
    put(out, prefix, "runout_m", runout_m);
    put(
        out,
        prefix,
        "normalised_runout",
        normalised_runout(runout_m, column.length)?,
    );
    put(out, prefix, "potential_energy_kept", kept);
    let fit = compare_with_measured(measured, column, s, &initial, &last);
    put_fit(out, prefix, runout_m, &fit);
    Ok(Some(ColumnMeasures {
        scene,
        column,
        phi,
        cone,
        spacing: s,
        run,
        back_drop,
        slip_rows,
        slip_deg,
        runout_m,
        kept,
        fit,
    }))
}

/// Records the comparison with Bui et al.'s measurements as metrics `{prefix}bui2008/…`.
fn put_fit(out: &mut Outcome, prefix: &str, runout_m: f64, fit: &MeasuredFit) {
    for (name, value) in [
        ("measured_runout_m", fit.measured_runout_m),
        ("runout_minus_measured_m", runout_m - fit.measured_runout_m),
        ("transcription_error_m", fit.transcription_m),
        ("profile_rms_m", fit.profile_rms_m),
        ("profile_max_m", fit.profile_max_m),
        ("moved_by_a_bar_zone_deg", fit.bar_zone_deg),
        ("measured_failure_line_deg", fit.measured_line_deg),
        ("failure_line_rms_m", fit.failure_rms_m),
        ("failure_line_rows", fit.failure_rows as f64),
    ] {
        put(out, prefix, &format!("bui2008/{name}"), value);
    }
}

/// Records metric `{prefix}{name}`.
fn put(out: &mut Outcome, prefix: &str, name: &str, value: f64) {
    out.metric(format!("{prefix}{name}"), value);
}

/// The checks on the column `m`: rest, the back, the first slip surface against Rankine's
/// line, the front clear of the far wall, the energy kept against SPHinXsys's `peer_kept`.
fn check_column(out: &mut Outcome, m: &ColumnMeasures, peer_kept: f64) {
    let (s, column) = (m.spacing, m.column);
    check_rest(out, &m.scene, &m.run);
    out.check(Check::at_most(
        format!("back of the column ({BACK_SPACINGS} spacings from the wall): height lost (m)"),
        m.back_drop.abs(),
        s,
        "physics: Rankine's active wedge fails in front of the line through the toe; the material behind it, held by the wall, does not move (one spacing: the grain size)",
    ));
    let rankine = 45.0 + 0.5 * m.phi;
    let tol = failure_line_tolerance_deg(rankine, s, column.height);
    out.metric("rankine_deg", rankine);
    out.metric("failure_line_tolerance_deg", tol);
    out.check(Check::within(
        format!("first slip surface at {SLIP_CHECK_S} s through the toe (deg) against Rankine's 45 + phi/2 = {rankine:.2}"),
        m.slip_deg,
        rankine - tol,
        rankine + tol,
        format!(
            "Rankine's active wedge (plane strain, c = 0: the slip lines at 45 deg + phi/2 from the horizontal, the minor principal stress horizontal); band 1.5 sin^2(beta) s/H0 = {tol:.2} deg: each row's boundary located to one spacing"
        ),
    ));
    out.metric("repose_angle_deg", m.cone.predicted_repose_angle_deg(m.phi));
    out.metric("max_stable_slope_deg", m.cone.max_stable_slope_deg(m.phi));
    let far_wall = m.scene.tank.map_or(f64::NAN, |t| t.max.x);
    out.check(Check::greater_than(
        "deposit's front clear of the far wall (m)",
        far_wall - (column.back_x + m.runout_m),
        2.0 * s,
        "validity: a front at the far wall was stopped by it",
    ));
    check_measured(out, m);
    out.metric("sphinxsys_potential_energy_kept", peer_kept);
    out.check(Check::within(
        "fraction of the initial potential energy kept at rest",
        m.kept,
        peer_kept - ENERGY_BAND,
        peer_kept + ENERGY_BAND,
        format!(
            "peer cross-check, not an experiment: SPHinXsys test_2d_column_collapse ({peer_kept:.3}, phi = 21.9 deg); band +-{ENERGY_BAND} this project's, set before the run"
        ),
    ));
}

/// The checks against Bui et al.'s measured deposit: the runout, the final surface and the
/// failure line, each to one spacing (the deposit is made of grains `s` across: its front,
/// its surface and each row's boundary are located to one grain) plus the digitisation's
/// error.
fn check_measured(out: &mut Outcome, m: &ColumnMeasures) {
    let fit = &m.fit;
    let tol = m.spacing + fit.transcription_m;
    let origin = |what: &str| {
        format!(
            "experiment: Bui et al. (2008) section 6, {what} as MaterialPointSolver.jl digitised it (reference-data/granular-column-bui/SOURCE.md); tolerance one spacing ({:.4} m: the deposit is resolved to a grain) plus the digitisation's error ({:.4} m, read at the back wall's top and the failure line's foot)",
            m.spacing, fit.transcription_m
        )
    };
    out.check(Check::within(
        format!(
            "runout from the back wall (m) against Bui et al.'s measured {:.4}",
            fit.measured_runout_m
        ),
        m.runout_m,
        fit.measured_runout_m - tol,
        fit.measured_runout_m + tol,
        origin("the final surface's front"),
    ));
    out.check(Check::at_most(
        "final surface: RMS height difference at the measured points (m)",
        fit.profile_rms_m,
        tol,
        origin(&format!(
            "the final surface ({} points, from the back wall to the front)",
            fit.surface_points
        )),
    ));
    out.check(Check::at_most(
        format!(
            "failure line: RMS horizontal distance of the rows' boundaries (grains moved by more than {BAR_DIAMETER_M} m) from the measured line (m)"
        ),
        fit.failure_rms_m,
        tol,
        origin("the failure line (the edge of the bars that did not move)"),
    ));
}

/// The rest check and the verdict's margins.
fn check_rest(out: &mut Outcome, scene: &Scene, run: &SceneRun) {
    let verdict = run.rest_verdict;
    for (name, _, m) in verdict.map_or_else(Vec::new, |v| v.margins()) {
        out.metric(format!("rest/{name}_at_end"), m.value);
    }
    out.check(Check::less_than(
        "at rest: time of rest (s)",
        run.rest_from_s.unwrap_or(f64::INFINITY),
        REST_BY_S,
        format!(
            "SPHinXsys's column of the same material keeps its energy within 0.1 % of its final value from about 0.7 s (reference-data/granular-column-bui/SOURCE.md); rest by granular_measure::rest (p99 and deep speeds < 0.05 sqrt(g s) for 0.5 s, angle moving < 0.3 deg over 1 s), cap {} s; at the end: {}",
            scene.duration_s,
            verdict.map_or_else(
                || "no verdict".to_string(),
                |v| v.summary(&RestCriterion::default().settings)
            )
        ),
    ));
}

/// `deposit_vs_measured.csv` and `failure_line_vs_measured.csv`: the deposit's height at the
/// measured surface's points, and each row's boundary beside the measured failure line.
fn write_measured_comparison(
    ctx: &mut Context,
    m: &ColumnMeasures,
    measured: &Measured,
) -> Result<()> {
    write_csv_rows(
        &ctx.path("deposit_vs_measured.csv"),
        &["x_m", "measured_height_m", "model_height_m"],
        measured.surface.iter().map(|&(x, y)| {
            let h = deposit_height(&m.run.final_positions, m.column, m.spacing, x);
            vec![format!("{x:.5}"), format!("{y:.5}"), format!("{h:.5}")]
        }),
    )?;
    ctx.add_file(
        "deposit_vs_measured.csv",
        "at each point of Bui et al.'s measured final surface (x from the back wall): the measured height and the deposit's (the top of the highest grain within half a spacing)",
    );
    write_csv_rows(
        &ctx.path("failure_line_vs_measured.csv"),
        &["y_m", "boundary_x_m", "measured_x_m"],
        m.fit.bar_rows.iter().map(|&(y, xb)| {
            let x = measured
                .failure_x_at(y)
                .map_or(String::from("NaN"), |x| format!("{x:.5}"));
            vec![format!("{y:.5}"), format!("{xb:.5}"), x]
        }),
    )?;
    ctx.add_file(
        "failure_line_vs_measured.csv",
        "per initial row: the boundary of the grains that moved by more than one bar (1.5 mm) by the end, and Bui et al.'s measured failure line at that height (NaN outside its span)",
    );
    Ok(())
}

/// `deposit.png`: the deposit's grains, the initial column, the boundary of each row and
/// the fitted failure line, and Rankine's line, all through the toe; Bui et al.'s measured
/// surface and failure line.
fn plot_deposit(ctx: &mut Context, m: &ColumnMeasures, measured: &Measured) -> Result<()> {
    let (run, column, rows, beta_deg) = (&m.run, m.column, &m.slip_rows, m.slip_deg);
    let rankine_deg = 45.0 + 0.5 * m.phi;
    let toe = (column.back_x + column.length, column.floor_y);
    let line = |deg: f64| {
        let run_x = column.height / deg.to_radians().tan();
        vec![toe, (toe.0 - run_x, toe.1 + column.height)]
    };
    let (x0, y0, l, h) = (column.back_x, column.floor_y, column.length, column.height);
    let series = vec![
        Series::markers(
            "deposit (grains at rest)",
            run.final_positions.iter().map(|p| (p.x, p.y)).collect(),
            Marker::Circle,
            0,
        ),
        Series::line(
            "initial column",
            vec![(x0, y0 + h), (x0 + l, y0 + h), (x0 + l, y0)],
            7,
        ),
        Series::markers(
            "boundary of the grains that moved (per initial row)",
            rows.iter().map(|&(y, x)| (x0 + x, y0 + y)).collect(),
            Marker::Cross,
            3,
        ),
        Series::line(
            format!("first slip surface (0.1 s): {beta_deg:.1}°"),
            line(beta_deg),
            3,
        ),
        Series::styled(
            format!("Rankine 45° + φ/2 = {rankine_deg:.1}°"),
            line(rankine_deg),
            SeriesStyle::Dashed,
            1,
        ),
        Series::line(
            "Bui et al. (2008), measured surface",
            measured
                .surface
                .iter()
                .map(|&(x, y)| (x0 + x, y0 + y))
                .collect(),
            2,
        ),
        Series::styled(
            "Bui et al. (2008), measured failure line",
            measured
                .failure
                .iter()
                .map(|&(x, y)| (x0 + x, y0 + y))
                .collect(),
            SeriesStyle::Dashed,
            2,
        ),
    ];
    let x_end = run
        .final_positions
        .iter()
        .map(|p| p.x)
        .fold(x0 + 2.0 * l, f64::max)
        .max(x0 + measured.runout_m());
    let spec = PlotSpec {
        legend: Legend::UpperRight,
        series,
        x_range: Some((x0, x_end + 0.02)),
        y_range: Some((y0, y0 + 0.25)),
        ..PlotSpec::new(
            "Column of Bui et al. (2008): deposit and failure line",
            "x (m)",
            "y (m)",
        )
    };
    plot_xy(&ctx.path("deposit.png"), &spec)?;
    ctx.add_plot(
        "deposit.png",
        "the deposit at rest, the initial column, each row's boundary at 0.1 s and the first slip surface fitted through the toe, and Rankine's line",
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column() -> Column {
        Column {
            back_x: 0.0,
            floor_y: 0.0,
            length: 0.2,
            height: 0.1,
        }
    }

    #[test]
    fn the_line_through_the_toe_recovers_a_known_angle() {
        // Boundaries on the line through (0.2, 0) at 30 deg: x_b = 0.2 - y cot 30°.
        let cot = 30f64.to_radians().tan().recip();
        let points: Vec<(f64, f64)> = [0.01, 0.04, 0.09]
            .iter()
            .map(|&y| (y, 0.2 - y * cot))
            .collect();
        assert!((line_through_toe_deg(&points, 0.2) - 30.0).abs() < 1e-9);
    }

    #[test]
    fn the_measured_line_is_interpolated_between_its_points_and_not_beyond() {
        let m = Measured {
            surface: vec![(0.0, 0.1), (0.4, 0.0)],
            failure: vec![(0.02, 0.1), (0.18, 0.0)],
        };
        assert!((m.failure_x_at(0.05).unwrap() - 0.10).abs() < 1e-12);
        assert_eq!(m.failure_x_at(0.11), None);
        assert!((m.runout_m() - 0.4).abs() < 1e-12);
        // The surface's first point is read exactly, the failure line's foot on the floor.
        assert_eq!(m.transcription_error_m(0.1), 0.0);
    }

    #[test]
    fn the_deposit_height_is_the_top_of_the_highest_grain_within_half_a_spacing() {
        let s = 0.01;
        let grains = [
            Vec3::new(0.103, 0.005, 0.0),
            Vec3::new(0.103, 0.015, 0.0),
            Vec3::new(0.125, 0.045, 0.0),
        ];
        assert!((deposit_height(&grains, column(), s, 0.10) - 0.02).abs() < 1e-12);
        assert_eq!(deposit_height(&grains, column(), s, 0.30), 0.0);
    }
}
