//! A water column coming to rest in a closed tank, as `scenes/boundary_rest.toml` describes
//! it in quick mode but with PCISPH (Solenthaler & Pajarola 2009) and volume-map walls
//! (Bender et al. 2019), built from this crate alone: 12 × 24 × 12 particles, 10 steps per
//! 16 ms frame.
//!
//! ```sh
//! cargo run --release -p pcisph --example water_at_rest [FRAMES]
//! ```
//!
//! Prints the kinetic energy per particle relative to `m g H` and the largest density ratio
//! every 25 frames.

use pcisph::{
    cubic_lattice, Aabb, BoxSdf, Inverted, ParticleSet, Pcisph, PcisphParams, Solids, Vec3,
    VolumeMapBoundary, VolumeMapOptions, PCISPH_KERNEL,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let frames: usize = match std::env::args().nth(1) {
        Some(a) => a.parse()?,
        None => 125,
    };
    let mut params = PcisphParams::<f32>::for_spacing(0.025); // m; h = 2 s
    params.common.dt = 0.016; // s per frame
    params.common.substeps = 10; // the PBF paper's PCISPH comparison (§8)
    let c = &params.common;

    let tank = Aabb::new(Vec3::zeros(), Vec3::new(0.3, 1.2, 0.3))?;
    let column = Aabb::new(Vec3::zeros(), Vec3::new(0.3, 0.6, 0.3))?;
    let solids: Solids<f32> = vec![Box::new(Inverted(BoxSdf::new(tank)?))];
    let walls = VolumeMapBoundary::new(
        solids,
        PCISPH_KERNEL, // the maps integrate the solver's density kernel
        c.support_radius,
        tank,
        c.volume_map_contact_distance(),
        VolumeMapOptions::default(),
    )?;
    let (m, rho0) = (c.particle_mass(), c.rest_density);
    let mut state = ParticleSet::from_positions(
        cubic_lattice(&column, c.particle_spacing, 1 << 22)?,
        m,
        rho0,
    );
    let mgh = (m * 9.81 * 0.6) as f64;
    let mut solver = Pcisph::with_boundary(params, Box::new(walls))?;

    println!("{} particles", state.len());
    for frame in 1..=frames {
        let stats = solver.step(&mut state)?;
        if frame % 25 == 0 {
            let ke: f64 = state
                .velocities
                .iter()
                .zip(&state.masses)
                .map(|(v, &m)| 0.5 * (m * v.norm_squared()) as f64)
                .sum();
            println!(
                "frame {frame:3}: kinetic energy per particle {:.2e} m g H, max rho/rho0 {:.4}",
                ke / state.len() as f64 / mgh,
                stats.max_density_ratio
            );
        }
    }
    Ok(())
}
