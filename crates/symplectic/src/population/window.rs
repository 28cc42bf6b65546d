//! The window engine of a [`Population`](super::Population): every active member steps
//! through a synchronisation window, four at a time in SIMD lanes when they apply
//! ([`crate::lanes`]), one at a time otherwise.

use std::collections::VecDeque;

use rayon::prelude::*;

use super::ends::{geometric_end, SunState};
use super::events::{CheckPoint, EventContext, EventRules};
use super::members::{DistanceFrame, PopulationMember, RemovalRules, ENCOUNTER_SEPARATION_FACTOR};
use crate::encounter::{
    regularisation, Encounter, EncounterScratch, Encounters, ENCOUNTER_STATE_LEN,
};
use crate::ephemeris::{BodyStates, Ephemeris, GridView};
use crate::lanes::{self, norm, norm_squared, KickLanes, Mask, LANES, V, V3};
use crate::particles::ParticlePiece;
use crate::particles::{KickTerms, ParticleIntegrator, TestParticle};
use crate::run::ParticleStatus;
use crate::solar_system::SUN_RADIUS_AU;
use crate::{SymplecticError, Variant, Vec3};

/// Per-thread scratch of [`Population::advance_to`](crate::Population::advance_to).
struct Worker {
    bodies: BodyStates,
    /// Time `bodies` holds (`NaN` if none).
    bodies_time: f64,
    /// The last barycentric kick's terms.
    kick: KickTerms,
    /// The encounter mode's buffers.
    encounter: EncounterScratch,
}

/// The read-only context of a window.
struct WindowContext<'a> {
    /// The planets, read through one view of the grid for the whole window.
    grid: GridView<'a>,
    integrator: ParticleIntegrator,
    rules: RemovalRules,
    /// Integration through close encounters.
    encounters: Option<Encounters>,
    /// What is recorded without removing.
    events: &'a EventRules,
    /// Jupiter's index among the bodies, if any.
    jupiter: Option<usize>,
    /// Whether every step end is checked by the scalar code (events, or the geometric end
    /// rules of [`geometric_end`]), in the encounter mode as in the map.
    every_step: bool,
    /// Whether the lanes flag every lane for the scalar checks (events, which the lanes do not
    /// evaluate); the geometric end rules are flagged by a wider test in the lanes instead
    /// ([`WindowContext::removal_lanes`]).
    flag_every_lane: bool,
    /// Radius of each planet, if known.
    radii: Vec<Option<f64>>,
    /// `(m_j/3m₀)^{1/3}` per planet.
    hill_coefficients: Vec<f64>,
    total_gm: f64,
    end: f64,
    /// `G m_j` of the Sun and the planets, as the interpolation gives them.
    gm: Vec<f64>,
    /// `μ'` of the Kepler drift when the particles go through the lanes (barycentric variant,
    /// valid `μ'`); `None`: one particle at a time ([`WindowContext::advance_member`]).
    lanes_mu: Option<f64>,
    /// Whether the lanes run as AVX code (the same operations, four `f64` per register).
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    avx: bool,
}

/// Chunks of at most this many members take turns in the lanes
/// ([`WindowContext::advance_lanes`]).
const ROTATION_MAX_MEMBERS: usize = 16 * LANES;

/// Lane steps per turn of a member in a small chunk.
const ROTATION_STEPS: u32 = 32;

/// How [`Population::advance_with`](super::Population) steps the barycentric particles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum StepPath {
    /// One at a time.
    Scalar,
    /// In lanes, compiled for AVX when the processor has it.
    Lanes,
    /// In lanes, portable code only (SSE2 on x86-64).
    #[cfg_attr(not(test), allow(dead_code))]
    PortableLanes,
}

/// Whether the processor runs AVX instructions.
fn avx_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// What one scalar step of a member did ([`WindowContext::step_member`]).
enum StepOutcome {
    /// The step was taken (the member may have been removed at its end).
    Stepped,
    /// The step failed; the member is removed with the reason (or switched to the
    /// encounter mode).
    Failed,
    /// The step needs the planets at this time, beyond the ephemeris: redone next window.
    Beyond(f64),
}

/// One lane of [`WindowContext::advance_lanes`].
struct Slot {
    /// The member in the lane (index in the chunk).
    member: Option<usize>,
    /// Time of the lane's bodies in [`LaneState`] (`NaN`: none).
    bodies_time: f64,
    /// The scalar path's scratch.
    worker: Worker,
    /// Whether the lanes' kick terms hold this member's at its `(t, q)`.
    kick_valid: bool,
}

/// The lanes of [`WindowContext::advance_lanes`]: the particles' slots and the bodies and kick
/// terms per lane.
struct LaneState {
    slots: [Slot; LANES],
    /// Barycentric positions and velocities of each body, lane `l` at the time of its member.
    positions: Vec<V3>,
    velocities: Vec<V3>,
    kick: KickLanes,
    /// One lane's body positions and velocities, for [`WindowContext::transition`].
    column: Vec<Vec3>,
    column_velocities: Vec<Vec3>,
}

/// One window: every active member steps while its time is before `end`, reading `ephemeris`.
/// Returns the steps taken and the latest time a step needed beyond the ephemeris.
pub(super) fn run_window(
    ephemeris: &Ephemeris,
    integrator: ParticleIntegrator,
    (rules, encounters): (RemovalRules, Option<Encounters>),
    (events, jupiter): (&EventRules, Option<usize>),
    members: &mut [PopulationMember],
    end: f64,
    path: StepPath,
) -> (u64, f64) {
    let planets = ephemeris.planets();
    let m0 = planets.sun_mass();
    // The bodies' `G m` exactly as the interpolation fills them (any retained time will do).
    let mut bodies = BodyStates::default();
    let lanes_mu = match ephemeris.interpolate(ephemeris.newest_time(), &mut bodies, false) {
        Ok(()) if path != StepPath::Scalar && integrator.variant == Variant::Barycentric => {
            let mu = integrator.kepler_mu(&bodies);
            (mu.is_finite() && mu > 0.0).then_some(mu)
        }
        _ => None,
    };
    let ctx = WindowContext {
        grid: ephemeris.view(),
        integrator,
        rules,
        encounters,
        events,
        jupiter,
        every_step: events.any()
            || rules.sun_collision
            || rules.min_distance.is_some()
            || rules.max_distance.is_some(),
        flag_every_lane: events.any(),
        radii: (1..=planets.len()).map(|j| planets.radius(j)).collect(),
        hill_coefficients: planets
            .masses()
            .iter()
            .map(|m| (m / (3.0 * m0)).cbrt())
            .collect(),
        total_gm: total_gm(planets),
        end,
        gm: bodies.gm,
        lanes_mu,
        avx: path == StepPath::Lanes && avx_available(),
    };
    // Chunks of particles, each stepped `LANES` at a time (a lane whose particle is done
    // takes the chunk's next one): one chunk on one thread; on more, about four chunks per
    // thread, so that a thread that finishes the next window's planets (see
    // `Population::advance_to`) can take over chunks that the others have not reached.
    let threads = rayon::current_num_threads();
    let chunk = if threads <= 1 {
        members.len().max(1)
    } else {
        members.len().div_ceil(4 * threads).max(LANES)
    };
    members
        .par_chunks_mut(chunk)
        .with_max_len(1)
        .map(|chunk| ctx.advance_chunk(chunk))
        .reduce(|| (0, f64::NEG_INFINITY), sum_steps)
}

/// `x < y`, or either is NaN (the regularisation margin of the encounter switch: a NaN `F₁`
/// switches too).
#[inline(always)]
fn below_or_nan(x: f64, y: f64) -> bool {
    matches!(x.partial_cmp(&y), None | Some(std::cmp::Ordering::Less))
}

/// The lanes that may meet one of [`geometric_end`]'s rules at barycentric `(q, v)` with the
/// Sun at `(sun, sun_velocity)` and `G m_sun = sun_gm`: a wider test than the rules' own
/// (the lanes' flag only sends a lane to the scalar check, which decides; a lane flagged for
/// nothing goes on unchanged, so the result is the scalar path's bit for bit), without a
/// division, a square root or an angle:
///
/// - the Sun: within [`SUN_RADIUS_FLAG_FACTOR`] solar radii, or a heliocentric osculating
///   pericentre below that many (passed or not: `perihelion_passed_within` also asks that it
///   was passed within the step), from `q < L ⟺ h² − Lμ < Lμe` squared as in
///   [`WindowContext::orbit_removal_at`];
/// - `min_distance` / `max_distance`: the squared distance against the squared limit widened
///   by [`DISTANCE_FLAG_MARGIN`].
///
/// The widenings cover the rounding of the two formulas (relative 10⁻¹⁵ here), by far.
#[inline(always)]
fn geometric_end_lanes(
    rules: &RemovalRules,
    q: &V3,
    v: &V3,
    sun: &V3,
    sun_velocity: &V3,
    sun_gm: f64,
) -> Mask {
    let sub = |a: &V3, b: &V3| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let helio = sub(q, sun);
    let mut hit = [false; LANES];
    if rules.sun_collision {
        let v_helio = sub(v, sun_velocity);
        let limit = SUN_RADIUS_FLAG_FACTOR * SUN_RADIUS_AU;
        let mu = sun_gm;
        let r2 = norm_squared(&helio);
        let r = norm(&helio);
        let h = [
            helio[1] * v_helio[2] - helio[2] * v_helio[1],
            helio[2] * v_helio[0] - helio[0] * v_helio[2],
            helio[0] * v_helio[1] - helio[1] * v_helio[0],
        ];
        let h2 = norm_squared(&h);
        let v2r = norm_squared(&v_helio) * r;
        let r_mu2_e2 = (r * mu * mu + (v2r - 2.0 * mu) * h2).max(0.0);
        let (u, w) = (h2 - limit * mu, limit * mu);
        let (left, right) = (u * u * (r * mu * mu), w * w * r_mu2_e2);
        for (l, flag) in hit.iter_mut().enumerate() {
            *flag |= r2.0[l] < limit * limit || u.0[l] < 0.0 || left.0[l] < right.0[l];
        }
    }
    let distance2 = |frame: DistanceFrame| match frame {
        DistanceFrame::Heliocentric => norm_squared(&helio),
        DistanceFrame::Barycentric => norm_squared(q),
    };
    if let Some(limit) = &rules.min_distance {
        let (d2, bound) = (distance2(limit.frame), limit.distance * limit.distance);
        for (l, flag) in hit.iter_mut().enumerate() {
            *flag |= d2.0[l] < bound * (1.0 + DISTANCE_FLAG_MARGIN);
        }
    }
    if let Some(limit) = &rules.max_distance {
        let (d2, bound) = (distance2(limit.frame), limit.distance * limit.distance);
        for (l, flag) in hit.iter_mut().enumerate() {
            *flag |= d2.0[l] > bound * (1.0 - DISTANCE_FLAG_MARGIN);
        }
    }
    hit
}

/// How many solar radii the lanes' Sun test flags ([`geometric_end_lanes`]).
const SUN_RADIUS_FLAG_FACTOR: f64 = 2.0;
/// The relative widening of the squared distance limits in the lanes' test
/// ([`geometric_end_lanes`]).
const DISTANCE_FLAG_MARGIN: f64 = 1e-9;

/// Adds two `(steps, beyond)` pairs.
fn sum_steps(a: (u64, f64), b: (u64, f64)) -> (u64, f64) {
    (a.0 + b.0, a.1.max(b.1))
}

impl Worker {
    fn new() -> Self {
        Self {
            bodies: BodyStates::default(),
            bodies_time: f64::NAN,
            kick: KickTerms::default(),
            encounter: EncounterScratch::default(),
        }
    }
}

pub(super) fn total_gm(planets: &crate::Planets) -> f64 {
    let g = planets.g();
    std::iter::once(g * planets.sun_mass())
        .chain(planets.masses().iter().map(|m| g * m))
        .sum()
}

impl WindowContext<'_> {
    /// Steps the members of a chunk through the window: through the lanes when they apply,
    /// one at a time otherwise. Returns the steps and the latest time needed beyond the
    /// ephemeris.
    fn advance_chunk(&self, members: &mut [PopulationMember]) -> (u64, f64) {
        match self.lanes_mu {
            #[cfg(target_arch = "x86_64")]
            Some(mu) if self.avx => {
                // SAFETY: `avx` is set only when the processor runs AVX (`avx_available`).
                #[allow(unsafe_code)]
                unsafe {
                    self.advance_lanes_avx(members, mu)
                }
            }
            Some(mu) => self.advance_lanes(members, mu),
            None => {
                let mut w = Worker::new();
                members
                    .iter_mut()
                    .map(|m| self.advance_member(m, &mut w))
                    .fold((0, f64::NEG_INFINITY), sum_steps)
            }
        }
    }

    /// [`WindowContext::advance_lanes`] compiled for AVX: the same operations (IEEE `+ − × ÷ √`
    /// round alike in SSE2 and AVX; no FMA is enabled), four lanes per register instead of
    /// two.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn advance_lanes_avx(&self, members: &mut [PopulationMember], mu: f64) -> (u64, f64) {
        self.advance_lanes(members, mu)
    }

    /// [`LANES`] members at a time ([`crate::lanes`]), each on its own clock: a lane whose
    /// member is done with the window (or removed) takes the next one, until none is left.
    #[inline(always)]
    fn advance_lanes(&self, members: &mut [PopulationMember], mu: f64) -> (u64, f64) {
        let zero = [V::splat(0.0); 3];
        let mut lanes = LaneState {
            slots: std::array::from_fn(|_| Slot {
                member: None,
                bodies_time: f64::NAN,
                worker: Worker::new(),
                kick_valid: false,
            }),
            positions: vec![zero; self.gm.len()],
            velocities: vec![zero; self.gm.len()],
            kick: KickLanes::zero(),
            column: Vec::with_capacity(self.gm.len()),
            column_velocities: Vec::with_capacity(self.gm.len()),
        };
        let mut queue: VecDeque<usize> = (0..members.len())
            .filter(|&i| {
                let m = &members[i];
                m.status == ParticleStatus::Active && m.particle.time < self.end
            })
            .collect();
        // A small chunk takes turns: a member leaves its lane after ROTATION_STEPS steps for
        // one that waits, so that the chunk's members finish the window together instead of
        // the last few running with idle lanes (a turn costs one kick evaluation and one
        // interpolation more, nothing else: the trajectory is the same).
        let rotate = members.len() <= ROTATION_MAX_MEMBERS;
        let mut stint = [0u32; LANES];
        let mut total = (0, f64::NEG_INFINITY);
        loop {
            for (slot, stint) in lanes.slots.iter_mut().zip(&mut stint) {
                while slot.member.is_none() {
                    let Some(i) = queue.pop_front() else { break };
                    // A member in the encounter mode goes on in it first; it takes the lane
                    // if handed back to the map before the window's end.
                    if members[i].encounter.is_some() {
                        let done = self.run_encounter(&mut members[i], &mut slot.worker);
                        total = sum_steps(total, done);
                        if !self.in_map_within_window(&members[i]) {
                            continue;
                        }
                    }
                    slot.member = Some(i);
                    slot.bodies_time = f64::NAN;
                    slot.kick_valid = false;
                    *stint = 0;
                }
            }
            // Ctrl-C (`guard::request_stop`): every member's state is written back at each
            // lane step, so the chunk stops here with each member on its own clock.
            if lanes.slots.iter().all(|s| s.member.is_none()) || crate::guard::stop_requested() {
                return total;
            }
            total = sum_steps(total, self.lane_step(members, &mut lanes, mu));
            if rotate && !queue.is_empty() {
                for (slot, stint) in lanes.slots.iter_mut().zip(&mut stint) {
                    *stint += 1;
                    if let Some(i) = slot.member.filter(|_| *stint >= ROTATION_STEPS) {
                        queue.push_back(i);
                        slot.member = None;
                    }
                }
            }
        }
    }

    /// One step of every member in a lane: [`ParticleIntegrator::advance`] and the removal
    /// rules, lane by lane bit for bit; a lane the lanes cannot finish is redone by
    /// [`WindowContext::step_member`] from its unchanged state.
    #[inline(always)]
    fn lane_step(
        &self,
        members: &mut [PopulationMember],
        lanes: &mut LaneState,
        mu: f64,
    ) -> (u64, f64) {
        let live: Mask = std::array::from_fn(|l| lanes.slots[l].member.is_some());
        // Empty lanes repeat a live one; their results are dropped.
        let fill = lanes.slots.iter().find_map(|s| s.member).unwrap_or(0);
        let index: [usize; LANES] = std::array::from_fn(|l| lanes.slots[l].member.unwrap_or(fill));
        let zero = V::splat(0.0);
        let (mut q, mut v): (V3, V3) = ([zero; 3], [zero; 3]);
        let (mut t, mut p4, mut step) = (zero, zero, zero);
        for (l, &i) in index.iter().enumerate() {
            let p = &members[i].particle;
            for c in 0..3 {
                q[c].0[l] = p.position[c];
                v[c].0[l] = p.velocity[c];
            }
            (t.0[l], p4.0[l], step.0[l]) = (p.time, p.p4, p.step);
        }
        let (b0, b1) = (self.integrator.b0, self.integrator.b1);
        let mut redo: Mask = [false; LANES];
        let mut iterations = [0u32; LANES];
        let (mut drifts, mut kicks) = (0u64, 0u64);
        for (k, stage) in self.integrator.stages().iter().enumerate() {
            self.fetch_lanes(lanes, &t, live, &mut redo);
            let h = stage.coefficient * step;
            match stage.piece {
                ParticlePiece::KeplerDrift => {
                    // ParticleIntegrator::kepler_drift: F₀, Δt = h/F₀, the drift.
                    let r = norm(&q);
                    let f0 = 0.5 * norm_squared(&v) - mu / r + p4 + b0;
                    for (l, flag) in redo.iter_mut().enumerate() {
                        *flag |= !(f0.0[l] > 0.0 && f0.0[l].is_finite());
                    }
                    let dt = h / f0;
                    let it = lanes::drift(&mut q, &mut v, r, V::splat(mu), dt, live, &mut redo);
                    for (total, it) in iterations.iter_mut().zip(it) {
                        *total += it;
                    }
                    t = t + dt;
                    drifts += 1;
                    for slot in &mut lanes.slots {
                        slot.kick_valid = false;
                    }
                }
                ParticlePiece::Perturbation => {
                    // ParticleIntegrator::perturbation_cached, barycentric: the terms kept
                    // from the last kick at the same (t, q) (the closing kick of the previous
                    // step), computed otherwise.
                    let need: Mask = std::array::from_fn(|l| {
                        live[l] && !redo[l] && !(k == 0 && lanes.slots[l].kick_valid)
                    });
                    if need.iter().any(|&n| n) {
                        let fresh = KickLanes::at(
                            b0,
                            b1,
                            &q,
                            &self.gm,
                            &lanes.positions,
                            &lanes.velocities,
                        );
                        lanes.kick = KickLanes::select(need, &fresh, &lanes.kick);
                    }
                    let f1 = lanes.kick.f1;
                    for (l, flag) in redo.iter_mut().enumerate() {
                        *flag |= !(f1.0[l] > 0.0 && f1.0[l].is_finite());
                    }
                    let sigma = h / f1;
                    for (vi, gi) in v.iter_mut().zip(&lanes.kick.gradient) {
                        *vi = *vi + *gi * sigma;
                    }
                    p4 = p4 + lanes.kick.dt_part * sigma;
                    kicks += 1;
                    for slot in &mut lanes.slots {
                        slot.kick_valid = true;
                    }
                }
            }
        }
        self.fetch_lanes(lanes, &t, live, &mut redo);
        let finite: [Mask; 7] = [q[0], q[1], q[2], v[0], v[1], v[2], p4].map(lanes::finite);
        let mut removal = self.removal_lanes(
            &q,
            &v,
            (&lanes.positions, &lanes.velocities),
            &lanes.kick.f1,
        );
        // A member with an encounter under way goes through the scalar checks, which follow
        // it out to the separation radius (`EncounterTally`); its step is the lane's.
        for (flag, slot) in removal.iter_mut().zip(&lanes.slots) {
            *flag |= slot.member.is_some_and(|i| members[i].tally.open.is_some());
        }
        let (mut steps, mut beyond) = (0, f64::NEG_INFINITY);
        let forces = kicks * self.gm.len() as u64;
        for (l, slot) in lanes.slots.iter_mut().enumerate() {
            let Some(i) = slot.member else { continue };
            let m = &mut members[i];
            if redo[l] || !finite.iter().all(|f| f[l]) {
                slot.kick_valid = false;
                // The scalar path fetches its own bodies; the lane's are not updated.
                slot.worker.bodies_time = f64::NAN;
                let outcome = self.step_member(m, &mut slot.worker);
                slot.bodies_time = f64::NAN;
                match outcome {
                    StepOutcome::Stepped => steps += 1,
                    StepOutcome::Failed => {}
                    StepOutcome::Beyond(time) => {
                        beyond = beyond.max(time);
                        slot.member = None;
                        continue;
                    }
                }
                if m.encounter.is_some() {
                    let (s, b) = self.run_encounter(m, &mut slot.worker);
                    (steps, beyond) = (steps + s, beyond.max(b));
                    slot.kick_valid = false;
                }
            } else {
                let p = &mut m.particle;
                let previous_time = p.time;
                p.position = lanes::lane(&q, l);
                p.velocity = lanes::lane(&v, l);
                p.time = t.0[l];
                p.p4 = p4.0[l];
                p.steps += 1;
                p.work.kepler_solves += drifts;
                p.work.kepler_iterations += u64::from(iterations[l]);
                p.work.force_evaluations += forces;
                steps += 1;
                m.sun_position = lanes::lane(&lanes.positions[0], l);
                if removal[l] {
                    lanes.column.clear();
                    lanes
                        .column
                        .extend(lanes.positions.iter().map(|x| lanes::lane(x, l)));
                    lanes.column_velocities.clear();
                    lanes
                        .column_velocities
                        .extend(lanes.velocities.iter().map(|x| lanes::lane(x, l)));
                    let f1 = lanes.kick.f1.0[l];
                    let bodies = (&lanes.column[..], &lanes.column_velocities[..]);
                    if self.transition(m, bodies, f1, previous_time, &mut slot.worker) {
                        let (s, b) = self.run_encounter(m, &mut slot.worker);
                        (steps, beyond) = (steps + s, beyond.max(b));
                        slot.bodies_time = f64::NAN;
                        slot.kick_valid = false;
                    }
                }
            }
            if !self.in_map_within_window(m) {
                slot.member = None;
            }
        }
        (steps, beyond)
    }

    /// The bodies at each live lane's time `t` where its lane holds another time (as
    /// [`ParticleIntegrator::advance`] fetches them); a lane whose time the ephemeris does not
    /// hold is marked for the scalar path.
    #[inline(always)]
    fn fetch_lanes(&self, lanes: &mut LaneState, t: &V, live: Mask, redo: &mut Mask) {
        let need: Mask =
            std::array::from_fn(|l| live[l] && !redo[l] && lanes.slots[l].bodies_time != t.0[l]);
        if !need.iter().any(|&n| n) {
            return;
        }
        let bad =
            self.grid
                .interpolate_lanes(*t, need, &mut lanes.positions, &mut lanes.velocities);
        for (l, slot) in lanes.slots.iter_mut().enumerate() {
            if need[l] {
                redo[l] |= bad[l];
                slot.bodies_time = if bad[l] { f64::NAN } else { t.0[l] };
            }
        }
    }

    /// Steps one member through the window with the scalar path; returns its steps and the
    /// time it needed beyond the ephemeris (`-∞` if none).
    fn advance_member(&self, m: &mut PopulationMember, w: &mut Worker) -> (u64, f64) {
        let mut steps = 0;
        while m.status == ParticleStatus::Active
            && m.particle.time < self.end
            && !crate::guard::stop_requested()
        {
            if m.encounter.is_some() {
                let (s, beyond) = self.run_encounter(m, w);
                steps += s;
                if m.encounter.is_some() || beyond > f64::NEG_INFINITY {
                    return (steps, beyond);
                }
                continue;
            }
            match self.step_member(m, w) {
                StepOutcome::Stepped => steps += 1,
                StepOutcome::Failed => {}
                StepOutcome::Beyond(time) => return (steps, time),
            }
        }
        (steps, f64::NEG_INFINITY)
    }

    /// Whether `m` is active, in the map (not in the encounter mode) and before the window's
    /// end: whether it steps on in a lane.
    fn in_map_within_window(&self, m: &PopulationMember) -> bool {
        m.status == ParticleStatus::Active && m.particle.time < self.end && m.encounter.is_none()
    }

    /// One step of one member with the scalar path ([`ParticleIntegrator::advance`]), with the
    /// removal rules; a step that fails leaves the member's state as it was.
    #[inline(never)]
    fn step_member(&self, m: &mut PopulationMember, w: &mut Worker) -> StepOutcome {
        let accelerations = self.integrator.variant == Variant::Mixed;
        let saved = m.particle.clone();
        let bodies_time = w.bodies_time;
        w.bodies_time = f64::NAN;
        let result = self.integrator.advance(
            &mut m.particle,
            &mut w.bodies,
            bodies_time,
            &mut w.kick,
            &mut |t: f64, out: &mut BodyStates| self.grid.interpolate(t, out, accelerations),
        );
        match result {
            Ok(t) => {
                w.bodies_time = t;
                m.sun_position = w.bodies.positions[0];
                let positions = std::mem::take(&mut w.bodies.positions);
                let velocities = std::mem::take(&mut w.bodies.velocities);
                let f1 = w.kick.f1();
                self.transition(m, (&positions, &velocities), f1, saved.time, w);
                (w.bodies.positions, w.bodies.velocities) = (positions, velocities);
                StepOutcome::Stepped
            }
            Err(SymplecticError::BeyondEphemeris { time, .. }) => {
                m.particle = saved;
                StepOutcome::Beyond(time)
            }
            Err(SymplecticError::RegularisationLost {
                quantity,
                value,
                time,
            }) => {
                m.particle = saved;
                if self.encounters.is_some() {
                    // Not removed: the encounter integrator takes over from the state before
                    // the step.
                    w.bodies_time = f64::NAN;
                    self.begin_encounter(m, w);
                } else {
                    m.status = ParticleStatus::RegularisationLost {
                        time,
                        quantity: quantity.to_string(),
                        value,
                    };
                }
                StepOutcome::Failed
            }
            Err(e) => {
                m.particle = saved;
                m.status = ParticleStatus::IntegrationFailed {
                    time: m.particle.time,
                    reason: e.to_string(),
                };
                StepOutcome::Failed
            }
        }
    }

    /// Per lane, whether [`WindowContext::removal`] removes the barycentric particle at `q`,
    /// `v` among the bodies at `positions`: the same tests with the same operations, so that
    /// only the lanes it flags need the scalar form (which names the rule).
    #[inline(always)]
    fn removal_lanes(
        &self,
        q: &V3,
        v: &V3,
        (positions, velocities): (&[V3], &[V3]),
        f1: &V,
    ) -> Mask {
        let rules = &self.rules;
        if self.flag_every_lane {
            return [true; LANES];
        }
        let mut hit = [false; LANES];
        let mut flag = |test: Mask| {
            for (h, t) in hit.iter_mut().zip(test) {
                *h |= t;
            }
        };
        let sub = |a: &V3, b: &V3| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        if self.encounters.is_some() {
            // The regularisation margin of the switch ([`WindowContext::transition`]).
            let r = norm(q);
            let part = V::splat(self.integrator.b0) + V::splat(self.integrator.b1) / r;
            let half = V::splat(0.5) * part;
            flag(std::array::from_fn(|l| below_or_nan(f1.0[l], half.0[l])));
        }
        if let Some(factor) = self.switch_factor() {
            let sun = &positions[0];
            for (c, planet) in self.hill_coefficients.iter().zip(&positions[1..]) {
                let distance2 = norm_squared(&sub(q, planet));
                let hill2 = norm_squared(&sub(planet, sun)) * (c * c);
                let limit = factor * factor * hill2;
                flag(std::array::from_fn(|l| distance2.0[l] < limit.0[l]));
            }
        }
        flag(geometric_end_lanes(
            rules,
            q,
            v,
            &positions[0],
            &velocities[0],
            self.gm[0],
        ));
        if rules.min_perihelion.is_none() && rules.ejection_distance.is_none() {
            return hit;
        }
        let mu = self.total_gm;
        let r = norm(q);
        let v2r = norm_squared(v) * r;
        if let Some(limit) = rules.ejection_distance {
            flag(std::array::from_fn(|l| {
                v2r.0[l] >= 2.0 * mu && r.0[l] > limit
            }));
        }
        if let Some(limit) = rules.min_perihelion {
            let h = [
                q[1] * v[2] - q[2] * v[1],
                q[2] * v[0] - q[0] * v[2],
                q[0] * v[1] - q[1] * v[0],
            ];
            let h2 = norm_squared(&h);
            let r_mu2_e2 = (r * mu * mu + (v2r - 2.0 * mu) * h2).max(0.0);
            let (u, w) = (h2 - limit * mu, limit * mu);
            let left = u * u * (r * mu * mu);
            let right = w * w * r_mu2_e2;
            flag(std::array::from_fn(|l| {
                u.0[l] < 0.0 || left.0[l] < right.0[l]
            }));
        }
        hit
    }

    /// The Hill factor that the lanes flag: the encounter switch's, or the removal rule's.
    #[inline(always)]
    fn switch_factor(&self) -> Option<f64> {
        match &self.encounters {
            Some(e) => Some(e.hill_factor),
            None => self.rules.hill_factor,
        }
    }

    /// Applies to `m`, just stepped by the map from `previous_time`, the first rule it meets
    /// with the bodies at its time (`positions`, `velocities`) and `F₁` at its end (`f1`):
    /// removal, or the switch to the encounter mode ([`Encounters`]), after recording its
    /// events. Returns whether it switched.
    fn transition(
        &self,
        m: &mut PopulationMember,
        (positions, velocities): (&[Vec3], &[Vec3]),
        f1: f64,
        previous_time: f64,
        w: &mut Worker,
    ) -> bool {
        self.record_events(m, positions, velocities, true);
        self.end_encounter_beyond_separation(m, positions);
        if let Some(settings) = self.encounters {
            // The same operations as the lanes' flags (`removal_lanes`).
            let r = m.particle.position.norm();
            let part = self.integrator.b0 + self.integrator.b1 / r;
            let margin_lost = below_or_nan(f1, 0.5 * part);
            let near = self.hill_entry(&m.particle, positions, settings.hill_factor);
            if margin_lost || near.is_some() {
                self.begin_encounter(m, w);
                return true;
            }
        }
        if let Some(status) = self.removal(&m.particle, positions) {
            m.status = status;
        } else if let Some(status) =
            self.geometric_end_at(&m.particle, previous_time, positions, velocities)
        {
            m.status = status;
        }
        false
    }

    /// Ends the encounter under way of `m` ([`EncounterTally`](crate::EncounterTally)) if it is beyond the
    /// separation radius of its planet, with the bodies at its time.
    fn end_encounter_beyond_separation(&self, m: &mut PopulationMember, positions: &[Vec3]) {
        let (Some(open), Some(settings)) = (m.tally.open, self.encounters) else {
            return;
        };
        let factor = (ENCOUNTER_SEPARATION_FACTOR * settings.hill_factor)
            .max(settings.hand_back_hill_factor);
        let q = self.barycentric(&m.particle, positions);
        let j = open.planet as usize;
        let (Some(c), Some(planet)) = (
            self.hill_coefficients.get(j.wrapping_sub(1)),
            positions.get(j),
        ) else {
            return;
        };
        let hill2 = (planet - positions[0]).norm_squared() * (c * c);
        if (q - planet).norm_squared() >= factor * factor * hill2 {
            m.tally.open = None;
        }
    }

    /// The particle's barycentric position, with the bodies at its time.
    fn barycentric(&self, p: &TestParticle, positions: &[Vec3]) -> Vec3 {
        match self.integrator.variant {
            Variant::Barycentric => p.position,
            Variant::Mixed => p.position + positions[0],
        }
    }

    /// Records the events of `m` at its time with the bodies then ([`EventRules`]);
    /// `elements_apply`: whether its barycentric elements describe its orbit.
    fn record_events(
        &self,
        m: &mut PopulationMember,
        positions: &[Vec3],
        velocities: &[Vec3],
        elements_apply: bool,
    ) {
        if !self.events.any() {
            return;
        }
        let ctx = EventContext {
            rules: self.events,
            total_gm: self.total_gm,
            hill_coefficients: &self.hill_coefficients,
            jupiter: self.jupiter,
        };
        let c = CheckPoint {
            time: m.particle.time,
            position: self.barycentric(&m.particle, positions),
            velocity: m.particle.velocity,
            body_positions: positions,
            body_velocities: velocities,
        };
        m.events
            .get_or_insert_with(Default::default)
            .check(&ctx, &c, elements_apply);
    }

    /// The Sun-collision and distance rules ([`geometric_end`]) for `p`, its previous check
    /// at `previous_time`.
    fn geometric_end_at(
        &self,
        p: &TestParticle,
        previous_time: f64,
        positions: &[Vec3],
        velocities: &[Vec3],
    ) -> Option<ParticleStatus> {
        let sun = SunState {
            position: positions[0],
            velocity: velocities[0],
            gm: self.gm[0],
        };
        let q = self.barycentric(p, positions);
        geometric_end(&self.rules, p.time, previous_time, q, p.velocity, &sun)
    }

    /// Switches `m` (at its time, in the map) to the encounter mode.
    fn begin_encounter(&self, m: &mut PopulationMember, w: &mut Worker) {
        let p = &m.particle;
        // One map step's time from here: `h/F₁` with the ephemeris' planets (`h/(B₀ + B₁/r)`
        // where `F₁` is not positive); the map's `H + p₄` and `F₁` at the switch.
        let (map_dt, switch) = match self.grid.interpolate(p.time, &mut w.bodies, false) {
            Ok(()) => {
                let (f1, part) = regularisation(&self.integrator, &p.position, &w.bodies);
                let energy = self.integrator.hamiltonian(p, &w.bodies) + p.p4;
                let dt = p.step / if f1 > 0.0 { f1 } else { part };
                (dt, Some((energy, f1)))
            }
            Err(_) => (0.0, None),
        };
        // The planet whose switch radius it is inside, if any (not where the regularisation
        // was lost away from the planets).
        let planet = match (switch, self.encounters) {
            (Some(_), Some(settings)) => self
                .hill_entry(p, &w.bodies.positions, settings.hill_factor)
                .map(|(j, _, _)| j),
            _ => None,
        };
        w.bodies_time = f64::NAN;
        m.encounter = Some(Box::new(Encounter::begin(p, &self.grid, map_dt, switch)));
        m.encounters_begun = m.encounters_begun.saturating_add(1);
        if let Some(j) = planet.and_then(|j| u32::try_from(j).ok()) {
            m.tally.switch(j);
        }
    }

    /// Advances `m` in the encounter mode until it is handed back to the map, removed, or
    /// reaches the window's end. Returns its steps and the time it needed beyond the
    /// ephemeris (`-∞` if none).
    fn run_encounter(&self, m: &mut PopulationMember, w: &mut Worker) -> (u64, f64) {
        let Some(settings) = self.encounters else {
            return (0, f64::NEG_INFINITY);
        };
        let mut steps = 0;
        // `w.bodies` holds the planets at the encounter's time once a step is taken.
        w.bodies_time = f64::NAN;
        while m.status == ParticleStatus::Active
            && m.particle.time < self.end
            && !crate::guard::stop_requested()
        {
            let Some(e) = m.encounter.as_deref_mut() else {
                break;
            };
            if e.state.len() != ENCOUNTER_STATE_LEN {
                // A state of an older checkpoint.
                let upgraded = self
                    .grid
                    .interpolate(e.time, &mut w.bodies, false)
                    .and_then(|()| e.upgrade(&self.integrator, &m.particle, &w.bodies));
                if let Err(err) = upgraded {
                    return self.encounter_failed(m, err, steps);
                }
            }
            if e.steps > 0 && e.time >= e.earliest_hand_back {
                if w.bodies_time != e.time {
                    if let Err(err) = self.grid.interpolate(e.time, &mut w.bodies, false) {
                        return self.encounter_failed(m, err, steps);
                    }
                    w.bodies_time = e.time;
                }
                let g = e.geometry(&w.bodies, &self.hill_coefficients, &self.radii);
                let (q, _) = e.particle();
                let (f1, part) = regularisation(&self.integrator, &q, &w.bodies);
                if g.nearest_ratio >= settings.hand_back_hill_factor && f1 >= 0.75 * part {
                    // The map's `F₀ = F₁ + (H + p₄)` must be positive too, with the switch's
                    // margin (`F₀ ≥ ½ (B₀ + B₁/r)`).
                    let mut p = e.hand_back(&m.particle);
                    let hamiltonian = self.integrator.hamiltonian(&p, &w.bodies);
                    let energy = e.hand_back_energy(hamiltonian, f1);
                    if f1 + energy >= 0.5 * part {
                        p.p4 = energy - hamiltonian;
                        m.particle = p;
                        m.sun_position = w.bodies.positions[0];
                        m.encounter = None;
                        w.bodies_time = f64::NAN;
                        break;
                    }
                }
            }
            let previous_time = e.time;
            let stepped = e.step(
                &self.grid,
                &settings,
                &mut w.encounter,
                &mut m.particle.work,
            );
            if let Err(err) = stepped {
                return self.encounter_failed(m, err, steps);
            }
            steps += 1;
            let (q, v) = e.particle();
            (m.particle.position, m.particle.velocity) = (q, v);
            (m.particle.time, m.particle.p4) = (e.time, e.p4());
            if let Err(err) = self.grid.interpolate(e.time, &mut w.bodies, false) {
                return self.encounter_failed(m, err, steps);
            }
            w.bodies_time = e.time;
            m.sun_position = w.bodies.positions[0];
            let g = e.geometry(&w.bodies, &self.hill_coefficients, &self.radii);
            if let Some((planet, distance, radius)) = g.collision {
                m.status = ParticleStatus::Collision {
                    time: e.time,
                    planet,
                    distance,
                    radius,
                };
            } else {
                let beyond_switch = g.nearest_ratio >= settings.hill_factor;
                if self.every_step {
                    self.check_in_encounter(m, previous_time, beyond_switch, w);
                }
                if m.status == ParticleStatus::Active && beyond_switch {
                    if let Some(status) = self.orbit_removal(&m.particle) {
                        m.status = status;
                    }
                }
            }
        }
        w.bodies_time = f64::NAN;
        // A member removed in the encounter mode (collision, perihelion, ejection, a failed
        // step) is no longer in it: its state at removal is in `particle`.
        if m.status != ParticleStatus::Active {
            m.encounter = None;
        }
        (steps, f64::NEG_INFINITY)
    }

    /// An encounter step or a reading of the planets failed: a time beyond the ephemeris
    /// pauses the member until the next window (returned as the time needed); anything else
    /// removes it.
    fn encounter_failed(
        &self,
        m: &mut PopulationMember,
        err: SymplecticError,
        steps: u64,
    ) -> (u64, f64) {
        if let SymplecticError::BeyondEphemeris { time, .. } = err {
            return (steps, time);
        }
        m.status = ParticleStatus::IntegrationFailed {
            time: m.particle.time,
            reason: format!("encounter integrator: {err}"),
        };
        m.encounter = None;
        (steps, f64::NEG_INFINITY)
    }

    /// Events and geometric end rules of `m` in the encounter mode, after a step from
    /// `previous_time`, with the planets of the ephemeris at its time.
    fn check_in_encounter(
        &self,
        m: &mut PopulationMember,
        previous_time: f64,
        elements_apply: bool,
        w: &mut Worker,
    ) {
        if w.bodies_time != m.particle.time {
            w.bodies_time = f64::NAN;
            if let Err(err) = self.grid.interpolate(m.particle.time, &mut w.bodies, false) {
                m.status = ParticleStatus::IntegrationFailed {
                    time: m.particle.time,
                    reason: err.to_string(),
                };
                return;
            }
            w.bodies_time = m.particle.time;
        }
        let bodies = &w.bodies;
        self.record_events(m, &bodies.positions, &bodies.velocities, elements_apply);
        let p = &m.particle;
        if let Some(status) =
            self.geometric_end_at(p, previous_time, &bodies.positions, &bodies.velocities)
        {
            m.status = status;
        }
    }

    /// The planet (1-based) whose `factor` Hill radii the particle is inside, with the
    /// distance and the Hill radius.
    fn hill_entry(
        &self,
        p: &TestParticle,
        positions: &[Vec3],
        factor: f64,
    ) -> Option<(usize, f64, f64)> {
        let q = self.barycentric(p, positions);
        // Compared squared (no square root per planet and step); the distances are taken
        // only for the report.
        let sun = positions[0];
        for (j, c) in self.hill_coefficients.iter().enumerate() {
            let planet = positions[j + 1];
            let distance2 = (q - planet).norm_squared();
            let hill2 = (planet - sun).norm_squared() * (c * c);
            if distance2 < factor * factor * hill2 {
                return Some((j + 1, distance2.sqrt(), (planet - sun).norm() * c));
            }
        }
        None
    }

    /// The first removal rule the particle meets, with the bodies at its time.
    fn removal(&self, p: &TestParticle, positions: &[Vec3]) -> Option<ParticleStatus> {
        if let Some(factor) = self.rules.hill_factor {
            if let Some((planet, distance, hill_radius)) = self.hill_entry(p, positions, factor) {
                return Some(ParticleStatus::HillSphereEntry {
                    time: p.time,
                    planet,
                    distance,
                    hill_radius,
                });
            }
        }
        let q = self.barycentric(p, positions);
        self.orbit_removal_at(p, &q)
    }

    /// The perihelion and ejection rules for a barycentric particle.
    fn orbit_removal(&self, p: &TestParticle) -> Option<ParticleStatus> {
        self.orbit_removal_at(p, &p.position)
    }

    /// The perihelion and ejection rules at barycentric position `q`.
    fn orbit_removal_at(&self, p: &TestParticle, q: &Vec3) -> Option<ParticleStatus> {
        let q = *q;
        let rules = &self.rules;
        if rules.min_perihelion.is_none() && rules.ejection_distance.is_none() {
            return None;
        }
        // Barycentric osculating energy and perihelion from the energy and angular momentum
        // (no angles): e² = 1 + 2E h²/μ², q = h²/(μ (1 + e)). Multiplied through by r (and
        // μ²) so that no division is needed per step: 2E r = v² r − 2μ.
        let mu = self.total_gm;
        let r = q.norm();
        let v2r = p.velocity.norm_squared() * r;
        if let Some(limit) = rules.ejection_distance {
            if v2r >= 2.0 * mu && r > limit {
                return Some(ParticleStatus::Ejected {
                    time: p.time,
                    distance: r,
                });
            }
        }
        if let Some(limit) = rules.min_perihelion {
            let h2 = q.cross(&p.velocity).norm_squared();
            // r μ² e² = r μ² + (v² r − 2μ) h².
            let r_mu2_e2 = (r * mu * mu + (v2r - 2.0 * mu) * h2).max(0.0);
            // q < L ⟺ h² − Lμ < Lμ e: true when the left side is negative, otherwise compared
            // squared; q itself only for the report.
            let (u, w) = (h2 - limit * mu, limit * mu);
            if u < 0.0 || u * u * (r * mu * mu) < w * w * r_mu2_e2 {
                let e = (r_mu2_e2 / r).sqrt() / mu;
                let perihelion = h2 / (mu * (1.0 + e));
                return Some(ParticleStatus::PerihelionBelowLimit {
                    time: p.time,
                    perihelion,
                });
            }
        }
        None
    }
}
