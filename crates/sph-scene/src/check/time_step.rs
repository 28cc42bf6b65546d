//! The time-step checks: refuse a frame length, substep count or duration that cannot give a
//! simulation, with the reason.
//!
//! * **Substeps** at most [`MAX_SUBSTEPS`] per frame (the cap every solver of the workspace
//!   applies, [`sph_solver::CommonParams::validate`]).
//! * **Frames** at most [`MAX_FRAMES`](crate::MAX_FRAMES) (`duration / frame_dt`).
//! * **Travel per step.** A solver step of `Δt = frame_dt / substeps` moves a particle that
//!   starts at the fluid's largest initial speed `|v0|` and falls freely by
//!   `d = (|v0| + |g| Δt) Δt` (semi-implicit Euler, the integrator of every solver here).
//!   The scene is refused when `d` exceeds the support radius `h` (the solver's own: its
//!   `support_over_spacing`, or its default, times the spacing): such a particle leaves
//!   its whole kernel neighbourhood within one step, so the neighbours found once per step
//!   cannot see what it hits, and the density or pressure solve cannot act on it. This is
//!   the Courant–Friedrichs–Lewy condition `v Δt ≤ λ h` (Courant, Friedrichs & Lewy 1928,
//!   "Über die partiellen Differenzengleichungen der mathematischen Physik",
//!   Mathematische Annalen 100, 32–74, doi:10.1007/BF01448839; for SPH, Monaghan 1992,
//!   "Smoothed particle hydrodynamics", Annu. Rev. Astron. Astrophys. 30, 543–574,
//!   doi:10.1146/annurev.aa.30.090192.002551) with `λ = 1` at the first step, taken as a
//!   refusal bound, not an accuracy bound: accurate runs use `λ ≈ 0.4` with respect to the
//!   particle diameter (M. Ihmsen, J. Orthmann, B. Solenthaler, A. Kolb and M. Teschner,
//!   "SPH Fluids in Computer Graphics", Eurographics 2014 State of the Art Reports,
//!   doi:10.2312/egst.20141034), and speeds grow after the first step. The message says
//!   how many substeps would pass.

use sph_solver::MAX_SUBSTEPS;

use crate::error::Ctx;
use crate::geom::v3;
use crate::limits::MAX_FRAMES;
use crate::{QuickSpec, Scene, SceneError};

/// Checks the time stepping of `scene`; `quick` are the overrides applied to it (the field
/// names then point at `quick.*` for the values they set).
pub(super) fn check(ctx: &Ctx, scene: &Scene, quick: Option<&QuickSpec>) -> Result<(), SceneError> {
    let field = |name: &str, overridden: bool, main: &str| {
        if overridden {
            format!("quick.{name}")
        } else {
            main.to_string()
        }
    };
    let f_substeps = field(
        "substeps",
        quick.is_some_and(|q| q.substeps.is_some()),
        "solver.substeps",
    );
    let f_frame_dt = field(
        "frame_dt",
        quick.is_some_and(|q| q.frame_dt_s.is_some()),
        "simulation.frame_dt",
    );
    let f_duration = field(
        "duration",
        quick.is_some_and(|q| q.duration_s.is_some()),
        "simulation.duration",
    );

    let substeps = scene.solver.substeps();
    if substeps > MAX_SUBSTEPS {
        return Err(ctx.invalid(
            f_substeps,
            format!(
                "{substeps} substeps per frame is more than the maximum of {MAX_SUBSTEPS} (a frame of {} s would take steps of {} s)",
                num(scene.frame_dt_s),
                num(scene.frame_dt_s / substeps as f64)
            ),
        ));
    }

    let frames = scene.duration_s / scene.frame_dt_s;
    if !(frames <= MAX_FRAMES) {
        return Err(ctx.invalid(
            f_duration,
            format!(
                "duration {} s in frames of {} s is {} frames, more than the maximum of {MAX_FRAMES:.0e}",
                num(scene.duration_s),
                num(scene.frame_dt_s),
                num(frames)
            ),
        ));
    }

    let dt = scene.frame_dt_s / substeps as f64;
    // The solver's own support radius: `support_over_spacing` if set, else its default.
    let h = scene
        .solver
        .params(&scene.scene_values())
        .common()
        .support_radius;
    let ratio = h / scene.particle_spacing;
    // No substeps, or no neighbourhood: refused by the solver's own checks, which follow
    // (`params.rs`), at their fields.
    if substeps == 0 || !(ratio.is_finite() && ratio > 1.0) {
        return Ok(());
    }
    let g = v3(scene.gravity).norm();
    let v0 = scene
        .fluids
        .iter()
        .map(|f| v3(f.velocity()).norm())
        .fold(0.0, f64::max);
    let travel = (v0 + g * dt) * dt;
    if !(travel <= h) {
        // Blame the override that made the step too long, else the frame length.
        let substeps_only = quick.is_some_and(|q| q.substeps.is_some() && q.frame_dt_s.is_none());
        let field = if substeps_only {
            f_substeps
        } else {
            f_frame_dt
        };
        return Err(ctx.invalid(
            field,
            format!(
                "a solver step of {} s (frame_dt {} s / {substeps} substeps) moves a particle starting at {} m/s under gravity {} m/s² by {} m, more than the support radius h = {} m: it would leave its neighbourhood within one step (CFL condition v·Δt <= h); {}",
                num(dt),
                num(scene.frame_dt_s),
                num(v0),
                num(g),
                num(travel),
                num(h),
                advice(scene.frame_dt_s, substeps, v0, g, h)
            ),
        ));
    }
    Ok(())
}

/// What to do: the fewest substeps `n` with `(v0 + g T/n) T/n <= h` for a frame of
/// `frame_dt` = `T` (when within [`MAX_SUBSTEPS`]), and the longest frame that passes with
/// the current `substeps`.
fn advice(frame_dt: f64, substeps: usize, v0: f64, g: f64, h: f64) -> String {
    let dt_max = longest_step(v0, g, h);
    let mut n = (frame_dt / dt_max).ceil().max(1.0);
    // At the boundary rounding can leave the check's own travel just above h: step up.
    let travel = |n: f64| {
        let dt = frame_dt / n;
        (v0 + g * dt) * dt
    };
    while n.is_finite() && n <= MAX_SUBSTEPS as f64 && !(travel(n) <= h) {
        n += 1.0;
    }
    let frame = format!(
        "a frame_dt of at most {} s with {substeps} substeps",
        num(dt_max * substeps as f64)
    );
    if n.is_finite() && n <= MAX_SUBSTEPS as f64 {
        format!(
            "use at least {} substeps per frame or {frame}",
            n.max(1.0) as usize
        )
    } else {
        format!("use {frame} (more than {MAX_SUBSTEPS} substeps would be needed)")
    }
}

/// The largest `Δt` with `g Δt² + v0 Δt − h <= 0`.
fn longest_step(v0: f64, g: f64, h: f64) -> f64 {
    if g > 0.0 {
        // The positive root, written without cancellation.
        2.0 * h / (v0 + (v0 * v0 + 4.0 * g * h).sqrt())
    } else {
        h / v0
    }
}

/// `x` for a message: plain when moderate, else in scientific notation with 4 digits.
fn num(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{}", (x * 1e6).round() / 1e6)
    } else {
        format!("{x:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn longest_step_meets_the_rule() {
        for &(v0, g, h) in &[(0.0, 9.81, 0.05), (3.0, 9.81, 0.02), (3.0, 0.0, 0.02)] {
            let dt = longest_step(v0, g, h);
            assert!(((v0 + g * dt) * dt - h).abs() <= 1e-12 * h, "{v0} {g} {h}");
        }
        // The advised substep count is the fewest that passes.
        for &(t, v0, g, h) in &[
            (0.5, 0.0, 9.81, 0.1),
            (1.0, 2.0, 9.81, 0.05),
            (0.1, 3.0, 0.0, 0.02),
        ] {
            let a = advice(t, 2, v0, g, h);
            let n: f64 = a.split(' ').nth(3).unwrap().parse().unwrap();
            let travel = |n: f64| {
                let dt = t / n;
                (v0 + g * dt) * dt
            };
            assert!(travel(n) <= h && travel(n - 1.0) > h, "{a}");
        }
    }
}
