//! The slab set-ups the crate's tests share: a slope cut in a settled layer ([`cut_slope`],
//! the static bracket) and a heap poured onto a floor ([`poured_heap`], the pours). Both
//! are slabs periodic along `x` and `z` over a floor of no-slip boundary particles. (The
//! shipped scenes `scenes/granular_repose_poured_{20,30,40}.toml` are the poured heaps a
//! user runs: `particles run SCENE --quick --until-rest`.)

#![allow(dead_code)] // each test file uses a part

use elastoplastic_granular::{
    boundary_block, cubic_lattice, Aabb, Elastoplastic, ElastoplasticParams, ElastoplasticScheme,
    InitialStress, ParticleSet, PeriodicAxis, Plane, Pour, Solids, SolverError, Vec3, WallModel,
};
use sph_core::Real;

fn v<R: Real>(x: f64, y: f64, z: f64) -> Vec3<R> {
    Vec3::new(R::of_f64(x), R::of_f64(y), R::of_f64(z))
}

fn aabb<R: Real>(lo: [f64; 3], hi: [f64; 3]) -> Result<Aabb<R>, SolverError> {
    Ok(Aabb::new(v(lo[0], lo[1], lo[2]), v(hi[0], hi[1], hi[2]))?)
}

/// Rows of boundary particles standing for a wall (three spacings thick: the support is
/// 2.4 spacings).
const BOUNDARY_ROWS: f64 = 3.0;

/// A slope cut in a settled layer: a mound of grains on a flat no-slip floor, periodic
/// along `x` (period `period_x_m`) and along `z` (`slab_depth_m`: plane strain without
/// walls), its cross-section the trapezoid
/// `y ≤ min(H, tan θ · min(x − x0, x0 + W − x))`, `x0 = (period − W)/2`, `W` its base
/// width: two flanks at `θ` rising from the floor to a flat top `H` high. The floor is
/// three rows of no-slip boundary particles under `y = 0` across the whole period (the
/// floor plane only keeps grains out); the grains start at rest on the lattice under the
/// surface with the geostatic stress of their columns
/// ([`InitialStress::Geostatic`],
/// `elastoplastic_granular::initial::geostatic`), the static bracket's set-up (a slope formed without
/// flowing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlopeSetup {
    /// The period along `x` (m; a multiple of the spacing, wide enough for a failing
    /// flank's runout).
    pub period_x_m: f64,
    /// The mound's base width `W` (m).
    pub base_width_m: f64,
    /// The mound's height `H` (m).
    pub height_m: f64,
    /// The flanks' angle `θ` (degrees, in `(0, 90)`).
    pub slope_deg: f64,
    /// The slab's depth along `z` (m; a multiple of the spacing).
    pub slab_depth_m: f64,
}

impl SlopeSetup {
    /// The surface's height (m) over `x` (m).
    pub fn surface_m(&self, x: f64) -> f64 {
        let x0 = 0.5 * (self.period_x_m - self.base_width_m);
        let rise = (x - x0).min(x0 + self.base_width_m - x).max(0.0);
        (self.slope_deg.to_radians().tan() * rise).min(self.height_m)
    }
}

/// The solver and the mound's particles at `t = 0` for `params` (its spacing sets the
/// lattice; its `periodic`, `wall_models` and `initial_stress` are replaced), set up as
/// `setup` says ([`SlopeSetup`]).
pub fn cut_slope<R: Real>(
    mut params: ElastoplasticParams<R>,
    setup: SlopeSetup,
) -> Result<(Elastoplastic<R>, ParticleSet<R>), SolverError> {
    let s = params.common.particle_spacing;
    let (l, d) = (setup.period_x_m, setup.slab_depth_m);
    if !(setup.slope_deg > 0.0 && setup.slope_deg < 90.0) {
        return Err(SolverError::InvalidParameter {
            solver: "elastoplastic",
            name: "slope_deg",
            value: setup.slope_deg,
            reason: "a slope's angle must lie in (0, 90) degrees",
        });
    }
    params.initial_stress = InitialStress::Geostatic;
    let region = aabb([0.0, 0.0, 0.0], [l, setup.height_m, d])?;
    let mut positions = cubic_lattice(&region, s, 1 << 22)?;
    positions.retain(|p| p.y.as_f64() <= setup.surface_m(p.x.as_f64()));
    let state = ParticleSet::from_positions(
        positions,
        params.common.particle_mass(),
        params.common.rest_density,
    );
    let solver = floored_slab(params, l, d, setup.height_m)?;
    Ok((solver, state))
}

/// The solver of a slab periodic along `x` (period `l`, m) and `z` (depth `d`, m) over a
/// floor at `y = 0`: the floor's plane only keeps grains out, [`BOUNDARY_ROWS`] rows of
/// no-slip boundary particles under it carry its stress; the walls' domain reaches `top_m`
/// above the floor. Replaces `params`' `periodic` and `wall_models`.
fn floored_slab<R: Real>(
    mut params: ElastoplasticParams<R>,
    l: f64,
    d: f64,
    top_m: f64,
) -> Result<Elastoplastic<R>, SolverError> {
    let s = params.common.particle_spacing;
    params.periodic = [(0, l), (2, d)]
        .into_iter()
        .map(|(axis, hi)| PeriodicAxis {
            axis,
            lo: R::zero(),
            hi: R::of_f64(hi),
        })
        .collect();
    params.wall_models = vec![WallModel::ContactOnly];
    let solids: Solids<R> = vec![Box::new(Plane::new(v(0.0, 0.0, 0.0), v(0.0, 1.0, 0.0))?)];
    let domain = aabb([-0.05, -0.05, -0.05], [l + 0.05, top_m + 0.1, d + 0.05])?;
    let walls = Elastoplastic::volume_map_walls(solids, &params, domain, None)?;
    let mut solver = ElastoplasticScheme::solver(params, walls)?;
    let rows = aabb([0.0, -BOUNDARY_ROWS * s.as_f64(), 0.0], [l, 0.0, d])?;
    let floor = boundary_block(&rows, s, v(0.0, 1.0, 0.0), WallModel::NoSlip, 1 << 22)?;
    solver.scheme_mut().set_boundary_particles(floor)?;
    Ok(solver)
}

/// A heap poured onto a floor (the funnel method; [`Pour`]): a no-slip floor of
/// boundary particles (three rows under `y = 0`, the floor plane only keeping grains out)
/// across a period `period_x_m` along `x` and `slab_depth_m` along `z` (plane strain
/// without walls), no grains at the start, and a funnel `funnel_width_m` wide across the
/// slab at the period's middle that pours `volume_m3` at `rate_m3_s`, its top
/// `funnel_top_m` above the floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PouredSetup {
    /// The period along `x` (m; a multiple of the spacing).
    pub period_x_m: f64,
    /// The slab's depth along `z` (m; a multiple of the spacing).
    pub slab_depth_m: f64,
    /// The funnel's width along `x` (m; at least a spacing).
    pub funnel_width_m: f64,
    /// The funnel's top above the floor (m): the heap must stay below it.
    pub funnel_top_m: f64,
    /// The bulk volume poured (m³).
    pub volume_m3: f64,
    /// The rate (m³/s).
    pub rate_m3_s: f64,
    /// The pour's seed ([`Pour::seed`]).
    pub seed: Option<u64>,
}

impl PouredSetup {
    /// The poured heap (the shipped scenes' at 20 mm, where their slab is three spacings
    /// deep) at spacing `s` (m): period
    /// 1.6 m, slab three spacings deep, a funnel 0.1 m wide (a stream five grains wide at
    /// 20 mm: a stream one grain wide builds a loose heap), 0.16 m² of cross-section poured
    /// at 0.012 m² a second (30 grains a second at 20 mm).
    pub fn for_spacing(s: f64) -> Self {
        let slab = 3.0 * s;
        Self {
            period_x_m: 1.6,
            slab_depth_m: slab,
            funnel_width_m: 0.1,
            funnel_top_m: 1.0,
            volume_m3: 0.16 * slab,
            rate_m3_s: 0.012 * slab,
            seed: None,
        }
    }
}

/// The solver and its (empty) particle set at `t = 0` for `params` (its spacing sets the
/// lattice; its `periodic`, `wall_models`, `pour` and `initial_stress` are replaced), set
/// up as `setup` says ([`PouredSetup`]).
pub fn poured_heap<R: Real>(
    mut params: ElastoplasticParams<R>,
    setup: PouredSetup,
) -> Result<(Elastoplastic<R>, ParticleSet<R>), SolverError> {
    let (l, d) = (setup.period_x_m, setup.slab_depth_m);
    params.initial_stress = InitialStress::None;
    let half = 0.5 * setup.funnel_width_m;
    params.pour = Some(Pour {
        region: aabb(
            [0.5 * l - half, 0.0, 0.0],
            [0.5 * l + half, setup.funnel_top_m, d],
        )?,
        volume_m3: R::of_f64(setup.volume_m3),
        rate_m3_s: R::of_f64(setup.rate_m3_s),
        seed: setup.seed,
    });
    let solver = floored_slab(params, l, d, setup.funnel_top_m)?;
    let state = ParticleSet::from_positions(Vec::new(), R::zero(), R::zero());
    Ok((solver, state))
}
