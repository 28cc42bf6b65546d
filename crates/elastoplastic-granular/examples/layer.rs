//! A settled layer between walls of one model (diagnostic): a 0.08 × 0.2 × 0.03 m block in
//! a box (one solid; `faces` as the second word of the model, e.g. `free-faces`: each face
//! a separate plane), printing each frame the bottom layer's mean `σ_yy` against hydrostatics and the
//! fastest particle.
//!
//! ```sh
//! cargo run --release --example layer -p elastoplastic-granular [free|noslip] [E_PA] [CFL] [FRAMES] [ALPHA_PI] [NU]
//! ```

use elastoplastic_granular::{
    volume_map_walls, Aabb, BoxSdf, ElastoplasticParams, ElastoplasticScheme, Inverted,
    ParticleSet, Plane, Solids, Vec3, WallModel,
};
use sph_core::sampling::cubic_lattice;

const S: f64 = 0.01;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let word = args.get(1).map_or("free", String::as_str);
    let model = if word.starts_with("noslip") {
        WallModel::NoSlip
    } else {
        WallModel::FreeSlip
    };
    let faces = word.ends_with("faces");
    let num = |k: usize, d: f64| args.get(k).and_then(|a| a.parse().ok()).unwrap_or(d);
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.youngs_modulus = num(2, 5.84e5);
    p.cfl_number = num(3, p.cfl_number);
    let frames = num(4, 63.0) as usize;
    p.viscosity_alpha = num(5, p.viscosity_alpha);
    p.poisson_ratio = num(6, p.poisson_ratio);
    let tank = Aabb::new(Vec3::zeros(), Vec3::new(0.08, 0.5, 0.03))?;
    let solids: Solids<f64> = if faces {
        let hi = Vec3::new(0.08, 0.5, 0.03);
        let mut v: Solids<f64> = Vec::new();
        for a in 0..3 {
            let mut n = Vec3::zeros();
            n[a] = 1.0;
            v.push(Box::new(Plane::new(Vec3::zeros(), n)?));
            if a != 1 {
                v.push(Box::new(Plane::new(hi, -n)?));
            }
        }
        v
    } else {
        vec![Box::new(Inverted(BoxSdf::new(tank)?))]
    };
    p.wall_models = vec![model; solids.len()];
    let walls = volume_map_walls(solids, &p, tank)?;
    let region = Aabb::new(Vec3::zeros(), Vec3::new(0.08, 0.2, 0.03))?;
    let x = cubic_lattice(&region, S, 100_000)?;
    let mut state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    let rho0 = p.common.rest_density;
    let expected = -rho0 * 9.81 * (0.2 - S / 2.0);
    let mut solver = ElastoplasticScheme::solver(p, walls)?;
    println!(
        "{model:?}, {} steps/frame",
        solver.params().explicit_steps().0
    );
    for frame in 1..=frames {
        solver.step(&mut state)?;
        let bottom: Vec<f64> = state
            .positions
            .iter()
            .zip(solver.stress())
            .filter(|(x, _)| x.y < S)
            .map(|(_, s)| s[(1, 1)])
            .collect();
        let mean = bottom.iter().sum::<f64>() / bottom.len().max(1) as f64;
        let (k, vmax) = state
            .velocities
            .iter()
            .map(|v| v.norm())
            .enumerate()
            .fold((0, 0.0), |a, (k, s)| if s > a.1 { (k, s) } else { a });
        let xk = state.positions[k];
        println!(
            "frame {frame:3}: bottom sigma_yy {mean:9.1} Pa ({:.3} of hydrostatic, {} particles), fastest {vmax:.3} m/s at ({:.4}, {:.4}, {:.4}), kappa max {:.2e}",
            mean / expected,
            bottom.len(),
            xk.x,
            xk.y,
            xk.z,
            solver.plastic_strain().iter().cloned().fold(0.0, f64::max)
        );
    }
    Ok(())
}
