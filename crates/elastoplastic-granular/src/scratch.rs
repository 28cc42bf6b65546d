//! The per-particle arrays of the solver: what it carries between frames (stress, plastic
//! strain) and its working arrays.

use nalgebra::Matrix3;
use sph_core::{Real, Vec3};

use sph_solver::boundary::wall_extrapolation::BoundaryLists;
use sph_solver::boundary::BoundaryParticle;
use sph_solver::pair_lanes::Packed;
use sph_solver::scene_boundary::PeriodicImages;

use crate::passes::Pair;

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
    /// The pair terms of the momentum pass, once per particle: `σ_i/ρ_i²` of the next
    /// step's stress and density, and whether `R_i` is non-zero.
    pub stress_over_rho2: Vec<Matrix3<R>>,
    pub art_on: Vec<bool>,
    /// `m_j/ρ_j` of the step's densities (the velocity gradient's volume).
    pub volume: Vec<R>,
    /// The kernel gradient of each grain's listed pair (CSR order of the neighbour lists),
    /// once per explicit step for both passes, where the lanes run.
    pub pair_grad: Vec<Vec3<R>>,
    /// Elsewhere each grain's pairs inside the support, at the start of its CSR range, and
    /// how many ([`crate::passes::pair_gradients`]).
    pub pairs: Vec<Pair<R>>,
    pub pair_count: Vec<u32>,
    /// The masses of the grains followed by the boundary particles', and the positions and
    /// masses packed for the lanes ([`crate::lanes`]; filled only where they run).
    pub mass_all: Vec<R>,
    pub packed: Packed,
    /// The boundary particles' grain neighbours and Shepard weights.
    pub boundary_lists: BoundaryLists<R>,
    pub x_new: Vec<Vec3<R>>,
    pub v_new: Vec<Vec3<R>>,
    /// Positions at the last neighbour search.
    pub anchor: Vec<Vec3<R>>,
    /// Wall gradients `∇Ψ_k`, `slots` per particle.
    pub wall_grad: Vec<Vec3<R>>,
    /// Images of the particles near periodic ends, and the particles followed by them (the
    /// array the neighbour lists index; with images, refreshed each step by the pairs'
    /// pass).
    pub images: PeriodicImages<R>,
    pub x_ext: Vec<Vec3<R>>,
    /// The particle whose values each of the lists' particles carries (itself, or an
    /// image's particle), from the last neighbour search.
    pub owner: Vec<u32>,
    /// Permutation scratch.
    pub permute_m: Vec<Matrix3<R>>,
    pub permute_r: Vec<R>,
}

impl<R: Real> Scratch<R> {
    /// Sizes every array for `n` particles followed by the boundary particles `boundary`
    /// (positions, velocities, stresses, densities; the particles' own arrays hold `n`)
    /// and `slots` wall gradients each; a new particle starts unstressed. Writes the
    /// boundary particles' positions and density `rho0`.
    /// The boundary particles' mass is `boundary_mass` (their volume `boundary_mass/ρ0`).
    pub(crate) fn resize(
        &mut self,
        n: usize,
        boundary: &[BoundaryParticle<R>],
        rho0: R,
        boundary_mass: R,
        slots: usize,
    ) {
        let z = Vec3::zeros();
        let zm = Matrix3::zeros();
        let all = n + boundary.len();
        self.stress.resize(all, zm);
        self.plastic_strain.resize(n, R::zero());
        self.x.resize(all, z);
        self.v.resize(all, z);
        self.rho.resize(all, R::zero());
        self.stress_new.resize(all, zm);
        self.rho_new.resize(all, R::zero());
        self.plastic_new.resize(n, R::zero());
        self.art.resize(all, zm);
        self.stress_over_rho2.resize(all, zm);
        self.art_on.resize(all, false);
        self.volume.resize(all, R::zero());
        self.x_new.resize(all, z);
        self.v_new.resize(all, z);
        self.anchor.resize(all, z);
        for (k, b) in boundary.iter().enumerate() {
            for x in [&mut self.x, &mut self.x_new, &mut self.anchor] {
                x[n + k] = b.position;
            }
            self.rho[n + k] = rho0;
            self.rho_new[n + k] = rho0;
            self.volume[n + k] = boundary_mass / rho0;
        }
        // At least one slot, so that the stress pass (which zips over chunks of it) sees
        // every particle without walls too.
        self.wall_grad.resize(n * slots.max(1), z);
    }
}
