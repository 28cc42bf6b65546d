//! Scenes, independent oracle formulas and helpers shared by the solver crates' tests
//! (feature `testing`; not part of the solvers' API).

mod alloc;
pub mod formulas;

pub use alloc::{assert_warm_steps_do_not_allocate, CountingAllocator};

use sph_core::{
    sampling::cubic_lattice, Aabb, BoxSdf, CoreError, Inverted, ParticleSet, Real, Vec3,
};

use crate::{CommonParams, FluidSolver, Solids, SolverError};

/// Whether two `f32` sums of the same `n` terms taken in different orders, `a` (the lanes')
/// and `b` (the scalar loop's), agree within `2 γ_n Σ|t_k|` (`abs_sum`), `γ_n = n u /
/// (1 − n u)`, `u = 2⁻²⁴`: each is within `γ_n Σ|t_k|` of the exact sum whatever its order
/// (Higham 2002, *Accuracy and Stability of Numerical Algorithms*, §3.1 and §4.2). `Err`
/// names `what` with the figures.
pub fn reordered_sums_agree(
    what: &str,
    a: f32,
    b: f32,
    n: usize,
    abs_sum: f64,
) -> Result<(), String> {
    let nu = n as f64 * f64::from(f32::EPSILON) / 2.0;
    let bound = 2.0 * nu / (1.0 - nu) * abs_sum;
    let diff = (f64::from(a) - f64::from(b)).abs();
    if diff <= bound {
        Ok(())
    } else {
        Err(format!(
            "{what}: lanes {a} scalar {b} differ by {diff} > {bound}"
        ))
    }
}

/// A fluid block of `n = [nx, ny, nz]` particles at spacing `s`, at rest in the corner
/// `(0, 0, 0)` of a tank of `tank = [tx, ty, tz]` spacings (an `Inverted<BoxSdf>`), with
/// masses `ρ0 s³`. The particles start `s/2` from the walls, i.e. touching them.
pub fn block_in_tank<R: Real>(
    params: &CommonParams<R>,
    n: [usize; 3],
    tank: [f64; 3],
) -> (ParticleSet<R>, Solids<R>, Aabb<R>) {
    let s = params.particle_spacing;
    let v = |a: [f64; 3]| Vec3::new(R::of_f64(a[0]), R::of_f64(a[1]), R::of_f64(a[2])) * s;
    let block = Aabb::new(Vec3::zeros(), v([n[0] as f64, n[1] as f64, n[2] as f64])).unwrap();
    let tank = Aabb::new(Vec3::zeros(), v(tank)).unwrap();
    let pts = cubic_lattice(&block, s, 1 << 20).unwrap();
    assert_eq!(pts.len(), n[0] * n[1] * n[2]);
    let state = ParticleSet::from_positions(pts, params.particle_mass(), params.rest_density);
    let solids: Solids<R> = vec![Box::new(Inverted(BoxSdf::new(tank).unwrap()))];
    (state, solids, tank)
}

/// Bit patterns of positions and velocities, for exact comparisons.
pub fn bits<R: Real>(state: &ParticleSet<R>) -> Vec<u64> {
    state
        .positions
        .iter()
        .chain(&state.velocities)
        .flat_map(|v| v.iter().map(|c| c.as_f64().to_bits()).collect::<Vec<_>>())
        .collect()
}

/// Runs `f` in a rayon pool of `threads` threads.
pub fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// Steps `solver` on `state` with particle 7's `y` set to NaN: the error must name particle 7
/// and axis `y`, and the state must be left untouched.
pub fn assert_nan_position_rejected(
    solver: &mut dyn FluidSolver<f64>,
    mut state: ParticleSet<f64>,
) {
    state.positions[7].y = f64::NAN;
    let before = bits(&state);
    let e = solver.step(&mut state).unwrap_err();
    assert!(
        matches!(
            e,
            SolverError::InvalidState(CoreError::NonFinitePosition {
                index: 7,
                axis: 'y',
                ..
            })
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("particle 7"), "{e}");
    assert_eq!(bits(&state), before, "state untouched");
}

/// The resume check of [`crate::FluidSolver::save_state`] and
/// [`crate::FluidSolver::restore_state`]: runs `2 k` frames straight; separately runs `k`
/// frames, saves the solver state, builds a *fresh* solver with `make`, restores the state
/// with the saved particles (a clone) and runs `k` more. Positions, velocities, densities
/// and passive points must be bit-identical after frame `2 k`, and so must both solvers'
/// saved states. Returns the state saved after `k` frames (for further checks).
pub fn assert_resume_is_bit_identical<R: Real>(
    make: &dyn Fn() -> Box<dyn FluidSolver<R>>,
    initial: &ParticleSet<R>,
    k: usize,
) -> crate::SolverState<R> {
    let mut straight = make();
    let mut a = initial.clone();
    for _ in 0..2 * k {
        straight.step(&mut a).unwrap();
    }
    let mut first = make();
    let mut b = initial.clone();
    for _ in 0..k {
        first.step(&mut b).unwrap();
    }
    let saved = first.save_state();
    let particles = b.clone();
    drop((first, b));
    assert_eq!(saved.frames, k as u64);
    let mut resumed = make();
    resumed.restore_state(&saved, particles.len()).unwrap();
    let mut c = particles;
    for _ in 0..k {
        resumed.step(&mut c).unwrap();
    }
    let bits_of = |v: &[R]| v.iter().map(|x| x.as_f64().to_bits()).collect::<Vec<_>>();
    let vec_bits = |v: &[Vec3<R>]| {
        v.iter()
            .flat_map(|p| [p.x, p.y, p.z])
            .map(|x| x.as_f64().to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(vec_bits(&a.positions), vec_bits(&c.positions), "positions");
    assert_eq!(
        vec_bits(&a.velocities),
        vec_bits(&c.velocities),
        "velocities"
    );
    assert_eq!(bits_of(&a.densities), bits_of(&c.densities), "densities");
    assert_eq!(
        straight.passive_points().map(vec_bits),
        resumed.passive_points().map(vec_bits),
        "passive points"
    );
    let (s1, s2) = (straight.save_state(), resumed.save_state());
    assert_eq!(s1.solver, s2.solver);
    assert_eq!(s1.frames, s2.frames);
    assert_eq!(s1.arrays.len(), s2.arrays.len());
    for ((n1, v1), (n2, v2)) in s1.arrays.iter().zip(&s2.arrays) {
        assert_eq!(n1, n2);
        assert_eq!(bits_of(v1), bits_of(v2), "carried array {n1}");
    }
    saved
}

/// The walls of a tank for [`block_in_tank`]: the collision model at the particle radius
/// `s/2` (`kernel` `None`, what the solvers' `new` builds) or volume maps integrated with
/// `kernel` and a contact distance of `s/4`.
pub fn tank_walls<R: Real>(
    common: &CommonParams<R>,
    solids: Solids<R>,
    tank: Aabb<R>,
    kernel: Option<sph_kernels::KernelKind>,
) -> Box<dyn crate::Boundary<R>> {
    let r = common.particle_radius();
    match kernel {
        None => Box::new(crate::CollisionBoundary::new(solids, r).unwrap()),
        Some(k) => Box::new(
            crate::VolumeMapBoundary::new(
                solids,
                k,
                common.support_radius,
                tank,
                r * R::of_f64(0.5),
                crate::VolumeMapOptions::default(),
            )
            .unwrap(),
        ),
    }
}

/// [`assert_resume_is_bit_identical`] for solver `S` with `params` on a block of 6 × 6 × 4
/// particles in a tank of 12 × 10 × 4 spacings with [`tank_walls`] of `kernel`, 5 + 5
/// frames (set `common.reorder_every` so that both halves reorder).
pub fn assert_block_resumes<R, S>(
    params: &S::Params,
    kernel: Option<sph_kernels::KernelKind>,
) -> crate::SolverState<R>
where
    R: Real,
    S: crate::SubstepScheme<R> + 'static,
{
    const BLOCK: [usize; 3] = [6, 6, 4];
    const TANK: [f64; 3] = [12.0, 10.0, 4.0];
    let common = crate::SolverParameters::common(params);
    let (state, _, _) = block_in_tank(common, BLOCK, TANK);
    let make = || -> Box<dyn FluidSolver<R>> {
        let (_, solids, tank) = block_in_tank(common, BLOCK, TANK);
        let walls = tank_walls(common, solids, tank, kernel);
        Box::new(crate::FrameSolver::<R, S>::with_boundary(params.clone(), walls).unwrap())
    };
    assert_resume_is_bit_identical(&make, &state, 5)
}
