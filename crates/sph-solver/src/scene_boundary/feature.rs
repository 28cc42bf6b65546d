//! [`BoundaryFeature`]: one part of a scene's boundary, with the scene key that asks for
//! it (a leaf module: the solver errors name it).

/// One feature of a scene's boundary that a solver may or may not take.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum BoundaryFeature {
    /// Solids as collision boundaries (`[boundary] model = "collision"`).
    Collision,
    /// Solids as volume maps (`[boundary] model = "volume-map"`).
    VolumeMap,
    /// Walls of boundary particles (`[boundary] model = "particles"`,
    /// [`SceneBoundary::boundary_particle_region`](super::SceneBoundary::boundary_particle_region)).
    Particles,
    /// A wall model per solid (`wall` of `[tank]` and `[[solid]]`,
    /// [`SceneBoundary::wall_models`](super::SceneBoundary::wall_models)).
    WallModels,
    /// Moving walls (`motion` of a `[[solid]]`, [`SceneBoundary::moving_walls`](super::SceneBoundary::moving_walls)).
    MovingWalls,
    /// Periodic axes (`[boundary] periodic`, [`SceneBoundary::periodic`](super::SceneBoundary::periodic)).
    Periodic,
    /// A pour (`[pour]`, [`SceneBoundary::pour`](super::SceneBoundary::pour)).
    Pour,
}

impl BoundaryFeature {
    /// Every feature.
    pub const ALL: [BoundaryFeature; 7] = [
        BoundaryFeature::Collision,
        BoundaryFeature::VolumeMap,
        BoundaryFeature::Particles,
        BoundaryFeature::WallModels,
        BoundaryFeature::MovingWalls,
        BoundaryFeature::Periodic,
        BoundaryFeature::Pour,
    ];

    /// The scene key that asks for it, as the file writes it (`[pour]`, `boundary.periodic`,
    /// `[boundary] model = "particles"`, …).
    pub fn scene_key(self) -> &'static str {
        match self {
            BoundaryFeature::Collision => "[boundary] model = \"collision\"",
            BoundaryFeature::VolumeMap => "[boundary] model = \"volume-map\"",
            BoundaryFeature::Particles => "[boundary] model = \"particles\"",
            BoundaryFeature::WallModels => "wall (of [tank] or a [[solid]])",
            BoundaryFeature::MovingWalls => "motion (of a [[solid]])",
            BoundaryFeature::Periodic => "boundary.periodic",
            BoundaryFeature::Pour => "[pour]",
        }
    }
}
