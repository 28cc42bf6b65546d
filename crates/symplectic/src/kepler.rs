//! The exact two-body drift in universal variables.
//!
//! Solves Kepler's problem `r̈ = −μ r/|r|³` for a time step `dt` from any initial state:
//! elliptic, parabolic or hyperbolic, forwards or backwards. Formulation of
//!
//! > J. M. A. Danby, *Fundamentals of Celestial Mechanics*, 2nd ed., Willmann-Bell 1988,
//! > §6.9–6.10 (universal variables, Stumpff functions `c_k`, Gauss `f` and `g` functions),
//!
//! with `β = 2μ/r₀ − v₀²`, `η₀ = r₀·v₀` and the universal anomaly `s`, which solves
//! Kepler's equation `dt = r₀ G₁(s) + η₀ G₂(s) + μ G₃(s)` where `G_k(s) = s^k c_k(β s²)`.
//! Then `f = 1 − μ G₂/r₀`, `g = r₀ G₁ + η₀ G₂`, `ḟ = −μ G₁/(r r₀)`, `ġ = 1 − μ G₂/r` with
//! `r = r₀ G₀ + η₀ G₁ + μ G₂`.
//!
//! The Stumpff functions are evaluated by their series after reducing the argument by
//! powers of four, then rebuilt with the quadruple-argument formulas (Danby §6.9), which
//! keeps them accurate to round-off for any `βs²`. The equation is solved by Newton's
//! method from Danby's starting value; Kepler's equation is strictly increasing in `s`
//! (its derivative is `r > 0`), so when Newton does not converge the solver falls back to
//! a bracketed bisection–Newton hybrid that always does. For bound orbits the step is
//! first reduced modulo the period, which changes nothing mathematically and keeps `s`
//! small for drifts of many orbits.

use crate::{SymplecticError, Vec3};

/// The four Stumpff functions `c₀..c₃` at `z`.
#[inline]
pub fn stumpff(z: f64) -> [f64; 4] {
    if !z.is_finite() {
        // No reduction terminates for ±∞ or NaN: the caller sees non-finite values.
        return [f64::NAN; 4];
    }
    // Reduce |z| below 0.1 by quarter steps: c_k(z) from c_k(z/4^n).
    let mut n = 0;
    let mut x = z;
    while x.abs() > 0.1 {
        x *= 0.25;
        n += 1;
    }
    // Series (Horner form) for c2 and c3 at small x, then c1 = 1 − x c3, c0 = 1 − x c2. The
    // divisors are multiplied as reciprocals (constant-folded): a division costs several
    // times a multiplication, and twelve of them made up most of a call.
    let c3 = (1.0
        - x * (1.0 / 20.0)
            * (1.0
                - x * (1.0 / 42.0)
                    * (1.0
                        - x * (1.0 / 72.0)
                            * (1.0
                                - x * (1.0 / 110.0)
                                    * (1.0 - x * (1.0 / 156.0) * (1.0 - x * (1.0 / 210.0)))))))
        * (1.0 / 6.0);
    let c2 = (1.0
        - x * (1.0 / 12.0)
            * (1.0
                - x * (1.0 / 30.0)
                    * (1.0
                        - x * (1.0 / 56.0)
                            * (1.0
                                - x * (1.0 / 90.0)
                                    * (1.0 - x * (1.0 / 132.0) * (1.0 - x * (1.0 / 182.0)))))))
        * 0.5;
    let mut c = [1.0 - x * c2, 1.0 - x * c3, c2, c3];
    for _ in 0..n {
        let [c0, c1, c2, c3] = c;
        c = [
            2.0 * c0 * c0 - 1.0,
            c1 * c0,
            0.5 * c1 * c1,
            0.25 * (c2 + c0 * c3),
        ];
    }
    c
}

/// Outcome of one drift, for diagnostics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriftInfo {
    /// Newton iterations used.
    pub iterations: u32,
    /// `true` when the bracketed fallback was needed.
    pub used_fallback: bool,
}

/// Advances `(r, v)` by `dt` on the Kepler orbit of gravitational parameter `mu` (length³/time²).
///
/// Errors when `mu <= 0`, the state is not finite, `r = 0`, or the solver fails (it cannot
/// for finite input, but a non-finite intermediate is reported rather than returned).
pub fn drift(r: &mut Vec3, v: &mut Vec3, mu: f64, dt: f64) -> Result<DriftInfo, SymplecticError> {
    let r0 = r.norm();
    drift_from_distance(r, v, r0, mu, dt)
}

/// [`drift`] with `r0 = |r|` already computed by the caller (bit for bit `r.norm()`).
pub(crate) fn drift_from_distance(
    r: &mut Vec3,
    v: &mut Vec3,
    r0: f64,
    mu: f64,
    dt: f64,
) -> Result<DriftInfo, SymplecticError> {
    if !(mu.is_finite() && mu > 0.0) {
        return Err(SymplecticError::InvalidParameter {
            name: "mu",
            value: mu,
            reason: "must be finite and > 0",
        });
    }
    if !(r0.is_finite() && r0 > 0.0 && v.iter().all(|x| x.is_finite()) && dt.is_finite()) {
        return Err(SymplecticError::InvalidState {
            what: "Kepler drift",
            reason: format!("r = {r:?}, v = {v:?}, dt = {dt}: need finite values and r != 0"),
        });
    }
    if dt == 0.0 {
        return Ok(DriftInfo {
            iterations: 0,
            used_fallback: false,
        });
    }
    let eta = r.dot(v);
    let beta = 2.0 * mu / r0 - v.norm_squared();
    // Bound orbit: reduce the step modulo the period.
    let mut dt_eff = dt;
    // |dt| > period ⟺ dt² β³ > (2πμ)², tested without the square root.
    let two_pi_mu = 2.0 * std::f64::consts::PI * mu;
    if beta > 0.0 && dt * dt * beta * beta * beta > two_pi_mu * two_pi_mu {
        let period = two_pi_mu / (beta * beta.sqrt());
        dt_eff = dt % period;
    }
    // Kepler's equation for the bracketed fallback. The Halley loop below evaluates the same
    // expressions inline: routing it through this closure cost ~10 % of a planet step.
    let kepler = |s: f64| -> (f64, f64, [f64; 4]) {
        let c = stumpff(beta * s * s);
        let g1 = s * c[1];
        let g2 = s * s * c[2];
        let g3 = s * s * s * c[3];
        let t = r0 * g1 + eta * g2 + mu * g3;
        let rr = r0 * c[0] + eta * g1 + mu * g2;
        (t - dt_eff, rr, c)
    };
    // Start from the third-order series inversion of Kepler's equation,
    // dt = r0 s + η0 s²/2 + (μ − β r0) s³/6 + O(s⁴), when it is a small correction to dt/r0
    // (the usual case of a step much shorter than the orbit); otherwise from dt/r0, a
    // first-order guess valid for any conic.
    let x = dt_eff / r0;
    let a2 = eta / (2.0 * r0);
    let a3 = (mu - beta * r0) / (6.0 * r0);
    let correction = -a2 * x * x + (2.0 * a2 * a2 - a3) * x * x * x;
    let mut s = if correction.abs() < 0.1 * x.abs() {
        x + correction
    } else {
        x
    };
    let mut info = DriftInfo {
        iterations: 0,
        used_fallback: false,
    };
    // Halley's iteration (cubic convergence; f'' = dr/ds = η0 G0 + (μ − β r0) G1). Once a
    // correction is below HALLEY_ACCEPT relative to s, the error left after applying it is
    // ~(1e-6)³: the iteration stops and the G_k are carried to the new s by their Taylor
    // series (dG0/ds = −β G1, dG_k/ds = G_(k−1)), to second order in the correction (the
    // third-order term is ~1e-18 relative), instead of a further Stumpff evaluation.
    const HALLEY_ACCEPT: f64 = 1e-6;
    let mut solution: Option<(f64, f64, f64, f64)> = None; // (s, G0, G1, G2)
    for _ in 0..40 {
        info.iterations += 1;
        let c = stumpff(beta * s * s);
        let (g0, g1, g2, g3) = (c[0], s * c[1], s * s * c[2], s * s * s * c[3]);
        let f = r0 * g1 + eta * g2 + mu * g3 - dt_eff;
        let fp = r0 * g0 + eta * g1 + mu * g2;
        let fpp = eta * g0 + (mu - beta * r0) * g1;
        // Halley, ds = f/(f' − f f''/2f'), written with one division, where it is a modest
        // change of Newton's step (|f f''| < f'², so |ds| is 2/3 to 2 Newton steps); Newton
        // otherwise (f' = r > 0). Without the upper bound a large −f f'' (far from the root,
        // near a pericentre passage) made the Halley step tiny though f was not, and the
        // test below accepted a wrong anomaly: e = 0.99, a third of an orbit from
        // pericentre, gave positions off by several AU in one drift of eight.
        let denominator = 2.0 * fp * fp - f * fpp;
        let ds = if denominator > fp * fp && denominator < 3.0 * fp * fp {
            2.0 * f * fp / denominator
        } else {
            f / fp
        };
        let s_new = s - ds;
        if !s_new.is_finite() {
            break;
        }
        if ds.abs() <= HALLEY_ACCEPT * s_new.abs() || ds == 0.0 {
            let d = -ds;
            let half_d2 = 0.5 * d * d;
            solution = Some((
                s_new,
                g0 - beta * (g1 * d + g0 * half_d2),
                g1 + g0 * d - beta * g1 * half_d2,
                g2 + g1 * d + g0 * half_d2,
            ));
            break;
        }
        s = s_new;
    }
    let (g0, g1, g2) = match solution {
        Some((_, g0, g1, g2)) => (g0, g1, g2),
        None => {
            let s = solve_bracketed(&kepler, dt_eff, r0)?;
            info.used_fallback = true;
            let c = stumpff(beta * s * s);
            (c[0], s * c[1], s * s * c[2])
        }
    };
    let rr = r0 * g0 + eta * g1 + mu * g2;
    // Two divisions for the four quotients.
    let (inv_r0, inv_rr) = (1.0 / r0, 1.0 / rr);
    let f = 1.0 - mu * g2 * inv_r0;
    let g = r0 * g1 + eta * g2;
    let fdot = -mu * g1 * (inv_rr * inv_r0);
    let gdot = 1.0 - mu * g2 * inv_rr;
    let (r_old, v_old) = (*r, *v);
    *r = r_old * f + v_old * g;
    *v = r_old * fdot + v_old * gdot;
    if !(r.iter().chain(v.iter()).all(|x| x.is_finite())) {
        return Err(SymplecticError::InvalidState {
            what: "Kepler drift",
            reason: format!(
                "non-finite result from r = {r_old:?}, v = {v_old:?}, mu = {mu}, dt = {dt}"
            ),
        });
    }
    Ok(info)
}

/// Bisection–Newton hybrid on the strictly increasing Kepler function (root of `f`).
fn solve_bracketed(
    kepler: &impl Fn(f64) -> (f64, f64, [f64; 4]),
    dt: f64,
    r0: f64,
) -> Result<f64, SymplecticError> {
    // Bracket: expand from 0 in the direction of dt until the sign changes.
    let (mut lo, mut hi) = (0.0f64, dt / r0);
    let mut f_lo = kepler(lo).0;
    let mut grow = 0;
    loop {
        let f_hi = kepler(hi).0;
        if f_hi.signum() != f_lo.signum() {
            break;
        }
        (lo, f_lo) = (hi, f_hi);
        hi *= 2.0;
        grow += 1;
        if grow > 2000 || !hi.is_finite() {
            return Err(SymplecticError::InvalidState {
                what: "Kepler drift",
                reason: format!("could not bracket the universal anomaly for dt = {dt}"),
            });
        }
    }
    if lo > hi {
        std::mem::swap(&mut lo, &mut hi);
    }
    let mut s = 0.5 * (lo + hi);
    for _ in 0..300 {
        let (f, fp, _) = kepler(s);
        if f == 0.0 {
            return Ok(s);
        }
        if f < 0.0 {
            lo = s;
        } else {
            hi = s;
        }
        let newton = s - f / fp;
        s = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if hi - lo <= 2.0 * f64::EPSILON * s.abs() {
            break;
        }
    }
    Ok(s)
}

/// Osculating elements of a two-body state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elements {
    /// Semi-major axis (negative for hyperbolae, infinite for a parabola).
    pub semi_major_axis: f64,
    /// Eccentricity.
    pub eccentricity: f64,
    /// Inclination to the reference plane (rad).
    pub inclination: f64,
    /// Perihelion distance `q = p/(1 + e)` (accurate for every conic).
    pub perihelion: f64,
}

/// Osculating elements of `(r, v)` about a centre of gravitational parameter `mu`.
pub fn elements(r: &Vec3, v: &Vec3, mu: f64) -> Result<Elements, SymplecticError> {
    let rn = r.norm();
    if !(mu.is_finite() && mu > 0.0 && rn > 0.0 && r.iter().chain(v.iter()).all(|x| x.is_finite()))
    {
        return Err(SymplecticError::InvalidState {
            what: "osculating elements",
            reason: format!("r = {r:?}, v = {v:?}, mu = {mu}: need finite values, r != 0, mu > 0"),
        });
    }
    let h = r.cross(v);
    let e_vec = v.cross(&h) / mu - r / rn;
    let e = e_vec.norm();
    let inv_a = 2.0 / rn - v.norm_squared() / mu;
    let hn = h.norm();
    Ok(Elements {
        semi_major_axis: 1.0 / inv_a,
        eccentricity: e,
        inclination: if hn > 0.0 {
            (h.z / hn).clamp(-1.0, 1.0).acos()
        } else {
            0.0
        },
        perihelion: h.norm_squared() / mu / (1.0 + e),
    })
}

/// The six classical elements of an elliptic or hyperbolic orbit, angles in radians.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ConicElements {
    /// Perihelion distance `q > 0`.
    pub perihelion: f64,
    /// Eccentricity `e ≥ 0`, `e ≠ 1`.
    pub eccentricity: f64,
    /// Inclination `i`.
    pub inclination: f64,
    /// Longitude of the ascending node `Ω`.
    pub node: f64,
    /// Argument of perihelion `ω`.
    pub argument_of_perihelion: f64,
    /// Mean anomaly `M` (`E − e sin E` for `e < 1`, `e sinh H − H` for `e > 1`).
    pub mean_anomaly: f64,
}

/// Position and velocity of `el` about a centre of gravitational parameter `mu`: Kepler's
/// equation solved by Newton's method from `E = M + e sin M` (ellipse) or
/// `H = asinh(M/e)` (hyperbola) to round-off, then the perifocal state rotated by
/// `R_z(Ω) R_x(i) R_z(ω)`. Errors name the element out of range (a parabola `e = 1` has no
/// mean anomaly of this form).
pub fn state_from_elements(el: &ConicElements, mu: f64) -> Result<(Vec3, Vec3), SymplecticError> {
    let bad = |name: &'static str, value: f64, reason: &'static str| {
        Err(SymplecticError::InvalidParameter {
            name,
            value,
            reason,
        })
    };
    let e = el.eccentricity;
    let q = el.perihelion;
    if !(mu.is_finite() && mu > 0.0) {
        return bad("mu", mu, "must be finite and > 0");
    }
    if !(q.is_finite() && q > 0.0) {
        return bad("perihelion", q, "must be finite and > 0");
    }
    if !(e.is_finite() && e >= 0.0) || e == 1.0 {
        return bad("eccentricity", e, "must be finite, >= 0 and != 1");
    }
    for (name, v) in [
        ("inclination", el.inclination),
        ("node", el.node),
        ("argument_of_perihelion", el.argument_of_perihelion),
        ("mean_anomaly", el.mean_anomaly),
    ] {
        if !v.is_finite() {
            return bad(name, v, "must be finite");
        }
    }
    let a = q / (1.0 - e); // negative for a hyperbola
    let (x, y, vx, vy);
    if e < 1.0 {
        let m = el.mean_anomaly.rem_euclid(std::f64::consts::TAU);
        let mut ea = if e < 0.8 {
            m + e * m.sin()
        } else {
            std::f64::consts::PI
        };
        for _ in 0..60 {
            let d = (ea - e * ea.sin() - m) / (1.0 - e * ea.cos());
            ea -= d;
            if d.abs() < 1e-15 {
                break;
            }
        }
        let (s, c) = ea.sin_cos();
        let b = a * (1.0 - e * e).sqrt();
        let n = (mu / (a * a * a)).sqrt();
        let edot = n / (1.0 - e * c);
        (x, y) = (a * (c - e), b * s);
        (vx, vy) = (-a * s * edot, b * c * edot);
    } else {
        let m = el.mean_anomaly;
        let mut h = (m / e).asinh();
        for _ in 0..100 {
            let d = (e * h.sinh() - h - m) / (e * h.cosh() - 1.0);
            h -= d;
            if d.abs() < 1e-15 * (1.0 + h.abs()) {
                break;
            }
        }
        let (sh, ch) = (h.sinh(), h.cosh());
        let b = -a * (e * e - 1.0).sqrt();
        let n = (mu / (-a * a * a)).sqrt();
        let hdot = n / (e * ch - 1.0);
        (x, y) = (a * (ch - e), b * sh);
        (vx, vy) = (a * sh * hdot, b * ch * hdot);
    }
    let rot = nalgebra::Rotation3::from_axis_angle(&Vec3::z_axis(), el.node)
        * nalgebra::Rotation3::from_axis_angle(&Vec3::x_axis(), el.inclination)
        * nalgebra::Rotation3::from_axis_angle(&Vec3::z_axis(), el.argument_of_perihelion);
    Ok((rot * Vec3::new(x, y, 0.0), rot * Vec3::new(vx, vy, 0.0)))
}
