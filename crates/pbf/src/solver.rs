//! The solver: Algorithm 1 of Macklin & Müller (2013).

use std::fmt;
use std::time::Instant;

use neighbour_search::{
    CellOrder, CellSorter, HashedGrid, NeighbourLists, NeighbourSearch, SearchError, SearchStats,
};
use rayon::prelude::*;
use sph_core::{
    validate_finite_positions, CoreError, ParticleSet, PermutationScratch, Real, Sdf, Vec3,
};
use sph_kernels::{Kernel, Poly6, Spiky};

use crate::{ArtificialPressure, PbfError, PbfParams, Solids};

/// Smallest number of particles handed to one rayon task.
pub(crate) const MIN_LEN: usize = 256;
/// Particles per partial sum of the end-of-step statistics (fixed, so that the statistics do
/// not depend on the number of threads).
pub(crate) const REDUCE_CHUNK: usize = 4096;

/// Wall-clock time of the phases of one [`Pbf::step`] call (all substeps), in seconds, named
/// after the rows of the paper's Table 2, and the state at the end of the call.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// "Integrate": input checks, applying gravity and predicting positions (Algorithm 1
    /// lines 1–4).
    pub integrate_s: f64,
    /// "Create Hash Grid": the neighbour search's build (cells, sort, cell table;
    /// [`SearchStats::build_s`]).
    pub create_hash_grid_s: f64,
    /// "Detect Neighbors": the neighbour search's query (distance tests and CSR lists;
    /// [`SearchStats::detect_s`]).
    pub detect_neighbours_s: f64,
    /// "Constraint Solve": the Jacobi iterations, collision handling included (lines 8–19).
    pub constraint_solve_s: f64,
    /// "Velocity Update": velocities, vorticity confinement, XSPH viscosity, position update
    /// (lines 20–24), the blow-up checks and the end-of-step statistics.
    pub velocity_update_s: f64,
    /// Reordering the particles by cell (not a row of Table 2; 0 when no reorder happened).
    pub reorder_s: f64,
    /// Steps of Algorithm 1 done (the `substeps` parameter).
    pub substeps: usize,
    /// Jacobi (PBF) or pressure (PCISPH) iterations done in total (`substeps ×
    /// solver_iterations` without a stopping tolerance).
    pub iterations: usize,
    /// Substeps whose iterations reached the maximum without meeting the stopping tolerance
    /// (PBF `mean_compression_tolerance`, PCISPH `density_error_tolerance`); 0 without one.
    /// Non-convergence is reported here, not as an error.
    pub unconverged_substeps: usize,
    /// The density error the stopping rule saw in the last iteration of the last substep
    /// (PBF: mean compression `(1/N) Σ max(ρ_i/ρ0 − 1, 0)` at the positions the iteration
    /// started from; PCISPH: maximum predicted compression); 0 without a tolerance.
    pub last_solve_error: f64,
    /// Ordered neighbour pairs found in the last substep.
    pub neighbour_pairs: usize,
    /// `max_i ρ_i / ρ0` at the end of the solve (eq. 2 at the final positions, with the
    /// neighbour lists of the last substep). 0 without particles.
    pub max_density_ratio: f64,
    /// Mean of `ρ_i / ρ0` at the end of the solve. 0 without particles.
    pub mean_density_ratio: f64,
    /// Kinetic energy `Σ m_i |v_i|² / 2` at the end of the call (J).
    pub kinetic_energy: f64,
    /// Whether the particles were reordered at the start of this call (see
    /// [`Pbf::last_permutation`]).
    pub reordered: bool,
}

impl StepStats {
    /// Sum of the phase times (s).
    pub fn total_s(&self) -> f64 {
        self.integrate_s
            + self.create_hash_grid_s
            + self.detect_neighbours_s
            + self.constraint_solve_s
            + self.velocity_update_s
            + self.reorder_s
    }
}

/// Per-particle working arrays of the solver (structure of arrays, one `Vec` per quantity),
/// kept between steps so that a step does not allocate. After a [`Pbf::step`] they hold the
/// values of its last substep, in the state's current particle order.
#[derive(Debug, Clone, Default)]
pub struct PbfScratch<R: Real> {
    predicted: Vec<Vec3<R>>,
    next: Vec<Vec3<R>>,
    lambda: Vec<R>,
    delta_p: Vec<Vec3<R>>,
    density: Vec<R>,
    velocity: Vec<Vec3<R>>,
    velocity_new: Vec<Vec3<R>>,
    vorticity: Vec<Vec3<R>>,
    vorticity_norm: Vec<R>,
    partials: Vec<[f64; 3]>,
    pairs: PairCache<R>,
}

impl<R: Real> PbfScratch<R> {
    fn resize(&mut self, n: usize) {
        if self.predicted.len() == n {
            return;
        }
        let z = Vec3::zeros();
        self.predicted.resize(n, z);
        self.next.resize(n, z);
        self.lambda.resize(n, R::zero());
        self.delta_p.resize(n, z);
        self.density.resize(n, R::zero());
        self.velocity.resize(n, z);
        self.velocity_new.resize(n, z);
        self.vorticity.resize(n, z);
        self.vorticity_norm.resize(n, R::zero());
        self.partials.resize(n.div_ceil(REDUCE_CHUNK), [0.0; 3]);
    }

    /// Predicted positions `x*` (m): after a step, the final positions of its last substep.
    pub fn predicted(&self) -> &[Vec3<R>] {
        &self.predicted
    }
    /// `λ_i` of the last iteration (eq. 11; m², see the crate docs for units).
    pub fn lambda(&self) -> &[R] {
        &self.lambda
    }
    /// `Δp_i` of the last iteration (eq. 14, before collision response; m).
    pub fn delta_p(&self) -> &[Vec3<R>] {
        &self.delta_p
    }
    /// Densities `ρ_i` (eq. 2, kg/m³): after a step, at the final positions; after
    /// [`Pbf::evaluate_constraints`], at the given positions.
    pub fn density(&self) -> &[R] {
        &self.density
    }
    /// Velocities `(x* − x)/Δt` of Algorithm 1 line 21 (m/s), before vorticity confinement
    /// and XSPH.
    pub fn velocity(&self) -> &[Vec3<R>] {
        &self.velocity
    }
    /// Vorticity `ω_i` of eq. 15 (1/s); zero when vorticity confinement is off.
    pub fn vorticity(&self) -> &[Vec3<R>] {
        &self.vorticity
    }
}

/// What [`Pbf::evaluate_constraints`] computed, borrowed from the solver.
#[derive(Debug, Clone, Copy)]
pub struct ConstraintEval<'a, R: Real> {
    /// `ρ_i` (eq. 2, kg/m³).
    pub density: &'a [R],
    /// `λ_i` (eq. 11).
    pub lambda: &'a [R],
    /// `Δp_i` (eq. 14, with `s_corr`, without collision response; m).
    pub delta_p: &'a [Vec3<R>],
    /// The neighbour lists used (within `h`, excluding the particle itself).
    pub neighbours: &'a NeighbourLists,
}

/// Kernels and constants shared by the per-particle loops.
#[derive(Debug, Clone, Copy)]
struct Consts<R: Real> {
    poly6: Poly6<R>,
    spiky: Spiky<R>,
    /// `W(0)` of Poly6: the self term of the density sum.
    w0: R,
    scorr: ArtificialPressure<R>,
    scorr_on: bool,
    /// `1 / D_ref` (m²): the unit in which `s_corr` is added to `λ_i + λ_j`.
    scorr_unit: R,
    inv_rho0: R,
    eps: R,
    /// [`PbfParams::clamp_negative_constraint`].
    unilateral: bool,
    /// Support radius `h` (m).
    h: R,
}

impl<R: Real> Consts<R> {
    fn new(p: &PbfParams<R>) -> Result<Self, PbfError> {
        let h = p.support_radius;
        let poly6 = Poly6::new(h)?;
        Ok(Self {
            poly6,
            spiky: Spiky::new(h)?,
            w0: poly6.value_r2(R::zero()),
            scorr: ArtificialPressure::new(h, p.scorr_k, p.scorr_n, p.scorr_delta_q)?,
            scorr_on: p.scorr_k > R::zero(),
            scorr_unit: p.scorr_unit()?,
            inv_rho0: R::one() / p.rest_density,
            eps: p.cfm_epsilon,
            unilateral: p.clamp_negative_constraint,
            h,
        })
    }
}

/// The Position Based Fluids solver of
///
/// > Miles Macklin and Matthias Müller, "Position Based Fluids", *ACM Transactions on
/// > Graphics* 32(4), Article 104, 2013 (SIGGRAPH 2013),
///
/// Algorithm 1, one call of [`Pbf::step`] being one frame of `substeps` steps of
/// `Δt = dt / substeps`:
///
/// 1. apply gravity and predict `x* = x + Δt (v + Δt g)` (lines 1–4);
/// 2. find the neighbours within `h` **once**, at the predicted positions (lines 5–7);
/// 3. `solver_iterations` Jacobi iterations (lines 8–19), each:
///    `ρ_i` (eq. 2, Poly6), `λ_i` (eqs. 1, 8, 11, Spiky gradients, CFM `ε`) for all `i`;
///    then `Δp_i` (eq. 14 with `s_corr` of eq. 13) and collision response against the solids
///    for all `i`; then `x* ← x* + Δp` (+ collision) for all `i`. With
///    [`PbfParams::mean_compression_tolerance`] (not in the paper; SPlisHSPlasH's rule) the
///    count is adaptive: between `min_solver_iterations` and `solver_iterations`, stopping
///    after the first iteration whose mean compression at its start is within the tolerance;
///    [`PbfParams::clamp_negative_constraint`] makes `C_i` unilateral;
/// 4. `v = (x* − x)/Δt` (line 21); vorticity `ω_i` (eq. 15) and the confinement
///    acceleration `ε N × ω` (eq. 16), XSPH (eq. 17), both from the line-21 velocities;
///    `x ← x*` (line 23).
///
/// See the crate documentation for the mass convention, the collision response, the blow-up
/// checks and the deviations from the paper.
pub struct Pbf<R: Real> {
    params: PbfParams<R>,
    c: Consts<R>,
    solids: Solids<R>,
    search: Box<dyn NeighbourSearch<R>>,
    fallback: Option<HashedGrid<R>>,
    neighbours: NeighbourLists,
    scratch: PbfScratch<R>,
    reorder: CellReorder<R>,
    steps: u64,
}

impl<R: Real> fmt::Debug for Pbf<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Pbf")
            .field("params", &self.params)
            .field("solids", &self.solids.len())
            .field("search", &self.search.name())
            .field("particles", &self.scratch.predicted.len())
            .field("steps", &self.steps)
            .finish()
    }
}

pub(crate) fn non_finite<R: Real>(v: &Vec3<R>) -> Option<usize> {
    (0..3).find(|&a| !v[a].is_finite_value())
}

pub(crate) fn check_masses<R: Real>(masses: &[R]) -> Result<(), PbfError> {
    match masses
        .par_iter()
        .with_min_len(MIN_LEN)
        .position_first(|&m| !(m.is_finite_value() && m > R::zero()))
    {
        Some(index) => Err(PbfError::InvalidMass {
            index,
            value: masses[index].as_f64(),
        }),
        None => Ok(()),
    }
}

/// Runs the configured search, falling back to a hashed grid when the cell-start grid
/// refuses the domain (an exceptional case: the fallback allocates on first use).
pub(crate) fn find_neighbours<R: Real>(
    search: &mut dyn NeighbourSearch<R>,
    fallback: &mut Option<HashedGrid<R>>,
    positions: &[Vec3<R>],
    h: R,
    out: &mut NeighbourLists,
) -> Result<SearchStats, SearchError> {
    match search.search(positions, h, out) {
        Ok(()) => Ok(search.stats()),
        Err(SearchError::DomainTooLarge { .. }) => {
            let fb = fallback.get_or_insert_with(HashedGrid::new);
            fb.search(positions, h, out)?;
            Ok(fb.stats())
        }
        Err(e) => Err(e),
    }
}

/// [`find_neighbours`] inside call `step`, substep `sub` of a solver: a position the
/// neighbour grid cannot hold (non-finite, or a cell coordinate overflowing `i32`) is a
/// [`PbfError::BlowUp`] naming the particle and `what` the positions are (e.g. "predicted
/// position"); other search errors pass through.
#[allow(clippy::too_many_arguments)]
pub(crate) fn find_step_neighbours<R: Real>(
    search: &mut dyn NeighbourSearch<R>,
    fallback: &mut Option<HashedGrid<R>>,
    positions: &[Vec3<R>],
    h: R,
    out: &mut NeighbourLists,
    step: u64,
    sub: usize,
    what: &str,
) -> Result<SearchStats, PbfError> {
    find_neighbours(search, fallback, positions, h, out).map_err(|e| match e {
        SearchError::NonFinitePosition { index, .. }
        | SearchError::CellCoordinateOverflow { index, .. } => blow_up(
            step,
            index,
            format!(
                "substep {sub}: {what} {:?} is out of the range of the neighbour grid",
                positions[index]
            ),
        ),
        e => e.into(),
    })
}

/// A non-finite predicted position (after applying the external forces) is a
/// [`PbfError::BlowUp`] of call `step`, substep `sub`, naming the first such particle.
pub(crate) fn check_predicted<R: Real>(
    step: u64,
    sub: usize,
    predicted: &[Vec3<R>],
) -> Result<(), PbfError> {
    match predicted
        .par_iter()
        .with_min_len(MIN_LEN)
        .position_first(|x| non_finite(x).is_some())
    {
        Some(i) => Err(blow_up(
            step,
            i,
            format!(
                "substep {sub}: predicted position {:?} is not finite",
                predicted[i]
            ),
        )),
        None => Ok(()),
    }
}

/// Collision detection and response (inside the constraint loop, Algorithm 1 line 14): for
/// each solid in order, a position closer than `radius` to it (signed distance `d < radius`)
/// is moved along the normalised SDF gradient by `radius − d`.
#[inline]
pub(crate) fn collide<R: Real>(solids: &[Box<dyn Sdf<R>>], mut x: Vec3<R>, radius: R) -> Vec3<R> {
    for s in solids {
        let d = s.signed_distance(&x);
        if d < radius {
            let g = s.gradient(&x);
            let len = g.norm();
            if len > R::zero() && len.is_finite_value() {
                x += g * ((radius - d) / len);
            }
        }
    }
    x
}

/// The divergence checks of a substep, before anything is written to the state: a non-finite
/// final position `x` or velocity `v`, or a position more than `h` inside a solid, is a
/// [`PbfError::BlowUp`] of call `step`, substep `sub`, naming the first such particle.
pub(crate) fn check_divergence<R: Real>(
    step: u64,
    sub: usize,
    x: &[Vec3<R>],
    v: &[Vec3<R>],
    solids: &[Box<dyn Sdf<R>>],
    h: R,
) -> Result<(), PbfError> {
    if let Some(i) = (0..x.len())
        .into_par_iter()
        .with_min_len(MIN_LEN)
        .position_first(|i| non_finite(&x[i]).is_some() || non_finite(&v[i]).is_some())
    {
        return Err(blow_up(
            step,
            i,
            format!(
                "substep {sub}: position {:?} or velocity {:?} is not finite",
                x[i], v[i]
            ),
        ));
    }
    if !solids.is_empty() {
        let margin = -h;
        if let Some(i) = x
            .par_iter()
            .with_min_len(MIN_LEN)
            .position_first(|xi| solids.iter().any(|sd| sd.signed_distance(xi) < margin))
        {
            let (k, d) = solids
                .iter()
                .enumerate()
                .map(|(k, sd)| (k, sd.signed_distance(&x[i])))
                .find(|&(_, d)| d < margin)
                .unwrap_or((0, R::zero()));
            return Err(blow_up(
                step,
                i,
                format!(
                    "substep {sub}: position {:?} is {} m inside solid {k} (more than h = {})",
                    x[i],
                    -d.as_f64(),
                    h.as_f64()
                ),
            ));
        }
    }
    Ok(())
}

pub(crate) fn blow_up(step: u64, particle: usize, reason: String) -> PbfError {
    PbfError::BlowUp {
        step,
        particle,
        reason,
    }
}

/// Density ratios and kinetic energy of `state` into `stats`, summed over fixed chunks of
/// [`REDUCE_CHUNK`] particles (`partials` holds one entry per chunk), so that the result does
/// not depend on the number of threads.
pub(crate) fn density_energy_stats<R: Real>(
    state: &ParticleSet<R>,
    rest_density: R,
    partials: &mut [[f64; 3]],
    stats: &mut StepStats,
) {
    let n = state.len();
    if n == 0 {
        return;
    }
    let inv_rho0 = 1.0 / rest_density.as_f64();
    let (rho, v, m) = (&state.densities, &state.velocities, &state.masses);
    partials.par_iter_mut().enumerate().for_each(|(c, part)| {
        let (a, b) = (c * REDUCE_CHUNK, ((c + 1) * REDUCE_CHUNK).min(n));
        let mut sum = 0.0;
        let mut max = f64::NEG_INFINITY;
        let mut ke = 0.0;
        for i in a..b {
            let r = rho[i].as_f64() * inv_rho0;
            sum += r;
            max = max.max(r);
            ke += 0.5 * m[i].as_f64() * v[i].norm_squared().as_f64();
        }
        *part = [sum, max, ke];
    });
    let mut sum = 0.0;
    let mut max = f64::NEG_INFINITY;
    let mut ke = 0.0;
    for part in partials.iter() {
        sum += part[0];
        max = max.max(part[1]);
        ke += part[2];
    }
    stats.mean_density_ratio = sum / n as f64;
    stats.max_density_ratio = max;
    stats.kinetic_energy = ke;
}

/// The periodic reordering of the particles by cell shared by [`Pbf`] and
/// [`crate::Pcisph`]: the sorter, the last permutation and its scratch buffers.
#[derive(Debug, Default)]
pub(crate) struct CellReorder<R: Real> {
    sorter: CellSorter,
    scratch: PermutationScratch<R>,
    permutation: Vec<u32>,
    reordered: bool,
}

impl<R: Real> CellReorder<R> {
    /// At the start of step `step`: every `every` steps (never when 0, nor for fewer than two
    /// particles) reorders `state` by cell of size `h` (lexicographic cell order, for
    /// locality), keeping the permutation, and records the time in `stats`.
    pub(crate) fn at_step(
        &mut self,
        state: &mut ParticleSet<R>,
        h: R,
        step: u64,
        every: usize,
        stats: &mut StepStats,
    ) -> Result<(), PbfError> {
        self.reordered = false;
        let every = every as u64;
        if every == 0 || !step.is_multiple_of(every) || state.len() < 2 {
            return Ok(());
        }
        let t = Instant::now();
        let perm = self
            .sorter
            .permutation(&state.positions, h, CellOrder::Lexicographic)?;
        self.permutation.clear();
        self.permutation.extend_from_slice(perm);
        state.permute(&self.permutation, &mut self.scratch)?;
        self.reordered = true;
        stats.reordered = true;
        stats.reorder_s = t.elapsed().as_secs_f64();
        Ok(())
    }

    /// The permutation of the last [`CellReorder::at_step`] (`new[k] = old[perm[k]]`), or
    /// `None` if it did not reorder.
    pub(crate) fn last_permutation(&self) -> Option<&[u32]> {
        self.reordered.then_some(&self.permutation[..])
    }
}

/// Per-pair values of one Jacobi iteration, in the CSR order of the neighbour lists:
/// computed by `lambda_pass` and reused by `delta_pass`, which sees the same positions, so
/// that the second pass needs no square root, division or kernel evaluation (measured: this
/// is faster than recomputing `s_corr` from `r²` in the second pass, although it streams a
/// second per-pair array).
#[derive(Debug, Clone, Default)]
struct PairCache<R: Real> {
    /// Spiky gradient factor `f_ij` with `∇W(p_i − p_j) = (p_i − p_j) f_ij` (`dW/dr / r`;
    /// 0 at `r = 0` and at or beyond `h`).
    grad_factor: Vec<R>,
    /// `s_corr` of the pair (eq. 13; 0 when the artificial pressure is off).
    scorr: Vec<R>,
}

impl<R: Real> PairCache<R> {
    /// Makes room for `pairs` pairs (reallocates only when the capacity is exceeded).
    fn resize(&mut self, pairs: usize) {
        self.grad_factor.resize(pairs, R::zero());
        self.scorr.resize(pairs, R::zero());
    }
}

/// The Spiky gradient factor `dW/dr / r` (see [`PairCache::grad_factor`]); the same
/// arithmetic as `Kernel::gradient`, so that `r * factor` equals `spiky.gradient(&r)`.
#[inline]
fn spiky_factor<R: Real>(c: &Consts<R>, r2: R) -> R {
    let len = r2.sqrt();
    if len > R::zero() && len < c.h {
        c.spiky.derivative(len) / len
    } else {
        R::zero()
    }
}

/// What the particle loops of one pass read.
#[derive(Clone, Copy)]
struct PassInput<'a, R: Real> {
    c: &'a Consts<R>,
    x: &'a [Vec3<R>],
    m: &'a [R],
    nb: &'a NeighbourLists,
}

/// Eqs. 1, 2, 8 and 11: densities and `λ_i` at positions `x`, and the pair cache for
/// [`delta_pass`]. Returns the sum of the compressions `max(ρ_i/ρ0 − 1, 0)` (in f64, summed
/// over a split tree that depends only on the particle count, so the result does not depend
/// on the number of threads).
fn lambda_pass<R: Real>(
    input: PassInput<'_, R>,
    density: &mut [R],
    lambda: &mut [R],
    cache: &mut PairCache<R>,
) -> f64 {
    let pairs = input.nb.pair_count();
    cache.resize(pairs);
    lambda_block(
        input,
        0,
        density,
        lambda,
        &mut cache.grad_factor[..pairs],
        &mut cache.scorr[..pairs],
    )
}

/// [`lambda_pass`] over the particles `first..first + density.len()`, whose pairs are
/// `grad_factor` and `scorr`: split in halves (rayon `join`) down to `MIN_LEN` particles, so
/// that each task owns its particles' contiguous CSR range of the cache. Returns the block's
/// compression sum.
fn lambda_block<R: Real>(
    input: PassInput<'_, R>,
    first: usize,
    density: &mut [R],
    lambda: &mut [R],
    grad_factor: &mut [R],
    scorr: &mut [R],
) -> f64 {
    let n = density.len();
    let offsets = input.nb.offsets();
    if n > MIN_LEN {
        let mid = n / 2;
        let split = offsets[first + mid] - offsets[first];
        let (d0, d1) = density.split_at_mut(mid);
        let (l0, l1) = lambda.split_at_mut(mid);
        let (g0, g1) = grad_factor.split_at_mut(split);
        let (s0, s1) = scorr.split_at_mut(split);
        let (a, b) = rayon::join(
            || lambda_block(input, first, d0, l0, g0, s0),
            || lambda_block(input, first + mid, d1, l1, g1, s1),
        );
        return a + b;
    }
    let PassInput { c, x, m, nb } = input;
    let base = offsets[first];
    let mut compression = R::zero();
    for (k, (rho, lam)) in density.iter_mut().zip(lambda.iter_mut()).enumerate() {
        let i = first + k;
        let (a, b) = (offsets[i] - base, offsets[i + 1] - base);
        let xi = x[i];
        let mut sum_w = m[i] * c.w0;
        let mut grad_i = Vec3::zeros();
        let mut sum_g2 = R::zero();
        for ((&j, gf), sc) in nb
            .neighbours(i)
            .iter()
            .zip(&mut grad_factor[a..b])
            .zip(&mut scorr[a..b])
        {
            let j = j as usize;
            let r = xi - x[j];
            let r2 = r.norm_squared();
            let w = c.poly6.value_r2(r2);
            sum_w += m[j] * w;
            *sc = if c.scorr_on {
                c.scorr.from_kernel_value(w)
            } else {
                R::zero()
            };
            let f = spiky_factor(c, r2);
            *gf = f;
            // ∇_{p_j} C_i = −(m_j/ρ0) ∇W(p_i − p_j); ∇_{p_i} C_i = Σ_j (m_j/ρ0) ∇W.
            let g = (r * f) * (m[j] * c.inv_rho0);
            grad_i += g;
            sum_g2 += g.norm_squared();
        }
        *rho = sum_w;
        let mut constraint = sum_w * c.inv_rho0 - R::one();
        if constraint > R::zero() {
            compression += constraint;
        } else if c.unilateral {
            constraint = R::zero();
        }
        *lam = -constraint / (sum_g2 + grad_i.norm_squared() + c.eps);
    }
    compression.as_f64()
}

/// Eqs. 13 and 14, then collision response: `delta_p` receives `Δp_i`, `next` the corrected
/// position `x_i + Δp_i` moved out of the solids. Reads the pair cache written by
/// [`lambda_pass`] at the same positions.
#[allow(clippy::too_many_arguments)]
fn delta_pass<R: Real>(
    input: PassInput<'_, R>,
    lambda: &[R],
    cache: &PairCache<R>,
    solids: &[Box<dyn Sdf<R>>],
    radius: R,
    delta_p: &mut [Vec3<R>],
    next: &mut [Vec3<R>],
) {
    let PassInput { c, x, m, nb } = input;
    let half_unit = R::of_f64(0.5) * c.scorr_unit;
    let offsets = nb.offsets();
    delta_p
        .par_iter_mut()
        .zip(next.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_LEN)
        .for_each(|(i, (dp, xn))| {
            let (xi, li, mi) = (x[i], lambda[i], m[i]);
            let (a, b) = (offsets[i], offsets[i + 1]);
            let mut acc = Vec3::zeros();
            for ((&j, &f), &sc) in nb
                .neighbours(i)
                .iter()
                .zip(&cache.grad_factor[a..b])
                .zip(&cache.scorr[a..b])
            {
                let j = j as usize;
                let r = xi - x[j];
                let mj = m[j];
                // λ_i ∇_{p_i} C_i + λ_j ∇_{p_i} C_j, with ∇_{p_i} C_j = (m_i/ρ0) ∇W(p_i − p_j).
                let mut coeff = li * mj + lambda[j] * mi;
                if c.scorr_on {
                    coeff += sc * (mi + mj) * half_unit;
                }
                acc += (r * f) * coeff;
            }
            let d = acc * c.inv_rho0;
            *dp = d;
            *xn = collide(solids, xi + d, radius);
        });
}

impl<R: Real> Pbf<R> {
    /// A solver with validated `params` and the given solids (signed distance fields,
    /// negative inside the solid; a tank is `sph_core::Inverted<BoxSdf>`).
    pub fn new(params: PbfParams<R>, solids: Solids<R>) -> Result<Self, PbfError> {
        params.validate()?;
        let c = Consts::new(&params)?;
        Ok(Self {
            search: params.neighbour_method.build::<R>(),
            params,
            c,
            solids,
            fallback: None,
            neighbours: NeighbourLists::new(),
            scratch: PbfScratch::default(),
            reorder: CellReorder::default(),
            steps: 0,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PbfParams<R> {
        &self.params
    }

    /// Replaces the parameters (validated; the kernels are rebuilt, the buffers kept).
    pub fn set_params(&mut self, params: PbfParams<R>) -> Result<(), PbfError> {
        params.validate()?;
        let c = Consts::new(&params)?;
        if params.neighbour_method != self.params.neighbour_method {
            self.search = params.neighbour_method.build::<R>();
        }
        self.params = params;
        self.c = c;
        Ok(())
    }

    /// The solids, in the order collisions are resolved.
    pub fn solids(&self) -> &[Box<dyn Sdf<R>>] {
        &self.solids
    }

    /// Adds a solid (resolved after the existing ones).
    pub fn add_solid(&mut self, solid: Box<dyn Sdf<R>>) {
        self.solids.push(solid);
    }

    /// The neighbour lists of the last substep (or of [`Pbf::evaluate_constraints`]).
    pub fn neighbours(&self) -> &NeighbourLists {
        &self.neighbours
    }

    /// The working arrays (values of the last substep).
    pub fn scratch(&self) -> &PbfScratch<R> {
        &self.scratch
    }

    /// Number of [`Pbf::step`] calls made (including failed ones).
    pub fn steps_done(&self) -> u64 {
        self.steps
    }

    /// The permutation applied to the particles at the start of the last [`Pbf::step`]
    /// call (`new[k] = old[perm[k]]`), or `None` if that call did not reorder. Apply it to any
    /// per-particle data kept beside the [`ParticleSet`] (`sph_core::apply_permutation`).
    pub fn last_permutation(&self) -> Option<&[u32]> {
        self.reorder.last_permutation()
    }

    /// Computes, at the given positions and without moving anything, the neighbours, the
    /// densities (eq. 2), `λ_i` (eq. 11) and `Δp_i` (eq. 14, before collision response) that
    /// one Jacobi iteration of [`Pbf::step`] computes (the same code). For tests and
    /// diagnostics.
    pub fn evaluate_constraints(
        &mut self,
        positions: &[Vec3<R>],
        masses: &[R],
    ) -> Result<ConstraintEval<'_, R>, PbfError> {
        validate_finite_positions(positions)?;
        if masses.len() != positions.len() {
            return Err(CoreError::LengthMismatch {
                what: "masses",
                found: masses.len(),
                expected: positions.len(),
            }
            .into());
        }
        check_masses(masses)?;
        let n = positions.len();
        self.scratch.resize(n);
        let s = &mut self.scratch;
        s.predicted.copy_from_slice(positions);
        find_neighbours(
            &mut *self.search,
            &mut self.fallback,
            &s.predicted,
            self.params.support_radius,
            &mut self.neighbours,
        )?;
        let input = PassInput {
            c: &self.c,
            x: &s.predicted,
            m: masses,
            nb: &self.neighbours,
        };
        let _ = lambda_pass(input, &mut s.density, &mut s.lambda, &mut s.pairs);
        delta_pass(
            input,
            &s.lambda,
            &s.pairs,
            &self.solids,
            self.params.particle_radius(),
            &mut s.delta_p,
            &mut s.next,
        );
        Ok(ConstraintEval {
            density: &s.density,
            lambda: &s.lambda,
            delta_p: &s.delta_p,
            neighbours: &self.neighbours,
        })
    }

    /// Advances `state` by `dt`: `substeps` steps of Algorithm 1 (see [`Pbf`]).
    ///
    /// Checks the state first (array lengths, finite positions and velocities, positive
    /// masses: [`PbfError::InvalidState`], [`PbfError::InvalidMass`]), reorders it by cell
    /// every `reorder_every` calls, and after each substep checks for divergence before
    /// writing the substep's result into `state` ([`PbfError::BlowUp`]; `state` then holds
    /// the last completed substep, never a non-finite value). Writes positions, velocities
    /// and densities (at the final positions).
    ///
    /// Does not allocate once its buffers have grown to the particle count (and the neighbour
    /// lists to the pair count).
    pub fn step(&mut self, state: &mut ParticleSet<R>) -> Result<StepStats, PbfError> {
        let step = self.steps;
        self.steps += 1;
        let mut stats = StepStats::default();
        let t = Instant::now();
        state.validate()?;
        check_masses(&state.masses)?;
        let n = state.len();
        self.scratch.resize(n);
        stats.integrate_s += t.elapsed().as_secs_f64();

        self.reorder.at_step(
            state,
            self.params.support_radius,
            step,
            self.params.reorder_every,
            &mut stats,
        )?;

        for sub in 0..self.params.substeps {
            self.substep(state, step, sub, &mut stats)?;
        }

        let t = Instant::now();
        self.end_of_step_stats(state, &mut stats);
        stats.velocity_update_s += t.elapsed().as_secs_f64();
        Ok(stats)
    }

    fn substep(
        &mut self,
        state: &mut ParticleSet<R>,
        step: u64,
        sub: usize,
        stats: &mut StepStats,
    ) -> Result<(), PbfError> {
        let p = &self.params;
        let c = self.c;
        let dt = p.substep_dt();
        let inv_dt = R::one() / dt;
        let g = p.gravity;
        let h = p.support_radius;
        let radius = p.particle_radius();
        let s = &mut self.scratch;
        let solids = &self.solids[..];

        // Lines 1–4: apply forces, predict positions.
        let t = Instant::now();
        {
            let (x, v) = (&state.positions[..], &state.velocities[..]);
            s.predicted
                .par_iter_mut()
                .enumerate()
                .with_min_len(MIN_LEN)
                .for_each(|(i, xp)| {
                    let vi = v[i] + g * dt;
                    *xp = x[i] + vi * dt;
                });
        }
        check_predicted(step, sub, &s.predicted)?;
        stats.integrate_s += t.elapsed().as_secs_f64();

        // Lines 5–7: neighbours at the predicted positions, once per step.
        let search_stats = find_step_neighbours(
            &mut *self.search,
            &mut self.fallback,
            &s.predicted,
            h,
            &mut self.neighbours,
            step,
            sub,
            "predicted position",
        )?;
        stats.create_hash_grid_s += search_stats.build_s();
        stats.detect_neighbours_s += search_stats.detect_s();
        let nb = &self.neighbours;
        let m = &state.masses[..];

        // Lines 8–19: Jacobi iterations with collision handling.
        let t = Instant::now();
        let inv_n = 1.0 / (state.len().max(1) as f64);
        let mut done = 0;
        loop {
            let input = PassInput {
                c: &c,
                x: &s.predicted,
                m,
                nb,
            };
            let compression =
                lambda_pass(input, &mut s.density, &mut s.lambda, &mut s.pairs) * inv_n;
            delta_pass(
                input,
                &s.lambda,
                &s.pairs,
                solids,
                radius,
                &mut s.delta_p,
                &mut s.next,
            );
            std::mem::swap(&mut s.predicted, &mut s.next);
            done += 1;
            // The stopping rule of `mean_compression_tolerance` (fixed count without it).
            let Some(tol) = p.mean_compression_tolerance else {
                if done == p.solver_iterations {
                    break;
                }
                continue;
            };
            stats.last_solve_error = compression;
            let met = compression <= tol.as_f64();
            if done >= p.solver_iterations || (met && done >= p.min_solver_iterations) {
                if !met {
                    stats.unconverged_substeps += 1;
                }
                break;
            }
        }
        stats.constraint_solve_s += t.elapsed().as_secs_f64();
        stats.iterations += done;

        // Lines 20–24: velocity update, vorticity confinement, XSPH, position update.
        let t = Instant::now();
        let x_old = &state.positions[..];
        let x = &s.predicted[..];
        s.velocity
            .par_iter_mut()
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(i, v)| *v = (x[i] - x_old[i]) * inv_dt);
        let vort_on = p.vorticity_epsilon > R::zero();
        let xsph_on = p.xsph_c > R::zero();
        let v = &s.velocity[..];
        // Densities at the final positions (for the statistics and the state) and eq. 15;
        // without vorticity confinement, XSPH (eq. 17) in the same pass (it needs the same
        // Poly6 values and nothing else of this pass).
        let (eps_v, xsph_c) = (p.vorticity_epsilon, p.xsph_c);
        s.density
            .par_iter_mut()
            .zip(s.vorticity.par_iter_mut())
            .zip(s.vorticity_norm.par_iter_mut())
            .zip(s.velocity_new.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_LEN)
            .for_each(|(i, (((rho, w), wn), vn))| {
                let (xi, vi) = (x[i], v[i]);
                let mut sum_w = m[i] * c.w0;
                let mut omega = Vec3::zeros();
                let mut xsph = Vec3::zeros();
                for &j in nb.neighbours(i) {
                    let j = j as usize;
                    let r = xi - x[j];
                    let wij = c.poly6.value_r2(r.norm_squared());
                    sum_w += m[j] * wij;
                    if vort_on {
                        // v_ij × ∇_{p_j} W(p_i − p_j) = ∇W(p_i − p_j) × v_ij, volume m_j/ρ0.
                        omega += c.spiky.gradient(&r).cross(&(v[j] - vi)) * (m[j] * c.inv_rho0);
                    } else if xsph_on {
                        xsph += (v[j] - vi) * (m[j] * c.inv_rho0 * wij);
                    }
                }
                *rho = sum_w;
                *w = omega;
                *wn = omega.norm();
                if !vort_on {
                    *vn = vi + xsph * xsph_c;
                }
            });
        if vort_on {
            let (omega, omega_norm) = (&s.vorticity[..], &s.vorticity_norm[..]);
            s.velocity_new
                .par_iter_mut()
                .enumerate()
                .with_min_len(MIN_LEN)
                .for_each(|(i, vn)| {
                    let (xi, vi) = (x[i], v[i]);
                    let mut eta = Vec3::zeros();
                    let mut xsph = Vec3::zeros();
                    for &j in nb.neighbours(i) {
                        let j = j as usize;
                        let r = xi - x[j];
                        let vol = m[j] * c.inv_rho0;
                        // η = ∇|ω| (SPH gradient, difference form).
                        eta += c.spiky.gradient(&r) * (vol * (omega_norm[j] - omega_norm[i]));
                        if xsph_on {
                            xsph += (v[j] - vi) * (vol * c.poly6.value_r2(r.norm_squared()));
                        }
                    }
                    let mut out = vi + xsph * xsph_c;
                    let len = eta.norm();
                    if len > R::zero() {
                        out += (eta / len).cross(&omega[i]) * (eps_v * dt);
                    }
                    *vn = out;
                });
        }

        // Divergence checks before anything is written to the state.
        check_divergence(step, sub, x, &s.velocity_new, solids, h)?;
        state.positions.copy_from_slice(x);
        state.velocities.copy_from_slice(&s.velocity_new);
        state.densities.copy_from_slice(&s.density);
        stats.velocity_update_s += t.elapsed().as_secs_f64();
        stats.substeps += 1;
        stats.neighbour_pairs = nb.pair_count();
        Ok(())
    }

    /// Density ratios and kinetic energy, summed over fixed chunks (independent of the
    /// thread count).
    fn end_of_step_stats(&mut self, state: &ParticleSet<R>, stats: &mut StepStats) {
        density_energy_stats(
            state,
            self.params.rest_density,
            &mut self.scratch.partials,
            stats,
        );
    }
}
