//! The factory: a scene's solver parameters and boundary to a running solver.
//!
//! Adding a solver to the workspace means one crate implementing
//! [`sph_solver::FluidSolver`] (through `sph_solver::FrameSolver`) and
//! [`sph_solver::SolverSettings`] for its settings struct, and one registration line in
//! `sph-scene`'s `solvers!`; [`build_solver`] and [`density_kernel`] follow from it.

use sph_core::{Aabb, Real, Vec3};
use sph_kernels::KernelKind;
use sph_scene::{BoundaryModel, Scene, SolverParams};
use sph_solver::boundary::{
    CacheUse, VolumeMapBoundary, VolumeMapBuild, VolumeMapCache, VolumeMapOptions,
};
use sph_solver::{Boundary, CollisionBoundary, CommonParams, FluidSolver, SolverError};

use crate::error::SimError;

/// The contact distance of volume-map walls, as a fraction of the particle radius (defined
/// in `sph-solver`, where every solver crate reaches it).
pub use sph_solver::VOLUME_MAP_CONTACT_FRACTION;

/// A solver or boundary refusing `scene`'s parameters.
fn setup_error(scene: &Scene, source: SolverError) -> SimError {
    SimError::Setup {
        file: scene.source.display().to_string(),
        source,
    }
}

/// The solver with parameters `params` and boundary `boundary` (e.g. of a
/// [`crate::SceneSetup`]): [`SolverParams::build`], one arm per registered solver. The
/// solver's constructor checks the parameters and that the boundary fits them.
pub fn build_solver<R: Real>(
    params: SolverParams<R>,
    boundary: Box<dyn Boundary<R>>,
) -> Result<Box<dyn FluidSolver<R>>, SolverError> {
    params.build(boundary)
}

/// The density kernel of the solver a scene asks for (the kernel its volume maps are
/// integrated with), as its crate's settings state it: Poly6 for PBF and PCISPH, the cubic
/// spline for the IISPH kinds.
pub fn density_kernel(scene: &Scene) -> KernelKind {
    scene.solver.density_kernel()
}

/// The region where the fluid can be: the tank, or else the box of the fluid's initial
/// `positions` (a cube of one spacing at the origin when there are none).
fn domain<R: Real>(scene: &Scene, positions: &[Vec3<R>]) -> Result<Aabb<R>, SimError> {
    let cast = |v: &Vec3<f64>| Vec3::new(R::of_f64(v.x), R::of_f64(v.y), R::of_f64(v.z));
    let (lo, hi) = match (&scene.tank, positions.first()) {
        (Some(t), _) => (cast(&t.min), cast(&t.max)),
        (None, Some(first)) => positions
            .iter()
            .fold((*first, *first), |(lo, hi), p| (lo.inf(p), hi.sup(p))),
        (None, None) => (
            Vec3::zeros(),
            Vec3::repeat(R::of_f64(scene.particle_spacing)),
        ),
    };
    Aabb::new(lo, hi).map_err(|e| {
        SimError::Invalid(format!(
            "{}: no domain for the volume maps: {e}",
            scene.source.display()
        ))
    })
}

/// The boundary a scene asks for (`[boundary] model`), for a solver with the parameters
/// `c`, the density kernel of the scene's solver ([`density_kernel`]) and the fluid's
/// initial `positions` (they bound the volume maps when there is no tank): the tank and
/// solids ([`Scene::build_solids`], built once here) as a [`CollisionBoundary`] at the
/// particle radius (`collision`, and `particles`, whose boundary particles the solver
/// samples from these solids), or as a [`VolumeMapBoundary`] of the kernel at the support radius with
/// contact distance [`VOLUME_MAP_CONTACT_FRACTION`] of the particle radius.
///
/// With `cache`, volume maps are loaded from (or built into) that cache
/// ([`VolumeMapCache`]); a refused cache file is rebuilt and reported on stderr.
pub fn build_boundary<R: Real>(
    scene: &Scene,
    c: &CommonParams<R>,
    positions: &[Vec3<R>],
    cache: Option<&VolumeMapCache>,
) -> Result<Box<dyn Boundary<R>>, SimError> {
    let how = VolumeMapBuild {
        cache,
        cancel: None,
    };
    build_boundary_reporting(scene, c, positions, how).map(|(b, _)| b)
}

/// A boundary and how each solid's volume map was obtained.
pub(crate) type BoundaryWithMaps<R> = (Box<dyn Boundary<R>>, Vec<CacheUse>);

/// [`build_boundary`] with the volume maps obtained as `how` says (a cache, a cancellation
/// flag), and how each solid's map was obtained (built, loaded from the cache, ...; empty
/// for the collision boundary).
pub(crate) fn build_boundary_reporting<R: Real>(
    scene: &Scene,
    c: &CommonParams<R>,
    positions: &[Vec3<R>],
    how: VolumeMapBuild<'_>,
) -> Result<BoundaryWithMaps<R>, SimError> {
    let solids = scene.build_solids::<R>()?;
    let setup = |source| setup_error(scene, source);
    match scene.boundary.model {
        // Boundary particles are sampled from these solids by the solver (the parameters
        // carry the region and each solid's model); the solids keep particles out, with
        // boundary particles at the volume maps' contact distance, a quarter spacing: a net
        // under the wall the boundary particles carry. At the particle radius (the
        // `collision` model's) it would hold the first layer, which rests half a spacing
        // above the wall, rigidly in place of the boundary particles' stress and round the
        // solids' edges by half a spacing (docs/elastoplastic-granular.md, "Walls, moving walls, periodic axes and the pour").
        BoundaryModel::Collision | BoundaryModel::Particles => {
            let contact = if scene.boundary.model == BoundaryModel::Particles {
                c.volume_map_contact_distance()
            } else {
                c.particle_radius()
            };
            Ok((
                Box::new(CollisionBoundary::new(solids, contact).map_err(setup)?),
                Vec::new(),
            ))
        }
        BoundaryModel::VolumeMap => {
            let b = VolumeMapBoundary::build(
                solids,
                density_kernel(scene),
                c.support_radius,
                domain(scene, positions)?,
                c.volume_map_contact_distance(),
                VolumeMapOptions::default(),
                how,
            )
            .map_err(setup)?;
            for w in b.cache_warnings() {
                eprintln!("warning: {w} (the map was rebuilt)");
            }
            let uses = b.maps().iter().map(|m| m.stats().cache).collect();
            Ok((Box::new(b), uses))
        }
    }
}
