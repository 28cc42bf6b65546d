//! The per-particle arrays of the solver: what it carries between frames (stress, plastic
//! strain) and its working arrays.

use nalgebra::Matrix3;
use sph_core::{Real, Vec3};

/// Per-particle arrays (structure of arrays).
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch<R: Real> {
    /// Cauchy stress `σ_i` (Pa), carried between frames.
    pub stress: Vec<Matrix3<R>>,
    /// Equivalent plastic shear strain, carried between frames.
    pub plastic_strain: Vec<R>,
    /// Working positions, velocities and densities of the explicit steps.
    pub x: Vec<Vec3<R>>,
    pub v: Vec<Vec3<R>>,
    pub rho: Vec<R>,
    /// The next step's stress, density, plastic strain.
    pub stress_new: Vec<Matrix3<R>>,
    pub rho_new: Vec<R>,
    pub plastic_new: Vec<R>,
    /// Gray et al.'s artificial stress `R_i`.
    pub art: Vec<Matrix3<R>>,
    pub x_new: Vec<Vec3<R>>,
    pub v_new: Vec<Vec3<R>>,
    /// Positions at the last neighbour search.
    pub anchor: Vec<Vec3<R>>,
    /// Wall gradients `∇Ψ_k`, `slots` per particle.
    pub wall_grad: Vec<Vec3<R>>,
    /// Permutation scratch.
    pub permute_m: Vec<Matrix3<R>>,
    pub permute_r: Vec<R>,
}

impl<R: Real> Scratch<R> {
    /// Sizes every array for `n` particles and `slots` wall gradients each; a new particle
    /// starts unstressed.
    pub(crate) fn resize(&mut self, n: usize, slots: usize) {
        let z = Vec3::zeros();
        let zm = Matrix3::zeros();
        self.stress.resize(n, zm);
        self.plastic_strain.resize(n, R::zero());
        self.x.resize(n, z);
        self.v.resize(n, z);
        self.rho.resize(n, R::zero());
        self.stress_new.resize(n, zm);
        self.rho_new.resize(n, R::zero());
        self.plastic_new.resize(n, R::zero());
        self.art.resize(n, zm);
        self.x_new.resize(n, z);
        self.v_new.resize(n, z);
        self.anchor.resize(n, z);
        // At least one slot, so that the stress pass (which zips over chunks of it) sees
        // every particle without walls too.
        self.wall_grad.resize(n * slots.max(1), z);
    }
}
