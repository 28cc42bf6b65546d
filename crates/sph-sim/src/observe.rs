//! Observers of the frame loop that measure rather than write files: [`Recorder`] keeps
//! every [`FrameRecord`], [`DensityLimit`] ends a run whose density has left any liquid's
//! range, [`RestObserver`] ends it when the material has come to rest, [`Snapshots`] keeps
//! the positions at chosen frames, [`FrameTimer`] times the frames, and [`OnFrame`] runs a closure after each frame (a
//! measurement of the experiment's own). The observers writing files are in [`crate::run`],
//! [`crate::checkpoint`] and [`crate::render`].

use sph_core::{Aabb, Real, Vec3};

use crate::error::SimError;
use crate::frame_loop::{Flow, FrameObserver, RunPlan};
use crate::record::FrameRecord;
use crate::sim::SceneSim;

/// Keeps the record of every frame, in order.
#[derive(Debug, Clone, Default)]
pub struct Recorder {
    /// The records of the frames done.
    pub records: Vec<FrameRecord>,
}

impl<R: Real> FrameObserver<R> for Recorder {
    fn start(&mut self, _: &SceneSim<R>, plan: &RunPlan) -> Result<(), SimError> {
        self.records.reserve(plan.frames());
        Ok(())
    }
    fn frame(&mut self, _: &SceneSim<R>, record: &FrameRecord) -> Result<Flow, SimError> {
        self.records.push(*record);
        Ok(Flow::Continue)
    }
}

/// Ends a run as diverged ([`Flow::Diverged`]) when a frame ends with `max ρ/ρ0` above
/// `limit` or not a number: the solver reports no error then (its state is finite), but the
/// state is no longer a simulation of the scene's liquid.
#[derive(Debug, Clone, Copy)]
pub struct DensityLimit {
    /// Largest `max ρ/ρ0` of a run that goes on.
    pub limit: f64,
}

impl<R: Real> FrameObserver<R> for DensityLimit {
    fn frame(&mut self, sim: &SceneSim<R>, r: &FrameRecord) -> Result<Flow, SimError> {
        let ratio = r.max_density_ratio;
        Ok(if ratio.is_nan() || ratio > self.limit {
            Flow::Diverged(format!(
                "diverged: max rho/rho0 = {ratio:.3} > {} at t = {:.3} s (frame {})",
                self.limit, sim.time_s, sim.frame
            ))
        } else {
            Flow::Continue
        })
    }
}

/// When a run counts as at rest: the largest speed of the particles in `region` has stayed
/// below `speed_m_s` for `hold_s` (checked at the end of each frame).
#[derive(Debug, Clone, Copy)]
pub struct RestCriterion {
    /// Speed bound (m/s).
    pub speed_m_s: f64,
    /// How long every particle must stay below it (s).
    pub hold_s: f64,
    /// The particles that count: those inside this box (m); `None` = all.
    pub region: Option<Aabb<f64>>,
}

impl RestCriterion {
    /// The largest speed (m/s) of the particles at `positions` with `velocities` inside the
    /// criterion's region.
    pub fn max_speed<R: Real>(&self, positions: &[Vec3<R>], velocities: &[Vec3<R>]) -> f64 {
        let inside = |p: &Vec3<R>| {
            self.region.is_none_or(|b| {
                (0..3).all(|a| p[a].as_f64() >= b.min[a] && p[a].as_f64() <= b.max[a])
            })
        };
        positions
            .iter()
            .zip(velocities)
            .filter(|(p, _)| inside(p))
            .map(|(_, v)| v.norm().as_f64())
            .fold(0.0, f64::max)
    }
}

/// Stops a run ([`Flow::Stop`]) once its [`RestCriterion`] holds; the scene's duration is
/// then a cap.
#[derive(Debug, Clone)]
pub struct RestObserver {
    /// The criterion.
    pub criterion: RestCriterion,
    /// The largest speed in the criterion's region at the end of each frame (m/s).
    pub speeds_m_s: Vec<f64>,
    /// The time (s) from which the speed stayed below the bound for the hold time, once
    /// it has (the run stopped then).
    pub rest_from_s: Option<f64>,
    below_since_s: Option<f64>,
}

impl RestObserver {
    /// An observer of `criterion`.
    pub fn new(criterion: RestCriterion) -> Self {
        Self {
            criterion,
            speeds_m_s: Vec::new(),
            rest_from_s: None,
            below_since_s: None,
        }
    }

    /// An observer of `criterion` going on with a hold that started at `below_since_s` (s),
    /// as [`RestObserver::below_since_s`] of an earlier run ending at this run's first
    /// frame reported it: a run split in two then stops where the whole run does.
    pub fn resumed(criterion: RestCriterion, below_since_s: Option<f64>) -> Self {
        Self {
            below_since_s,
            ..Self::new(criterion)
        }
    }

    /// The start (s) of the hold under way: the speed has stayed below the bound since
    /// then (`None` if the last frame's speed was not below it).
    pub fn below_since_s(&self) -> Option<f64> {
        self.below_since_s
    }
}

impl<R: Real> FrameObserver<R> for RestObserver {
    fn frame(&mut self, sim: &SceneSim<R>, _: &FrameRecord) -> Result<Flow, SimError> {
        let c = self.criterion;
        let speed = c.max_speed(&sim.state.positions, &sim.state.velocities);
        self.speeds_m_s.push(speed);
        // A speed at or above the bound (or not a number) starts the hold afresh.
        let below = speed < c.speed_m_s;
        if !below {
            self.below_since_s = None;
            return Ok(Flow::Continue);
        }
        // The frame's start time: the speeds of the previous frame's end held since then.
        let t_start = sim.time_s - sim.scene.frame_dt_s;
        let since = *self.below_since_s.get_or_insert(t_start);
        if sim.time_s - since < c.hold_s - 1e-9 {
            return Ok(Flow::Continue);
        }
        self.rest_from_s = Some(since);
        Ok(Flow::Stop(format!(
            "at rest: the largest speed below {} m/s for {} s from t = {since:.3} s",
            c.speed_m_s, c.hold_s
        )))
    }
}

/// Keeps the positions (in the solver's current order, as `f64`) at the chosen frames,
/// the run's first frame included if chosen.
#[derive(Debug, Clone, Default)]
pub struct Snapshots {
    /// The frames to keep.
    pub frames: Vec<usize>,
    /// `(frame, positions)` of the kept frames, in order.
    pub taken: Vec<(usize, Vec<Vec3<f64>>)>,
}

impl Snapshots {
    /// Snapshots at `frames`.
    pub fn at(frames: &[usize]) -> Self {
        Self {
            frames: frames.to_vec(),
            taken: Vec::new(),
        }
    }

    fn take<R: Real>(&mut self, sim: &SceneSim<R>) {
        if self.frames.contains(&sim.frame) {
            self.taken
                .push((sim.frame, positions_f64(&sim.state.positions)));
        }
    }
}

/// `p` widened to `f64`.
pub fn positions_f64<R: Real>(p: &[Vec3<R>]) -> Vec<Vec3<f64>> {
    p.iter()
        .map(|v| Vec3::new(v.x.as_f64(), v.y.as_f64(), v.z.as_f64()))
        .collect()
}

impl<R: Real> FrameObserver<R> for Snapshots {
    fn start(&mut self, sim: &SceneSim<R>, _: &RunPlan) -> Result<(), SimError> {
        self.take(sim);
        Ok(())
    }
    fn frame(&mut self, sim: &SceneSim<R>, _: &FrameRecord) -> Result<Flow, SimError> {
        self.take(sim);
        Ok(Flow::Continue)
    }
}

/// The wall-clock seconds of each frame, for the timing experiments: from this observer's
/// previous call (or the run's start) to its call after the frame, that is the solver's
/// step, the frame's record and the observers given before it. Given last, it times the
/// frame and every other observer of it.
#[derive(Debug, Clone, Default)]
pub struct FrameTimer {
    /// Seconds of each frame, in order.
    pub frame_s: Vec<f64>,
    last: Option<std::time::Instant>,
}

impl<R: Real> FrameObserver<R> for FrameTimer {
    fn start(&mut self, _: &SceneSim<R>, _: &RunPlan) -> Result<(), SimError> {
        self.last = Some(std::time::Instant::now());
        Ok(())
    }
    fn frame(&mut self, _: &SceneSim<R>, _: &FrameRecord) -> Result<Flow, SimError> {
        let now = std::time::Instant::now();
        if let Some(t0) = self.last {
            self.frame_s.push((now - t0).as_secs_f64());
        }
        self.last = Some(now);
        Ok(Flow::Continue)
    }
}

/// Runs a closure after each frame: an experiment's own measurement (a front position, a
/// vorticity, a frame's wall time), or its own stop.
pub struct OnFrame<F>(pub F);

impl<F> std::fmt::Debug for OnFrame<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("OnFrame")
    }
}

impl<R: Real, F> FrameObserver<R> for OnFrame<F>
where
    F: FnMut(&SceneSim<R>, &FrameRecord) -> Flow,
{
    fn frame(&mut self, sim: &SceneSim<R>, record: &FrameRecord) -> Result<Flow, SimError> {
        Ok((self.0)(sim, record))
    }
}
