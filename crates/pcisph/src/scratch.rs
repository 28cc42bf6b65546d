//! The per-particle working arrays of the solver.

use sph_core::{Real, Vec3};

/// Per-particle working arrays (structure of arrays), kept between steps.
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch<R: Real> {
    /// Velocity after the non-pressure velocity change (XSPH), `v_i` of the loop.
    pub velocity: Vec<Vec3<R>>,
    /// Predicted positions `x*` (after the contact response); at the end, the final
    /// positions.
    pub predicted: Vec<Vec3<R>>,
    pub pressure: Vec<R>,
    /// Pressure acceleration `F^p_i / m_i`.
    pub accel: Vec<Vec3<R>>,
    /// `∇Ψ` of a volume boundary at `x(t)` (zero otherwise).
    pub boundary_grad: Vec<Vec3<R>>,
    pub density: Vec<R>,
    pub velocity_new: Vec<Vec3<R>>,
}

impl<R: Real> Scratch<R> {
    pub(crate) fn resize(&mut self, n: usize) {
        if self.predicted.len() == n {
            return;
        }
        let z = Vec3::zeros();
        self.velocity.resize(n, z);
        self.predicted.resize(n, z);
        self.pressure.resize(n, R::zero());
        self.accel.resize(n, z);
        self.boundary_grad.resize(n, z);
        self.density.resize(n, R::zero());
        self.velocity_new.resize(n, z);
    }
}
