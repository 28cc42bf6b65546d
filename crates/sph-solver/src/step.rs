//! The in-step plumbing every particle solver needs: state checks, the neighbour search
//! inside a step, periodic reordering by cell, the blow-up checks made before a substep's
//! result is written, and the end-of-step statistics.
//!
//! Every parallel loop here writes one particle's values or reduces over fixed chunks, so
//! results do not depend on the number of threads.

use std::time::Instant;

use neighbour_search::{
    CellOrder, CellSorter, HashedGrid, Method, NeighbourLists, NeighbourSearch, SearchError,
    SearchStats,
};
use rayon::prelude::*;
use sph_core::{ParticleSet, PermutationScratch, Real, Vec3};
use sph_kernels::Kernel;

use crate::{Boundary, CommonParams, SolverError, StepStats};

/// Smallest number of particles handed to one rayon task.
pub const MIN_LEN: usize = 256;
/// Particles per partial sum of the end-of-step statistics (fixed, so that the statistics do
/// not depend on the number of threads).
pub const REDUCE_CHUNK: usize = 4096;

/// Updates two per-particle arrays in parallel, `f(i, &mut a[i], &mut b[i])` for every
/// particle `i`, and returns the sum of what `f` returns, added up in fixed chunks of
/// [`REDUCE_CHUNK`] particles (one entry of `partials` each, which must have
/// `a.len().div_ceil(REDUCE_CHUNK)` entries) and then in chunk order, so that the sum does
/// not depend on the number of threads. The iterative solvers use it for an update and the
/// residual of its stopping rule in one pass.
pub fn par_update_sum<A: Send, B: Send>(
    a: &mut [A],
    b: &mut [B],
    partials: &mut [f64],
    f: impl Fn(usize, &mut A, &mut B) -> f64 + Sync,
) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    debug_assert_eq!(partials.len(), a.len().div_ceil(REDUCE_CHUNK));
    a.par_chunks_mut(REDUCE_CHUNK)
        .zip(b.par_chunks_mut(REDUCE_CHUNK))
        .zip(partials.par_iter_mut())
        .enumerate()
        .for_each(|(ch, ((ac, bc), part))| {
            let base = ch * REDUCE_CHUNK;
            *part = ac
                .iter_mut()
                .zip(bc.iter_mut())
                .enumerate()
                .map(|(o, (x, y))| f(base + o, x, y))
                .sum();
        });
    partials.iter().sum()
}

/// The first non-finite axis of `v`.
#[inline]
pub fn non_finite<R: Real>(v: &Vec3<R>) -> Option<usize> {
    (0..3).find(|&a| !v[a].is_finite_value())
}

/// Whether an axis of `v` is not finite: [`non_finite`] without its early exit (no branch),
/// for the passes of [`first_where`].
#[inline]
fn any_non_finite<R: Real>(v: &Vec3<R>) -> bool {
    !(v.x.is_finite_value() & v.y.is_finite_value() & v.z.is_finite_value())
}

/// Checks a state on entry to a step: array lengths, finite positions and velocities
/// ([`SolverError::InvalidState`]) and finite positive masses ([`SolverError::InvalidMass`]),
/// naming the first offending particle.
pub fn check_state<R: Real>(state: &ParticleSet<R>) -> Result<(), SolverError> {
    let n = state.positions.len();
    let lengths_match = [
        state.velocities.len(),
        state.masses.len(),
        state.densities.len(),
    ]
    .iter()
    .all(|&len| len == n);
    let not_finite = any_non_finite::<R>;
    // The fast pass only says whether something is wrong; `validate` names it.
    if !lengths_match
        || first_where(&state.positions, not_finite).is_some()
        || first_where(&state.velocities, not_finite).is_some()
    {
        state.validate()?;
    }
    check_masses(&state.masses)
}

/// The index of the first element of `items` for which `bad` holds (`None` if none does),
/// as rayon's `position_first` but at the cost of a plain pass: `bad` is evaluated for every
/// element of fixed chunks of [`REDUCE_CHUNK`] (without an early exit, so that the pass has
/// no branch per element), the chunks in parallel, and only the first chunk that holds a bad
/// element is scanned again for its index. For the checks made on every step, where nothing
/// is found.
pub fn first_where<T: Sync>(items: &[T], bad: impl Fn(&T) -> bool + Sync) -> Option<usize> {
    first_index_where(items.len(), |i| bad(&items[i]))
}

/// [`first_where`] over the indices `0..len`: the first `i` for which `bad(i)` holds.
pub fn first_index_where(len: usize, bad: impl Fn(usize) -> bool + Sync) -> Option<usize> {
    let chunks = len.div_ceil(REDUCE_CHUNK);
    let chunk = (0..chunks).into_par_iter().position_first(|c| {
        let end = ((c + 1) * REDUCE_CHUNK).min(len);
        (c * REDUCE_CHUNK..end).fold(false, |any, i| any | bad(i))
    })?;
    (chunk * REDUCE_CHUNK..len).find(|&i| bad(i))
}

/// Finite, positive masses ([`SolverError::InvalidMass`] naming the first other one).
pub fn check_masses<R: Real>(masses: &[R]) -> Result<(), SolverError> {
    match first_where(masses, |&m| !(m.is_finite_value() && m > R::zero())) {
        Some(index) => Err(SolverError::InvalidMass {
            index,
            value: masses[index].as_f64(),
        }),
        None => Ok(()),
    }
}

/// A [`SolverError::BlowUp`] of `solver` in call `step` at `particle`.
pub fn blow_up(solver: &'static str, step: u64, particle: usize, reason: String) -> SolverError {
    SolverError::BlowUp {
        solver,
        step,
        particle,
        reason,
    }
}

/// The neighbour search of a solver: the configured method, a hashed-grid fallback for
/// domains the cell-start grid refuses (it allocates on first use), and the lists.
pub struct StepNeighbours<R: Real> {
    method: Method,
    search: Box<dyn NeighbourSearch<R>>,
    fallback: Option<HashedGrid<R>>,
    lists: NeighbourLists,
}

impl<R: Real> std::fmt::Debug for StepNeighbours<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StepNeighbours")
            .field("method", &self.method)
            .field("pairs", &self.lists.pair_count())
            .finish()
    }
}

impl<R: Real> StepNeighbours<R> {
    /// A search with `method` and empty lists.
    pub fn new(method: Method) -> Self {
        Self {
            method,
            search: method.build::<R>(),
            fallback: None,
            lists: NeighbourLists::new(),
        }
    }

    /// The method in use.
    pub fn method(&self) -> Method {
        self.method
    }

    /// Switches to `method` (no-op when unchanged).
    pub fn set_method(&mut self, method: Method) {
        if method != self.method {
            self.method = method;
            self.search = method.build::<R>();
        }
    }

    /// The lists of the last search (within `h`, excluding the particle itself).
    pub fn lists(&self) -> &NeighbourLists {
        &self.lists
    }

    /// Finds the neighbours of `positions` within `h`, falling back to a hashed grid when the
    /// cell-start grid refuses the domain.
    pub fn find(&mut self, positions: &[Vec3<R>], h: R) -> Result<SearchStats, SearchError> {
        self.find_active(positions, positions.len(), h)
    }

    /// [`StepNeighbours::find`] with the positions `active..` passive
    /// ([`NeighbourSearch::search_active`]): they list only the positions `..active` (a
    /// solver's boundary particles after its particles: no boundary–boundary pair, which no
    /// sum reads), and are listed by them. `active >= positions.len()`: every pair.
    pub fn find_active(
        &mut self,
        positions: &[Vec3<R>],
        active: usize,
        h: R,
    ) -> Result<SearchStats, SearchError> {
        match self
            .search
            .search_active(positions, active, h, &mut self.lists)
        {
            Ok(()) => Ok(self.search.stats()),
            Err(SearchError::DomainTooLarge { .. }) => {
                let fb = self.fallback.get_or_insert_with(HashedGrid::new);
                fb.search_active(positions, active, h, &mut self.lists)?;
                Ok(fb.stats())
            }
            Err(e) => Err(e),
        }
    }

    /// [`StepNeighbours::find`] inside call `step`, substep `sub` of `solver`: a position the
    /// grid cannot hold (non-finite, or a cell coordinate overflowing `i32`) is a
    /// [`SolverError::BlowUp`] naming the particle and `what` the positions are.
    pub fn find_in_step(
        &mut self,
        positions: &[Vec3<R>],
        h: R,
        at: StepAt,
        what: &str,
    ) -> Result<SearchStats, SolverError> {
        self.find_active_in_step(positions, positions.len(), h, at, what)
    }

    /// [`StepNeighbours::find_active`] inside a step, with the errors of
    /// [`StepNeighbours::find_in_step`].
    pub fn find_active_in_step(
        &mut self,
        positions: &[Vec3<R>],
        active: usize,
        h: R,
        at: StepAt,
        what: &str,
    ) -> Result<SearchStats, SolverError> {
        self.find_active(positions, active, h).map_err(|e| match e {
            SearchError::NonFinitePosition { index, .. }
            | SearchError::CellCoordinateOverflow { index, .. } => blow_up(
                at.solver,
                at.step,
                index,
                format!(
                    "substep {}: {what} {:?} is out of the range of the neighbour grid",
                    at.substep, positions[index]
                ),
            ),
            e => e.into(),
        })
    }
}

/// The SPH density `Σ_j m_j W(x_i − x_j) + ρ0 Ψ(x_i)` of particle `i` at positions `x`
/// (kernel `kernel`, self term `m_i W(0)` included, the neighbours of `nb`; `Ψ` of a
/// boundary that takes part in the density, none when `volume` is `None`).
#[inline]
pub fn density_at<R: Real, K: Kernel<R>>(
    kernel: &K,
    rest_density: R,
    x: &[Vec3<R>],
    m: &[R],
    nb: &NeighbourLists,
    volume: Option<&dyn Boundary<R>>,
    i: usize,
) -> R {
    let xi = x[i];
    let mut sum = m[i] * kernel.value(R::zero());
    for &j in nb.neighbours(i) {
        let j = j as usize;
        sum += m[j] * kernel.value_r2((xi - x[j]).norm_squared());
    }
    if let Some(b) = volume {
        sum += rest_density * b.sample(&xi).volume;
    }
    sum
}

/// Where in a run a check happens: the solver, its `step` call (0-based) and the substep.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepAt {
    /// The solver's name.
    pub solver: &'static str,
    /// 0-based count of `step` calls.
    pub step: u64,
    /// 0-based substep within the call.
    pub substep: usize,
}

/// A non-finite predicted position is a [`SolverError::BlowUp`] naming the first such
/// particle.
pub fn check_predicted<R: Real>(at: StepAt, predicted: &[Vec3<R>]) -> Result<(), SolverError> {
    match first_where(predicted, any_non_finite) {
        Some(i) => Err(blow_up(
            at.solver,
            at.step,
            i,
            format!(
                "substep {}: predicted position {:?} is not finite",
                at.substep, predicted[i]
            ),
        )),
        None => Ok(()),
    }
}

/// The divergence checks of a substep, before anything is written to the state: a non-finite
/// final position `x` or velocity `v`, or a position more than `h` inside a solid of the
/// boundary, is a [`SolverError::BlowUp`] naming the first such particle.
pub fn check_divergence<R: Real>(
    at: StepAt,
    x: &[Vec3<R>],
    v: &[Vec3<R>],
    boundary: &dyn Boundary<R>,
    h: R,
) -> Result<(), SolverError> {
    check_divergence_cleared(at, x, v, boundary, h, None)
}

/// [`check_divergence`], with each particle's lower bound on its distance to the solids
/// (`clearance`, one per position; see [`crate::boundary::ContactGuard`]): a particle whose
/// bound is at least `−h` cannot be more than `h` inside a solid, so its distances are not
/// evaluated. The same verdict and the same error as [`check_divergence`].
pub fn check_divergence_cleared<R: Real>(
    at: StepAt,
    x: &[Vec3<R>],
    v: &[Vec3<R>],
    boundary: &dyn Boundary<R>,
    h: R,
    clearance: Option<&[R]>,
) -> Result<(), SolverError> {
    let first_x = first_where(x, any_non_finite);
    let first_v = first_where(v, any_non_finite);
    if let Some(i) = first_x.into_iter().chain(first_v).min() {
        return Err(blow_up(
            at.solver,
            at.step,
            i,
            format!(
                "substep {}: position {:?} or velocity {:?} is not finite",
                at.substep, x[i], v[i]
            ),
        ));
    }
    let solids = boundary.solids();
    if solids.is_empty() {
        return Ok(());
    }
    let margin = -h;
    if let Some(c) = clearance {
        assert_eq!(c.len(), x.len(), "one distance bound per position");
    }
    // A bound of at least −h clears a particle (a NaN bound proves nothing).
    let cleared = |i: usize| clearance.is_some_and(|c| c[i] >= margin);
    let inside = |xi: &Vec3<R>| solids.iter().any(|sd| sd.signed_distance(xi) < margin);
    if let Some(i) = first_index_where(x.len(), |i| !cleared(i) && inside(&x[i])) {
        let (k, d) = solids
            .iter()
            .enumerate()
            .map(|(k, sd)| (k, sd.signed_distance(&x[i])))
            .find(|&(_, d)| d < margin)
            .unwrap_or((0, R::zero()));
        return Err(blow_up(
            at.solver,
            at.step,
            i,
            format!(
                "substep {}: position {:?} is {} m inside solid {k} (more than h = {})",
                at.substep,
                x[i],
                -d.as_f64(),
                h.as_f64()
            ),
        ));
    }
    Ok(())
}

/// Density ratios and kinetic energy of `state` into `stats`, summed over fixed chunks of
/// [`REDUCE_CHUNK`] particles (`partials` is resized to one entry per chunk), so that the
/// result does not depend on the number of threads.
pub fn density_energy_stats<R: Real>(
    state: &ParticleSet<R>,
    rest_density: R,
    partials: &mut Vec<[f64; 3]>,
    stats: &mut StepStats,
) {
    let n = state.len();
    if n == 0 {
        return;
    }
    partials.resize(n.div_ceil(REDUCE_CHUNK), [0.0; 3]);
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

/// Periodic reordering of the particles by cell (for locality): the sorter, the last
/// permutation and its scratch buffers.
#[derive(Debug, Default)]
pub struct CellReorder<R: Real> {
    sorter: CellSorter,
    scratch: PermutationScratch<R>,
    permutation: Vec<u32>,
    reordered: bool,
}

impl<R: Real> CellReorder<R> {
    /// At the start of call `step`: every `every` calls (never when 0, nor for fewer than two
    /// particles) reorders `state` by cell of size `h` (lexicographic cell order), keeping the
    /// permutation. Returns the seconds spent (0 when it did not reorder).
    pub fn at_step(
        &mut self,
        state: &mut ParticleSet<R>,
        h: R,
        step: u64,
        every: usize,
    ) -> Result<f64, SolverError> {
        self.reordered = false;
        let every = every as u64;
        if every == 0 || !step.is_multiple_of(every) || state.len() < 2 {
            return Ok(0.0);
        }
        let t = Instant::now();
        let perm = self
            .sorter
            .permutation(&state.positions, h, CellOrder::Lexicographic)?;
        self.permutation.clear();
        self.permutation.extend_from_slice(perm);
        state.permute(&self.permutation, &mut self.scratch)?;
        self.reordered = true;
        Ok(t.elapsed().as_secs_f64())
    }

    /// The permutation of the last [`CellReorder::at_step`] (`new[k] = old[perm[k]]`), or
    /// `None` if it did not reorder.
    pub fn last_permutation(&self) -> Option<&[u32]> {
        self.reordered.then_some(&self.permutation[..])
    }
}

/// The phases [`begin_frame`] and [`end_frame`] time, as indices into the solver's
/// phase list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FramePhases {
    /// Input checks (the solver's "integrate" phase).
    pub checks: usize,
    /// Reordering by cell.
    pub reorder: usize,
    /// End-of-frame statistics (the solver's "velocity update" phase).
    pub statistics: usize,
}

/// The start of a solver's frame (call `step`): checks `state` ([`check_state`]) and
/// reorders it by cell every `common.reorder_every` calls, timing both into `stats`.
pub fn begin_frame<R: Real>(
    state: &mut ParticleSet<R>,
    reorder: &mut CellReorder<R>,
    common: &CommonParams<R>,
    step: u64,
    phases: FramePhases,
    stats: &mut StepStats,
) -> Result<(), SolverError> {
    let t = Instant::now();
    check_state(state)?;
    stats.phases.add(phases.checks, t.elapsed().as_secs_f64());
    let secs = reorder.at_step(state, common.support_radius, step, common.reorder_every)?;
    stats.phases.add(phases.reorder, secs);
    stats.reordered = reorder.last_permutation().is_some();
    Ok(())
}

/// The end of a solver's frame: the density and energy statistics of `state`
/// ([`density_energy_stats`]), timed into `stats`.
pub fn end_frame<R: Real>(
    state: &ParticleSet<R>,
    rest_density: R,
    partials: &mut Vec<[f64; 3]>,
    phases: FramePhases,
    stats: &mut StepStats,
) {
    let t = Instant::now();
    density_energy_stats(state, rest_density, partials, stats);
    stats
        .phases
        .add(phases.statistics, t.elapsed().as_secs_f64());
}

#[cfg(test)]
mod tests {
    use super::{par_update_sum, REDUCE_CHUNK};

    /// Every element is updated once with its own index, and the sum is the chunked
    /// sequential sum, bitwise the same on 1 and 3 threads.
    #[test]
    fn par_update_sum_updates_all_and_sums_in_chunks() {
        let n = 3 * REDUCE_CHUNK + 17;
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut a = vec![0usize; n];
                let mut b = vec![0.0f64; n];
                let mut partials = vec![0.0; n.div_ceil(REDUCE_CHUNK)];
                let total = par_update_sum(&mut a, &mut b, &mut partials, |i, x, y| {
                    *x = i;
                    *y = 0.1 * i as f64;
                    1.0 / (1.0 + i as f64)
                });
                (a, b, total)
            })
        };
        let (a, b, total) = run(1);
        assert!(a.iter().enumerate().all(|(i, &x)| x == i));
        assert!(b.iter().enumerate().all(|(i, &y)| y == 0.1 * i as f64));
        let expect: f64 = (0..n.div_ceil(REDUCE_CHUNK))
            .map(|c| {
                (c * REDUCE_CHUNK..((c + 1) * REDUCE_CHUNK).min(n))
                    .map(|i| 1.0 / (1.0 + i as f64))
                    .sum::<f64>()
            })
            .sum();
        assert_eq!(total.to_bits(), expect.to_bits());
        assert_eq!(run(3).2.to_bits(), total.to_bits());
    }
}
