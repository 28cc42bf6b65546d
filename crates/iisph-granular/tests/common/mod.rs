//! Scenes shared by the tests.

#![allow(dead_code)]

use iisph_granular::{Iisph, IisphParams, ParticleSet, Real};
use sph_core::{Aabb, BoxSdf, Inverted};
use sph_kernels::KernelKind;
use sph_solver::boundary::{VolumeMapBoundary, VolumeMapOptions};
use sph_solver::testing as t;
use sph_solver::Solids;

/// A block of `n` particles in the corner of a tank of `tank` spacings (the outer layers
/// `s/2` from the walls), with volume-map walls of the solver's kernel (contact distance s/4).
pub fn block_solver<R: Real>(
    p: IisphParams<R>,
    n: [usize; 3],
    tank: [f64; 3],
) -> (Iisph<R>, ParticleSet<R>) {
    let (state, solids, tank_box) = t::block_in_tank(&p.common, n, tank);
    let b = VolumeMapBoundary::new(
        solids,
        KernelKind::CubicSpline,
        p.common.support_radius,
        tank_box,
        p.common.particle_radius() * R::of_f64(0.5),
        VolumeMapOptions::default(),
    )
    .unwrap();
    (Iisph::with_boundary(p, Box::new(b)).unwrap(), state)
}

/// [`block_solver`] with the masses scaled so that no particle starts compressed: on the
/// lattice with volume-map walls the wall layers start up to 7.5 % above `ρ0` (the
/// volume map integrates the wall continuously, the fluid is a lattice sum), which IISPH
/// removes within one time step, throwing the block up.
pub fn relaxed_block_solver<R: Real>(
    p: IisphParams<R>,
    n: [usize; 3],
    tank: [f64; 3],
) -> (Iisph<R>, ParticleSet<R>) {
    let rho0 = p.common.rest_density;
    let (mut solver, mut state) = block_solver(p, n, tank);
    solver.assemble_system(&state).unwrap();
    let max = solver
        .system_density()
        .iter()
        .fold(R::zero(), |a, &b| if b > a { b } else { a });
    let k = rho0 / max;
    for m in &mut state.masses {
        *m *= k;
    }
    (solver, state)
}

/// Solids of a closed tank of `tank` spacings.
pub fn tank<R: Real>(s: R, tank: [f64; 3]) -> (Solids<R>, Aabb<R>) {
    let v =
        |a: [f64; 3]| sph_core::Vec3::new(R::of_f64(a[0]), R::of_f64(a[1]), R::of_f64(a[2])) * s;
    let b = Aabb::new(sph_core::Vec3::zeros(), v(tank)).unwrap();
    (vec![Box::new(Inverted(BoxSdf::new(b).unwrap()))], b)
}
