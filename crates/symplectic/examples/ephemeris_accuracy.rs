//! How far the planets' trajectory of an [`Ephemeris`] (the quintic Hermite interpolant of its
//! grid, the one function of time both the map and the encounter mode read) lies from the
//! Newtonian flow of its grid states, per planet step:
//!
//! `cargo run --release -p symplectic --example ephemeris_accuracy`
//!
//! The Sun and the four giants of `outer_solar_system` (ecliptic J2000) integrated by S6 at
//! each planet step `τ` over two orbits of Jupiter; from every grid state the bodies are
//! integrated by Bulirsch–Stoer at a relative tolerance of 2·10⁻¹⁵ per step (the reference,
//! an algorithm independent of the interpolant) to 8 times across the interval, and the
//! largest distance between the interpolant and that flow is printed per planet, with the
//! part at the interval's end (the S6 map's own one-step error, which no interpolant can
//! remove), the wall time of a planet step and the memory a whole grid of 1 Myr would take
//! (the population retains only a window of it).
use std::time::Instant;

use symplectic::{
    integrate_through, outer_solar_system, BodyStates, Encounters, Ephemeris, Frame, Integrator,
    Vec3,
};

const JUPITER_PERIOD_DAYS: f64 = 4332.59;
const DAYS_PER_MYR: f64 = 365.25e6;

fn main() -> Result<(), symplectic::SymplecticError> {
    let reference = Encounters {
        tolerance: 2e-15,
        ..Default::default()
    };
    println!("tau_days,planet,max_error_au,map_step_error_au,planet_step_us,grid_bytes_per_myr");
    for tau in [
        730.5,
        365.25,
        243.5,
        182.625,
        146.1,
        121.75,
        104.357_142_857_142_86,
        91.3125,
    ] {
        let planets = outer_solar_system(Frame::EclipticJ2000);
        let bodies_count = planets.len() + 1;
        let mut ephemeris = Ephemeris::new(planets, Integrator::S6 { step: tau })?;
        let span = 2.0 * JUPITER_PERIOD_DAYS;
        let clock = Instant::now();
        ephemeris.extend_to(span + tau)?;
        let step_us = clock.elapsed().as_secs_f64() * 1e6 / ephemeris.planet_steps() as f64;
        let mut worst = vec![0.0f64; bodies_count];
        let mut at_end = vec![0.0f64; bodies_count];
        let (mut grid_state, mut interpolated) = (BodyStates::default(), BodyStates::default());
        let mut k = 0u64;
        while ephemeris.grid_time(k) < span {
            ephemeris.bodies_at(ephemeris.grid_time(k), &mut grid_state)?;
            for i in 1..=8 {
                let t = ephemeris.grid_time(k) + tau * (i as f64 / 8.0);
                // A massless particle far away: the flow of the bodies alone.
                let far = Vec3::new(1e4, 0.0, 0.0);
                let flow = integrate_through(&grid_state, far, Vec3::zeros(), t, &reference)?;
                ephemeris.bodies_at(t, &mut interpolated)?;
                for j in 1..bodies_count {
                    let error = (flow.bodies[j].0 - interpolated.positions[j]).norm();
                    worst[j] = worst[j].max(error);
                    if i == 8 {
                        at_end[j] = at_end[j].max(error);
                    }
                }
            }
            k += 1;
        }
        let grid_bytes = DAYS_PER_MYR / tau * (72 * bodies_count) as f64;
        for (j, name) in ["jupiter", "saturn", "uranus", "neptune"]
            .iter()
            .enumerate()
        {
            println!(
                "{tau},{name},{:.3e},{:.3e},{step_us:.2},{grid_bytes:.3e}",
                worst[j + 1],
                at_end[j + 1]
            );
        }
    }
    Ok(())
}
