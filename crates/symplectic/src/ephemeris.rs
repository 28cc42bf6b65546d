//! The planets' trajectory as a smooth function of time, for test particles that live on
//! their own clocks.

use serde::{Deserialize, Serialize};

use std::ops::{Add, Mul, Sub};

use crate::lanes::{Mask, LANES, V, V3};
use crate::{Integrator, Planets, SymplecticError, Vec3, WorkCounters};

/// Largest number of planet steps an [`Ephemeris`] covers (2⁵²: its grid times `t₀ + kτ` stay
/// exact, and 4.5·10¹⁵ steps of a year would take longer than anyone waits).
const MAX_GRID_STEPS: f64 = 4_503_599_627_370_496.0;

/// Barycentric positions, velocities and accelerations of the Sun (index 0) and the planets
/// (1..=n) at one time, with `G m` of each body. Filled by [`Ephemeris::bodies_at`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BodyStates {
    /// Time of the states.
    pub time: f64,
    /// `G m_j` of each body (Sun first).
    pub gm: Vec<f64>,
    /// Barycentric positions.
    pub positions: Vec<Vec3>,
    /// Barycentric velocities (the exact time derivative of `positions`).
    pub velocities: Vec<Vec3>,
    /// Barycentric accelerations (the exact time derivative of `velocities`).
    pub accelerations: Vec<Vec3>,
}

impl BodyStates {
    fn resize(&mut self, bodies: usize) {
        self.gm.resize(bodies, 0.0);
        self.positions.resize(bodies, Vec3::zeros());
        self.velocities.resize(bodies, Vec3::zeros());
        self.accelerations.resize(bodies, Vec3::zeros());
    }

    /// `G M`, the total of `G m_j`.
    pub fn total_gm(&self) -> f64 {
        self.gm.iter().sum()
    }
}

/// The planets integrated on a fixed grid of times `t₀ + kτ` by a symplectic map, and
/// interpolated in between for the test particles.
///
/// Chegodaeva (2004) integrates the test particles separately from the planets and obtains
/// the planets at a particle's own time `T_part` by advancing them from their last grid time
/// `T_pl` (eqs. 33–34: the Kepler part for `T_part − T_pl`, then the interaction and Sun parts
/// for `T_part − T_pl + Δt/2`). **Deviation (documented choice):** we interpolate instead.
/// Each grid state stores the barycentric positions, velocities and Newtonian accelerations of
/// every body, and the trajectory between two grid times is the quintic Hermite polynomial
/// that matches all three at both ends. The particle then sees a planet trajectory that is
/// smooth (C² across grid points) and whose velocity is *exactly* the derivative of its
/// position, so the particle's extended Hamiltonian `H + p₄` is an exact invariant of the
/// particle's continuous dynamics and its drift measures only the particle integrator's
/// error. The paper's recipe gives a trajectory that is discontinuous in velocity at grid
/// points and whose `dQ/dt` of eq. 33 is not the derivative of its `Q`.
///
/// **One trajectory for every reader.** This interpolant is *the* planets' trajectory of a
/// [`Population`](crate::Population): the map reads it at its kicks and the encounter mode
/// ([`encounter`](crate::encounter)) at every substep of its integrator, so that a switch
/// and a hand-back change nothing the comet feels. Its accuracy is that of the planets in a
/// close encounter; measured (`cargo run --release -p symplectic --example
/// ephemeris_accuracy`, 2026-12-05) as the largest distance, over two orbits of Jupiter,
/// between the interpolant and the Newtonian flow of the grid state before it (integrated by
/// Bulirsch–Stoer at 2·10⁻¹⁵ per step), for the four giants integrated by S6 at `τ`:
///
/// | τ (days) | Jupiter (AU) | Saturn (AU) | Uranus, Neptune (AU) | of which S6's one step, Jupiter |
/// | ---: | ---: | ---: | ---: | ---: |
/// | 730.5 | 5.0·10⁻⁴ | 4.9·10⁻⁶ | 6.3·10⁻⁸ | 1.5·10⁻⁶ |
/// | 365.25 | 8.3·10⁻⁶ | 1.0·10⁻⁷ | 4.2·10⁻⁹ | 1.4·10⁻⁸ |
/// | 182.625 | 1.3·10⁻⁷ | 2.3·10⁻⁹ | 5.5·10⁻¹⁰ | 7.2·10⁻¹⁰ |
/// | 121.75 | 1.2·10⁻⁸ | 4.5·10⁻¹⁰ | 1.6·10⁻¹⁰ | 1.8·10⁻¹⁰ |
/// | 91.3125 | 2.1·10⁻⁹ | 1.8·10⁻¹⁰ | 6.9·10⁻¹¹ | 7.3·10⁻¹¹ |
///
/// The interpolant's error goes as `τ⁶` (`≈ (ωτ)⁶/46080` of the orbit radius for a circular
/// orbit, `ω` the mean motion; three times that for Jupiter, whose perihelion speed sets
/// it); the S6 map's own one-step error (the flow at the interval's end against the next
/// grid state) as `τ⁷`, and no interpolant of a grid can be nearer the flow than that. A
/// higher-order interpolant of the 730.5 d grid is therefore no way to 10⁻⁸ AU (S6 alone
/// is 1.5·10⁻⁶ AU off); the planet step is: 91.3125 d (a quarter of a year, the step of the
/// shipped Centaur population) puts Jupiter within 2.1·10⁻⁹ AU of the flow
/// (`tests/ephemeris_accuracy.rs` holds it under 10⁻⁸ AU). Its cost: eight planet steps
/// instead of one per 730.5 d, about 1 µs each (4·10⁶ steps, some 4 s, per simulated Myr,
/// shared by the whole population), and nothing per particle step (one interpolation as
/// before). Memory: a grid state is 360 bytes for five bodies; a whole Myr would be
/// 1.4 GB at this step, but an ephemeris retains only its window
/// ([`Ephemeris::discard_before`]; a population about three windows of
/// [`DEFAULT_WINDOW_STEPS`](crate::DEFAULT_WINDOW_STEPS) states, 280 kB), whatever the span.
///
/// The grid is a window: states older than needed are dropped with
/// [`Ephemeris::discard_before`]; newer ones are computed on demand.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ephemeris {
    planets: Planets,
    integrator: Integrator,
    /// Time of grid point 0.
    start_time: f64,
    /// Index (from the start) of the first stored grid state.
    first_index: u64,
    /// Flattened grid states, `9 (n+1)` values each: positions, velocities, accelerations;
    /// the retained window starts at `offset` (the front is compacted now and then).
    grid: Vec<f64>,
    offset: usize,
    /// Work of the grid states' accelerations and of the interpolations (the planets' own
    /// steps are counted in `planets`).
    #[serde(default)]
    work: WorkCounters,
}

impl Ephemeris {
    /// Starts the ephemeris at the planets' current time; `integrator` (its step `τ > 0` is the
    /// grid spacing) advances them.
    pub fn new(planets: Planets, integrator: Integrator) -> Result<Self, SymplecticError> {
        let tau = integrator.step_size();
        if !(tau.is_finite() && tau > 0.0) {
            return Err(SymplecticError::InvalidParameter {
                name: "planet step",
                value: tau,
                reason: "must be finite and > 0 for an ephemeris",
            });
        }
        let mut e = Self {
            start_time: planets.time(),
            planets,
            integrator,
            first_index: 0,
            grid: Vec::new(),
            offset: 0,
            work: WorkCounters::default(),
        };
        e.push_state();
        Ok(e)
    }

    fn stride(&self) -> usize {
        9 * (self.planets.len() + 1)
    }

    /// The planets at the newest grid time.
    pub fn planets(&self) -> &Planets {
        &self.planets
    }

    /// Work done so far: the planets' steps, the accelerations stored with each grid state
    /// (`n(n+1)/2` force evaluations) and the interpolations ([`Ephemeris::bodies_at`]).
    pub fn work(&self) -> WorkCounters {
        self.work + self.planets.work()
    }

    /// The planets' integrator.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    /// Grid spacing `τ`.
    pub fn grid_step(&self) -> f64 {
        self.integrator.step_size()
    }

    /// Time of grid point `k`.
    pub fn grid_time(&self, k: u64) -> f64 {
        self.start_time + k as f64 * self.grid_step()
    }

    /// Number of planet steps taken so far.
    pub fn planet_steps(&self) -> u64 {
        self.first_index + ((self.grid.len() - self.offset) / self.stride()) as u64 - 1
    }

    /// Appends the barycentric state of every body at the planets' current state.
    fn push_state(&mut self) {
        push_state(&self.planets, &mut self.grid, &mut self.work);
    }

    /// Integrates the planets until the grid covers time `t`.
    pub fn extend_to(&mut self, t: f64) -> Result<(), SymplecticError> {
        let extension = self.extension(t)?;
        self.append(extension)
    }

    /// The grid states from the newest one until `t` is covered, computed from a copy of the
    /// planets without changing the ephemeris (so that the particles can read it meanwhile):
    /// [`Ephemeris::append`] adds them. Exactly the states [`Ephemeris::extend_to`] computes.
    pub(crate) fn extension(&self, t: f64) -> Result<Extension, SymplecticError> {
        // Grid times are start + k·τ with an integer k: exact only below 2⁵³ steps, and a
        // request that far out would run for ages. Refuse it by name instead.
        let steps_needed = (t - self.start_time) / self.grid_step();
        if steps_needed.is_nan() || steps_needed >= MAX_GRID_STEPS {
            return Err(SymplecticError::InvalidParameter {
                name: "ephemeris time",
                value: t,
                reason: "beyond 2^52 planet steps from the start (or not finite): grid times would lose exactness",
            });
        }
        let mut planets = self.planets.clone();
        let mut states = Vec::new();
        let mut work = WorkCounters::default();
        let mut step = self.planet_steps();
        // The grid states asked for, allocated up front and fallibly: a planet step far
        // shorter than the particles' steps asks for more than the memory holds.
        let new_states = ((t - self.grid_time(step)) / self.grid_step())
            .ceil()
            .max(0.0);
        crate::guard::try_reserve(
            &mut states,
            (new_states as usize).saturating_mul(self.stride()),
            "the planets' ephemeris grid (planet step too short for the particles' steps)",
        )?;
        while self.grid_time(step) < t {
            if step.is_multiple_of(1024) {
                crate::guard::check_stop("integrating the planets' ephemeris")?;
            }
            if let Err(e) = self.integrator.step(&mut planets) {
                return Ok(Extension {
                    planets,
                    states,
                    work,
                    error: Some(e),
                });
            }
            if let Some(body) = planets.first_non_finite() {
                let error = Some(SymplecticError::BlowUp { step, body });
                return Ok(Extension {
                    planets,
                    states,
                    work,
                    error,
                });
            }
            // Keep the planets' clock on the grid (no accumulation of rounding).
            planets.set_time(self.grid_time(step + 1));
            push_state(&planets, &mut states, &mut work);
            step += 1;
        }
        Ok(Extension {
            planets,
            states,
            work,
            error: None,
        })
    }

    /// Appends the states of an [`Ephemeris::extension`] computed from this ephemeris's newest
    /// state (and the planets where they stopped); returns the planets' error if the
    /// extension stopped on one.
    pub(crate) fn append(&mut self, extension: Extension) -> Result<(), SymplecticError> {
        self.planets = extension.planets;
        self.grid.extend_from_slice(&extension.states);
        self.work += extension.work;
        extension.error.map_or(Ok(()), Err)
    }

    /// Drops the grid states no longer needed for times `>= t`.
    pub fn discard_before(&mut self, t: f64) {
        let stride = self.stride();
        while self.grid.len() - self.offset >= 2 * stride
            && self.grid_time(self.first_index + 1) <= t
        {
            self.offset += stride;
            self.first_index += 1;
        }
        if self.offset > 64 * stride && 2 * self.offset > self.grid.len() {
            self.grid.drain(..self.offset);
            self.offset = 0;
        }
    }

    /// Fills `out` with the bodies' barycentric states at time `t`, integrating the planets
    /// forward if needed. Errors if `t` precedes the retained window.
    pub fn bodies_at(&mut self, t: f64, out: &mut BodyStates) -> Result<(), SymplecticError> {
        if !t.is_finite() {
            return Err(SymplecticError::InvalidParameter {
                name: "ephemeris time",
                value: t,
                reason: "must be finite",
            });
        }
        self.extend_to(t)?;
        self.check_retained(t)?;
        self.work.interpolations += 1;
        self.interpolate_unchecked(t, out, true);
        Ok(())
    }

    /// Fills `out` with the bodies' barycentric states at time `t` without integrating the
    /// planets: the read-only form of [`Ephemeris::bodies_at`], which many threads can call
    /// at once on one shared ephemeris. The values are bit for bit those of
    /// [`Ephemeris::bodies_at`] (the same grid, the same interpolant). With
    /// `accelerations = false` the accelerations are left as they were (the barycentric
    /// variant does not use them). Errors with [`SymplecticError::BeyondEphemeris`] if `t`
    /// lies after the newest grid time, and names `t` if it precedes the retained window.
    /// Does not count the interpolation (the caller does).
    pub fn interpolate(
        &self,
        t: f64,
        out: &mut BodyStates,
        accelerations: bool,
    ) -> Result<(), SymplecticError> {
        self.view().interpolate(t, out, accelerations)
    }

    /// The grid as the interpolation reads it, with what it needs per call (the newest index
    /// and time, `1/τ`) computed once: for many interpolations between two extensions.
    pub(crate) fn view(&self) -> GridView<'_> {
        let tau = self.grid_step();
        let last = self.planet_steps();
        GridView {
            ephemeris: self,
            tau,
            inv_tau: 1.0 / tau,
            last,
            newest: self.grid_time(last),
            oldest: self.grid_time(self.first_index),
        }
    }

    /// Time of the oldest retained grid state.
    pub fn oldest_time(&self) -> f64 {
        self.grid_time(self.first_index)
    }

    /// Time of the newest grid state.
    pub fn newest_time(&self) -> f64 {
        self.grid_time(self.planet_steps())
    }

    /// Number of grid states retained (each `9 (n+1)` values of 8 bytes).
    pub fn retained_states(&self) -> usize {
        (self.grid.len() - self.offset) / self.stride()
    }

    fn check_retained(&self, t: f64) -> Result<(), SymplecticError> {
        let rel = (t - self.start_time) / self.grid_step();
        if rel < self.first_index as f64 {
            return Err(SymplecticError::InvalidParameter {
                name: "ephemeris time",
                value: t,
                reason:
                    "precedes the retained window of planet states (discarded or before the start)",
            });
        }
        Ok(())
    }

    /// The interpolation proper; `t` must lie in the retained window.
    fn interpolate_unchecked(&self, t: f64, out: &mut BodyStates, accelerations: bool) {
        self.view().interpolate_unchecked(t, out, accelerations);
    }

    fn vec_at(&self, o: usize) -> Vec3 {
        Vec3::from_column_slice(&self.grid[o..o + 3])
    }
}

/// [`Ephemeris::view`]: the retained grid with the per-call constants of the interpolation.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GridView<'a> {
    ephemeris: &'a Ephemeris,
    tau: f64,
    inv_tau: f64,
    /// Index of the newest grid state, and its time.
    last: u64,
    newest: f64,
    /// Time of the oldest retained grid state.
    oldest: f64,
}

impl GridView<'_> {
    /// The grid step `τ`.
    pub(crate) fn step(&self) -> f64 {
        self.tau
    }

    /// Index of the grid point at or before `t` (rounding corrected against the grid times).
    #[inline(always)]
    fn grid_index(&self, t: f64) -> u64 {
        let e = self.ephemeris;
        let rel = (t - e.start_time) * self.inv_tau;
        let mut k = (rel.max(0.0) as u64).clamp(e.first_index, self.last);
        if k > e.first_index && t < e.grid_time(k) {
            k -= 1;
        }
        if k < self.last && e.grid_time(k + 1) <= t {
            k += 1;
        }
        k
    }

    /// [`Ephemeris::interpolate`].
    pub(crate) fn interpolate(
        &self,
        t: f64,
        out: &mut BodyStates,
        accelerations: bool,
    ) -> Result<(), SymplecticError> {
        if t > self.newest {
            return Err(SymplecticError::BeyondEphemeris {
                time: t,
                newest: self.newest,
            });
        }
        if !t.is_finite() {
            return Err(SymplecticError::InvalidParameter {
                name: "ephemeris time",
                value: t,
                reason: "must be finite",
            });
        }
        if t < self.oldest {
            return Err(SymplecticError::InvalidParameter {
                name: "ephemeris time",
                value: t,
                reason:
                    "precedes the retained window of planet states (discarded or before the start)",
            });
        }
        self.interpolate_unchecked(t, out, accelerations);
        Ok(())
    }

    /// The interpolation proper; `t` must lie in the retained window.
    fn interpolate_unchecked(&self, t: f64, out: &mut BodyStates, accelerations: bool) {
        let (e, tau, last) = (self.ephemeris, self.tau, self.last);
        // The grid point at or before t (rounding of `rel` corrected against the grid times),
        // so that the result depends on t and the grid only, not on how far the grid reaches:
        // a time on a grid point takes that state, anything else the interval after it.
        // (`as u64` truncates: the floor of a non-negative `rel`, without a libm call.)
        let k = self.grid_index(t);
        let n1 = e.planets.len() + 1;
        out.resize(n1);
        out.time = t;
        out.gm[0] = e.planets.g() * e.planets.sun_mass();
        for (i, &m) in e.planets.masses().iter().enumerate() {
            out.gm[i + 1] = e.planets.g() * m;
        }
        let stride = e.stride();
        let base = e.offset + (k - e.first_index) as usize * stride;
        if t == e.grid_time(k) || k == last {
            // On a grid point: the stored state itself.
            for j in 0..n1 {
                let o = base + 9 * j;
                out.positions[j] = e.vec_at(o);
                out.velocities[j] = e.vec_at(o + 3);
                out.accelerations[j] = e.vec_at(o + 6);
            }
            return;
        }
        let x = (t - e.grid_time(k)) * self.inv_tau;
        let w = QuinticHermite::at(x);
        // The weights with the scaling to the unit interval folded in (the stored velocities
        // and accelerations are per day): one multiply-add per datum and component.
        let (tau2, inv_tau) = (tau * tau, self.inv_tau);
        let fold = |c: &[f64; 6], s: f64| {
            [
                c[0] * s,
                c[1] * (tau * s),
                c[2] * (tau2 * s),
                c[3] * s,
                c[4] * (tau * s),
                c[5] * (tau2 * s),
            ]
        };
        let value = fold(&w.value, 1.0);
        let first = fold(&w.first, inv_tau);
        let second = if accelerations {
            fold(&w.second, inv_tau * inv_tau)
        } else {
            [0.0; 6]
        };
        let grid = &e.grid[base..base + 2 * stride];
        let (before, after) = grid.split_at(stride);
        let (before, after) = (before.as_chunks::<9>().0, after.as_chunks::<9>().0);
        for (j, (a, b)) in before.iter().zip(after).enumerate().take(n1) {
            out.positions[j] = combine(a, b, &value);
            out.velocities[j] = combine(a, b, &first);
            if accelerations {
                out.accelerations[j] = combine(a, b, &second);
            }
        }
    }
}

impl GridView<'_> {
    /// [`GridView::interpolate`] without accelerations for the lanes in `mask`, each at its
    /// own time `t`: lane `l` of `positions[j]` and `velocities[j]`, bit for bit the scalar
    /// values (the same grid interval, weights and sums per lane). Returns the lanes whose
    /// time the view does not hold (left unchanged; the scalar path reports them).
    #[inline(always)]
    pub(crate) fn interpolate_lanes(
        &self,
        t: V,
        mask: Mask,
        positions: &mut [V3],
        velocities: &mut [V3],
    ) -> Mask {
        let (e, last) = (self.ephemeris, self.last);
        let stride = e.stride();
        let mut bad = [false; LANES];
        let mut base = [usize::MAX; LANES];
        let mut blend = [false; LANES];
        let mut x = V::splat(0.0);
        for l in 0..LANES {
            let tl = t.0[l];
            if !mask[l] {
                continue;
            }
            if !(tl <= self.newest && tl.is_finite() && tl >= self.oldest) {
                bad[l] = true;
                continue;
            }
            // GridView::interpolate_unchecked's grid point at or before t.
            let rel = (tl - e.start_time) * self.inv_tau;
            let mut k = (rel.max(0.0) as u64).clamp(e.first_index, last);
            if k > e.first_index && tl < e.grid_time(k) {
                k -= 1;
            }
            if k < last && e.grid_time(k + 1) <= tl {
                k += 1;
            }
            let b = e.offset + (k - e.first_index) as usize * stride;
            if tl == e.grid_time(k) || k == last {
                // On a grid point: the stored state itself.
                for (j, (pj, vj)) in positions.iter_mut().zip(velocities.iter_mut()).enumerate() {
                    for i in 0..3 {
                        pj[i].0[l] = e.grid[b + 9 * j + i];
                        vj[i].0[l] = e.grid[b + 9 * j + 3 + i];
                    }
                }
            } else {
                base[l] = b;
                blend[l] = true;
                x.0[l] = (tl - e.grid_time(k)) * self.inv_tau;
            }
        }
        let Some(fill) = base.iter().copied().find(|&b| b != usize::MAX) else {
            return bad;
        };
        let base = base.map(|b| if b == usize::MAX { fill } else { b });
        let w = QuinticHermite::at(x);
        let (tau, inv_tau) = (self.tau, self.inv_tau);
        let tau2 = tau * tau;
        let fold = |c: &[V; 6], s: f64| {
            [
                c[0] * s,
                c[1] * (tau * s),
                c[2] * (tau2 * s),
                c[3] * s,
                c[4] * (tau * s),
                c[5] * (tau2 * s),
            ]
        };
        let value = fold(&w.value, 1.0);
        let first = fold(&w.first, inv_tau);
        // Each lane's two grid states, body by body (one bounds check per lane and body).
        let states = base.map(|b| {
            let (before, after) = e.grid[b..b + 2 * stride].split_at(stride);
            (before.as_chunks::<9>().0, after.as_chunks::<9>().0)
        });
        let all = blend == [true; LANES];
        for (j, (pj, vj)) in positions.iter_mut().zip(velocities.iter_mut()).enumerate() {
            let (a, b) = (states.map(|s| &s.0[j]), states.map(|s| &s.1[j]));
            for i in 0..3 {
                // combine(): the six data of component i, lane by lane.
                let d = [
                    V(a.map(|x| x[i])),
                    V(a.map(|x| x[3 + i])),
                    V(a.map(|x| x[6 + i])),
                    V(b.map(|x| x[i])),
                    V(b.map(|x| x[3 + i])),
                    V(b.map(|x| x[6 + i])),
                ];
                let sum = |c: &[V; 6]| {
                    d[0] * c[0]
                        + d[1] * c[1]
                        + d[2] * c[2]
                        + d[3] * c[3]
                        + d[4] * c[4]
                        + d[5] * c[5]
                };
                let (p, v) = (sum(&value), sum(&first));
                if all {
                    (pj[i], vj[i]) = (p, v);
                } else {
                    pj[i] = V::select(blend, p, pj[i]);
                    vj[i] = V::select(blend, v, vj[i]);
                }
            }
        }
        bad
    }
}

/// Grid states computed ahead by [`Ephemeris::extension`].
pub(crate) struct Extension {
    planets: Planets,
    states: Vec<f64>,
    work: WorkCounters,
    error: Option<SymplecticError>,
}

/// Appends to `grid` the barycentric positions, velocities and accelerations of every body at
/// the state of `planets` (`9 (n+1)` values; no allocation once `grid` has its capacity),
/// counting the `n(n+1)/2` pair forces in `work`.
fn push_state(planets: &Planets, grid: &mut Vec<f64>, work: &mut WorkCounters) {
    let n = planets.len();
    let g = planets.g();
    let m0 = planets.sun_mass();
    let (sun_pos, sun_vel) = planets.sun_barycentric_state();
    let base = grid.len();
    grid.resize(base + 9 * (n + 1), 0.0);
    let body = |j: usize| base + 9 * j;
    let vec_at = |grid: &[f64], o: usize| Vec3::from_column_slice(&grid[o..o + 3]);
    grid[body(0)..body(0) + 3].copy_from_slice(sun_pos.as_slice());
    grid[body(0) + 3..body(0) + 6].copy_from_slice(sun_vel.as_slice());
    for i in 0..n {
        let m = planets.masses()[i];
        let o = body(i + 1);
        let q = planets.positions()[i] + sun_pos;
        let v = planets.momenta()[i] / m;
        grid[o..o + 3].copy_from_slice(q.as_slice());
        grid[o + 3..o + 6].copy_from_slice(v.as_slice());
    }
    let mass = |j: usize| if j == 0 { m0 } else { planets.masses()[j - 1] };
    work.force_evaluations += (n * (n + 1) / 2) as u64;
    for j in 0..=n {
        for k in j + 1..=n {
            let d = vec_at(grid, body(k)) - vec_at(grid, body(j));
            let r2 = d.norm_squared();
            let f = d * (g / (r2 * r2.sqrt()));
            let (aj, ak) = (
                vec_at(grid, body(j) + 6) + f * mass(k),
                vec_at(grid, body(k) + 6) - f * mass(j),
            );
            grid[body(j) + 6..body(j) + 9].copy_from_slice(aj.as_slice());
            grid[body(k) + 6..body(k) + 9].copy_from_slice(ak.as_slice());
        }
    }
}

/// `Σ_k c_k d_k` over the six data `d = (p₀, v₀, a₀, p₁, v₁, a₁)` of one body (`a` and `b` its
/// nine stored values at the two grid points).
#[inline(always)]
fn combine(a: &[f64; 9], b: &[f64; 9], c: &[f64; 6]) -> Vec3 {
    let mut out = [0.0; 3];
    for (i, o) in out.iter_mut().enumerate() {
        *o = a[i] * c[0]
            + a[3 + i] * c[1]
            + a[6 + i] * c[2]
            + b[i] * c[3]
            + b[3 + i] * c[4]
            + b[6 + i] * c[5];
    }
    Vec3::new(out[0], out[1], out[2])
}

/// Weights of the quintic Hermite interpolant on `[0, 1]` for the data
/// `(p₀, v₀, a₀, p₁, v₁, a₁)` (derivatives scaled to the unit interval), and of its first and
/// second derivatives.
/// Generic over `f64` and [`V`] (the same operations per lane).
struct QuinticHermite<T = f64> {
    value: [T; 6],
    first: [T; 6],
    second: [T; 6],
}

impl<T> QuinticHermite<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T> + Mul<f64, Output = T>,
    f64: Mul<T, Output = T> + Sub<T, Output = T>,
{
    #[inline(always)]
    fn at(x: T) -> Self {
        let x2 = x * x;
        let x3 = x2 * x;
        let x4 = x3 * x;
        let x5 = x4 * x;
        Self {
            value: [
                1.0 - 10.0 * x3 + 15.0 * x4 - 6.0 * x5,
                x - 6.0 * x3 + 8.0 * x4 - 3.0 * x5,
                0.5 * (x2 - 3.0 * x3 + 3.0 * x4 - x5),
                10.0 * x3 - 15.0 * x4 + 6.0 * x5,
                -4.0 * x3 + 7.0 * x4 - 3.0 * x5,
                0.5 * (x3 - 2.0 * x4 + x5),
            ],
            first: [
                -30.0 * x2 + 60.0 * x3 - 30.0 * x4,
                1.0 - 18.0 * x2 + 32.0 * x3 - 15.0 * x4,
                0.5 * (2.0 * x - 9.0 * x2 + 12.0 * x3 - 5.0 * x4),
                30.0 * x2 - 60.0 * x3 + 30.0 * x4,
                -12.0 * x2 + 28.0 * x3 - 15.0 * x4,
                0.5 * (3.0 * x2 - 8.0 * x3 + 5.0 * x4),
            ],
            second: [
                -60.0 * x + 180.0 * x2 - 120.0 * x3,
                -36.0 * x + 96.0 * x2 - 60.0 * x3,
                0.5 * (2.0 - 18.0 * x + 36.0 * x2 - 20.0 * x3),
                60.0 * x - 180.0 * x2 + 120.0 * x3,
                -24.0 * x + 84.0 * x2 - 60.0 * x3,
                0.5 * (6.0 * x - 24.0 * x2 + 20.0 * x3),
            ],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The interpolant reproduces any quintic polynomial and its two derivatives exactly.
    #[test]
    fn quintic_hermite_is_exact_for_quintics() {
        let c = [0.3, -1.2, 0.7, 2.1, -0.4, 0.9];
        let p = |x: f64| c.iter().rev().fold(0.0, |acc, &ci| acc * x + ci);
        let dp = |x: f64| (1..6).rev().fold(0.0, |acc, k| acc * x + k as f64 * c[k]);
        let ddp = |x: f64| {
            (2..6)
                .rev()
                .fold(0.0, |acc, k| acc * x + (k * (k - 1)) as f64 * c[k])
        };
        let data = [p(0.0), dp(0.0), ddp(0.0), p(1.0), dp(1.0), ddp(1.0)];
        for &x in &[0.0, 0.1, 0.37, 0.5, 0.81, 1.0] {
            let w = QuinticHermite::at(x);
            let dot = |ws: &[f64; 6]| ws.iter().zip(&data).map(|(a, b)| a * b).sum::<f64>();
            assert!((dot(&w.value) - p(x)).abs() < 1e-14, "value at {x}");
            assert!((dot(&w.first) - dp(x)).abs() < 1e-13, "first at {x}");
            assert!((dot(&w.second) - ddp(x)).abs() < 1e-12, "second at {x}");
        }
    }
}
