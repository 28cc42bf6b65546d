//! A check of the discrete operators on their own (diagnostic): an unstressed block
//! 0.1 × 0.1 × 0.1 m without gravity or walls, cohesion 1 MPa (so it stays elastic), given a
//! small pseudo-random velocity; prints its kinetic energy each frame. A stable
//! discretisation keeps it bounded (the artificial viscosity lets it decay).
//!
//! ```sh
//! cargo run --release --example perturbed_block -p elastoplastic-granular [FRAMES] [ALPHA_PI] [EPSILON]
//! ```

use elastoplastic_granular::{Aabb, Elastoplastic, ElastoplasticParams, ParticleSet, Vec3};
use sph_core::sampling::cubic_lattice;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let frames: usize = args.get(1).map_or(Ok(30), |a| a.parse())?;
    let s = 0.01;
    let mut p = ElastoplasticParams::<f64>::for_spacing(s, 30.0);
    p.youngs_modulus = 5.84e5;
    p.cohesion = 1e6;
    p.common.gravity = Vec3::zeros();
    p.viscosity_alpha = args.get(2).map_or(Ok(p.viscosity_alpha), |a| a.parse())?;
    p.artificial_stress_epsilon = args
        .get(3)
        .map_or(Ok(p.artificial_stress_epsilon), |a| a.parse())?;
    let region = Aabb::new(Vec3::zeros(), Vec3::new(0.1, 0.1, 0.1))?;
    let x = cubic_lattice(&region, s, 100_000)?;
    let mut state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02
    };
    for v in &mut state.velocities {
        *v = Vec3::new(next(), next(), next());
    }
    let mut solver = Elastoplastic::new(p, Vec::new())?;
    let energy = |st: &ParticleSet<f64>| {
        st.velocities
            .iter()
            .zip(&st.masses)
            .map(|(v, m)| 0.5 * m * v.norm_squared())
            .sum::<f64>()
    };
    println!("frame 0: kinetic energy {:.3e} J", energy(&state));
    for frame in 1..=frames {
        solver.step(&mut state)?;
        let vmax = state
            .velocities
            .iter()
            .map(|v| v.norm())
            .fold(0.0, f64::max);
        println!(
            "frame {frame}: kinetic energy {:.3e} J, fastest {vmax:.3e} m/s, kappa max {:.2e}",
            energy(&state),
            solver.plastic_strain().iter().cloned().fold(0.0, f64::max)
        );
    }
    Ok(())
}
