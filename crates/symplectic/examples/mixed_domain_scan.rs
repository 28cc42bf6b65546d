//! Evidence for the mixed variant's validity domain (`symplectic::MIXED_DOMAIN_MIN_RATIO`):
//! the paper's two particles, S2 with the paper's first steps, for a range of `B₁`; prints
//! (first steps scaled by a factor) the domain ratio, the first five steps relative to the requested one, and what became of
//! a 2 kyr run. Particles outside the domain are built anyway (bypassing the check through a
//! large `B₁` and then setting `p₄` and `h` for the `B₁` under study) to show why they are
//! refused. Run from the workspace root:
//! `cargo run --release -p symplectic --example mixed_domain_scan`.
use symplectic::*;
fn main() {
    let text = std::fs::read_to_string("reference-data/symplectic-100myr/particles.csv").unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| {
            l.split(',')
                .skip(1)
                .map(|x| x.trim().parse().unwrap())
                .collect()
        })
        .collect();
    for (b1, scale) in [
        (0.21e-6, 1.0),
        // The paper's B1 with steps 10 and 50 times shorter: K1/r is lost at about the same
        // epochs, so the loss is a property of the trajectory, not of the step.
        (0.21e-6, 0.1),
        (0.21e-6, 0.02),
        (0.5e-6, 1.0),
        (1e-6, 1.0),
        (1.5e-6, 1.0),
        (2e-6, 1.0),
        (3e-6, 1.0),
        (4e-6, 1.0),
        (8e-6, 1.0),
    ] {
        for (k, row) in rows.iter().enumerate() {
            let planets = outer_solar_system(Frame::EclipticJ2000);
            let (sq, sv) = planets.sun_barycentric_state();
            let pos = Vec3::new(row[6], row[7], row[8]);
            let vel = Vec3::new(row[9], row[10], row[11]) + sv;
            let _ = sq;
            let mut eph = Ephemeris::new(planets, Integrator::S2 { step: 365.0 }).unwrap();
            let integ = ParticleIntegrator::new(Variant::Mixed, Scheme::S2, 0.0, b1).unwrap();
            let mut scratch = ParticleScratch::default();
            let dt0 = row[12] * scale;
            let dom = integ.mixed_domain(&pos, &vel, eph.planets()).unwrap();
            println!(
                "domain ratio {:.3} at r {:.1}, b1 needed {:e}",
                dom.ratio, dom.at_distance, dom.b1_needed
            );
            let p = match integ.particle(pos, vel, 0.0, dt0, &mut eph, &mut scratch) {
                Ok(p) => p,
                Err(e) => {
                    println!("refused: {e}");
                    let i2 = ParticleIntegrator::new(Variant::Mixed, Scheme::S2, 0.0, 1.0).unwrap();
                    let mut p = i2
                        .particle(pos, vel, 0.0, dt0, &mut eph, &mut scratch)
                        .unwrap();
                    p.p4 = -integ.hamiltonian(&p, scratch.bodies());
                    p.step = dt0
                        * (0.5 * vel.norm_squared() - (scratch.bodies().gm[0] - b1) / pos.norm()
                            + p.p4);
                    p
                }
            };
            let mut p1 = p.clone();
            let mut firsts = vec![];
            for _ in 0..5 {
                match integ.step(&mut p1, &mut eph, &mut scratch) {
                    Ok(info) => firsts.push(format!("{:.3}", info.dt / dt0 - 1.0)),
                    Err(e) => {
                        firsts.push(format!("ERR {e}"));
                        break;
                    }
                }
            }
            let eph2 = Ephemeris::new(
                outer_solar_system(Frame::EclipticJ2000),
                Integrator::S2 { step: 365.0 },
            )
            .unwrap();
            let mut run = CometRun::new(
                eph2,
                integ,
                vec![p],
                Limits {
                    min_perihelion: 26.0,
                    ejection_distance: 1e4,
                },
            );
            let mut maxerr = 0.0f64;
            let mut maxdt = 0.0f64;
            let mut mindt = f64::MAX;
            let r = run.advance_to(2000.0 * 365.25, |_, _, info| {
                maxerr = maxerr.max(info.relative_error.abs());
                maxdt = maxdt.max(info.dt);
                mindt = mindt.min(info.dt);
            });
            println!("B1 {b1:e} dt0 {dt0} particle{} first steps rel {:?}; 2 kyr: {:?} status {:?} max|dH| {maxerr:e} dt [{mindt:.1}, {maxdt:.1}]",
                k + 1, firsts, r.err(), run.particles[0].status);
        }
    }
    // Barycentric for comparison
    for (k, row) in rows.iter().enumerate() {
        let planets = outer_solar_system(Frame::EclipticJ2000);
        let (sq, sv) = planets.sun_barycentric_state();
        let pos = Vec3::new(row[6], row[7], row[8]) + sq;
        let vel = Vec3::new(row[9], row[10], row[11]) + sv;
        let mut eph = Ephemeris::new(planets, Integrator::S2 { step: 365.0 }).unwrap();
        let integ =
            ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 0.21e-6).unwrap();
        let mut scratch = ParticleScratch::default();
        let dt0 = row[12];
        let mut p = integ
            .particle(pos, vel, 0.0, dt0, &mut eph, &mut scratch)
            .unwrap();
        let mut firsts = vec![];
        for _ in 0..5 {
            let info = integ.step(&mut p, &mut eph, &mut scratch).unwrap();
            firsts.push(format!("{:.4}", info.dt / dt0 - 1.0));
        }
        println!("barycentric particle{} first steps rel {:?}", k + 1, firsts);
    }
}
