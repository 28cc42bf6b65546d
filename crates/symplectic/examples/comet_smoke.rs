// temporary exploration
#[path = "../tests/common/mod.rs"]
mod common;
use symplectic::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scheme = if args.get(1).map(|s| s.as_str()) == Some("s6") {
        Scheme::S6
    } else {
        Scheme::S2
    };
    let years: f64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(1e5);
    let variant = if args.get(3).map(|s| s.as_str()) == Some("mixed") {
        Variant::Mixed
    } else {
        Variant::Barycentric
    };
    let b1: f64 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(0.21e-6);
    let planets = common::outer_solar_system_ecliptic();
    let integ = match scheme {
        Scheme::S2 => Integrator::S2 { step: 365.0 },
        Scheme::S6 => Integrator::S6 { step: 365.0 },
    };
    let mut eph = Ephemeris::new(planets.clone(), integ).unwrap();
    let pi = ParticleIntegrator::new(variant, scheme, 0.0, b1).unwrap();
    let mut scratch = ParticleScratch::default();
    let mut ps = vec![];
    for row in common::particle_rows() {
        let (q, v) = common::barycentric_particle(&planets, row.position, row.velocity);
        let q = if variant == Variant::Mixed {
            row.position
        } else {
            q
        };
        let dt0 = if scheme == Scheme::S2 {
            row.dt0_s2
        } else {
            row.dt0_s6
        };
        ps.push(pi.particle(q, v, 0.0, dt0, &mut eph, &mut scratch).unwrap());
    }
    let mut run = CometRun::new(
        eph,
        pi,
        ps,
        Limits {
            min_perihelion: 26.0,
            ejection_distance: 1e4,
        },
    );
    let t0 = std::time::Instant::now();
    let mut maxerr = [0.0f64; 2];
    let mut first = [0.0f64; 2];
    let mut nsteps = [0u64; 2];
    let e0 = run.ephemeris.planets().energy();
    let n = 20;
    for k in 1..=n {
        let t = years * 365.25 * k as f64 / n as f64;
        run.advance_to(t, |i, _p, info| {
            if nsteps[i] == 0 {
                first[i] = info.dt;
            }
            nsteps[i] += 1;
            maxerr[i] = maxerr[i].max(info.relative_error.abs());
        })
        .unwrap();
        let el0 = run.elements(0).unwrap_or(symplectic::kepler::Elements {
            semi_major_axis: 0.0,
            eccentricity: 0.0,
            inclination: 0.0,
            perihelion: 0.0,
        });
        let el1 = run.elements(1).unwrap_or(symplectic::kepler::Elements {
            semi_major_axis: 0.0,
            eccentricity: 0.0,
            inclination: 0.0,
            perihelion: 0.0,
        });
        println!("t={:.3e} yr maxerr={:.3e} {:.3e} a={:.2} {:.2} q={:.2} {:.2} status={:?} {:?} planetsE={:.2e}", t/365.25, maxerr[0], maxerr[1], el0.semi_major_axis, el1.semi_major_axis, el0.perihelion, el1.perihelion, run.particles[0].status, run.particles[1].status, (run.ephemeris.planets().energy()-e0)/e0.abs());
    }
    println!(
        "first dt {:?} steps {:?} wall {:.2}s",
        first,
        nsteps,
        t0.elapsed().as_secs_f64()
    );
}
