//! The factory: a scene's `[solver]` and `[boundary]` sections to a running solver.
//!
//! Adding a solver to the workspace means one crate implementing
//! [`sph_solver::FluidSolver`], its variant in `sph_scene::SolverSpec`, and one arm in
//! [`build_solver`] with the function that turns the variant's settings into the solver's
//! parameters.

use iisph_granular::{GranularParams, Iisph, IisphParams};
use pbf::{Pbf, PbfParams};
use pcisph::{Pcisph, PcisphParams};
use sph_core::{Aabb, Real, Vec3};
use sph_kernels::KernelKind;
use sph_scene::{BoundaryModel, GranularSpec, IisphSpec, PbfSpec, PcisphSpec, Scene, SolverSpec};
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapOptions};
use sph_solver::{Boundary, CollisionBoundary, CommonParams, FluidSolver, SolverError};

use crate::SimError;

/// Contact distance of the volume-map model, as a fraction of the particle radius `s/2`:
/// particles are projected out of a solid only when closer than `s/4` to it (a safety net
/// against tunnelling in fast impacts); at rest the boundary density keeps them near `s/2`.
pub const VOLUME_MAP_CONTACT_FRACTION: f64 = 0.5;

fn r<R: Real>(x: f64) -> R {
    R::of_f64(x)
}

fn vec3<R: Real>(v: [f64; 3]) -> Vec3<R> {
    Vec3::new(r(v[0]), r(v[1]), r(v[2]))
}

/// A solver or boundary refusing `scene`'s parameters.
fn setup_error(scene: &Scene, source: SolverError) -> SimError {
    SimError::Setup {
        file: scene.source.display().to_string(),
        source,
    }
}

/// The solver a scene describes, with its boundary, in precision `R`. Errors name the scene
/// file and the refused parameter.
pub fn build_solver<R: Real>(scene: &Scene) -> Result<Box<dyn FluidSolver<R>>, SimError> {
    let setup = |source| setup_error(scene, source);
    match &scene.solver {
        SolverSpec::Pbf(s) => {
            let p = pbf_params::<R>(scene, s).map_err(setup)?;
            let b = build_boundary(scene, &p.common)?;
            Ok(Box::new(Pbf::with_boundary(p, b).map_err(setup)?))
        }
        SolverSpec::Pcisph(s) => {
            let p = pcisph_params::<R>(scene, s).map_err(setup)?;
            let b = build_boundary(scene, &p.common)?;
            Ok(Box::new(Pcisph::with_boundary(p, b).map_err(setup)?))
        }
        SolverSpec::Iisph(s) => {
            let p = iisph_params::<R>(scene, s).map_err(setup)?;
            let b = build_boundary_with_kernel(scene, &p.common, density_kernel(scene))?;
            Ok(Box::new(Iisph::with_boundary(p, b).map_err(setup)?))
        }
        SolverSpec::Granular(s) => {
            let p = granular_params::<R>(scene, s).map_err(setup)?;
            let b = build_boundary_with_kernel(scene, &p.common, density_kernel(scene))?;
            Ok(Box::new(Iisph::with_boundary(p, b).map_err(setup)?))
        }
    }
}

/// The density kernel of the solver a scene asks for (the kernel its volume maps are
/// integrated with): Poly6 for PBF and PCISPH, the cubic spline for the IISPH kinds.
pub fn density_kernel(scene: &Scene) -> KernelKind {
    match scene.solver {
        SolverSpec::Pbf(_) | SolverSpec::Pcisph(_) => KernelKind::Poly6,
        SolverSpec::Iisph(_) | SolverSpec::Granular(_) => KernelKind::CubicSpline,
    }
}

/// The IISPH (water) parameters a scene asks for: `IisphParams::for_spacing` at the scene's
/// spacing, then the scene's frame length and gravity and the settings `s` of its
/// `[solver]` section. Validated.
pub fn iisph_params<R: Real>(scene: &Scene, s: &IisphSpec) -> Result<IisphParams<R>, SolverError> {
    let mut p = IisphParams::<R>::for_spacing(r(scene.particle_spacing));
    p.common = common_from_scene(
        scene,
        p.common,
        s.substeps,
        s.support_over_spacing,
        s.rest_density,
        s.reorder_every,
    );
    if let Some(k) = s.max_iterations {
        p.max_iterations = k;
    }
    if let Some(k) = s.min_iterations {
        p.min_iterations = k;
    }
    if let Some(t) = s.density_error_tolerance {
        p.density_error_tolerance = r(t);
    }
    if let Some(w) = s.relaxation {
        p.relaxation = r(w);
    }
    if let Some(nu) = s.viscosity {
        p.viscosity = r(nu);
    }
    p.validate()?;
    Ok(p)
}

/// The granular IISPH parameters a scene asks for: [`iisph_params`] of the shared settings,
/// then friction angle, drag, air velocity and upscaling. Validated.
pub fn granular_params<R: Real>(
    scene: &Scene,
    s: &GranularSpec,
) -> Result<IisphParams<R>, SolverError> {
    let shared = IisphSpec {
        substeps: s.substeps,
        max_iterations: s.max_iterations,
        min_iterations: s.min_iterations,
        density_error_tolerance: s.density_error_tolerance,
        relaxation: s.relaxation,
        rest_density: s.rest_density,
        support_over_spacing: s.support_over_spacing,
        reorder_every: s.reorder_every,
        viscosity: s.viscosity,
    };
    let mut p = iisph_params::<R>(scene, &shared)?;
    let mut g = GranularParams::with_friction_angle(r(s.friction_angle_deg));
    if let Some(c) = s.drag_coefficient {
        g.drag_coefficient = r(c);
    }
    if let Some(v) = s.air_velocity {
        g.air_velocity = vec3(v);
    }
    if let Some(n) = s.friction_max_iterations {
        g.friction_max_iterations = n;
    }
    if let Some(t) = s.friction_tolerance {
        g.friction_tolerance = r(t);
    }
    p.granular = Some(g);
    p.upscaling_factor = s.upscaling_factor;
    p.validate()?;
    Ok(p)
}

/// The parameters every solver takes from the scene: spacing, support radius, rest
/// density, frame length, gravity, substeps, reordering.
fn common_from_scene<R: Real>(
    scene: &Scene,
    mut c: CommonParams<R>,
    substeps: usize,
    support_over_spacing: Option<f64>,
    rest_density: Option<f64>,
    reorder_every: Option<usize>,
) -> CommonParams<R> {
    if let Some(ratio) = support_over_spacing {
        c.support_radius = r::<R>(scene.particle_spacing * ratio);
    }
    if let Some(rho0) = rest_density {
        c.rest_density = r(rho0);
    }
    if let Some(k) = reorder_every {
        c.reorder_every = k;
    }
    c.dt = r(scene.frame_dt_s);
    c.gravity = vec3(scene.gravity);
    c.substeps = substeps;
    c
}

/// The PBF parameters a scene asks for: `PbfParams::for_spacing` at the scene's spacing,
/// then the scene's frame length and gravity and the settings `s` of its `[solver]`
/// section. Validated.
pub fn pbf_params<R: Real>(scene: &Scene, s: &PbfSpec) -> Result<PbfParams<R>, SolverError> {
    let mut p = PbfParams::<R>::for_spacing(r(scene.particle_spacing));
    p.common = common_from_scene(
        scene,
        p.common,
        s.substeps,
        s.support_over_spacing,
        s.rest_density,
        s.reorder_every,
    );
    let relative_cfm = s.relative_cfm.unwrap_or(pbf::DEFAULT_RELATIVE_CFM);
    if let Some(d_ref) = p.reference_denominator() {
        p.cfm_epsilon = d_ref * r::<R>(relative_cfm);
    }
    p.solver_iterations = s.iterations;
    if let Some(k) = s.scorr_k {
        p.scorr_k = r(k);
    }
    if let Some(n) = s.scorr_n {
        p.scorr_n = n;
    }
    if let Some(dq) = s.scorr_delta_q {
        p.scorr_delta_q = r(dq);
    }
    if let Some(e) = s.vorticity_epsilon {
        p.vorticity_epsilon = r(e);
    }
    if let Some(c) = s.xsph_c {
        p.xsph_c = r(c);
    }
    if let Some(c) = s.clamp_negative_constraint {
        p.clamp_negative_constraint = c;
    }
    if let Some(t) = s.mean_compression_tolerance {
        p.mean_compression_tolerance = Some(r(t));
        p.min_solver_iterations = s
            .min_iterations
            .unwrap_or(p.min_solver_iterations.min(s.iterations));
    }
    p.validate()?;
    Ok(p)
}

/// The PCISPH parameters a scene asks for: `PcisphParams::for_spacing` at the scene's
/// spacing, then the scene's frame length and gravity and the settings `s` of its
/// `[solver]` section. Validated.
pub fn pcisph_params<R: Real>(
    scene: &Scene,
    s: &PcisphSpec,
) -> Result<PcisphParams<R>, SolverError> {
    let mut p = PcisphParams::<R>::for_spacing(r(scene.particle_spacing));
    p.common = common_from_scene(
        scene,
        p.common,
        s.substeps,
        s.support_over_spacing,
        s.rest_density,
        s.reorder_every,
    );
    p.pressure_iterations = s.iterations;
    if let Some(c) = s.xsph_c {
        p.xsph_c = r(c);
    }
    if let Some(c) = s.clamp_negative_pressure {
        p.clamp_negative_pressure = c;
    }
    if let Some(t) = s.density_error_tolerance {
        p.density_error_tolerance = Some(r(t));
    }
    p.validate()?;
    Ok(p)
}

/// The region where the fluid can be: the tank, or else the fluid's initial box and the
/// bounded solids, in the solver's precision.
fn domain<R: Real>(scene: &Scene) -> Result<Aabb<R>, SimError> {
    let (lo, hi) = match scene.tank {
        Some(t) => (t.min, t.max),
        None => {
            let pts = scene.fluid_positions::<f64>()?;
            let mut lo = Vec3::repeat(f64::INFINITY);
            let mut hi = Vec3::repeat(f64::NEG_INFINITY);
            for p in &pts {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
            if pts.is_empty() {
                lo = Vec3::zeros();
                hi = Vec3::repeat(scene.particle_spacing);
            }
            (lo, hi)
        }
    };
    Aabb::new(vec3(lo.into()), vec3(hi.into())).map_err(|e| {
        SimError::Invalid(format!(
            "{}: no domain for the volume maps: {e}",
            scene.source.display()
        ))
    })
}

/// The boundary a scene asks for (`[boundary] model`), for a solver with the parameters
/// `c` and the density kernel of the scene's solver ([`density_kernel`]):
/// [`build_boundary_with_kernel`].
pub fn build_boundary<R: Real>(
    scene: &Scene,
    c: &CommonParams<R>,
) -> Result<Box<dyn Boundary<R>>, SimError> {
    build_boundary_with_kernel(scene, c, density_kernel(scene))
}

/// The boundary a scene asks for (`[boundary] model`), for a solver with the parameters
/// `c` and the density kernel `kernel`: its solids as a [`CollisionBoundary`] at the
/// particle radius, or as a [`VolumeMapBoundary`] of `kernel` at the support radius with
/// contact distance [`VOLUME_MAP_CONTACT_FRACTION`] of the particle radius.
pub fn build_boundary_with_kernel<R: Real>(
    scene: &Scene,
    c: &CommonParams<R>,
    kernel: KernelKind,
) -> Result<Box<dyn Boundary<R>>, SimError> {
    let solids = scene.build_solids::<R>()?;
    let setup = |source| setup_error(scene, source);
    match scene.boundary.model {
        BoundaryModel::Collision => Ok(Box::new(
            CollisionBoundary::new(solids, c.particle_radius()).map_err(setup)?,
        )),
        BoundaryModel::VolumeMap => {
            let b = VolumeMapBoundary::new(
                solids,
                kernel,
                c.support_radius,
                domain(scene)?,
                c.particle_radius() * r::<R>(VOLUME_MAP_CONTACT_FRACTION),
                VolumeMapOptions::default(),
            )
            .map_err(setup)?;
            Ok(Box::new(b))
        }
    }
}
