//! The Bulirsch–Stoer integrator of the encounter mode: Gragg's modified midpoint rule with
//! polynomial extrapolation in `h²` and an adaptive step, for the Newtonian equations of
//! motion of the Sun, the planets and one massless particle.
//!
//! > R. Bulirsch and J. Stoer, "Numerical treatment of ordinary differential equations by
//! > extrapolation methods", *Numerische Mathematik* 8, 1–13 (1966)
//! > (doi:10.1007/BF02165234); W. B. Gragg, "On extrapolation algorithms for ordinary initial
//! > value problems", *SIAM Journal on Numerical Analysis* 2, 384–403 (1965)
//! > (doi:10.1137/0702030); E. Hairer, S. P. Nørsett and G. Wanner, *Solving Ordinary
//! > Differential Equations I*, 2nd ed., Springer (1993), §II.9 (the step and error control).
//!
//! With `n` substeps of `h = H/n`: `z₀ = y`, `z₁ = z₀ + h f(z₀)`,
//! `z_{m+1} = z_{m−1} + 2h f(z_m)`, `T_{j,1} = (z_n + z_{n−1} + h f(z_n))/2`; the sequence
//! `n_j = 2j` (Deuflhard's), and the Aitken–Neville extrapolation
//! `T_{j,k+1} = T_{j,k} + (T_{j,k} − T_{j−1,k})/((n_j/n_{j−k})² − 1)`, of order `2k` in `H`.
//! The step is accepted at the first row `j ≥ 3` where the scaled difference
//! `err = max_i |T_{j,j} − T_{j,j−1}|_i / (tol · s_i)` is at most 1 (`s_i` the length of the
//! position or velocity vector the component belongs to), and the next step is
//! `H · min(4, max(0.2, 0.94 (0.65/err)^{1/(2j−1)}))` (Hairer, Nørsett & Wanner's eq. 9.25
//! with their safety factors); a step that has not converged by row [`ROWS`] is retried
//! shorter by the same rule. MERCURY's hybrid integrator (Chambers 1999) integrates its
//! close encounters with this method.
//!
//! The right-hand side is the caller's function of time and state ([`Field`]): the Newtonian
//! equations of a few bodies integrated together ([`derivative`]), or a massless particle among
//! bodies given as functions of time (the encounter mode, planets from the ephemeris).
//!
//! Everything is a function of the state and the proposed step: the same input gives the same
//! trajectory bit for bit, whoever calls it and however often it pauses between steps. A step
//! whose right-hand side fails (the ephemeris does not reach a substep's time) leaves the state
//! as it was and returns that error, so the step can be redone later with the same result.

use crate::SymplecticError;

/// Rows of the extrapolation table (`n = 2, 4, …, 16`: order up to 16).
pub(crate) const ROWS: usize = 8;

/// The first row (1-based) at which a step may be accepted: order 6.
const FIRST_ACCEPTED_ROW: usize = 3;

/// The right-hand side: `Σ` objects, the first `massive` of which attract (`G m` in `gm`),
/// the rest massless. State layout: positions of every object (`3` values each), then
/// velocities. Counts the pair terms in `forces`.
pub(crate) fn derivative(gm: &[f64], y: &[f64], dy: &mut [f64], forces: &mut u64) {
    let objects = y.len() / 6;
    let massive = gm.len().min(objects);
    let (q, v) = y.split_at(3 * objects);
    let (dq, dv) = dy.split_at_mut(3 * objects);
    dq.copy_from_slice(v);
    dv.fill(0.0);
    for i in 0..objects {
        let qi = [q[3 * i], q[3 * i + 1], q[3 * i + 2]];
        // Pairs among the massive bodies once each; the massless ones feel every massive one.
        let first = if i < massive { i + 1 } else { 0 };
        for j in first..massive {
            let d = [q[3 * j] - qi[0], q[3 * j + 1] - qi[1], q[3 * j + 2] - qi[2]];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let inv_r3 = 1.0 / (r2 * r2.sqrt());
            *forces += 1;
            for c in 0..3 {
                dv[3 * i + c] += gm[j] * d[c] * inv_r3;
                if i < massive {
                    dv[3 * j + c] -= gm[i] * d[c] * inv_r3;
                }
            }
        }
    }
}

/// A right-hand side `dy = f(t, y)`; an error stops the step and leaves the state unchanged.
pub(crate) trait Field {
    /// Fills `dy` with the derivative of `y` at time `t`.
    fn derivative(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), SymplecticError>;
}

/// [`derivative`] as a [`Field`]: bodies integrated together (no explicit time), counting the
/// pair terms.
pub(crate) struct Bodies<'a> {
    /// `G m` of the massive bodies.
    pub gm: &'a [f64],
    /// Pair terms evaluated so far.
    pub forces: u64,
}

impl Field for Bodies<'_> {
    fn derivative(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), SymplecticError> {
        derivative(self.gm, y, dy, &mut self.forces);
        Ok(())
    }
}

/// Buffers of [`BulirschStoer::step`], sized for one state length (no allocation per step
/// once sized).
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch {
    /// Rows `j − 1` and `j` of the table, [`ROWS`] columns each.
    previous: Vec<Vec<f64>>,
    current: Vec<Vec<f64>>,
    z0: Vec<f64>,
    z1: Vec<f64>,
    f: Vec<f64>,
}

impl Scratch {
    fn size(&mut self, len: usize) {
        if self.z0.len() == len {
            return;
        }
        self.previous = vec![vec![0.0; len]; ROWS];
        self.current = vec![vec![0.0; len]; ROWS];
        self.z0 = vec![0.0; len];
        self.z1 = vec![0.0; len];
        self.f = vec![0.0; len];
    }
}

/// The integrator: its relative tolerance per step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BulirschStoer {
    pub tolerance: f64,
}

/// One accepted step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Taken {
    /// The step taken.
    pub step: f64,
    /// The step proposed for the next one.
    pub next: f64,
    /// Right-hand-side evaluations (accepted and rejected attempts).
    pub evaluations: u64,
}

impl BulirschStoer {
    /// One accepted step from `(t, y)` of at most `max_step` (`f64::INFINITY`: none), trying
    /// `proposed` first; `y` and `t` advance. Errors if the step shrinks below the time's
    /// resolution or the state stops being finite.
    pub(crate) fn step(
        &self,
        field: &mut impl Field,
        y: &mut [f64],
        t: &mut f64,
        proposed: f64,
        max_step: f64,
        scratch: &mut Scratch,
    ) -> Result<Taken, SymplecticError> {
        scratch.size(y.len());
        let mut h = proposed.min(max_step);
        let mut evaluations = 0;
        loop {
            if !(h.is_finite() && h > 0.0) || *t + h == *t {
                return Err(SymplecticError::InvalidState {
                    what: "encounter integrator",
                    reason: format!(
                        "step {h:e} days at t = {t} days is below the time's resolution"
                    ),
                });
            }
            let mut err = f64::INFINITY;
            let mut accepted_row = 0;
            for row in 0..ROWS {
                let n = 2 * (row + 1);
                evaluations += (n + 1) as u64;
                let (previous, current) = (&mut scratch.previous, &mut scratch.current);
                std::mem::swap(previous, current);
                let buffers = (&mut scratch.z0, &mut scratch.z1, &mut scratch.f);
                midpoint(field, y, *t, h, n, &mut current[0], buffers)?;
                for k in 1..=row {
                    let ratio = (n as f64) / ((2 * (row + 1 - k)) as f64);
                    let denominator = ratio * ratio - 1.0;
                    let (done, rest) = current.split_at_mut(k);
                    let (lower, target) = (&done[k - 1], &mut rest[0]);
                    for ((x, &a), &b) in target.iter_mut().zip(lower).zip(&previous[k - 1]) {
                        *x = a + (a - b) / denominator;
                    }
                }
                if row + 1 >= FIRST_ACCEPTED_ROW {
                    err = scaled_difference(&current[row], &current[row - 1], self.tolerance);
                    if err <= 1.0 {
                        accepted_row = row + 1;
                        break;
                    }
                }
            }
            let order_row = if accepted_row > 0 { accepted_row } else { ROWS };
            let factor = if err == 0.0 {
                4.0
            } else {
                (0.94 * (0.65 / err).powf(1.0 / (2 * order_row - 1) as f64)).clamp(0.2, 4.0)
            };
            let factor = if factor.is_nan() { 0.2 } else { factor };
            if accepted_row > 0 {
                let result = &scratch.current[accepted_row - 1];
                if !result.iter().all(|x| x.is_finite()) {
                    return Err(SymplecticError::InvalidState {
                        what: "encounter integrator",
                        reason: format!("non-finite state after a step of {h:e} days at t = {t}"),
                    });
                }
                y.copy_from_slice(result);
                *t += h;
                return Ok(Taken {
                    step: h,
                    next: h * factor,
                    evaluations,
                });
            }
            h *= factor;
        }
    }
}

/// Gragg's modified midpoint rule: `n` substeps of `H/n` from `y` at `t`, the smoothed end
/// value in `out`; `(z0, z1, f)` are buffers of the state's length.
fn midpoint(
    field: &mut impl Field,
    y: &[f64],
    t: f64,
    big_h: f64,
    n: usize,
    out: &mut [f64],
    (z0, z1, f): (&mut Vec<f64>, &mut Vec<f64>, &mut Vec<f64>),
) -> Result<(), SymplecticError> {
    let h = big_h / n as f64;
    // Substep `m` at `t + m H/n` (the last one at `t + H`).
    let at = |m: usize| t + big_h * (m as f64 / n as f64);
    z0.copy_from_slice(y);
    field.derivative(at(0), z0, f)?;
    for ((z, &a), &d) in z1.iter_mut().zip(y).zip(f.iter()) {
        *z = a + h * d;
    }
    for m in 1..n {
        field.derivative(at(m), z1, f)?;
        for ((a, b), &d) in z0.iter_mut().zip(z1.iter_mut()).zip(f.iter()) {
            let next = *a + 2.0 * h * d;
            *a = *b;
            *b = next;
        }
    }
    field.derivative(at(n), z1, f)?;
    for (((o, &a), &b), &d) in out.iter_mut().zip(z0.iter()).zip(z1.iter()).zip(f.iter()) {
        *o = 0.5 * (b + a + h * d);
    }
    Ok(())
}

/// `max_i |a_i − b_i| / (tol · s_i)` with `s_i` the length of the 3-vector (one object's
/// position or velocity) that component `i` belongs to, in the layout of [`derivative`]. A
/// remainder shorter than 3 (the encounter mode's `p₄`, a quadrature along the trajectory
/// the vectors control) is extrapolated with them but not controlled: its own size is no
/// scale (it passes through zero when a close encounter turns the comet's barycentric
/// energy round, and a relative test there would stall the step).
fn scaled_difference(a: &[f64], b: &[f64], tolerance: f64) -> f64 {
    let mut worst = 0.0f64;
    for (va, vb) in a.chunks_exact(3).zip(b.chunks_exact(3)) {
        let scale = (va[0] * va[0] + va[1] * va[1] + va[2] * va[2]).sqrt() * tolerance;
        for (x, z) in va.iter().zip(vb) {
            let d = (x - z).abs();
            // An object at rest at the origin (a zero vector) converges when its difference is 0.
            let e = if d == 0.0 { 0.0 } else { d / scale };
            // A NaN difference counts as not converged.
            worst = if e.is_nan() {
                f64::INFINITY
            } else {
                worst.max(e)
            };
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A circular two-body orbit (`G M = 1`, radius 1) over one period by steps of the
    /// integrator returns to its start within a few tolerances per step (an exact solution,
    /// independent of the code).
    #[test]
    fn circular_orbit_returns_to_its_start() {
        let gm = [1.0];
        // Sun fixed by giving the massless particle only: the Sun is object 0, the particle 1.
        let mut y = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let period = 2.0 * std::f64::consts::PI;
        let bs = BulirschStoer { tolerance: 1e-12 };
        let (mut t, mut h, mut scratch) = (0.0, 0.1, Scratch::default());
        let mut field = Bodies { gm: &gm, forces: 0 };
        let mut steps = 0;
        while t < period {
            let remaining = period - t;
            let taken = bs
                .step(&mut field, &mut y, &mut t, h, remaining, &mut scratch)
                .unwrap();
            if taken.step >= remaining {
                t = period;
            }
            h = taken.next;
            steps += 1;
        }
        assert!((t - period).abs() < 1e-12);
        let error = ((y[3] - 1.0).powi(2) + y[4].powi(2) + y[5].powi(2)).sqrt();
        // Tolerance: 10 × tol per step, the local bound the controller enforces.
        assert!(
            error < 10.0 * 1e-12 * steps as f64,
            "error {error:e} after {steps} steps"
        );
    }
}
