//! The per-particle loops of one explicit step (see the crate docs for the equations). Each
//! writes one particle's values from the previous arrays, so results do not depend on the
//! thread count.

use nalgebra::Matrix3;
use rayon::prelude::*;
use sph_core::{Real, Vec3};
use sph_kernels::Kernel;
use sph_solver::boundary::wall_extrapolation::{CHUNKS_PER_TASK, READ_CHUNK};
use sph_solver::boundary::Boundary;
use sph_solver::csr::par_csr_blocks;
use sph_solver::pair_lanes::f32s;
use sph_solver::step::MIN_LEN;
use sph_solver::NeighbourLists;

use crate::kernels::Consts;
use crate::lanes::{flat, GrainLanes, MomentumArrays, StressArrays, StressSums};
use crate::params::WallModel;
use crate::scratch::Scratch;
use crate::stress::artificial_stress;
use crate::walls::{wall_part, WallSampler};

/// What the passes read besides the scratch arrays.
pub(crate) struct StepInputs<'a, R: Real, K> {
    pub c: Consts<R, K>,
    pub masses: &'a [R],
    pub nb: &'a NeighbourLists,
    pub boundary: &'a dyn Boundary<R>,
    pub walls: &'a WallSampler<R>,
    pub models: &'a [WallModel],
    pub gravity: Vec3<R>,
    pub dt: R,
    /// Mass of a boundary particle (kg): neighbours `j ≥ masses.len()` are boundary
    /// particles.
    pub boundary_mass: R,
}

impl<R: Real, K> StepInputs<'_, R, K> {
    #[inline]
    fn mass(&self, j: usize) -> R {
        self.masses.get(j).copied().unwrap_or(self.boundary_mass)
    }
}

/// The density re-initialisation
/// ([`ElastoplasticParams::density_reinit_interval_s`](crate::ElastoplasticParams)): each
/// grain's density becomes the kernel sum over itself, its grain neighbours and the boundary
/// particles, normalised by the full lattice's, floored at `ρ0` (free surface, separated
/// grains).
pub(crate) fn reinitialise_density<R: Real, K: Kernel<R>>(
    s: &mut Scratch<R>,
    inp: &StepInputs<'_, R, K>,
) {
    let c = inp.c;
    let n = inp.masses.len();
    let h2 = c.support2_above;
    let w0 = c.kernel.value(R::zero());
    let (x, images) = (&s.x[..], &s.images);
    s.rho[..n]
        .par_iter_mut()
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, rho)| {
            let xi = x[i];
            let mut sum = inp.masses[i] * w0;
            for &j in inp.nb.neighbours(i) {
                let (j, xj) = images.resolve(j as usize, x);
                let r2 = (xi - xj).norm_squared();
                if r2 <= h2 {
                    sum += inp.mass(j) * c.kernel.value(r2.sqrt());
                }
            }
            let summed = sum * c.summation_scale;
            *rho = if summed > c.rho0 { summed } else { c.rho0 };
        });
}

/// The lane constants where the pair loops run in lanes ([`GrainLanes::new`]): the lists'
/// particles are the positions `s.x` (no periodic images).
fn grain_lanes<R: Real, K: Kernel<R>>(
    s: &Scratch<R>,
    inp: &StepInputs<'_, R, K>,
) -> Option<GrainLanes> {
    let listed = inp.nb.offsets().len().checked_sub(1)?;
    if listed != s.x.len() {
        return None;
    }
    GrainLanes::new(&inp.c, inp.nb, listed, !s.images.src.is_empty())
}

/// The kernel gradient `∇_i W_ij` at the offset `x_ij = x_i − x_j`: zero beyond the
/// support (a listed pair in the lists' skin).
#[inline]
pub(crate) fn pair_gradient<R: Real, K: Kernel<R>>(c: &Consts<R, K>, xij: &Vec3<R>) -> Vec3<R> {
    if xij.norm_squared() > c.support2_above {
        Vec3::zeros()
    } else {
        c.kernel.gradient(xij)
    }
}

/// One of a grain's pairs inside the kernel's support, as the scalar passes read it: the
/// particle `j` whose values the neighbour carries (a periodic image resolved to its
/// particle), the offset `x_ij = x_i − x_j` (m) and the kernel gradient `∇_i W_ij` (1/m⁴),
/// non-zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pair<R: Real> {
    pub j: u32,
    pub xij: Vec3<R>,
    pub grad: Vec3<R>,
}

impl<R: Real> Default for Pair<R> {
    fn default() -> Self {
        Self {
            j: 0,
            xij: Vec3::zeros(),
            grad: Vec3::zeros(),
        }
    }
}

/// Grain `i`'s listed neighbours `list` whose kernel gradient is non-zero, in list order,
/// into `out` (at least `list.len()` long); returns how many. `listed` holds the positions
/// of the lists' particles (a periodic image's included) and `owner` the particle whose
/// values each carries (itself, or an image's particle). The listed pairs beyond the support
/// (the lists' skin, about 30 % of them at the default skin) and coincident ones add zero
/// terms to both passes' sums, which therefore skip them. Without branches on the data but
/// in the kernel's spline: first the pairs within `support2_above`, then those of a non-zero
/// gradient ([`pair_gradient`]).
#[inline]
pub(crate) fn support_pairs<R: Real, K: Kernel<R>>(
    c: &Consts<R, K>,
    listed: &[Vec3<R>],
    owner: &[u32],
    i: usize,
    list: &[u32],
    out: &mut [Pair<R>],
) -> usize {
    let xi = listed[i];
    let mut near = 0;
    for &j in list {
        let xij = xi - listed[j as usize];
        out[near] = Pair {
            j: owner[j as usize],
            xij,
            grad: Vec3::zeros(),
        };
        near += usize::from(xij.norm_squared() <= c.support2_above);
    }
    let mut kept = 0;
    for k in 0..near {
        let p = out[k];
        let grad = pair_gradient(c, &p.xij);
        out[kept] = Pair { grad, ..p };
        kept += usize::from(grad != Vec3::zeros());
    }
    kept
}

/// The pairs of every grain, computed once per explicit step and read by both passes. In
/// lanes where they run ([`crate::lanes`]): the kernel gradient of every listed pair in the
/// lists' CSR order (`s.pair_grad`, zero beyond the support; bit for bit the scalar
/// gradients), after packing the positions and masses they and the momentum pass read.
/// Otherwise grain `i`'s pairs inside the support ([`support_pairs`]) at the start of its
/// CSR range of `s.pairs`, `s.pair_count[i]` of them.
pub(crate) fn pair_gradients<R: Real, K: Kernel<R>>(
    s: &mut Scratch<R>,
    inp: &StepInputs<'_, R, K>,
) {
    let n = inp.masses.len();
    let offsets = &inp.nb.offsets()[..=n];
    let pairs = offsets[n];
    let Some(lanes) = grain_lanes(s, inp) else {
        s.pairs.resize(pairs, Pair::default());
        s.pair_count.resize(n, 0);
        let listed = if s.images.src.is_empty() {
            &s.x[..]
        } else {
            s.images.refresh(&s.x, &mut s.x_ext);
            &s.x_ext[..]
        };
        let owner = &s.owner[..];
        par_csr_blocks(
            offsets,
            &mut s.pair_count[..n],
            &mut s.pairs[..pairs],
            &|first, counts: &mut [u32], out: &mut [Pair<R>]| {
                let base = offsets[first];
                for (k, count) in counts.iter_mut().enumerate() {
                    let i = first + k;
                    let out = &mut out[offsets[i] - base..offsets[i + 1] - base];
                    let list = inp.nb.neighbours(i);
                    *count = support_pairs(&inp.c, listed, owner, i, list, out) as u32;
                }
                0.0
            },
        );
        return;
    };
    s.pair_grad.resize(pairs, Vec3::zeros());
    let all = s.x.len();
    s.mass_all.clear();
    s.mass_all.extend_from_slice(inp.masses);
    s.mass_all.resize(all, inp.boundary_mass);
    s.packed.fill(&s.x, &s.mass_all);
    let xm = s.packed.values();
    let mut grains = vec![(); n];
    par_csr_blocks(
        offsets,
        &mut grains[..],
        &mut s.pair_grad[..pairs],
        &|first, grains: &mut [()], out: &mut [Vec3<R>]| {
            let base = offsets[first];
            for i in first..first + grains.len() {
                let out = &mut out[offsets[i] - base..offsets[i + 1] - base];
                lanes.gradients(xm, inp.nb, i, out);
            }
            0.0
        },
    );
}

/// Grain `i`'s pairs for the scalar passes: its first `s.pair_count[i]` entries of `pairs`
/// ([`pair_gradients`]).
#[inline]
fn grain_pairs<'a, R: Real>(
    pairs: &'a [Pair<R>],
    counts: &[u32],
    offsets: &[usize],
    i: usize,
) -> &'a [Pair<R>] {
    &pairs[offsets[i]..offsets[i] + counts[i] as usize]
}

/// The arrays the stress pass's pair sums read.
pub(crate) struct StressFields<'a, R: Real> {
    /// Velocities and `m/ρ` of the particles (grains, then boundary particles).
    pub v: &'a [Vec3<R>],
    pub volume: &'a [R],
    /// The grains' masses; the boundary particles' is `boundary_mass`.
    pub masses: &'a [R],
    pub boundary_mass: R,
}

/// Grain `i`'s velocity gradient `L_i = Σ_j V_j (v_j − v_i) ⊗ ∇W_ij`, its continuity rate
/// `−Σ_j m_j (v_j − v_i)·∇W_ij` (no wall share) and whether a grain other than `i` lies
/// inside its support, from its pairs inside the support ([`support_pairs`]), left to right.
#[inline(always)]
pub(crate) fn stress_sums<R: Real>(
    f: &StressFields<'_, R>,
    i: usize,
    pairs: &[Pair<R>],
) -> StressSums<R> {
    let n = f.masses.len();
    let vi = f.v[i];
    let mut grad_v = Matrix3::zeros();
    let mut drho = R::zero();
    let mut in_contact = false;
    for p in pairs {
        let (j, gw) = (p.j as usize, p.grad);
        in_contact |= j < n && j != i;
        let dv = f.v[j] - vi;
        grad_v += dv * gw.transpose() * f.volume[j];
        let m = f.masses.get(j).copied().unwrap_or(f.boundary_mass);
        drho -= m * dv.dot(&gw);
    }
    StressSums {
        grad_v,
        drho,
        in_contact,
    }
}

/// Pass 1: the wall gradients at `x`, the velocity gradient `L_i` and the continuity rate
/// from `x`, `v`, `ρ`; the stress update (rate and return, [`crate::DruckerPrager::update`];
/// zero for a particle without granular neighbours inside the support), the density and
/// plastic strain after `Δt`, and the artificial stress of the new stress.
pub(crate) fn stress_pass<R: Real, K: Kernel<R>>(s: &mut Scratch<R>, inp: &StepInputs<'_, R, K>) {
    let c = inp.c;
    let slots = inp.models.len();
    let n = inp.masses.len();
    // `m_j / ρ_j` of every neighbour, once per particle rather than once per pair (the
    // boundary particles' stays `m_b / ρ0` from `Scratch::resize`).
    s.volume[..n]
        .par_iter_mut()
        .zip(inp.masses.par_iter().zip(s.rho[..n].par_iter()))
        .with_min_len(MIN_LEN)
        .for_each(|(vol, (&m, &r))| *vol = m / r);
    let lanes = grain_lanes(s, inp);
    let fields = StressFields {
        v: &s.v,
        volume: &s.volume,
        masses: inp.masses,
        boundary_mass: inp.boundary_mass,
    };
    let lane_arrays = lanes.map(|_| StressArrays {
        v: flat::<_, R>(&s.v, 3),
        volume: f32s(&s.volume),
        mass: f32s(&s.mass_all),
    });
    let (x, v, rho) = (&s.x[..], &s.v[..], &s.rho[..]);
    let (stress, plastic) = (&s.stress[..], &s.plastic_strain[..]);
    let (grad, offsets) = (&s.pair_grad[..], inp.nb.offsets());
    let (pairs, counts) = (&s.pairs[..], &s.pair_count[..]);
    s.stress_new[..n]
        .par_iter_mut()
        .zip(s.rho_new[..n].par_iter_mut())
        .zip(s.plastic_new.par_iter_mut())
        .zip(s.art[..n].par_iter_mut())
        .zip(s.wall_grad.par_chunks_mut(slots.max(1)))
        .zip(s.stress_over_rho2[..n].par_iter_mut())
        .zip(s.art_on[..n].par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(
            |(i, ((((((sig, r), kappa), art), grads), sig_rho2), art_on))| {
                let (xi, vi) = (x[i], v[i]);
                let StressSums {
                    mut grad_v,
                    mut drho,
                    in_contact,
                } = match (&lanes, &lane_arrays) {
                    (Some(l), Some(a)) => {
                        let grad_i = &grad[offsets[i]..offsets[i + 1]];
                        l.stress_sums(a, inp.nb, n, i, flat::<_, R>(grad_i, 3))
                    }
                    _ => stress_sums(&fields, i, grain_pairs(pairs, counts, offsets, i)),
                };
                if slots > 0 {
                    inp.walls.sample(inp.boundary, &xi, grads);
                    for (g, &model) in grads.iter().zip(inp.models) {
                        if model != WallModel::ContactOnly && g.norm_squared() > R::zero() {
                            grad_v -= wall_part(model, g, &vi) * g.transpose();
                            drho += c.rho0 * vi.dot(g);
                        }
                    }
                }
                let mut up = c.material.update(&stress[i], &grad_v, inp.dt);
                if !in_contact {
                    // A grain without a granular neighbour is out of contact: it carries no
                    // stress (else it keeps the last one, its velocity gradient being zero).
                    up.stress = Matrix3::zeros();
                    up.plastic_strain = R::zero();
                }
                let rho_next = rho[i] + drho * inp.dt;
                *sig = up.stress;
                *r = rho_next;
                *kappa = plastic[i] + up.plastic_strain;
                *art = artificial_stress(&up.stress, rho_next, c.eps_stress);
                *sig_rho2 = up.stress / (rho_next * rho_next);
                *art_on = *art != Matrix3::zeros();
            },
        );
}

/// The arrays the momentum pass's pair terms read.
pub(crate) struct MomentumFields<'a, R: Real> {
    /// Velocities and the new densities of the particles (grains, then boundary particles).
    pub v: &'a [Vec3<R>],
    pub rho: &'a [R],
    /// `σ/ρ²` of the new stresses and densities, the artificial stresses `R` and whether each
    /// is non-zero.
    pub sig_rho2: &'a [Matrix3<R>],
    pub art: &'a [Matrix3<R>],
    pub art_on: &'a [bool],
    /// The grains' masses; the boundary particles' is `boundary_mass`.
    pub masses: &'a [R],
    pub boundary_mass: R,
}

/// The pair stress `σ_i/ρ_i² + σ_j/ρ_j² − Π_ij I + f_ij^n (R_i + R_j)` (Pa m⁶/kg²) of grain
/// `i`'s pair `p` ([`support_pairs`]) and the neighbour's mass `m_j`:
/// Monaghan's artificial viscosity on approaching pairs, Gray, Monaghan & Swift's artificial
/// stress where either side has one.
#[inline(always)]
pub(crate) fn pair_stress<R: Real, K: Kernel<R>>(
    c: &Consts<R, K>,
    f: &MomentumFields<'_, R>,
    i: usize,
    p: &Pair<R>,
) -> (Matrix3<R>, R) {
    let (vi, ri) = (f.v[i], f.rho[i]);
    let (j, xij) = (p.j as usize, p.xij);
    let rj = f.rho[j];
    let mut t = f.sig_rho2[i] + f.sig_rho2[j];
    // Monaghan's artificial viscosity, for approaching pairs (`Π_ij > 0`: only the diagonal
    // changes).
    let vij = vi - f.v[j];
    let vx = vij.dot(&xij);
    if vx < R::zero() {
        let phi = c.h * vx / (xij.norm_squared() + c.eta2);
        let pi = (-c.alpha * c.c0 * phi + c.beta * phi * phi) / ((ri + rj) * R::of_f64(0.5));
        for k in 0..3 {
            t[(k, k)] -= pi;
        }
    }
    // Gray, Monaghan & Swift's artificial stress.
    if f.art_on[i] || f.art_on[j] {
        let w = (c.kernel.value(xij.norm()) * c.inv_w_spacing).powf(c.exponent);
        t += (f.art[i] + f.art[j]) * w;
    }
    (t, f.masses.get(j).copied().unwrap_or(f.boundary_mass))
}

/// The momentum pass's term `m_j T_ij ∇W_ij` of grain `i`'s pair `p` with the pair stress
/// `T_ij` ([`pair_stress`]).
#[inline(always)]
pub(crate) fn pair_term<R: Real, K: Kernel<R>>(
    c: &Consts<R, K>,
    f: &MomentumFields<'_, R>,
    i: usize,
    p: &Pair<R>,
) -> Vec3<R> {
    let (t, m) = pair_stress(c, f, i, p);
    t * p.grad * m
}

/// Pass 2: the acceleration from the new stresses (with the artificial viscosity and
/// stress and the walls' share), the velocity and position after `Δt` (symplectic Euler),
/// the position projected out of the solids and the velocity corrected by that projection.
/// The pair terms ([`pair_term`]) in lanes where they run, for a grain without artificial
/// stress ([`crate::lanes`]).
pub(crate) fn momentum_pass<R: Real, K: Kernel<R>>(s: &mut Scratch<R>, inp: &StepInputs<'_, R, K>) {
    let c = inp.c;
    let slots = inp.models.len();
    let n = inp.masses.len();
    let lanes = grain_lanes(s, inp);
    let f = MomentumFields {
        v: &s.v,
        rho: &s.rho_new,
        sig_rho2: &s.stress_over_rho2,
        art: &s.art,
        art_on: &s.art_on,
        masses: inp.masses,
        boundary_mass: inp.boundary_mass,
    };
    let lane_arrays = lanes.map(|_| MomentumArrays {
        xm: s.packed.values(),
        v: flat::<_, R>(&s.v, 3),
        rho: f32s(&s.rho_new),
        sig_rho2: flat::<_, R>(&s.stress_over_rho2, 9),
        art_on: &s.art_on,
    });
    let (sig, grads) = (&s.stress_new[..], &s.wall_grad);
    let (grad, offsets) = (&s.pair_grad[..], inp.nb.offsets());
    let (pairs, counts, x) = (&s.pairs[..], &s.pair_count[..], &s.x[..]);
    let two = R::of_f64(2.0);
    let inv_dt = R::one() / inp.dt;
    s.v_new[..n]
        .par_iter_mut()
        .zip(s.x_new[..n].par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, (vn, xn))| {
            let (xi, vi, ri) = (x[i], f.v[i], f.rho[i]);
            let mut a = inp.gravity;
            match (&lanes, &lane_arrays) {
                (Some(l), Some(arrays)) => {
                    let list = inp.nb.neighbours(i);
                    let grad_i = &grad[offsets[i]..offsets[i + 1]];
                    let listed = |k: usize| {
                        let j = list[k];
                        Pair {
                            j,
                            xij: xi - x[j as usize],
                            grad: grad_i[k],
                        }
                    };
                    if f.art_on[i] {
                        for p in (0..list.len()).map(listed) {
                            if p.grad != Vec3::zeros() {
                                a += pair_term(&c, &f, i, &p);
                            }
                        }
                    } else {
                        let mut rest = Vec3::zeros();
                        let mut scalar = |k: usize| rest += pair_term(&c, &f, i, &listed(k));
                        let lanes_sum: Vec3<R> =
                            l.acceleration(arrays, inp.nb, i, flat::<_, R>(grad_i, 3), &mut scalar);
                        a += lanes_sum + rest;
                    }
                }
                _ => {
                    for p in grain_pairs(pairs, counts, offsets, i) {
                        a += pair_term(&c, &f, i, p);
                    }
                }
            }
            if slots > 0 {
                let gi = &grads[i * slots..(i + 1) * slots];
                for (g, &model) in gi.iter().zip(inp.models) {
                    if model != WallModel::ContactOnly && g.norm_squared() > R::zero() {
                        a += wall_part(model, g, &(sig[i] * g)) * (two * c.rho0 / (ri * ri));
                    }
                }
            }
            let v_star = vi + a * inp.dt;
            let y = xi + v_star * inp.dt;
            let p = inp.boundary.project(y);
            *xn = p;
            *vn = v_star + (p - y) * inv_dt;
        });
}

/// `σ_b/ρ_b²` and whether the artificial stress is non-zero, for the boundary particles
/// `n..` (after their stress and artificial stress are extrapolated), as the stress pass
/// writes them for the grains; only for those a grain's sum reads
/// (`BoundaryLists::is_read`).
pub(crate) fn boundary_pair_terms<R: Real>(s: &mut Scratch<R>, n: usize) {
    let (sig, rho, art) = (&s.stress_new[n..], &s.rho_new[n..], &s.art[n..]);
    let lists = &s.boundary_lists;
    s.stress_over_rho2[n..]
        .par_chunks_mut(READ_CHUNK)
        .zip(s.art_on[n..].par_chunks_mut(READ_CHUNK))
        .enumerate()
        .with_min_len(CHUNKS_PER_TASK)
        .filter(|(c, _)| lists.is_chunk_read(*c))
        .for_each(|(c, (srs, ons))| {
            for (e, (sr, on)) in srs.iter_mut().zip(ons).enumerate() {
                let k = c * READ_CHUNK + e;
                if !lists.is_read(k) {
                    continue;
                }
                *sr = sig[k] / (rho[k] * rho[k]);
                *on = art[k] != Matrix3::zeros();
            }
        });
}

/// The largest distance (m) any particle has moved since the last neighbour search.
pub(crate) fn max_displacement<R: Real>(s: &Scratch<R>, n: usize) -> R {
    s.x[..n]
        .par_iter()
        .zip(s.anchor.par_iter())
        .with_min_len(MIN_LEN)
        .map(|(a, b)| (a - b).norm())
        .reduce(R::zero, |a, b| if b > a { b } else { a })
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use sph_kernels::CubicSpline;
    use sph_solver::scene_boundary::{PeriodicAxis, PeriodicImages};
    use sph_solver::step::StepNeighbours;
    use sph_solver::Method;

    use super::*;
    use crate::ElastoplasticParams;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// The pairs the scalar passes read ([`support_pairs`], from the images' refreshed
        /// positions and their owners) against each listed pair resolved through
        /// [`PeriodicImages::resolve`] and its [`pair_gradient`], those of a zero gradient
        /// dropped: the same pairs in the same order, bit for bit (the same arithmetic), on
        /// a random cloud in a slab periodic along `x` and `z` (three grains deep, as the
        /// poured heaps), searched once and then moved by up to half the skin, as between
        /// two searches.
        #[test]
        fn the_support_pairs_are_the_resolved_listed_pairs(
            count in 20usize..200,
            seed in any::<u64>(),
        ) {
            let s = 0.02f64;
            let p = ElastoplasticParams::<f64>::for_spacing(s, 30.0);
            let h = p.common.support_radius;
            let c = Consts::new(&p, CubicSpline::new(h).unwrap()).unwrap();
            let axes = [
                PeriodicAxis { axis: 0, lo: 0.0, hi: 0.2 },
                PeriodicAxis { axis: 2, lo: 0.0, hi: 0.06 },
            ];
            let mut state = seed | 1;
            let mut draw = |scale: f64| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                scale * ((state >> 11) as f64 / (1u64 << 53) as f64)
            };
            let mut x: Vec<Vec3<f64>> = (0..count)
                .map(|_| Vec3::new(draw(0.2), draw(0.1), draw(0.06)))
                .collect();
            let mut images = PeriodicImages::default();
            let mut ext = Vec::new();
            images.rebuild(&mut x, &axes, h + p.skin, &mut ext);
            let mut search = StepNeighbours::new(Method::CellStartGrid);
            search.find(&ext, h + p.skin).unwrap();
            let nb = search.lists();
            let mut owner = Vec::new();
            images.owners(count, &mut owner);
            for q in &mut x {
                *q += Vec3::new(draw(p.skin), draw(p.skin), draw(p.skin)) * 0.5 / 3f64.sqrt();
            }
            images.refresh(&x, &mut ext);
            let mut out = vec![Pair::default(); nb.offsets()[count]];
            let mut checked = 0;
            for i in 0..count {
                let list = nb.neighbours(i);
                let got = support_pairs(&c, &ext, &owner, i, list, &mut out);
                let want: Vec<Pair<f64>> = list
                    .iter()
                    .map(|&j| {
                        let (j, xj) = images.resolve(j as usize, &x);
                        let xij = x[i] - xj;
                        Pair { j: j as u32, xij, grad: pair_gradient(&c, &xij) }
                    })
                    .filter(|q| q.grad != Vec3::zeros())
                    .collect();
                prop_assert_eq!(&out[..got], &want[..], "pairs of grain {}", i);
                checked += got;
            }
            prop_assert!(checked > 0);
        }
    }
}
