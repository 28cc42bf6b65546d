//! The scene's boundary vocabulary, solver-neutral: what a scene file says about walls
//! besides the solids' shapes ([`SceneBoundary`]: the model of each wall, moving walls, the
//! region whose walls become boundary particles, periodic axes, a pour), and which of it a
//! solver takes ([`BoundaryFeatures`], declared by each solver's
//! [`SolverSettings::BOUNDARY_FEATURES`](crate::SolverSettings::BOUNDARY_FEATURES)).
//!
//! A scene reader (`sph-scene`) fills a [`SceneBoundary`] from the scene without knowing the
//! solver, and hands it to the solver's settings
//! ([`SolverSettings::take_scene_boundary`](crate::SolverSettings::take_scene_boundary)):
//! a solver that does not take a feature the scene uses refuses it
//! ([`SolverError::UnsupportedFeature`], naming the scene key).

mod emitter;
pub(crate) mod feature;
mod periodic;
mod pour;
mod walls;

use sph_core::{Aabb, Real};

pub use emitter::{PourEmitter, FALL_OVER_LANDING_TIME, ROOM_OVER_SPACING};
pub use feature::BoundaryFeature;
pub use periodic::{image_offsets, Axis, PeriodicAxis, PeriodicImages, PeriodicSetting};
pub use pour::{Pour, MAX_POURED_GRAINS};
pub use walls::{MovingWall, WallModel, MAX_WALL_FRICTION, MAX_WALL_MOTION_S};

use crate::SolverError;

/// Which [`BoundaryFeature`]s a solver takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoundaryFeatures {
    /// Collision boundaries ([`BoundaryFeature::Collision`]).
    pub collision: bool,
    /// Volume maps ([`BoundaryFeature::VolumeMap`]).
    pub volume_map: bool,
    /// Walls of boundary particles ([`BoundaryFeature::Particles`]).
    pub particles: bool,
    /// A wall model per solid ([`BoundaryFeature::WallModels`]).
    pub wall_models: bool,
    /// Moving walls ([`BoundaryFeature::MovingWalls`]).
    pub moving_walls: bool,
    /// Periodic axes ([`BoundaryFeature::Periodic`]).
    pub periodic: bool,
    /// A pour ([`BoundaryFeature::Pour`]).
    pub pour: bool,
}

impl BoundaryFeatures {
    /// A fluid solver's: solids as collision boundaries or volume maps, nothing else.
    pub const SOLIDS_ONLY: BoundaryFeatures = BoundaryFeatures {
        collision: true,
        volume_map: true,
        particles: false,
        wall_models: false,
        moving_walls: false,
        periodic: false,
        pour: false,
    };

    /// Whether the solver takes `feature`.
    pub fn supports(&self, feature: BoundaryFeature) -> bool {
        match feature {
            BoundaryFeature::Collision => self.collision,
            BoundaryFeature::VolumeMap => self.volume_map,
            BoundaryFeature::Particles => self.particles,
            BoundaryFeature::WallModels => self.wall_models,
            BoundaryFeature::MovingWalls => self.moving_walls,
            BoundaryFeature::Periodic => self.periodic,
            BoundaryFeature::Pour => self.pour,
        }
    }
}

/// What a scene says about its boundary besides the solids' shapes, solver-neutral (the
/// solids themselves reach the solver as its [`Boundary`](crate::Boundary)).
#[derive(Debug, Clone, PartialEq)]
pub struct SceneBoundary<R: Real> {
    /// The model of a wall that does not state one.
    pub default_wall: WallModel,
    /// The model each solid of the boundary states (in the boundary's order: the tank
    /// first, then the solids that stand still), `None` where it states none.
    pub wall_models: Vec<Option<WallModel>>,
    /// The moving walls.
    pub moving_walls: Vec<MovingWall<R>>,
    /// `Some(region)`: the walls are boundary particles sampled on the particle lattice over
    /// `region` (in scene files the tank, or else the box of the fluids).
    pub boundary_particle_region: Option<Aabb<R>>,
    /// The periodic axes.
    pub periodic: Vec<PeriodicAxis<R>>,
    /// The pour, if any.
    pub pour: Option<Pour<R>>,
}

impl<R: Real> SceneBoundary<R> {
    /// A boundary of solids only: no stated wall model (`default_wall` no-slip), no moving
    /// wall, no boundary particles, no periodic axis, no pour.
    pub fn solids_only() -> Self {
        Self {
            default_wall: WallModel::NoSlip,
            wall_models: Vec::new(),
            moving_walls: Vec::new(),
            boundary_particle_region: None,
            periodic: Vec::new(),
            pour: None,
        }
    }

    /// This boundary without the parts `features` do not take (a scene reader hands a
    /// solver only what it takes, and refuses the rest at the scene keys).
    pub fn only(mut self, features: &BoundaryFeatures) -> Self {
        if !features.particles {
            self.boundary_particle_region = None;
        }
        if !features.wall_models {
            self.wall_models.iter_mut().for_each(|w| *w = None);
        }
        if !features.moving_walls {
            self.moving_walls.clear();
        }
        if !features.periodic {
            self.periodic.clear();
        }
        if !features.pour {
            self.pour = None;
        }
        self
    }

    /// The features beyond solids this boundary uses, in [`BoundaryFeature::ALL`]'s order.
    pub fn features(&self) -> Vec<BoundaryFeature> {
        let used = [
            (
                BoundaryFeature::Particles,
                self.boundary_particle_region.is_some(),
            ),
            (
                BoundaryFeature::WallModels,
                self.wall_models.iter().any(Option::is_some),
            ),
            (BoundaryFeature::MovingWalls, !self.moving_walls.is_empty()),
            (BoundaryFeature::Periodic, !self.periodic.is_empty()),
            (BoundaryFeature::Pour, self.pour.is_some()),
        ];
        used.into_iter()
            .filter(|(_, u)| *u)
            .map(|(f, _)| f)
            .collect()
    }

    /// `Ok` when `features` (those of solver `solver`) cover every feature this boundary
    /// uses; otherwise [`SolverError::UnsupportedFeature`] for the first one not covered.
    pub fn check_supported(
        &self,
        solver: &'static str,
        features: &BoundaryFeatures,
    ) -> Result<(), SolverError> {
        match self.features().into_iter().find(|f| !features.supports(*f)) {
            Some(feature) => Err(SolverError::UnsupportedFeature { solver, feature }),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pour() -> Pour<f64> {
        Pour {
            region: Aabb {
                min: [0.0, 0.0, 0.0].into(),
                max: [0.1, 0.1, 0.1].into(),
            },
            volume_m3: 1e-3,
            rate_m3_s: 1e-3,
            seed: None,
        }
    }

    /// A solver of solids only refuses a pour by its scene key, takes a boundary without
    /// one, and takes what [`SceneBoundary::only`] leaves of any boundary.
    #[test]
    fn solids_only_refuses_what_it_does_not_take() {
        let solids = BoundaryFeatures::SOLIDS_ONLY;
        let plain = SceneBoundary::<f64>::solids_only();
        assert!(plain.features().is_empty());
        assert!(plain.check_supported("t", &solids).is_ok());
        let poured = SceneBoundary {
            pour: Some(pour()),
            wall_models: vec![None, Some(WallModel::FreeSlip)],
            ..SceneBoundary::solids_only()
        };
        assert_eq!(
            poured.features(),
            vec![BoundaryFeature::WallModels, BoundaryFeature::Pour]
        );
        let e = poured.check_supported("t", &solids).unwrap_err();
        assert_eq!(
            e,
            SolverError::UnsupportedFeature {
                solver: "t",
                feature: BoundaryFeature::WallModels
            }
        );
        assert!(e.to_string().contains("wall"), "{e}");
        let kept = poured.clone().only(&solids);
        assert!(kept.features().is_empty());
        assert!(kept.check_supported("t", &solids).is_ok());
        let all = BoundaryFeatures {
            particles: true,
            wall_models: true,
            moving_walls: true,
            periodic: true,
            pour: true,
            ..solids
        };
        assert_eq!(poured.clone().only(&all), poured);
        assert_eq!(BoundaryFeature::Pour.scene_key(), "[pour]");
    }
}
