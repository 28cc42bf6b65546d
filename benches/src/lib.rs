//! Scenes and peer adapters shared by the criterion benchmarks.

use rayon::prelude::*;
use sph_core::{Aabb, Real, Vec3};

/// The neighbour-search anchor scene of SPlisHSPlasH's `DamBreakModel.json` at particle
/// radius 0.0125 m (support 0.05 m): a fluid block of 39³ = 59,319 particles at spacing
/// 0.025 m starting at (−1.95, 0.05, −0.5) + half a spacing, and the walls of the 4 × 3 × 1.5 m
/// tank centred at (0, 1.5, 0), sampled here on square lattices of spacing 0.0186 m (131,976
/// particles, close to SPlisHSPlasH's 129,454 boundary particles from its own surface
/// sampling, which differs in detail). Returns (positions, fluid count).
pub fn dam_break_anchor<R: Real>() -> (Vec<Vec3<R>>, usize) {
    let s = 0.025;
    let mut p = Vec::new();
    for i in 0..39 {
        for j in 0..39 {
            for k in 0..39 {
                let f = |n: i32, lo: f64| R::of_f64(lo + s * (n as f64 + 0.5));
                p.push(Vec3::new(f(i, -1.95), f(j, 0.05), f(k, -0.5)));
            }
        }
    }
    let fluid = p.len();
    let (lo, hi): ([f64; 3], [f64; 3]) = ([-2.0, 0.0, -0.75], [2.0, 3.0, 0.75]);
    let ds: f64 = 0.0186;
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let nu = ((hi[u] - lo[u]) / ds).round() as usize;
        let nv = ((hi[v] - lo[v]) / ds).round() as usize;
        for side in [lo[axis], hi[axis]] {
            for a in 0..=nu {
                for b in 0..=nv {
                    let mut q = [0.0; 3];
                    q[axis] = side;
                    q[u] = lo[u] + (hi[u] - lo[u]) * a as f64 / nu as f64;
                    q[v] = lo[v] + (hi[v] - lo[v]) * b as f64 / nv as f64;
                    p.push(Vec3::new(R::of_f64(q[0]), R::of_f64(q[1]), R::of_f64(q[2])));
                }
            }
        }
    }
    (p, fluid)
}

/// The peer: kiddo's immutable k-d tree, built from the positions, then one fixed-radius
/// query per particle (exclusive boundary, unsorted, rayon-parallel). Returns the number of
/// neighbour pairs found (self excluded), so that the work cannot be optimised away.
pub fn kiddo_search(points: &[Vec3<f32>], radius: f32) -> usize {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    let entries: Vec<[f32; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    let tree: ImmutableKdTree<f32, 3> =
        ImmutableKdTree::new_from_slice(&entries).expect("finite points");
    let r2 = radius * radius;
    entries
        .par_iter()
        .map(|q| {
            tree.query(q)
                .within::<SquaredEuclidean<f32>>(r2)
                .unsorted()
                .exclusive_boundaries()
                .execute()
                .len()
                - 1
        })
        .sum()
}

/// The fluid of SPlisHSPlasH's `DamBreakModel.json` at particle radius 0.0125 m (the
/// side-by-side scene): the 39³ = 59,319 particles of [`dam_break_anchor`] without the
/// boundary samples, and the tank 4 × 3 × 1.5 m centred at (0, 1.5, 0) as an inverted box
/// (the solvers here use signed distance fields instead of boundary particles).
pub fn dam_break_fluid<R: Real>() -> (Vec<Vec3<R>>, Aabb<R>) {
    let (mut p, fluid) = dam_break_anchor::<R>();
    p.truncate(fluid);
    let tank = Aabb::new(
        Vec3::new(R::of_f64(-2.0), R::zero(), R::of_f64(-0.75)),
        Vec3::new(R::of_f64(2.0), R::of_f64(3.0), R::of_f64(0.75)),
    )
    .expect("valid tank");
    (p, tank)
}

/// The elastic–plastic granular solver (Bui et al. 2008, `elastoplastic-granular`, its
/// defaults for spacing 0.025 m and φ = 30°) on the grains of [`dam_break_fluid`] (59,319
/// particles) held at rest: the block stands in a box that fits it (an inverted box, open
/// above it), whose floor and sides are three rows of no-slip boundary particles
/// (`boundary_particle_region` = the block), from the geostatic stress, frames of `frame_dt`
/// seconds (one substep; the solver sub-cycles its explicit steps inside), Young's modulus
/// `youngs_modulus_pa`. Returns the solver and the grains.
pub fn settled_block_elastoplastic<R: Real>(
    frame_dt: f64,
    youngs_modulus_pa: f64,
) -> Result<
    (
        elastoplastic_granular::Elastoplastic<R>,
        sph_core::ParticleSet<R>,
    ),
    sph_solver::SolverError,
> {
    let s = 0.025;
    let v = |x: f64, y: f64, z: f64| Vec3::new(R::of_f64(x), R::of_f64(y), R::of_f64(z));
    let lo = (-1.95, 0.05, -0.5);
    let side = 39.0 * s;
    let block = Aabb::new(
        v(lo.0, lo.1, lo.2),
        v(lo.0 + side, lo.1 + side, lo.2 + side),
    )?;
    let container = Aabb::new(
        v(lo.0, lo.1, lo.2),
        v(lo.0 + side, lo.1 + 2.0 * side, lo.2 + side),
    )?;
    granular_block_in(frame_dt, youngs_modulus_pa, block, container)
}

/// The elastic–plastic granular solver (Bui et al. 2008, `elastoplastic-granular`, its
/// defaults for spacing 0.025 m and φ = 30°, Young's modulus `youngs_modulus_pa`) on a
/// granular dam break: the grains of [`dam_break_fluid`] (59,319 particles, a 0.975 m cube at
/// the tank's −x end) released in its tank, whose floor and walls are three rows of no-slip
/// boundary particles up to 1.2 m (`boundary_particle_region`: the tank's width and length,
/// 1.2 m high: the grains never climb higher), from the geostatic stress, frames of
/// `frame_dt` seconds (one substep; the solver sub-cycles its explicit steps inside). The
/// column collapses and spreads along the floor as the water's dam break does, so the
/// neighbour lists are rebuilt as a flowing scene needs. Returns the solver and the grains.
pub fn dam_break_elastoplastic<R: Real>(
    frame_dt: f64,
    youngs_modulus_pa: f64,
) -> Result<
    (
        elastoplastic_granular::Elastoplastic<R>,
        sph_core::ParticleSet<R>,
    ),
    sph_solver::SolverError,
> {
    let (_, tank) = dam_break_fluid::<R>();
    let region = Aabb::new(tank.min, Vec3::new(tank.max.x, R::of_f64(1.2), tank.max.z))?;
    granular_block_in(frame_dt, youngs_modulus_pa, region, tank)
}

/// The grains of [`dam_break_fluid`] under the elastic–plastic solver's defaults for spacing
/// 0.025 m and φ = 30° at Young's modulus `youngs_modulus_pa`, geostatic start, frames of
/// `frame_dt` s (one substep), boundary particles over `region`, inside the inverted box
/// `container` (the two scenes above).
fn granular_block_in<R: Real>(
    frame_dt: f64,
    youngs_modulus_pa: f64,
    region: Aabb<R>,
    container: Aabb<R>,
) -> Result<
    (
        elastoplastic_granular::Elastoplastic<R>,
        sph_core::ParticleSet<R>,
    ),
    sph_solver::SolverError,
> {
    use elastoplastic_granular::{ElastoplasticParams, InitialStress};
    use sph_core::{BoxSdf, Inverted};
    let (p, _) = dam_break_fluid::<R>();
    let mut params = ElastoplasticParams::<R>::for_spacing(R::of_f64(0.025), R::of_f64(30.0));
    params.common.dt = R::of_f64(frame_dt);
    params.common.substeps = 1;
    params.youngs_modulus = R::of_f64(youngs_modulus_pa);
    params.initial_stress = InitialStress::Geostatic;
    params.boundary_particle_region = Some(region);
    let mass = params.common.particle_mass();
    let rho0 = params.common.rest_density;
    let solids: sph_solver::Solids<R> = vec![Box::new(Inverted(BoxSdf::new(container)?))];
    let solver = elastoplastic_granular::Elastoplastic::new(params, solids)?;
    Ok((solver, sph_core::ParticleSet::from_positions(p, mass, rho0)))
}

/// Seed of the scattered-disk comet population.
pub const COMET_SEED: u64 = 2026;

/// The scattered-disk comet population (the `comet_throughput` example and the `population-step`
/// benchmark): the four giants of `outer_solar_system` (ecliptic J2000) integrated by
/// `planet_map`; `n` comets with barycentric perihelia 32–40 AU, semi-major axes 40–100 AU,
/// inclinations 0–30° and random angles (`symplectic::samples::SCATTERED_DISK`, seed
/// [`COMET_SEED`]), integrated by `scheme` in the barycentric variant with `B₀ = 0`,
/// `B₁ = 0.21·10⁻⁶` and a first step of `first_step_days`; removal at Hill-sphere entry,
/// perihelion below 26 AU or ejection beyond 1000 AU. Returns the population at time 0 and
/// the comets' initial barycentric states.
pub fn scattered_disk_population(
    n: usize,
    scheme: symplectic::Scheme,
    first_step_days: f64,
    planet_map: symplectic::Integrator,
) -> Result<
    (
        symplectic::Population,
        Vec<(symplectic::Vec3, symplectic::Vec3)>,
    ),
    String,
> {
    use symplectic::kepler::state_from_elements;
    use symplectic::samples::{sample_elements, SCATTERED_DISK};
    use symplectic::{
        outer_solar_system, Ephemeris, Frame, ParticleIntegrator, Population, RemovalRules, Variant,
    };
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let mu = planets.g() * (planets.sun_mass() + planets.masses().iter().sum::<f64>());
    let states = sample_elements(&SCATTERED_DISK, n, COMET_SEED)
        .iter()
        .map(|el| state_from_elements(el, mu))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())?;
    let ids: Vec<u64> = (0..n as u64).collect();
    let ephemeris = Ephemeris::new(planets, planet_map).map_err(|e| e.to_string())?;
    let integrator = ParticleIntegrator::new(Variant::Barycentric, scheme, 0.0, 0.21e-6)
        .map_err(|e| e.to_string())?;
    let rules = RemovalRules {
        hill_factor: Some(1.0),
        min_perihelion: Some(26.0),
        ejection_distance: Some(1000.0),
        ..RemovalRules::default()
    };
    let population = Population::new(
        ephemeris,
        integrator,
        rules,
        0.0,
        first_step_days,
        &states,
        &ids,
    )
    .map_err(|e| e.to_string())?;
    Ok((population, states))
}

/// Seed of the Centaur population.
pub const CENTAUR_SEED: u64 = 2027;

/// `B₁` of the Centaur population (AU³/day²): `F₁ ≥ ½ (B₀ + B₁/r)` holds far from the
/// planets down to r ≈ 2 AU (the Sun's offset from the barycentre, ≤ 0.01 AU, contributes at
/// most `G m₀ · 0.01/r²`, the planets at most `Σ G m_j/r`), so the map works everywhere
/// outside the Sun-vicinity limit and the encounter spheres.
pub const CENTAUR_B1: f64 = 4e-6;

/// A comet's first physical step in [`centaur_population`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FirstStep {
    /// This many days per AU of the comet's initial distance from the barycentre.
    PerAuDays(f64),
    /// This many days for every comet (`integrator.initial_step_days` of a population file).
    Days(f64),
}

/// The Centaur population (the `centaur_throughput` example): the four giants of
/// `outer_solar_system` (ecliptic J2000) integrated by S6 at `planet_step_days`; `n` comets
/// with `a` 5.5–30 AU, `e` 0–0.2, `i` 0–10° and
/// random angles (`symplectic::samples::CENTAURS`, seed `seed`), S2 in the barycentric
/// variant with `B₀ = 0`, `B₁ =` [`CENTAUR_B1`], a first step `first_step`,
/// integrated through close encounters (3 Hill radii, tolerance
/// `tolerance`); removal below a barycentric perihelion of 2.5 AU (the Sun's vicinity),
/// unbound beyond 100 AU (ejected), or at a collision with a planet or the Sun. Returns the
/// population at time 0 and the comets' initial barycentric states.
pub fn centaur_population(
    n: usize,
    seed: u64,
    first_step: FirstStep,
    tolerance: f64,
    planet_step_days: f64,
) -> Result<
    (
        symplectic::Population,
        Vec<(symplectic::Vec3, symplectic::Vec3)>,
    ),
    String,
> {
    use symplectic::kepler::state_from_elements;
    use symplectic::samples::{sample_elements, CENTAURS};
    use symplectic::{
        outer_solar_system, Encounters, Ephemeris, Frame, Integrator, ParticleIntegrator,
        Population, RemovalRules, Scheme, Variant,
    };
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let mu = planets.g() * (planets.sun_mass() + planets.masses().iter().sum::<f64>());
    let states = sample_elements(&CENTAURS, n, seed)
        .iter()
        .map(|el| state_from_elements(el, mu))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| e.to_string())?;
    let first_steps: Vec<f64> = states
        .iter()
        .map(|(q, _)| match first_step {
            FirstStep::PerAuDays(days) => days * q.norm(),
            FirstStep::Days(days) => days,
        })
        .collect();
    let ids: Vec<u64> = (0..n as u64).collect();
    let ephemeris = Ephemeris::new(
        planets,
        Integrator::S6 {
            step: planet_step_days,
        },
    )
    .map_err(|e| e.to_string())?;
    let integrator = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, CENTAUR_B1)
        .map_err(|e| e.to_string())?;
    let rules = RemovalRules {
        hill_factor: None,
        min_perihelion: Some(2.5),
        ejection_distance: Some(100.0),
        sun_collision: true,
        ..RemovalRules::default()
    };
    let mut population = Population::with_first_steps(
        ephemeris,
        integrator,
        rules,
        0.0,
        &first_steps,
        &states,
        &ids,
    )
    .map_err(|e| e.to_string())?;
    population
        .set_encounters(Some(Encounters {
            tolerance,
            ..Encounters::default()
        }))
        .map_err(|e| e.to_string())?;
    Ok((population, states))
}

/// Writes the initial barycentric states of the planets and the comets as CSV
/// (`kind,id,gm,x,y,z,vx,vy,vz`; AU, AU/day, `G m` in AU³/day²) for side-by-side runs with
/// other codes.
pub fn write_comet_states(
    path: &str,
    planets: &symplectic::Planets,
    states: &[(symplectic::Vec3, symplectic::Vec3)],
) -> std::io::Result<()> {
    use std::fmt::Write as _;
    let mut out = String::from("kind,id,gm,x,y,z,vx,vy,vz\n");
    let g = planets.g();
    let (sun_q, sun_v) = planets.sun_barycentric_state();
    let row = |out: &mut String,
               kind: &str,
               id: usize,
               gm: f64,
               q: &symplectic::Vec3,
               v: &symplectic::Vec3| {
        writeln!(
            out,
            "{kind},{id},{gm:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            q.x, q.y, q.z, v.x, v.y, v.z
        )
        .ok();
    };
    row(&mut out, "body", 0, g * planets.sun_mass(), &sun_q, &sun_v);
    let velocities = planets.barycentric_velocities();
    for (i, (m, q)) in planets.masses().iter().zip(planets.positions()).enumerate() {
        row(&mut out, "body", i + 1, g * m, &(q + sun_q), &velocities[i]);
    }
    for (i, (q, v)) in states.iter().enumerate() {
        row(&mut out, "particle", i, 0.0, q, v);
    }
    std::fs::write(path, out)
}

/// FNV-1a checksums of a state's bits: `(positions, velocities and densities)`. Equal
/// checksums mean bitwise equal runs (the dam-break examples print them).
pub fn state_checksums<R: Real>(state: &sph_core::ParticleSet<R>) -> (u64, u64) {
    let fnv = |h: u64, c: R| (h ^ c.as_f64().to_bits()).wrapping_mul(0x0000_0100_0000_01b3);
    let start = 0xcbf2_9ce4_8422_2325u64;
    let components = |v: &[Vec3<R>]| v.iter().flat_map(|x| [x.x, x.y, x.z]).collect::<Vec<R>>();
    let positions = components(&state.positions).into_iter().fold(start, fnv);
    let rest = components(&state.velocities)
        .into_iter()
        .chain(state.densities.iter().copied())
        .fold(start, fnv);
    (positions, rest)
}
