//! Observers of the frame loop that measure rather than write files: [`Recorder`] keeps
//! every [`FrameRecord`], [`DensityLimit`] ends a run whose density has left any liquid's
//! range, [`RestObserver`] ends it when the material has come to rest (by
//! [`granular_measure::rest`]), [`Snapshots`] keeps
//! the positions at chosen frames, [`FrameTimer`] times the frames, and [`OnFrame`] runs a closure after each frame (a
//! measurement of the experiment's own). The observers writing files are in [`crate::run`],
//! [`crate::checkpoint`] and [`crate::render`].

use granular_measure::rest::{judge_rest, rest_sample};
use granular_measure::{angle_of_repose, MeasureError, ReposeOptions};
pub use granular_measure::{PileShape, RestMargin, RestSample, RestSettings, RestVerdict};
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

/// When a run counts as at rest: [`granular_measure::rest`]'s criterion (the percentile
/// speed and the fastest particle two spacings below the surface under `0.05 √(g s)` for
/// 0.5 s, the heap's angle moving less than 0.3° over the last second, by default) on the
/// particles inside `region`, the scene's spacing and gravity setting the speed bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestCriterion {
    /// The criterion's figures.
    pub settings: RestSettings,
    /// The heap's particles: those inside this box (m); `None` = all.
    pub region: Option<Aabb<f64>>,
    /// How the heap's angle is measured and its columns taken: a planar (2.5D) heap or a
    /// conical pile.
    pub shape: PileShape,
    /// The floor the heap stands on (m); `None` = the scene tank's bottom, else `y = 0`.
    pub floor_y: Option<f64>,
}

impl Default for RestCriterion {
    /// The default criterion on a planar heap of all the particles on the tank's floor.
    fn default() -> Self {
        Self {
            settings: RestSettings::default(),
            region: None,
            shape: PileShape::Planar,
            floor_y: None,
        }
    }
}

impl RestCriterion {
    /// The criterion's sample of the particles at `positions` with `velocities` at
    /// `time_s` (s) for a scene of spacing `spacing_m` whose tank's bottom is `tank_floor`:
    /// the angle is measured with [`angle_of_repose`] (bins of one spacing, `None` when
    /// the heap cannot be measured). A non-finite velocity or position gives a sample that
    /// is not at rest (its speeds `NaN`: a diverged run is [`DensityLimit`]'s to report);
    /// a region holding no particle is an error.
    pub fn sample<R: Real>(
        &self,
        positions: &[Vec3<R>],
        velocities: &[Vec3<R>],
        spacing_m: f64,
        tank_floor: Option<f64>,
        time_s: f64,
    ) -> Result<RestSample, SimError> {
        let inside = |p: &Vec3<R>| {
            self.region.is_none_or(|b| {
                (0..3).all(|a| p[a].as_f64() >= b.min[a] && p[a].as_f64() <= b.max[a])
            })
        };
        let (x, v): (Vec<Vec3<R>>, Vec<Vec3<R>>) = positions
            .iter()
            .zip(velocities)
            .filter(|(p, _)| inside(p))
            .map(|(p, u)| (*p, *u))
            .unzip();
        if x.is_empty() {
            return Err(SimError::Invalid(format!(
                "rest criterion: no particle inside the region {:?} at t = {time_s} s",
                self.region
            )));
        }
        let angle = self.settings.angle_drift_deg.and_then(|_| {
            let floor = self.floor_y.or(tank_floor).unwrap_or(0.0);
            let opts = match self.shape {
                PileShape::Planar => ReposeOptions::planar(floor, spacing_m),
                shape => ReposeOptions {
                    shape,
                    ..ReposeOptions::conical(floor, spacing_m)
                },
            };
            angle_of_repose(&x, &opts).ok().map(|m| m.angle_deg)
        });
        match rest_sample(&x, &v, spacing_m, self.shape, time_s, angle, &self.settings) {
            Ok(s) => Ok(s),
            Err(MeasureError::NonFinite { .. } | MeasureError::NonFiniteVelocity { .. }) => {
                Ok(RestSample {
                    time_s,
                    percentile_speed_m_s: f64::NAN,
                    deep_max_speed_m_s: f64::NAN,
                    deep_particles: 0,
                    angle_deg: None,
                })
            }
            Err(e) => Err(SimError::Invalid(e.to_string())),
        }
    }

    /// The speed bound `c √(g s)` (m/s) of a scene with `gravity` (m/s²) and spacing
    /// `spacing_m`.
    pub fn speed_bound_m_s(&self, gravity: [f64; 3], spacing_m: f64) -> Result<f64, SimError> {
        let g = gravity.iter().map(|c| c * c).sum::<f64>().sqrt();
        self.settings
            .speed_bound_m_s(g, spacing_m)
            .map_err(|e| SimError::Invalid(e.to_string()))
    }
}

/// Stops a run ([`Flow::Stop`]) once its [`RestCriterion`] holds (judged with
/// [`judge_rest`] after each frame, on one sample per frame and one of the run's first
/// state) and the scene's moving solids have stopped ([`Scene::motion_end_s`]: a heap
/// is not at rest on a trapdoor still being lowered); the scene's duration is then a cap.
/// With a pour, only the frames after its last layer are sampled
/// ([`SceneSim::pour_finished`]).
///
/// [`Scene::motion_end_s`]: sph_scene::Scene::motion_end_s
#[derive(Debug, Clone)]
pub struct RestObserver {
    /// The criterion.
    pub criterion: RestCriterion,
    /// The samples, one per frame (and one of the first state), in time order; a resumed
    /// observer starts with the earlier run's [`RestObserver::carried`] samples.
    pub samples: Vec<RestSample>,
    /// The verdict at the last sample (`None` before the first frame).
    pub verdict: Option<RestVerdict>,
    /// The time (s) from which the criterion held (the run stopped then), once it has.
    pub rest_from_s: Option<f64>,
}

impl RestObserver {
    /// An observer of `criterion`.
    pub fn new(criterion: RestCriterion) -> Self {
        Self::resumed(criterion, Vec::new())
    }

    /// An observer of `criterion` going on from the samples `carried` by an earlier run
    /// ending at this run's first frame ([`RestObserver::carried`]): a run split in two
    /// then stops where the whole run does.
    pub fn resumed(criterion: RestCriterion, carried: Vec<RestSample>) -> Self {
        Self {
            criterion,
            samples: carried,
            verdict: None,
            rest_from_s: None,
        }
    }

    /// The index of the first sample of the trailing run below the speed bound (the
    /// samples' length when the last is not below it).
    fn hold_start(&self) -> usize {
        let Some(v) = self.verdict else {
            return self.samples.len();
        };
        let slow = |r: &RestSample| {
            r.percentile_speed_m_s < v.percentile_speed.bound
                && r.deep_max_speed_m_s < v.deep_speed.bound
        };
        self.samples
            .iter()
            .rposition(|r| !slow(r))
            .map_or(0, |i| i + 1)
    }

    /// The samples a run going on from here needs for the same verdicts: those of the
    /// angle's and the speeds' windows (and one before, which says the window is covered),
    /// and those of the speeds' hold under way.
    pub fn carried(&self) -> Vec<RestSample> {
        let Some(last) = self.samples.last() else {
            return Vec::new();
        };
        let s = &self.criterion.settings;
        let window = s.speed_hold_s.max(s.angle_window_s);
        let window_start = self
            .samples
            .iter()
            .position(|r| r.time_s >= last.time_s - window - 1e-9)
            .unwrap_or(0);
        let from = self.hold_start().min(window_start.saturating_sub(1));
        self.samples[from..].to_vec()
    }

    /// The start (s) of the speeds' hold under way: the time of the first sample of the
    /// trailing run of samples below the bound (`None` if the last sample is not below it).
    pub fn below_since_s(&self) -> Option<f64> {
        self.samples.get(self.hold_start()).map(|r| r.time_s)
    }

    fn take<R: Real>(&mut self, sim: &SceneSim<R>) -> Result<(), SimError> {
        if !sim.pour_finished() {
            // Grains are still being poured: the heap is judged on the frames after the
            // last layer only.
            self.samples.clear();
            self.verdict = None;
            return Ok(());
        }
        if self.samples.last().is_some_and(|s| s.time_s >= sim.time_s) {
            return Ok(()); // the carried samples end at this state
        }
        let sample = self.criterion.sample(
            &sim.state.positions,
            &sim.state.velocities,
            sim.scene.particle_spacing,
            sim.scene.tank.as_ref().map(|t| t.min.y),
            sim.time_s,
        )?;
        self.samples.push(sample);
        let bound = self
            .criterion
            .speed_bound_m_s(sim.scene.gravity, sim.scene.particle_spacing)?;
        self.verdict = Some(
            judge_rest(&self.samples, bound, &self.criterion.settings)
                .map_err(|e| SimError::Invalid(e.to_string()))?,
        );
        Ok(())
    }
}

impl<R: Real> FrameObserver<R> for RestObserver {
    fn start(&mut self, sim: &SceneSim<R>, _: &RunPlan) -> Result<(), SimError> {
        self.take(sim)
    }

    fn frame(&mut self, sim: &SceneSim<R>, _: &FrameRecord) -> Result<Flow, SimError> {
        self.take(sim)?;
        match self.verdict {
            Some(v) if v.at_rest && sim.time_s >= sim.scene.motion_end_s() => {
                let still_from = sim.scene.motion_end_s();
                self.rest_from_s = v.rest_from_s.map(|t| t.max(still_from));
                Ok(Flow::Stop(v.summary(&self.criterion.settings)))
            }
            _ => Ok(Flow::Continue),
        }
    }
}

/// Keeps the positions (as `f64`, in the order the scene created the particles: element `k`
/// is the particle with id `k`, [`SceneSim::to_original_order`]) at the chosen frames, the
/// run's first frame included if chosen, and the solver's per-particle fields
/// ([`SceneSim::particle_fields`], e.g. the elastic–plastic solver's `plastic_strain`) named
/// in [`Snapshots::fields`], in the same order.
#[derive(Debug, Clone, Default)]
pub struct Snapshots {
    /// The frames to keep.
    pub frames: Vec<usize>,
    /// `(frame, positions)` of the kept frames, in order.
    pub taken: Vec<(usize, Vec<Vec3<f64>>)>,
    /// The names of the solver's fields to keep with the positions.
    pub fields: Vec<String>,
    /// `(frame, name, values per particle, values)` of the kept fields, in order.
    pub taken_fields: Vec<(usize, String, usize, Vec<f64>)>,
}

impl Snapshots {
    /// Snapshots at `frames`.
    pub fn at(frames: &[usize]) -> Self {
        Self {
            frames: frames.to_vec(),
            ..Self::default()
        }
    }

    /// Also keeps the solver's fields `names` at the same frames.
    pub fn with_fields(mut self, names: &[&str]) -> Self {
        self.fields = names.iter().map(|s| s.to_string()).collect();
        self
    }

    fn take<R: Real>(&mut self, sim: &SceneSim<R>) -> Result<(), SimError> {
        if self.frames.contains(&sim.frame) {
            let positions = positions_f64(&sim.state.positions);
            // One id per particle by construction; the solver's order if that ever failed.
            let ordered = sim.to_original_order(&positions).unwrap_or(positions);
            self.taken.push((sim.frame, ordered));
            if !self.fields.is_empty() {
                for (name, k, values) in sim.particle_fields()? {
                    if self.fields.contains(&name) {
                        let values = values.iter().map(|v| v.as_f64()).collect();
                        self.taken_fields.push((sim.frame, name, k, values));
                    }
                }
            }
        }
        Ok(())
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
        self.take(sim)
    }
    fn frame(&mut self, sim: &SceneSim<R>, _: &FrameRecord) -> Result<Flow, SimError> {
        self.take(sim)?;
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
