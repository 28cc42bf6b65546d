//! The initial state against the walls: the density a fluid lattice starts at, and masses
//! calibrated so that no particle starts compressed.
//!
//! A fluid block sampled on a simple cubic lattice of spacing `s` with masses `ρ0 s³`
//! ([`CommonParams::particle_mass`]) has, in its interior, the lattice density
//! `ρ0 s³ Σ_j W(x_i − x_j)` (`0.99997 ρ0` for the cubic spline and `1.0098 ρ0` for Poly6 at
//! `h = 2 s`). Next to a boundary that takes part in the density (volume maps, Bender et al.
//! 2019) the particle also sees `ρ0 Ψ(x_i)`, the kernel-weighted volume of the solid. With the
//! first lattice layer half a spacing from the wall, `Ψ(s/2)` exceeds the share of the
//! lattice layers it stands for (the discrete sum of the missing layers is smaller than the
//! continuous integral over the solid), so the lattice starts compressed at the walls:
//! measured on the dam break of `scenes/dam_break_iisph.toml` (cubic spline, `h = 2 s`):
//! `ρ/ρ0` = 1.038 at a wall, 1.061 at an edge and 1.075 in a corner (particles farther than
//! `0.75 s` from every wall: up to 1.004). A unilateral pressure solver (IISPH with `p ≥ 0`,
//! PBF with the clamped constraint) releases that compression in its first steps as a jet
//! along the walls: with IISPH the largest speed after the first 16 ms frame is 3.1 m/s
//! (free fall: `g t` = 0.16 m/s), 0.29 m/s with calibrated masses. With collision walls (no
//! boundary share) the same lattice starts under-dense at the walls instead (0.85 at a wall,
//! 0.61 in a corner).
//!
//! [`calibrate_masses`] removes it without moving a particle: it lowers the masses of the
//! particles that start above `ρ0`, by the fixed-point iteration
//!
//! `m_i ← m_i · min(1, ρ0 / ρ_i)`, `ρ_i = Σ_j m_j W_ij + m_i W(0) + ρ0 Ψ(x_i)`,
//!
//! until `max_i ρ_i/ρ0 ≤ 1 +` [`CALIBRATION_TOLERANCE`]. Masses only decrease, so the
//! sequence converges, and its limit has no particle above `ρ0` (a particle still above would
//! be lowered again); particles below `ρ0` (free surface, the layers behind a lowered one)
//! keep their mass. The block keeps its geometry (every particle where the lattice put it,
//! so the fluid fills the block as specified) and loses only the excess mass of its wall
//! layers. Measured on the dam break above (12,288 particles): 25 iterations, 29 % of the
//! particles lowered, total mass −0.92 %; the largest reduction is a corner particle's,
//! −15 % (its own mass carries only `W(0) s³` ≈ 0.32 of its density, so it takes the larger
//! share of its neighbourhood's excess). The 4,096-particle slab of the IISPH curve of the
//! `dam-break-front` experiment, between two side walls 8 spacings apart, loses 1.7 %.
//!
//! # Why masses, and what the reference implementation does
//!
//! SPlisHSPlasH (Bender et al.; `FluidModel::initMasses`) gives every fluid particle the
//! volume `0.8 (2r)³`, "slightly reduced to prevent pressure at the beginning of the
//! simulation", fills blocks with the first particle one diameter `2r` inside the block
//! (`SimulatorBase::createFluidBlocks`), scales its volume maps by the same 0.8, smooths the
//! solid's indicator over a layer of one support radius, and places the boundary's virtual
//! particle at least one diameter from the fluid particle (`TimeStep::
//! computeVolumeAndBoundaryX`), and its dam-break scenes leave a gap of one diameter between
//! the block and the walls (`data/Scenes/DamBreakModel.json`). Its fluid therefore starts
//! below `ρ0` everywhere (0.8 of the lattice density in the interior) and settles under
//! gravity before it flows (source read at commit c5a063d of
//! <https://github.com/InteractiveComputerGraphics/SPlisHSPlasH>). Here the volume map is
//! the exact kernel integral of the solid, so none of those factors carries over; a uniform
//! mass reduction by the corner's excess would start the interior 7 % under-dense (the
//! column would settle by 7 % of its height before it flows), and moving the lattice away
//! from the walls cannot keep a block between two walls at the lattice density. Lowering
//! only the compressed particles' masses keeps both the block's geometry and the interior
//! at `ρ0` exactly.
//!
//! The density is summed in `f64` whatever `R` (the masses are rounded to `R` at the end and
//! the final ratio is measured with the rounded masses).

use rayon::prelude::*;
use sph_core::{ParticleSet, Real};
use sph_kernels::{Kernel, KernelKind};

use crate::boundary::{check_volume_kernel, Boundary};
use crate::step::StepNeighbours;
use crate::{CommonParams, SolverError};

/// Largest `ρ_i/ρ0 − 1` [`calibrate_masses`] leaves (relative). Far below the solvers'
/// density tolerances (IISPH 1e-3 on average), so the first pressure solve has nothing left
/// to correct at the walls.
pub const CALIBRATION_TOLERANCE: f64 = 1e-5;

/// Most iterations of [`calibrate_masses`]. The excess shrinks by a factor of about 1.4 per
/// iteration (each update removes only the share of `ρ_i` that the lowered masses carry), so
/// 25 iterations reach [`CALIBRATION_TOLERANCE`] from a 7.5 % corner excess.
pub const CALIBRATION_MAX_ITERATIONS: usize = 200;

/// What [`calibrate_masses`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassCalibration {
    /// Fixed-point iterations done.
    pub iterations: usize,
    /// `max_i ρ_i/ρ0` before.
    pub max_density_ratio_before: f64,
    /// `max_i ρ_i/ρ0` after (with the masses rounded to the state's precision).
    pub max_density_ratio_after: f64,
    /// Particles whose mass was lowered.
    pub lowered: usize,
    /// Smallest `m_i(after)/m_i(before)`.
    pub min_mass_ratio: f64,
    /// Total mass after over total mass before.
    pub total_mass_ratio: f64,
}

/// The densities of `state` at its positions, with `kernel` at `common.support_radius`
/// and the boundary's share `ρ0 Ψ` when it has volume, in `f64`.
struct DensitySum<'a, R: Real> {
    kernel: sph_kernels::AnyKernel<f64>,
    rest_density: f64,
    neighbours: StepNeighbours<R>,
    /// `ρ0 Ψ(x_i)` (kg/m³).
    boundary_density: Vec<f64>,
    positions: &'a [sph_core::Vec3<R>],
}

impl<'a, R: Real> DensitySum<'a, R> {
    fn new(
        kernel: KernelKind,
        common: &CommonParams<R>,
        boundary: &dyn Boundary<R>,
        positions: &'a [sph_core::Vec3<R>],
    ) -> Result<Self, SolverError> {
        let h = common.support_radius;
        let built = kernel.build::<f64>(h.as_f64())?;
        check_volume_kernel(boundary, "initial masses", kernel, h)?;
        let mut neighbours = StepNeighbours::new(common.neighbour_method);
        neighbours.find(positions, h)?;
        let rest_density = common.rest_density.as_f64();
        let boundary_density = if boundary.has_volume() {
            positions
                .par_iter()
                .map(|x| rest_density * boundary.sample(x).volume.as_f64())
                .collect()
        } else {
            vec![0.0; positions.len()]
        };
        Ok(Self {
            kernel: built,
            rest_density,
            neighbours,
            boundary_density,
            positions,
        })
    }

    /// `ρ_i/ρ0` for every particle with masses `m` (kg).
    fn ratios(&self, m: &[f64], out: &mut Vec<f64>) {
        let nb = self.neighbours.lists();
        let (x, k, w0) = (self.positions, &self.kernel, self.kernel.value(0.0));
        let (boundary_density, rho0) = (&self.boundary_density[..], self.rest_density);
        (0..x.len())
            .into_par_iter()
            .map(|i| {
                let xi = x[i];
                let mut rho = m[i] * w0 + boundary_density[i];
                for &j in nb.neighbours(i) {
                    let j = j as usize;
                    rho += m[j] * k.value((xi - x[j]).norm().as_f64());
                }
                rho / rho0
            })
            .collect_into_vec(out);
    }
}

/// `ρ_i/ρ0` of every particle of `state` as it stands: `Σ_j m_j W_ij` with the solver's
/// density kernel `kernel` at `common.support_radius` (self term included) plus `ρ0 Ψ(x_i)`
/// of a boundary that takes part in the density, summed in `f64`. Errors if the boundary's
/// volumes were integrated with another kernel or support radius, or if the neighbour search
/// refuses the positions.
pub fn density_ratios<R: Real>(
    kernel: KernelKind,
    common: &CommonParams<R>,
    boundary: &dyn Boundary<R>,
    state: &ParticleSet<R>,
) -> Result<Vec<f64>, SolverError> {
    let sum = DensitySum::new(kernel, common, boundary, &state.positions)?;
    let m: Vec<f64> = state.masses.iter().map(|m| m.as_f64()).collect();
    let mut out = Vec::new();
    sum.ratios(&m, &mut out);
    Ok(out)
}

/// Lowers the masses of the particles of `state` that start above the rest density (with
/// the boundary's share), leaving positions and velocities alone; see the module
/// documentation for the iteration and why. `kernel` is the solver's density kernel (the
/// boundary's, when it has volume). Errors as [`density_ratios`], or
/// [`SolverError::InvalidMass`] for a mass that is not finite and positive.
pub fn calibrate_masses<R: Real>(
    kernel: KernelKind,
    common: &CommonParams<R>,
    boundary: &dyn Boundary<R>,
    state: &mut ParticleSet<R>,
) -> Result<MassCalibration, SolverError> {
    if let Some(i) = state
        .masses
        .iter()
        .position(|m| !(m.is_finite_value() && *m > R::zero()))
    {
        return Err(SolverError::InvalidMass {
            index: i,
            value: state.masses[i].as_f64(),
        });
    }
    let sum = DensitySum::new(kernel, common, boundary, &state.positions)?;
    let before: Vec<f64> = state.masses.iter().map(|m| m.as_f64()).collect();
    let mut m = before.clone();
    let mut ratios = Vec::new();
    sum.ratios(&m, &mut ratios);
    let max_before = ratios.iter().copied().fold(0.0, f64::max);
    let mut iterations = 0;
    while iterations < CALIBRATION_MAX_ITERATIONS
        && ratios.iter().any(|&r| r > 1.0 + CALIBRATION_TOLERANCE)
    {
        for (mi, &r) in m.iter_mut().zip(&ratios) {
            if r > 1.0 {
                *mi /= r;
            }
        }
        sum.ratios(&m, &mut ratios);
        iterations += 1;
    }
    drop(sum);
    for (dst, &mi) in state.masses.iter_mut().zip(&m) {
        *dst = R::of_f64(mi);
    }
    let after = density_ratios(kernel, common, boundary, state)?;
    let lowered = state
        .masses
        .iter()
        .zip(&before)
        .filter(|(a, &b)| a.as_f64() < b)
        .count();
    let min_mass_ratio = state
        .masses
        .iter()
        .zip(&before)
        .map(|(a, &b)| a.as_f64() / b)
        .fold(1.0, f64::min);
    let total_before: f64 = before.iter().sum();
    let total_after: f64 = state.masses.iter().map(|m| m.as_f64()).sum();
    Ok(MassCalibration {
        iterations,
        max_density_ratio_before: max_before,
        max_density_ratio_after: after.iter().copied().fold(0.0, f64::max),
        lowered,
        min_mass_ratio,
        total_mass_ratio: if total_before > 0.0 {
            total_after / total_before
        } else {
            1.0
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CollisionBoundary;
    use sph_core::{sampling::cubic_lattice, Aabb, Vec3};

    fn block(n: usize, s: f64) -> ParticleSet<f64> {
        let b = Aabb::new(Vec3::zeros(), Vec3::repeat(n as f64 * s)).unwrap();
        let x = cubic_lattice(&b, s, 100_000).unwrap();
        ParticleSet::from_positions(x, 1000.0 * s * s * s, 1000.0)
    }

    /// Without walls that take part in the density, Poly6 at `h = 2 s` puts the lattice
    /// interior at `1.0098 ρ0` (the figure of `pbf::PbfParams`'s documentation, computed
    /// there independently): the calibration lowers every interior mass by that factor and
    /// leaves no particle above `ρ0`.
    #[test]
    fn poly6_lattice_interior_is_lowered_to_the_rest_density() {
        let s = 0.1;
        let common = CommonParams::<f64>::for_spacing(s);
        let boundary = CollisionBoundary::new(Vec::new(), 0.05).unwrap();
        let mut state = block(10, s);
        let m0 = state.masses[0];
        let r0 = density_ratios(KernelKind::Poly6, &common, &boundary, &state).unwrap();
        let max0 = r0.iter().copied().fold(0.0, f64::max);
        assert!((max0 - 1.0098).abs() < 5e-4, "{max0}");
        let cal = calibrate_masses(KernelKind::Poly6, &common, &boundary, &mut state).unwrap();
        assert!(
            cal.max_density_ratio_after <= 1.0 + CALIBRATION_TOLERANCE,
            "{cal:?}"
        );
        assert!(cal.iterations < 40, "{cal:?}");
        assert!(state.masses.iter().all(|&m| m <= m0));
        // the centre particle (4.5 s from every face: beyond h of the surface) has a
        // neighbourhood of lowered masses only, so it ends at ρ0 and its mass is ~m0/1.0098
        let centre = state
            .positions
            .iter()
            .position(|p| (p - Vec3::repeat(0.45)).norm() < 1e-9)
            .unwrap();
        let after = density_ratios(KernelKind::Poly6, &common, &boundary, &state).unwrap();
        assert!((after[centre] - 1.0).abs() < 2e-5, "{}", after[centre]);
        assert!((state.masses[centre] / m0 - 1.0 / 1.0098).abs() < 5e-4);
        // the free-surface corner (an eighth of a neighbourhood) stays far below ρ0
        assert!(after[0] < 0.9, "{}", after[0]);
    }

    #[test]
    fn non_positive_mass_is_refused() {
        let common = CommonParams::<f64>::for_spacing(0.1);
        let boundary = CollisionBoundary::new(Vec::new(), 0.05).unwrap();
        let mut state = block(3, 0.1);
        state.masses[4] = 0.0;
        let e = calibrate_masses(KernelKind::Poly6, &common, &boundary, &mut state).unwrap_err();
        assert!(
            matches!(e, SolverError::InvalidMass { index: 4, .. }),
            "{e}"
        );
    }
}
