//! The fixed-base heap of the shipped scene `granular_repose_thesis_30` built in Rust, a
//! drained bed ([`drained_bed`]) and a poured heap ([`poured_heap`]). Whether a heap is at rest is judged by
//! `granular_measure::rest` (the examples `heap_30` and `drained` do).
//!
//! Geometry (m): a tank `[0, 2.4] × [0, 0.8] × [0, 0.03]`, a base `[0.8, 1.6] × [0, 0.25]`
//! across the slab, and a block `[0.8, 1.6] × [0.25, 0.55]` on it, on a cubic lattice half
//! a spacing from its faces. Across the slab either free-slip walls (solids 0 and 1 the
//! front and back walls `z = 0`, `z = 0.03`, then 2 the tank's floor and ends, 3 the base)
//! or periodic ends (plane strain without walls); then the tank's floor, its two ends, and
//! the base.

use sph_core::sampling::cubic_lattice;
use sph_core::{Aabb, BoxSdf, ParticleSet, Plane, Real, Vec3};
use sph_solver::{Solids, SolverError};

use crate::boundary_particles::boundary_block;
use crate::params::{ElastoplasticParams, InitialStress, MovingWall, WallModel};
use crate::periodic::PeriodicAxis;
use crate::pour::Pour;
use crate::solver::{Elastoplastic, ElastoplasticScheme};
use crate::walls::volume_map_walls;

/// The base's top (m): the heap's floor.
pub const BASE_TOP_M: f64 = 0.25;
/// The base's ends along `x` (m) in the shipped scene; the block stands on `[0.8, 1.6]`
/// whatever the base's width ([`HeapSetup::base_x_m`]).
pub const BASE_X_M: [f64; 2] = [0.8, 1.6];
/// A base nearly as wide as the tank (m), so that the block's runout ends on it: at the
/// quick spacing only a tail one grain thick reaches its ends, and the heap's slope is
/// measured away from its feet, as a repose test is set up.
pub const WIDE_BASE_X_M: [f64; 2] = [0.05, 2.35];
/// The slab's depth along `z` (m).
pub const SLAB_DEPTH_M: f64 = 0.03;

fn v<R: Real>(x: f64, y: f64, z: f64) -> Vec3<R> {
    Vec3::new(R::of_f64(x), R::of_f64(y), R::of_f64(z))
}

fn aabb<R: Real>(lo: [f64; 3], hi: [f64; 3]) -> Result<Aabb<R>, SolverError> {
    Ok(Aabb::new(v(lo[0], lo[1], lo[2]), v(hi[0], hi[1], hi[2]))?)
}

/// What bounds the slab across `z`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SlabSides {
    /// Free-slip walls at `z = 0` and `z = SLAB_DEPTH_M`.
    FreeSlipWalls,
    /// Periodic ends: the slab repeats along `z` (plane strain without walls).
    Periodic,
}

/// How the heap is set up: what bounds the slab across `z`, whether the tank's floor and
/// the base are rows of boundary particles ([`crate::boundary_particles`], no-slip; the
/// solids then only keep particles out) or volume-map walls, and whether the block starts
/// from the geostatic stress of its columns ([`crate::initial::geostatic`]: `σ_yy = −ρ0 g
/// d`, `σ_xx = σ_zz = K0 σ_yy`, `K0 = ν/(1 − ν)`, `d` the depth below the column's top
/// grain plus half a spacing) or unstressed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeapSetup {
    /// What bounds the slab across `z`.
    pub sides: SlabSides,
    /// Floor and base as boundary particles.
    pub particle_walls: bool,
    /// The model of the base's vertical sides when they are boundary particles (the
    /// base's top and the floor are no-slip).
    pub base_sides: WallModel,
    /// Start from the geostatic stress.
    pub geostatic: bool,
    /// The base's ends along `x` (m), inside the tank `(0, 2.4)`: [`BASE_X_M`] (the scene's)
    /// or wider ([`WIDE_BASE_X_M`]); the block is `[0.8, 1.6]` along `x` either way.
    pub base_x_m: [f64; 2],
    /// `None`: the block `[0.8, 1.6] × [0.25, 0.55]`; `Some(θ)`: a symmetric wedge on the
    /// base with flanks at `θ` degrees (`y ≤ 0.25 + tan θ · min(x − 0.8, 1.6 − x)`, the
    /// particles of the block's lattice below it), the geostatic stress measured from
    /// the top grain of each column (half a spacing above it).
    pub wedge_deg: Option<f64>,
}

/// The initial stress of a set-up that starts from the geostatic stress or unstressed.
fn geostatic_or_none(geostatic: bool) -> InitialStress {
    if geostatic {
        InitialStress::Geostatic
    } else {
        InitialStress::None
    }
}

/// Rows of boundary particles standing for a wall (three spacings thick: the support is
/// 2.4 spacings).
const BOUNDARY_ROWS: f64 = 3.0;

/// The solver and the block's particles at `t = 0` for `params` (its spacing sets the
/// lattice), set up as `setup` says; the tank (floor and ends) and the base are no-slip.
pub fn fixed_base_heap<R: Real>(
    mut params: ElastoplasticParams<R>,
    setup: HeapSetup,
) -> Result<(Elastoplastic<R>, ParticleSet<R>), SolverError> {
    let s = params.common.particle_spacing;
    let d = SLAB_DEPTH_M;
    let (far_lo, far_hi) = (-0.5, d + 0.5);
    let mut solids: Solids<R> = Vec::new();
    params.wall_models.clear();
    params.periodic.clear();
    match setup.sides {
        SlabSides::FreeSlipWalls => {
            solids.push(Box::new(Plane::new(v(0.0, 0.0, 0.0), v(0.0, 0.0, 1.0))?));
            solids.push(Box::new(Plane::new(v(0.0, 0.0, d), v(0.0, 0.0, -1.0))?));
            params.wall_models = vec![WallModel::FreeSlip; 2];
        }
        SlabSides::Periodic => params.periodic.push(PeriodicAxis {
            axis: 2,
            lo: R::zero(),
            hi: R::of_f64(d),
        }),
    }
    let floor_and_base = if setup.particle_walls {
        WallModel::ContactOnly
    } else {
        WallModel::NoSlip
    };
    solids.push(Box::new(Plane::new(v(0.0, 0.0, 0.0), v(0.0, 1.0, 0.0))?));
    solids.push(Box::new(Plane::new(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0))?));
    solids.push(Box::new(Plane::new(v(2.4, 0.0, 0.0), v(-1.0, 0.0, 0.0))?));
    solids.push(Box::new(BoxSdf::new(aabb(
        [setup.base_x_m[0], -0.5, far_lo],
        [setup.base_x_m[1], BASE_TOP_M, far_hi],
    )?)?));
    params.wall_models.extend([
        floor_and_base,
        WallModel::NoSlip,
        WallModel::NoSlip,
        floor_and_base,
    ]);
    let domain = aabb([0.0, 0.0, -0.05], [2.4, 0.8, d + 0.05])?;
    let walls = volume_map_walls(solids, &params, domain)?;
    let top = 0.55;
    let block = aabb([BASE_X_M[0], BASE_TOP_M, 0.0], [BASE_X_M[1], top, d])?;
    let surface = |x: f64| match setup.wedge_deg {
        Some(a) => BASE_TOP_M + a.to_radians().tan() * (x - BASE_X_M[0]).min(BASE_X_M[1] - x),
        None => top,
    };
    let mut positions = cubic_lattice(&block, s, 1 << 22)?;
    positions.retain(|p| p.y.as_f64() <= surface(p.x.as_f64()));
    let state = ParticleSet::from_positions(
        positions,
        params.common.particle_mass(),
        params.common.rest_density,
    );
    params.initial_stress = geostatic_or_none(setup.geostatic);
    let mut solver = ElastoplasticScheme::solver(params, walls)?;
    if setup.particle_walls {
        let t = BOUNDARY_ROWS * s.as_f64();
        let ([x0, x1], yb) = (setup.base_x_m, BASE_TOP_M);
        let up = v(0.0, 1.0, 0.0);
        let mut rows = Vec::new();
        let (no, side) = (WallModel::NoSlip, setup.base_sides);
        for (lo, hi, normal, model) in [
            ([0.0, -t, 0.0], [x0, 0.0, d], up, no),
            ([x1, -t, 0.0], [2.4, 0.0, d], up, no),
            ([x0, yb - t, 0.0], [x1, yb, d], up, no),
            ([x0, 0.0, 0.0], [x0 + t, yb - t, d], v(-1.0, 0.0, 0.0), side),
            ([x1 - t, 0.0, 0.0], [x1, yb - t, d], v(1.0, 0.0, 0.0), side),
        ] {
            rows.extend(boundary_block(&aabb(lo, hi)?, s, normal, model, 1 << 22)?);
        }
        solver.scheme_mut().set_boundary_particles(rows)?;
    }
    Ok((solver, state))
}

/// A drained bed: a layer of grains on a perforated floor, drained through a slot into a
/// sump below, so that the two slopes left beside the slot form quasi-statically (the
/// drained angle of repose; Nedderman 1992, *Statics and Kinematics of Granular
/// Materials*, Cambridge University Press, ch. 1).
///
/// Geometry (m): periodic along `x` with period `period_x_m` and along `z` with
/// `slab_depth_m` (plane strain without walls); the slot `|x| < slot_width_m / 2` (mod the
/// period) is centred on the periodic seam, so that the grains left on the floor
/// `[slot/2, period − slot/2]` form one mound whose two flanks descend to the slot's edges
/// (a planar heap for the angle-of-repose measure of `granular-measure`, floor `y = 0`).
/// The floor is a plate of [`DRAINED_PLATE_ROWS`] rows of no-slip boundary particles under
/// `y = 0`, thick enough that none of them sees both the bed and the sump (support 2.4
/// spacings); the sump is the space `sump_depth_m` deep under the plate, closed by three rows of no-slip boundary
/// particles. At `t = 0` the bed `[0, period) × [0, bed_height_m]` is at rest, with the
/// geostatic stress if asked, and the grains over the slot start to fall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrainedSetup {
    /// The period along `x` (m; a multiple of the spacing).
    pub period_x_m: f64,
    /// The bed's initial height (m).
    pub bed_height_m: f64,
    /// The slot's width (m; an even multiple of the spacing).
    pub slot_width_m: f64,
    /// The sump's depth under the plate (m).
    pub sump_depth_m: f64,
    /// The slab's depth along `z` (m; a multiple of the spacing).
    pub slab_depth_m: f64,
    /// Start from the geostatic stress ([`crate::initial::geostatic`]: `σ_yy = −ρ0 g
    /// (H − y)`, `σ_xx = σ_zz = K0 σ_yy`, `K0 = ν/(1 − ν)`) rather than unstressed.
    pub geostatic: bool,
    /// `None`: the slot is open over the sump (the grains fall through it). `Some(v)`: a
    /// slow drain. The slot is a channel `sump_depth_m` deep with free-slip walls, closed at
    /// the plate's top by a trapdoor (three rows of no-slip boundary particles) that is
    /// lowered at `v` m/s until it reaches the channel's floor (a [`MovingWall`]): the grains
    /// over the slot descend with it and the flanks form by slow flows.
    pub trapdoor_speed_m_s: Option<f64>,
}

/// Rows of boundary particles in the drained bed's floor plate: with the support 2.4
/// spacings, a plate four or more rows thick has no boundary particle within the support of
/// both the bed above and the sump below (their stresses would mix in its Shepard average).
pub const DRAINED_PLATE_ROWS: f64 = 5.0;

impl DrainedSetup {
    /// The bed of the shipped scenes `scenes/granular_repose_30.toml` at spacing `s` (m):
    /// period 1.2 m, bed 0.2 m high, slot 0.24 m wide (twelve grains at 20 mm: a narrower
    /// one jams, run 30 of `docs/elastoplastic-granular.md`; runs 16–29 took 0.12 m), sump
    /// 0.6 m deep, slab three spacings deep, geostatic start.
    pub fn for_spacing(s: f64) -> Self {
        Self {
            period_x_m: 1.2,
            bed_height_m: 0.2,
            slot_width_m: 0.24,
            sump_depth_m: 0.6,
            slab_depth_m: 3.0 * s,
            geostatic: true,
            trapdoor_speed_m_s: None,
        }
    }

    /// How long the trapdoor takes to reach the channel's floor (s; `None` without one).
    pub fn trapdoor_travel_s(&self) -> Option<f64> {
        self.trapdoor_speed_m_s.map(|v| self.sump_depth_m / v)
    }

    /// Whether a grain at `p` is on the floor beside the slot (part of the drained heap).
    pub fn on_floor<R: Real>(&self, p: &Vec3<R>) -> bool {
        let (x, y) = (p.x.as_f64(), p.y.as_f64());
        let half = 0.5 * self.slot_width_m;
        y > 0.0 && x >= half && x <= self.period_x_m - half
    }
}

/// The solver and the bed's particles at `t = 0` for `params` (its spacing sets the
/// lattice), set up as `setup` says ([`DrainedSetup`]).
pub fn drained_bed<R: Real>(
    mut params: ElastoplasticParams<R>,
    setup: DrainedSetup,
) -> Result<(Elastoplastic<R>, ParticleSet<R>), SolverError> {
    let s = params.common.particle_spacing.as_f64();
    let (l, h, half, d) = (
        setup.period_x_m,
        setup.bed_height_m,
        0.5 * setup.slot_width_m,
        setup.slab_depth_m,
    );
    let plate = DRAINED_PLATE_ROWS * s;
    let sump_floor = -plate - setup.sump_depth_m;
    params.periodic = vec![
        PeriodicAxis {
            axis: 0,
            lo: R::zero(),
            hi: R::of_f64(l),
        },
        PeriodicAxis {
            axis: 2,
            lo: R::zero(),
            hi: R::of_f64(d),
        },
    ];
    // The solids only keep grains out of the plate (down to the channel's floor with a
    // trapdoor: its sides are the channel's walls) and under the sump's floor.
    let (far_lo, far_hi) = (-0.5, d + 0.5);
    let plate_bottom = if setup.trapdoor_speed_m_s.is_some() {
        sump_floor
    } else {
        -plate
    };
    let solids: Solids<R> = vec![
        Box::new(BoxSdf::new(aabb(
            [half, plate_bottom, far_lo],
            [l - half, 0.0, far_hi],
        )?)?),
        Box::new(Plane::new(v(0.0, sump_floor, 0.0), v(0.0, 1.0, 0.0))?),
    ];
    params.wall_models = vec![WallModel::ContactOnly; 2];
    let domain = aabb(
        [-0.05, sump_floor - 0.05, -0.05],
        [l + 0.05, h + 0.1, d + 0.05],
    )?;
    let walls = volume_map_walls(solids, &params, domain)?;
    let bed = aabb([0.0, 0.0, 0.0], [l, h, d])?;
    let positions = cubic_lattice(&bed, params.common.particle_spacing, 1 << 22)?;
    let state = ParticleSet::from_positions(
        positions,
        params.common.particle_mass(),
        params.common.rest_density,
    );
    params.initial_stress = geostatic_or_none(setup.geostatic);
    if let (Some(speed), Some(travel_s)) = (setup.trapdoor_speed_m_s, setup.trapdoor_travel_s()) {
        // The door: three rows under the slot, across the periodic seam (the wall's box
        // wraps), on the bed's lattice.
        params.boundary_particle_region = Some(bed);
        params.moving_walls = vec![MovingWall {
            region: aabb([-half, -BOUNDARY_ROWS * s, far_lo], [half, 0.0, far_hi])?,
            model: WallModel::NoSlip,
            velocity: v(0.0, -speed, 0.0),
            duration_s: R::of_f64(travel_s),
        }];
    }
    let mut solver = ElastoplasticScheme::solver(params, walls)?;
    let up = v(0.0, 1.0, 0.0);
    let mut rows = boundary_block(
        &aabb([half, -plate, 0.0], [l - half, 0.0, d])?,
        R::of_f64(s),
        up,
        WallModel::NoSlip,
        1 << 22,
    )?;
    rows.extend(boundary_block(
        &aabb(
            [0.0, sump_floor - BOUNDARY_ROWS * s, 0.0],
            [l, sump_floor, d],
        )?,
        R::of_f64(s),
        up,
        WallModel::NoSlip,
        1 << 22,
    )?);
    if setup.trapdoor_speed_m_s.is_some() {
        let wall = BOUNDARY_ROWS * s;
        for (x0, x1, nx) in [(half, half + wall, -1.0), (l - half - wall, l - half, 1.0)] {
            rows.extend(boundary_block(
                &aabb([x0, sump_floor, 0.0], [x1, -plate, d])?,
                R::of_f64(s),
                v(nx, 0.0, 0.0),
                WallModel::FreeSlip,
                1 << 22,
            )?);
        }
    }
    solver.scheme_mut().set_boundary_particles(rows)?;
    Ok((solver, state))
}

/// A slope cut in a settled layer: a mound of grains on a flat no-slip floor, periodic
/// along `x` (period `period_x_m`) and along `z` (`slab_depth_m`: plane strain without
/// walls), its cross-section the trapezoid
/// `y ≤ min(H, tan θ · min(x − x0, x0 + W − x))`, `x0 = (period − W)/2`, `W` its base
/// width: two flanks at `θ` rising from the floor to a flat top `H` high. The floor is
/// three rows of no-slip boundary particles under `y = 0` across the whole period (the
/// floor plane only keeps grains out); the grains start at rest on the lattice under the
/// surface with the geostatic stress of their columns
/// ([`InitialStress::Geostatic`],
/// [`crate::initial::geostatic`]), the static bracket's set-up (a slope formed without
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
            solver: crate::solver::NAME,
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
    let walls = volume_map_walls(solids, &params, domain)?;
    let mut solver = ElastoplasticScheme::solver(params, walls)?;
    let rows = aabb([0.0, -BOUNDARY_ROWS * s.as_f64(), 0.0], [l, 0.0, d])?;
    let floor = boundary_block(&rows, s, v(0.0, 1.0, 0.0), WallModel::NoSlip, 1 << 22)?;
    solver.scheme_mut().set_boundary_particles(floor)?;
    Ok(solver)
}

/// A heap poured onto a floor (the funnel method; [`crate::Pour`]): a no-slip floor of
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
}

impl PouredSetup {
    /// The heap of run 40 of `docs/elastoplastic-granular.md` at spacing `s` (m): period
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
    });
    let solver = floored_slab(params, l, d, setup.funnel_top_m)?;
    let state = ParticleSet::from_positions(Vec::new(), R::zero(), R::zero());
    Ok((solver, state))
}
