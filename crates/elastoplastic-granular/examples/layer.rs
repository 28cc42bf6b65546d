//! A layer settling on a floor (diagnostic): a block of `nx × ny × nz` particles (spacing
//! 10 mm) on the floor plane `y = 0`; along `x` and `z` either walls (one plane per face,
//! all of one model) or periodic ends. Prints every `every` frames the bottom layer's mean
//! `σ_yy` against `−ρ0 g (d − s/2)`, the 99th-percentile and the fastest speed (and where),
//! the largest plastic strain and the kinetic energy.
//!
//! ```sh
//! cargo run --release --example layer -p elastoplastic-granular -- [key=value ...]
//! ```
//!
//! Keys (defaults): `walls=free|noslip` (free), `px=0|1`, `pz=0|1` (0: walls at the ends of
//! that axis; 1: periodic), `nx=8 ny=20 nz=3`, `E=5.84e5`, `nu=0.3`, `C=0.2`, `alpha=0.1`,
//! `eps=0.5`, `c=0` (cohesion, Pa), `phi=30`, `frames=63`, `every=4`, `geo=0|1` (1: start
//! from the geostatic stress `σ_yy = −ρ0 g depth`, `σ_xx = σ_zz = K0 σ_yy`, `K0 = ν/(1 − ν)`),
//! `bp=0|1` (1: the floor is three rows of boundary particles of the wall model, the
//! floor plane only keeping particles out).

use elastoplastic_granular::{
    boundary_block, volume_map_walls, Aabb, ElastoplasticParams, ElastoplasticScheme, ParticleSet,
    PeriodicAxis, Plane, Solids, Vec3, WallModel,
};
use nalgebra::Matrix3;
use sph_core::sampling::cubic_lattice;

const S: f64 = 0.01;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let get = |key: &str| -> Option<&str> {
        args.iter()
            .find_map(|a| a.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
    };
    let num = |key: &str, d: f64| -> f64 { get(key).and_then(|a| a.parse().ok()).unwrap_or(d) };
    let model = match get("walls") {
        Some("noslip") => WallModel::NoSlip,
        _ => WallModel::FreeSlip,
    };
    let periodic = [num("px", 0.0) != 0.0, false, num("pz", 0.0) != 0.0];
    let n = [num("nx", 8.0), num("ny", 20.0), num("nz", 3.0)];
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, num("phi", 30.0));
    p.youngs_modulus = num("E", 5.84e5);
    p.poisson_ratio = num("nu", p.poisson_ratio);
    p.cfl_number = num("C", p.cfl_number);
    p.viscosity_alpha = num("alpha", p.viscosity_alpha);
    p.artificial_stress_epsilon = num("eps", p.artificial_stress_epsilon);
    p.cohesion = num("c", 0.0);
    let frames = num("frames", 63.0) as usize;
    let every = num("every", 4.0).max(1.0) as usize;
    let hi = Vec3::new(n[0] * S, n[1] * S, n[2] * S);
    let mut solids: Solids<f64> = vec![Box::new(Plane::new(Vec3::zeros(), Vec3::y())?)];
    for a in [0, 2] {
        if periodic[a] {
            p.periodic.push(PeriodicAxis {
                axis: a,
                lo: 0.0,
                hi: hi[a],
            });
        } else {
            let mut nrm = Vec3::zeros();
            nrm[a] = 1.0;
            solids.push(Box::new(Plane::new(Vec3::zeros(), nrm)?));
            solids.push(Box::new(Plane::new(hi, -nrm)?));
        }
    }
    p.wall_models = vec![model; solids.len()];
    let bp = num("bp", 0.0) != 0.0;
    if bp {
        p.wall_models[0] = WallModel::ContactOnly;
    }
    let margin = Vec3::new(0.05, 0.0, 0.05);
    let domain = Aabb::new(-margin, hi + Vec3::new(0.05, 0.3, 0.05))?;
    let walls = volume_map_walls(solids, &p, domain)?;
    let region = Aabb::new(Vec3::zeros(), hi)?;
    let x = cubic_lattice(&region, S, 1_000_000)?;
    let mut state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    let rho0 = p.common.rest_density;
    let g = 9.81;
    let depth = hi.y;
    let expected = -rho0 * g * (depth - S / 2.0);
    let nu = p.poisson_ratio;
    let mut solver = ElastoplasticScheme::solver(p, walls)?;
    if bp {
        let rows = Aabb::new(Vec3::new(0.0, -3.0 * S, 0.0), Vec3::new(hi.x, 0.0, hi.z))?;
        let floor = boundary_block(&rows, S, Vec3::y(), model, 1_000_000)?;
        println!("{} boundary particles under the floor", floor.len());
        solver.scheme_mut().set_boundary_particles(floor)?;
    }
    if num("geo", 0.0) != 0.0 {
        let k0 = nu / (1.0 - nu);
        let stress: Vec<Matrix3<f64>> = state
            .positions
            .iter()
            .map(|x| {
                let v = -rho0 * g * (depth - x.y);
                Matrix3::from_diagonal(&Vec3::new(k0 * v, v, k0 * v))
            })
            .collect();
        solver.scheme_mut().set_stress(&stress)?;
    }
    println!(
        "{} particles, walls {model:?}, periodic x {} z {}, {} steps/frame, expected bottom sigma_yy {expected:.1} Pa",
        state.len(),
        periodic[0],
        periodic[2],
        solver.params().explicit_steps().0
    );
    let bound = 0.05 * (g * S).sqrt();
    for frame in 1..=frames {
        solver.step(&mut state)?;
        if frame % every != 0 && frame != frames {
            continue;
        }
        let bottom: Vec<f64> = state
            .positions
            .iter()
            .zip(solver.stress())
            .filter(|(x, _)| x.y < S)
            .map(|(_, s)| s[(1, 1)])
            .collect();
        let mean = bottom.iter().sum::<f64>() / bottom.len().max(1) as f64;
        let mut speeds: Vec<f64> = state.velocities.iter().map(|v| v.norm()).collect();
        let (k, vmax) = speeds
            .iter()
            .enumerate()
            .fold((0, 0.0), |a, (k, &s)| if s > a.1 { (k, s) } else { a });
        let xk = state.positions[k];
        let energy: f64 = state
            .velocities
            .iter()
            .zip(&state.masses)
            .map(|(v, m)| 0.5 * m * v.norm_squared())
            .sum();
        let q = ((speeds.len() as f64) * 0.99) as usize;
        let q = q.min(speeds.len() - 1);
        let (_, p99, _) = speeds.select_nth_unstable_by(q, f64::total_cmp);
        println!(
            "frame {frame:3}: bottom {:.3} of hydrostatic ({} particles), p99 {:.4} m/s{}, fastest {vmax:.4} m/s at ({:.4}, {:.4}, {:.4}), kappa max {:.2e}, KE {energy:.3e} J",
            mean / expected,
            bottom.len(),
            *p99,
            if *p99 < bound { " (rest)" } else { "" },
            xk.x,
            xk.y,
            xk.z,
            solver.plastic_strain().iter().cloned().fold(0.0, f64::max)
        );
    }
    Ok(())
}
