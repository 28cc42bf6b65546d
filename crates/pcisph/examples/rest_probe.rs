//! Diagnostic: a block of water resting on the floor of a closed tank twice its height,
//! integrated for 2 s with PCISPH; prints the kinetic energy per particle relative to
//! `m g H` over time, split by region (within `h` of a side wall or the floor, the top two
//! layers, the bulk), and the density statistics.
//!
//! `cargo run --release -p pcisph --example rest_probe -- [substeps] [iterations] [xsph_c] [volume-map] [unclamped]`

use pcisph::{Pcisph, PcisphParams};
use sph_core::Vec3;

fn main() {
    let raw: Vec<String> = std::env::args().skip(1).collect();
    let volume_map = raw.iter().any(|a| a == "volume-map");
    let args: Vec<f64> = raw.iter().filter_map(|a| a.parse().ok()).collect();
    let mut p = PcisphParams::<f64>::default();
    if let Some(&n) = args.first() {
        p.common.substeps = n as usize;
    }
    if let Some(&n) = args.get(1) {
        p.pressure_iterations = n as usize;
    }
    if let Some(&c) = args.get(2) {
        p.xsph_c = c;
    }
    p.clamp_negative_pressure = !raw.iter().any(|a| a == "unclamped");
    let n = [20usize, 32, 20];
    let (mut state, solids, tank) =
        sph_solver::testing::block_in_tank(&p.common, n, [20.0, 64.0, 20.0]);
    let s = p.common.particle_spacing;
    let h = p.common.support_radius;
    let height = n[1] as f64 * s;
    let mgh = p.particle_mass() * 9.81 * height;
    let boundary: Box<dyn sph_solver::Boundary<f64>> = if volume_map {
        Box::new(
            sph_solver::boundary::VolumeMapBoundary::new(
                solids,
                sph_kernels::KernelKind::Poly6,
                h,
                tank,
                0.5 * p.particle_radius(),
                Default::default(),
            )
            .unwrap(),
        )
    } else {
        Box::new(sph_solver::CollisionBoundary::new(solids, p.particle_radius()).unwrap())
    };
    let mut solver = Pcisph::with_boundary(p.clone(), boundary).unwrap();
    let frames = (2.0 / p.common.dt).round() as usize;
    for f in 1..=frames {
        let st = solver.step(&mut state).unwrap();
        if f % 10 == 0 || f == frames {
            let mut ke = [0.0f64; 3];
            let mut cnt = [0usize; 3];
            let mut top = f64::MIN;
            for x in &state.positions {
                top = top.max(x.y);
            }
            for (x, v) in state.positions.iter().zip(&state.velocities) {
                let wall = [
                    x.x - tank.min.x,
                    tank.max.x - x.x,
                    x.z - tank.min.z,
                    tank.max.z - x.z,
                    x.y - tank.min.y,
                ]
                .iter()
                .cloned()
                .fold(f64::MAX, f64::min);
                let k = if wall < h {
                    0
                } else if x.y > height - 2.0 * s {
                    1
                } else {
                    2
                };
                ke[k] += 0.5 * p.particle_mass() * v.norm_squared();
                cnt[k] += 1;
            }
            let per = |k: usize| ke[k] / cnt[k].max(1) as f64 / mgh;
            let vmax = state.velocities.iter().map(Vec3::norm).fold(0.0, f64::max);
            println!(
                "t {:.3} KE/(N m g H) {:.2e}  wall {:.2e} ({}) top {:.2e} ({}) bulk {:.2e} ({})  vmax {:.3}  rho max {:.4} mean {:.4}  top y/s {:.1}",
                f as f64 * p.common.dt,
                st.kinetic_energy / state.len() as f64 / mgh,
                per(0), cnt[0], per(1), cnt[1], per(2), cnt[2],
                vmax,
                st.max_density_ratio,
                st.mean_density_ratio,
                top / s
            );
        }
    }
}
