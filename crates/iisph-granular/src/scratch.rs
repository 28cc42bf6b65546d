//! The per-particle working arrays of the solver.

use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_solver::boundary::BoundarySample;
use sph_solver::step::{MIN_LEN, REDUCE_CHUNK};
use sph_solver::Boundary;

use crate::granular::Sym3;

/// Per-particle working arrays (structure of arrays), kept between steps.
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch<R: Real> {
    /// `W'(r)/r` per neighbour pair (CSR order of the neighbour lists): `∇W_ij = (x_i − x_j)
    /// · grad_scale[k]`.
    pub grad_scale: Vec<R>,
    /// `ρ_i` at the step's start positions, boundary included (eq. 3 + eq. 29).
    pub density: Vec<R>,
    /// `G_i = Σ_j m_j ∇W_ij + ρ0 ∇Ψ_i` (the diagonal's gradient sum, reused by the friction).
    pub grad_sum: Vec<Vec3<R>>,
    /// `∇Ψ(x_i)` of a volume boundary.
    pub bgrad: Vec<Vec3<R>>,
    /// The drag's occlusion `max_j o_ij` (eq. 6; 0 without drag).
    pub occlusion: Vec<R>,
    /// `v_i^adv` (eq. 18).
    pub v_adv: Vec<Vec3<R>>,
    /// Source term `ρ0 − ρ_i^adv` (eq. 19) of the linear system.
    pub source: Vec<R>,
    /// Diagonal `a_ii` (eq. 24), Δt² included.
    pub aii: Vec<R>,
    /// Pressure `p_i` (Pa); kept between steps for the warm start.
    pub pressure: Vec<R>,
    /// `p_i / ρ_i²`.
    pub p_over_rho2: Vec<R>,
    /// Pressure acceleration `F^p_i / m_i` of the current iterate.
    pub accel: Vec<Vec3<R>>,
    /// Frictional stress `s_i` (Pa, deviatoric, inside the yield surface); kept between
    /// steps (the friction solve's warm start).
    pub stress: Vec<Sym3<R>>,
    /// `m_i s_i / ρ_i²`.
    pub mass_stress_over_rho2: Vec<Sym3<R>>,
    /// Friction acceleration `F^f_i / m_i` of the current stress; kept between steps (the
    /// next step's predicted friction, see `friction::predict`).
    pub friction_accel: Vec<Vec3<R>>,
    /// Whether `friction_accel` is that of `stress` (false after a restore without it).
    pub friction_accel_current: bool,
    /// `V_i = m_i / ρ_i` of the step (granular).
    pub volume: Vec<R>,
    /// Velocity at the step's end without friction, `v^adv + Δt (a^p − a^f_prev)`.
    pub v_base: Vec<Vec3<R>>,
    /// Velocity at the step's end with the current stress iterate.
    pub v_trial: Vec<Vec3<R>>,
    pub perm_sym: Vec<Sym3<R>>,
    pub perm_vec: Vec<Vec3<R>>,
    pub x_new: Vec<Vec3<R>>,
    pub v_new: Vec<Vec3<R>>,
    /// A lower bound on each particle's distance to the solids at `x_new`
    /// ([`sph_solver::ContactGuard`]; written only when the boundary has a guard).
    pub clearance: Vec<R>,
    pub density_new: Vec<R>,
    /// Partial sums of the density error per chunk of [`REDUCE_CHUNK`] particles.
    pub error_partials: Vec<f64>,
    pub perm_scalar: Vec<R>,
    /// The step's positions and masses packed for the lanes (filled only when they run);
    /// during the pressure solve `[x, y, z, m p/ρ²]` (`passes::pack_pressure`).
    pub packed: sph_solver::pair_lanes::Packed,
    /// `[v^adv, m]`, then `[a, m]` of the current pressure accelerations, for the pressure
    /// lanes (filled only when they run).
    pub packed_vectors: sph_solver::pair_lanes::Packed,
    /// `G_i = Σ_j m_j ∇W_ij` of the density pass (without the boundary's term).
    pub mass_grad: Vec<Vec3<R>>,
    /// The volume boundary's samples at the end-of-step positions, for the next step's
    /// density pass.
    pub end_samples: SampleCache<R>,
}

/// A volume boundary's samples `Ψ`, `∇Ψ` at the positions of the end of a step, which the
/// next step's density pass reuses instead of querying the boundary again at the same
/// positions (one query per particle and step instead of two). An entry counts only where
/// the particle's position is bit for bit the one sampled, so a reorder, an edit of the
/// state between steps or a change of the particle count falls back to a fresh query; the
/// boundary of a solver is fixed, so a reused sample is the one a query would return.
#[derive(Debug, Clone, Default)]
pub(crate) struct SampleCache<R: Real> {
    /// The positions sampled.
    positions: Vec<Vec3<R>>,
    /// The boundary's sample at each.
    samples: Vec<BoundarySample<R>>,
    /// The distance to the solids at each ([`Boundary::distance`]; filled only when the
    /// boundary has a contact guard, else empty).
    distances: Vec<R>,
}

impl<R: Real> SampleCache<R> {
    /// Samples `boundary` at every position of `x`, in parallel, replacing the entries; with
    /// a contact guard, the distances to the solids too (the next step's contact response
    /// starts from them), and positions beyond [`Boundary::volume_reach`] from every solid
    /// take the zero sample without a query (the same bits).
    pub(crate) fn fill(&mut self, x: &[Vec3<R>], boundary: &dyn Boundary<R>) {
        self.positions.clear();
        self.positions.extend_from_slice(x);
        self.samples.resize(x.len(), BoundarySample::default());
        if boundary.contact_guard().is_some() {
            self.distances.resize(x.len(), R::zero());
            self.samples
                .par_iter_mut()
                .zip(self.distances.par_iter_mut())
                .zip(x.par_iter())
                .with_min_len(MIN_LEN)
                .for_each(|((s, d), p)| {
                    let (distance, beyond) = boundary.distance_beyond_reach(p);
                    *d = distance;
                    *s = if beyond {
                        BoundarySample::default()
                    } else {
                        boundary.sample(p)
                    };
                });
        } else {
            self.distances.clear();
            self.samples
                .par_iter_mut()
                .zip(x.par_iter())
                .with_min_len(MIN_LEN)
                .for_each(|(s, p)| *s = boundary.sample(p));
        }
    }

    /// The distance to the solids of particle `i` if it was evaluated at `x` exactly.
    #[inline]
    pub(crate) fn distance(&self, i: usize, x: &Vec3<R>) -> Option<R> {
        let d = *self.distances.get(i)?;
        self.same_position(i, x).then_some(d)
    }

    /// Whether entry `i` was taken at `x` exactly (the same bits).
    #[inline]
    fn same_position(&self, i: usize, x: &Vec3<R>) -> bool {
        self.positions
            .get(i)
            .is_some_and(|at| (0..3).all(|a| at[a].as_f64().to_bits() == x[a].as_f64().to_bits()))
    }

    /// The sample of particle `i` if it was taken at `x` exactly (the same bits).
    #[inline]
    pub(crate) fn get(&self, i: usize, x: &Vec3<R>) -> Option<BoundarySample<R>> {
        self.same_position(i, x).then(|| self.samples[i])
    }

    /// The samples, one per position of the last [`SampleCache::fill`].
    pub(crate) fn samples(&self) -> &[BoundarySample<R>] {
        &self.samples
    }

    /// Forgets every entry (keeps the storage).
    pub(crate) fn clear(&mut self) {
        self.positions.clear();
    }
}

impl<R: Real> Scratch<R> {
    pub(crate) fn resize(&mut self, n: usize, granular: bool) {
        let z = Vec3::zeros();
        self.density.resize(n, R::zero());
        self.bgrad.resize(n, z);
        self.grad_sum.resize(n, z);
        self.mass_grad.resize(n, z);
        self.occlusion.resize(n, R::zero());
        self.v_adv.resize(n, z);
        self.source.resize(n, R::zero());
        self.aii.resize(n, R::zero());
        self.pressure.resize(n, R::zero());
        self.p_over_rho2.resize(n, R::zero());
        self.accel.resize(n, z);
        let ng = if granular { n } else { 0 };
        self.stress.resize(ng, [R::zero(); 6]);
        self.mass_stress_over_rho2.resize(ng, [R::zero(); 6]);
        self.friction_accel.resize(ng, z);
        self.volume.resize(ng, R::zero());
        self.v_base.resize(ng, z);
        self.v_trial.resize(ng, z);
        self.x_new.resize(n, z);
        self.v_new.resize(n, z);
        self.clearance.resize(n, R::zero());
        self.density_new.resize(n, R::zero());
        self.error_partials.resize(n.div_ceil(REDUCE_CHUNK), 0.0);
    }
}

#[cfg(test)]
mod tests {
    use sph_core::{Sdf, Vec3};
    use sph_solver::boundary::BoundarySample;
    use sph_solver::Boundary;

    use super::SampleCache;

    /// A boundary whose sample encodes where it was taken (`Ψ = x + 2y + 4z`).
    struct Ramp;

    impl Boundary<f32> for Ramp {
        fn name(&self) -> &'static str {
            "ramp"
        }
        fn solids(&self) -> &[Box<dyn Sdf<f32>>] {
            &[]
        }
        fn has_volume(&self) -> bool {
            true
        }
        fn volume_kernel(&self) -> Option<(sph_kernels::KernelKind, f32)> {
            None
        }
        fn sample(&self, x: &Vec3<f32>) -> BoundarySample<f32> {
            BoundarySample {
                volume: x.x + 2.0 * x.y + 4.0 * x.z,
                volume_gradient: Vec3::new(1.0, 2.0, 4.0),
            }
        }
        fn project(&self, x: Vec3<f32>) -> Vec3<f32> {
            x
        }
        fn contact_distance(&self) -> f32 {
            0.0
        }
    }

    /// An entry counts only at the very bits sampled: the same position gives the query's
    /// sample, a moved particle, `−0` for `+0`, another index or a cleared cache give none.
    #[test]
    fn samples_are_reused_only_at_the_sampled_bits() {
        let x = vec![Vec3::new(0.0f32, 1.0, 2.0), Vec3::new(0.5, 0.25, 0.0)];
        let mut cache = SampleCache::default();
        cache.fill(&x, &Ramp);
        for (i, p) in x.iter().enumerate() {
            assert_eq!(cache.get(i, p), Some(Ramp.sample(p)));
        }
        assert_eq!(cache.get(1, &Vec3::new(0.5, 0.25, -0.0)), None);
        let moved = Vec3::new(0.5, 0.25f32.next_up(), 0.0);
        assert_eq!(cache.get(1, &moved), None);
        assert_eq!(cache.get(0, &x[1]), None);
        assert_eq!(cache.get(2, &x[1]), None);
        cache.clear();
        assert_eq!(cache.get(0, &x[0]), None);
    }
}
