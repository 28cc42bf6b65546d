//! The geometric end rules of a [`Population`](crate::Population)'s particles: collision with
//! the Sun and the distance limits ([`RemovalRules`]).

use super::members::{DistanceFrame, DistanceLimit, RemovalRules};
use crate::run::ParticleStatus;
use crate::solar_system::SUN_RADIUS_AU;
use crate::Vec3;

/// The Sun at a check: barycentric position and velocity, `G m₀`.
pub(crate) struct SunState {
    pub position: Vec3,
    pub velocity: Vec3,
    pub gm: f64,
}

/// The first of the rules `sun_collision`, `min_distance`, `max_distance` that the particle
/// at barycentric `(q, v)` and time `time` meets, its previous check at `previous_time`.
pub(crate) fn geometric_end(
    rules: &RemovalRules,
    time: f64,
    previous_time: f64,
    q: Vec3,
    v: Vec3,
    sun: &SunState,
) -> Option<ParticleStatus> {
    let helio = q - sun.position;
    if rules.sun_collision {
        let r = helio.norm();
        let closest = if r < SUN_RADIUS_AU {
            Some(r)
        } else {
            perihelion_passed_within(
                helio,
                v - sun.velocity,
                sun.gm,
                SUN_RADIUS_AU,
                time - previous_time,
            )
        };
        if let Some(distance) = closest {
            return Some(ParticleStatus::SunCollision { time, distance });
        }
    }
    let distance = |limit: &DistanceLimit| match limit.frame {
        DistanceFrame::Heliocentric => helio.norm(),
        DistanceFrame::Barycentric => q.norm(),
    };
    if let Some(limit) = &rules.min_distance {
        let d = distance(limit);
        if d < limit.distance {
            return Some(ParticleStatus::InsideMinDistance {
                time,
                distance: d,
                frame: limit.frame,
            });
        }
    }
    if let Some(limit) = &rules.max_distance {
        let d = distance(limit);
        if d > limit.distance {
            return Some(ParticleStatus::BeyondMaxDistance {
                time,
                distance: d,
                frame: limit.frame,
            });
        }
    }
    None
}

/// The pericentre distance of the two-body orbit `(r, v)` about `mu` if it is below
/// `radius` and the body passed it within the last `dt` days (outbound, the time since
/// pericentre from Kepler's equation at most `dt`): Mercury's test for a collision with the
/// central body between two steps (`mce_cent`, Chambers 1999).
pub(crate) fn perihelion_passed_within(
    r: Vec3,
    v: Vec3,
    mu: f64,
    radius: f64,
    dt: f64,
) -> Option<f64> {
    let rv = r.dot(&v);
    if rv.is_nan() || rv <= 0.0 {
        return None;
    }
    let rn = r.norm();
    let h2 = r.cross(&v).norm_squared();
    // 1/a from the energy; e² = 1 − h² (1/a)/μ.
    let alpha = 2.0 / rn - v.norm_squared() / mu;
    let e = (1.0 - h2 * alpha / mu).max(0.0).sqrt();
    let pericentre = h2 / (mu * (1.0 + e));
    if pericentre.is_nan() || pericentre >= radius {
        return None;
    }
    let since = if alpha > 0.0 {
        // e cos E = 1 − r/a, e sin E = r·v/√(μa); M = E − e sin E.
        let (c, s) = (1.0 - rn * alpha, rv * (alpha / mu).sqrt());
        let big_e = s.atan2(c);
        (big_e - s) / (mu * alpha.powi(3)).sqrt()
    } else if alpha < 0.0 {
        // e sinh H = r·v/√(−μa); M = e sinh H − H.
        let s = rv * (-alpha / mu).sqrt();
        let big_h = (s / e).asinh();
        (s - big_h) / (mu * (-alpha).powi(3)).sqrt()
    } else {
        // Parabola (Barker): D = r·v/√μ, t = (q D + D³/6)/√μ.
        let d = rv / mu.sqrt();
        (pericentre * d + d.powi(3) / 6.0) / mu.sqrt()
    };
    (since <= dt).then_some(pericentre)
}
