//! The granular column collapse that `scenes/granular_column_collapse.toml` describes, in
//! quick mode (Lube, Huppert, Sparks & Freundt 2005; a = H0/L0 = 2), built from this crate
//! alone (its runout measured with `granular-measure`): volume-map walls, calibrated initial masses, Drucker–Prager friction at 30°.
//!
//! ```sh
//! cargo run --release -p iisph-granular --example granular_column [FRAMES]
//! ```
//!
//! Prints the runout every 10 frames and the normalised runout `(L∞ − L0)/L0` at the end:
//! 2.09 after 63 frames (1 s; the column has stopped by frame 30), against 1.2 a = 2.4 of
//! Lube et al.'s law (the `granular-column-collapse` experiment checks the five aspect
//! ratios against the law's ±30 % band). 7 s on one thread.

use granular_measure as measure;
use iisph_granular::{
    calibrate_masses, cubic_lattice, Aabb, BoxSdf, Iisph, IisphParams, Inverted, ParticleSet,
    Solids, Vec3, IISPH_KERNEL,
};

/// Particle spacing (m), as the scene's `[quick]` table.
const SPACING: f32 = 0.01;
/// Column width `L0` (m): the block against the wall `x = 0`.
const COLUMN_LENGTH: f32 = 0.1;

/// The solver and its particles at `t = 0`, as `SceneSetup` builds them from the scene.
pub fn build() -> Result<(Iisph<f32>, ParticleSet<f32>), Box<dyn std::error::Error>> {
    let mut params = IisphParams::<f32>::granular(SPACING, 30.0); // θ = 30°, no drag
    params.common.dt = 0.016; // s per frame ...
    params.common.substeps = 16; // ... in 1 ms steps

    let tank = Aabb::new(Vec3::zeros(), Vec3::new(0.8, 0.25, 0.04))?;
    let column = Aabb::new(Vec3::zeros(), Vec3::new(COLUMN_LENGTH, 0.2, 0.04))?;
    let solids: Solids<f32> = vec![Box::new(Inverted(BoxSdf::new(tank)?))];
    let walls = Iisph::volume_map_walls(solids, &params, tank, None)?;

    // Particles on a lattice half a spacing from the walls, masses ρ0 s³, then lowered
    // where the lattice plus the walls' share would start above ρ0.
    let positions = cubic_lattice(&column, SPACING, 1 << 20)?;
    let (m, rho0) = (params.common.particle_mass(), params.common.rest_density);
    let mut state = ParticleSet::from_positions(positions, m, rho0);
    calibrate_masses(IISPH_KERNEL, &params.common, &walls, &mut state)?;

    Ok((Iisph::with_boundary(params, Box::new(walls))?, state))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let frames: usize = match std::env::args().nth(1) {
        Some(a) => a.parse()?,
        None => 63,
    };
    let (mut solver, mut state) = build()?;
    let front = measure::RunoutOptions::connected(0.0, SPACING as f64);
    println!("{} particles", state.len());
    for frame in 1..=frames {
        let stats = solver.step(&mut state)?;
        if frame % 10 == 0 || frame == frames {
            let runout = measure::runout(&state.positions, &front)?;
            println!(
                "frame {frame:3}: runout {runout:.3} m, max rho/rho0 {:.4}",
                stats.max_density_ratio
            );
        }
    }
    let runout = measure::runout(&state.positions, &front)?;
    let normalised = measure::normalised_runout(runout, COLUMN_LENGTH as f64)?;
    println!("(L - L0)/L0 = {normalised:.2}");
    Ok(())
}
