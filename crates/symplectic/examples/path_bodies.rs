//! Initial states of comets that meet a giant planet, for the population path's comparison
//! with REBOUND's IAS15 (`reference-data/comet-encounters/`):
//!
//! `cargo run --release -p symplectic --example path_bodies > path_initial.csv`
//!
//! The planets are those of the shipped Centaur population (`populations/centaurs.toml`:
//! the Sun and the four giants of `outer_solar_system`, ecliptic J2000, at the epoch). Each
//! comet passes one planet at a closest distance of `f` Hill radii with a speed `u` relative
//! to it at infinity (5 km/s at Jupiter, 3 at Saturn, 2 at Uranus and Neptune); it is set up
//! at its closest approach at `t_c = 5 R_H/u` (the planets there read from the population's
//! ephemeris, the comet at the pericentre of its planetocentric hyperbola, speed
//! `√(u² + 2Gm/q)`) and integrated backwards (every velocity reversed) by
//! `symplectic::integrate_through` at tolerance 10⁻¹⁴ to the epoch. The comet's state at
//! the epoch and `t_end = 2 t_c` are printed: both codes start from it with the planets'
//! epoch states; how it was made does not enter the comparison. Its distance from the planet
//! at the epoch, in Hill radii, goes to standard error (every comet starts outside 3).
//!
//! Columns: `kind,index,planet,closest_hill_radii,gm,x,y,z,vx,vy,vz,t_end` (AU, AU/day,
//! AU³/day², days); `kind` is `body` (index 0 the Sun, 1–4 Jupiter … Neptune) or `comet`
//! (index: the comet's number; planet: the planet it passes, 1-based).
use symplectic::{
    integrate_through, outer_solar_system, BodyStates, Encounters, Ephemeris, Frame, Integrator,
    SymplecticError, Vec3,
};

const KM_S_IN_AU_DAY: f64 = 86_400.0 / 149_597_870.7;

/// The comets: planet passed (1-based), closest approach (Hill radii), speed at infinity
/// relative to the planet (km/s), tilt of the relative velocity out of the planet's orbital
/// plane (degrees).
const COMETS: [(usize, f64, f64, f64); 11] = [
    (1, 0.05, 5.0, 20.0),
    (1, 0.1, 5.0, -10.0),
    (1, 0.3, 5.0, 35.0),
    (1, 1.0, 5.0, 5.0),
    (1, 2.0, 5.0, -25.0),
    (1, 2.9, 5.0, 15.0),
    (2, 0.1, 3.0, 20.0),
    (2, 1.0, 3.0, -15.0),
    (3, 0.3, 2.0, 10.0),
    (4, 0.1, 2.0, 20.0),
    (4, 1.0, 2.0, -30.0),
];

fn main() -> Result<(), SymplecticError> {
    // The shipped Centaur population's planets: S6 at 91.3125 d.
    let mut ephemeris = Ephemeris::new(
        outer_solar_system(Frame::EclipticJ2000),
        Integrator::S6 { step: 91.3125 },
    )?;
    let planets = ephemeris.planets().clone();
    let m0 = planets.sun_mass();
    let mut epoch = BodyStates::default();
    ephemeris.bodies_at(0.0, &mut epoch)?;
    println!("kind,index,planet,closest_hill_radii,gm,x,y,z,vx,vy,vz,t_end");
    for (j, (q, v)) in epoch.positions.iter().zip(&epoch.velocities).enumerate() {
        row("body", j, j, 0.0, epoch.gm[j], *q, *v, 0.0);
    }
    let backwards = Encounters {
        tolerance: 1e-14,
        ..Default::default()
    };
    for (k, &(planet, f, speed_km_s, tilt_deg)) in COMETS.iter().enumerate() {
        let hill_at = |b: &BodyStates| {
            (b.positions[planet] - b.positions[0]).norm()
                * (planets.masses()[planet - 1] / (3.0 * m0)).cbrt()
        };
        let u = speed_km_s * KM_S_IN_AU_DAY;
        let t_close = 5.0 * hill_at(&epoch) / u;
        let mut bodies = BodyStates::default();
        ephemeris.bodies_at(t_close, &mut bodies)?;
        let (sun, p, pv) = (
            bodies.positions[0],
            bodies.positions[planet],
            bodies.velocities[planet],
        );
        let hill = hill_at(&bodies);
        let gm = bodies.gm[planet];
        // The relative velocity in the planet's orbital plane, tilted out of it; the offset
        // perpendicular to it.
        let radial = (p - sun).normalize();
        let normal = (p - sun).cross(&(pv - bodies.velocities[0])).normalize();
        let along = normal.cross(&radial);
        let tilt = tilt_deg.to_radians();
        let dir = (radial * 0.6 + along * 0.8).normalize() * tilt.cos() + normal * tilt.sin();
        let offset = dir.cross(&normal).normalize();
        let q = f * hill;
        let position = p + offset * q;
        let velocity = pv + dir * (u * u + 2.0 * gm / q).sqrt();
        let mut reversed = bodies.clone();
        reversed.time = 0.0;
        reversed.velocities.iter_mut().for_each(|v| *v = -*v);
        let back = integrate_through(&reversed, position, -velocity, t_close, &backwards)?;
        let start = (back.position - epoch.positions[planet]).norm() / hill_at(&epoch);
        eprintln!("comet {k}: planet {planet}, {f} R_H at t_c = {t_close:.1} d, {start:.2} R_H at the epoch");
        row(
            "comet",
            k,
            planet,
            f,
            0.0,
            back.position,
            -back.velocity,
            2.0 * t_close,
        );
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn row(kind: &str, index: usize, planet: usize, f: f64, gm: f64, q: Vec3, v: Vec3, t_end: f64) {
    println!(
        "{kind},{index},{planet},{f},{gm:e},{:e},{:e},{:e},{:e},{:e},{:e},{t_end:e}",
        q.x, q.y, q.z, v.x, v.y, v.z
    );
}
