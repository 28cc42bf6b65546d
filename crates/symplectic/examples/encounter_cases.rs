//! Initial conditions of single close encounters with Jupiter and Neptune, for comparison with
//! other codes (`reference-data/comet-encounters/`):
//!
//! `cargo run --release -p symplectic --example encounter_cases > initial.csv`
//!
//! The Sun and the four giants of `outer_solar_system` (ecliptic J2000) at the epoch, as
//! barycentric states, and for each case a massless particle that passes the planet at a
//! closest distance of `f` Hill radii (f = 0.02, 0.05, 0.3, 1.0; 0.02 and 0.05 inside a tenth
//! of a Hill radius) with a speed `u` at infinity relative to the planet (5 km/s at Jupiter,
//! 2 km/s at Neptune). The system is set up at the closest approach (the particle at the
//! pericentre of its planetocentric hyperbola, speed `√(u² + 2Gm/q)`) and integrated backwards
//! (velocities reversed) by `symplectic::integrate_through` for `T = 3.5 R_H/u`; the states
//! printed are those at `−T`, relabelled time 0, to be integrated for `2T` through the
//! encounter.
//!
//! Columns: `case,kind,index,gm,x,y,z,vx,vy,vz,t_end` (AU, AU/day, AU³/day², days); `kind` is
//! `body` (index 0 the Sun) or `particle` (index: the planet passed, 1-based).
use symplectic::{outer_solar_system, BodyStates, Ephemeris, Frame, Integrator, Vec3};

const KM_S_IN_AU_DAY: f64 = 86_400.0 / 149_597_870.7;

fn main() -> Result<(), symplectic::SymplecticError> {
    let planets = outer_solar_system(Frame::EclipticJ2000);
    let m0 = planets.sun_mass();
    let masses = planets.masses().to_vec();
    let mut ephemeris = Ephemeris::new(planets, Integrator::S6 { step: 730.5 })?;
    let mut bodies = BodyStates::default();
    ephemeris.bodies_at(0.0, &mut bodies)?;
    println!("case,kind,index,gm,x,y,z,vx,vy,vz,t_end");
    let mut case = 0;
    for (planet, speed_km_s) in [(1usize, 5.0), (4, 2.0)] {
        let sun = bodies.positions[0];
        let p = bodies.positions[planet];
        let pv = bodies.velocities[planet];
        let hill = (p - sun).norm() * (masses[planet - 1] / (3.0 * m0)).cbrt();
        let gm = bodies.gm[planet];
        let u = speed_km_s * KM_S_IN_AU_DAY;
        // (`b` for reference: the impact parameter is q √(1 + 2Gm/(q u²)).)
        // Directions: the relative velocity in the planet's orbital plane, tilted by 20°
        // out of it; the offset perpendicular to it.
        let radial = (p - sun).normalize();
        let normal = (p - sun).cross(&(pv - bodies.velocities[0])).normalize();
        let along = normal.cross(&radial);
        let tilt = 20f64.to_radians();
        let dir = (radial * 0.6 + along * 0.8).normalize() * tilt.cos() + normal * tilt.sin();
        let offset = dir.cross(&normal).normalize();
        for f in [0.02, 0.05, 0.3, 1.0] {
            let q = f * hill;
            let t_close = 3.5 * hill / u;
            let position = p + offset * q;
            let velocity = pv + dir * (u * u + 2.0 * gm / q).sqrt();
            // Backwards in time: every velocity reversed.
            let mut reversed = bodies.clone();
            reversed.velocities.iter_mut().for_each(|v| *v = -*v);
            let settings = symplectic::Encounters {
                tolerance: 1e-14,
                ..Default::default()
            };
            let back =
                symplectic::integrate_through(&reversed, position, -velocity, t_close, &settings)?;
            let t_end = 2.0 * t_close;
            for (j, (bq, bv)) in back.bodies.iter().enumerate() {
                row(case, "body", j, bodies.gm[j], *bq, -*bv, t_end);
            }
            row(
                case,
                "particle",
                planet,
                0.0,
                back.position,
                -back.velocity,
                t_end,
            );
            case += 1;
        }
    }
    Ok(())
}

fn row(case: usize, kind: &str, index: usize, gm: f64, q: Vec3, v: Vec3, t_end: f64) {
    println!(
        "{case},{kind},{index},{gm:e},{:e},{:e},{:e},{:e},{:e},{:e},{t_end:e}",
        q.x, q.y, q.z, v.x, v.y, v.z
    );
}
