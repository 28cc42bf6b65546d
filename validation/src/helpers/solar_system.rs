//! The comet-like test particles of Chegodaeva (2004), read from `reference-data/symplectic-100myr/`
//! (the planets come from `symplectic::outer_solar_system`).

use anyhow::Result;
use symplectic::{Planets, Vec3};

use super::load_reference_csv;
use crate::Context;

/// Days per Julian year.
pub const DAYS_PER_YEAR: f64 = 365.25;

/// One test particle of `particles.csv`.
#[derive(Debug, Clone)]
pub struct ParticleInitial {
    /// Name.
    pub name: String,
    /// Semi-major axis (AU) and perihelion (AU) given by the paper.
    pub a_au: f64,
    /// Perihelion distance (AU).
    pub q_au: f64,
    /// Heliocentric ecliptic position (AU) and velocity (AU/day).
    pub position: Vec3,
    /// Velocity (AU/day).
    pub velocity: Vec3,
    /// Initial steps of the paper (days) for S2 and S6.
    pub dt0_s2_day: f64,
    /// For S6.
    pub dt0_s6_day: f64,
}

/// The particles of `particles.csv`.
pub fn particles(ctx: &Context) -> Result<Vec<ParticleInitial>> {
    let cols = [
        "name",
        "a_au",
        "q_au",
        "x",
        "y",
        "z",
        "vx",
        "vy",
        "vz",
        "dt0_s2_day",
        "dt0_s6_day",
    ];
    let t = load_reference_csv(ctx, "symplectic-100myr/particles.csv", &cols)?;
    (0..t.len())
        .map(|r| {
            Ok(ParticleInitial {
                name: t.text(r, "name")?.to_string(),
                a_au: t.number(r, "a_au")?,
                q_au: t.number(r, "q_au")?,
                position: Vec3::new(t.number(r, "x")?, t.number(r, "y")?, t.number(r, "z")?),
                velocity: Vec3::new(t.number(r, "vx")?, t.number(r, "vy")?, t.number(r, "vz")?),
                dt0_s2_day: t.number(r, "dt0_s2_day")?,
                dt0_s6_day: t.number(r, "dt0_s6_day")?,
            })
        })
        .collect()
}

/// Barycentric position and velocity of a heliocentric state, at the planets' time.
pub fn to_barycentric(planets: &Planets, position: Vec3, velocity: Vec3) -> (Vec3, Vec3) {
    let (sun_q, sun_v) = planets.sun_barycentric_state();
    (position + sun_q, velocity + sun_v)
}

/// CPU time of the calling thread, seconds (falls back to wall time where unsupported).
// Unsafe: the thread's CPU clock (`clock_gettime`) has no safe std API.
#[allow(unsafe_code)]
pub fn thread_cpu_seconds() -> f64 {
    #[cfg(unix)]
    {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: clock_gettime writes into the timespec we own.
        let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
        if rc == 0 {
            return ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9;
        }
    }
    use std::time::{SystemTime, UNIX_EPOCH};
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}
