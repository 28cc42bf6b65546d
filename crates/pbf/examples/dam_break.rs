//! The dam break of the PBF paper (Macklin & Müller 2013, Table 1) as
//! `scenes/dam_break.toml` describes it in quick mode, built from this crate alone: a water
//! column of 16 × 32 × 24 particles against the −x wall of a closed tank, SDF collision
//! walls (the paper's handling), 4 steps and 3 iterations per 16 ms frame.
//!
//! ```sh
//! cargo run --release -p position-based-fluids --example dam_break [FRAMES]
//! ```
//!
//! Prints the front (largest `x`) and the largest density ratio every 10 frames.

use pbf::{cubic_lattice, Aabb, BoxSdf, Inverted, ParticleSet, Pbf, PbfParams, Solids, Vec3};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let frames: usize = match std::env::args().nth(1) {
        Some(a) => a.parse()?,
        None => 60,
    };
    let mut params = PbfParams::<f32>::for_spacing(0.025); // m; h = 2 s
    params.common.dt = 0.016; // s per frame ("a frame time of 16 ms is used in all cases")
    params.common.substeps = 4; // Table 1
    params.solver_iterations = 3; // Table 1
    params.vorticity_epsilon = 0.0; // vorticity confinement off, as the scene

    let tank = Aabb::new(Vec3::zeros(), Vec3::new(1.6, 1.0, 0.6))?;
    let column = Aabb::new(Vec3::zeros(), Vec3::new(0.4, 0.8, 0.6))?;
    let s = params.common.particle_spacing;
    let (m, rho0) = (params.particle_mass(), params.common.rest_density);
    let mut state = ParticleSet::from_positions(cubic_lattice(&column, s, 1 << 22)?, m, rho0);
    let solids: Solids<f32> = vec![Box::new(Inverted(BoxSdf::new(tank)?))];
    // `Pbf::new` takes collision walls; `Pbf::with_boundary` takes any other boundary
    // (e.g. a `pbf::VolumeMapBoundary`).
    let mut solver = Pbf::new(params, solids)?;

    println!("{} particles", state.len());
    for frame in 1..=frames {
        let stats = solver.step(&mut state)?;
        if frame % 10 == 0 {
            let front = state.positions.iter().map(|p| p.x).fold(0.0, f32::max);
            println!(
                "frame {frame:3}: front x = {front:.3} m, max rho/rho0 {:.4}",
                stats.max_density_ratio
            );
        }
    }
    Ok(())
}
