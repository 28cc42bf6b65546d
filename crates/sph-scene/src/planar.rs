//! Scenes in the plane (`[simulation] dimensions = 2`): the section at `z = 0` of the scene
//! as written, at the scene's spacing `s`. The fluid blocks fill their one lattice layer at
//! `z = 0`; the tank is open along `z`; the pour's box is the layer at `z = 0` and its volume
//! and rate, given per metre of depth, become those of the slab one spacing deep that the
//! particles stand for.

use sph_core::Aabb;
use sph_solver::Dimensions;

use crate::error::Ctx;
use crate::{FluidSpec, PourSpec, Scene, SceneError};

impl Scene {
    /// Whether the scene is the plane `z = 0` ([`Scene::dimensions`]).
    pub fn is_planar(&self) -> bool {
        self.dimensions == Dimensions::Two
    }

    /// The solver's pour of the scene's `[pour]` at its spacing: as written in 3D; in the
    /// plane, its box cut to the layer `|z| ≤ s/2` and its volume and rate (per metre of
    /// depth) times `s`.
    pub fn pour_of(&self, p: &PourSpec) -> sph_solver::Pour<f64> {
        let mut pour = p.to_pour();
        if self.is_planar() {
            let s = self.particle_spacing;
            pour.region.min.z = -0.5 * s;
            pour.region.max.z = 0.5 * s;
            pour.volume_m3 *= s;
            pour.rate_m3_s *= s;
        }
        pour
    }

    /// The box of a fluid block to fill at the scene's spacing: as written in 3D; in the
    /// plane, cut to the layer `|z| ≤ s/2` (whose lattice is the one layer at `z = 0`).
    pub(crate) fn block_to_fill(&self, b: Aabb<f64>) -> Aabb<f64> {
        if !self.is_planar() {
            return b;
        }
        let s = self.particle_spacing;
        let mut b = b;
        b.min.z = -0.5 * s;
        b.max.z = 0.5 * s;
        b
    }

    /// The axes along which particles must lie within the tank and a block must hold a
    /// layer: all three in 3D, `x` and `y` in the plane.
    pub(crate) fn spanned_axes(&self) -> std::ops::Range<usize> {
        0..self.dimensions.count()
    }

    /// The checks of a planar scene: a solver that runs in the plane, gravity in it, no
    /// periodic `z` axis, fluids that are blocks (a mesh or a cylinder has no section here).
    pub(crate) fn check_planar(&self, ctx: &Ctx) -> Result<(), SceneError> {
        if !self.is_planar() {
            return Ok(());
        }
        if !self.solver.kind().planar() {
            return Err(ctx.invalid(
                "simulation.dimensions",
                format!(
                    "solver kind = \"{}\" runs in 3D only; dimensions = 2 is taken by kind = \"elastoplastic\"",
                    self.solver.kind_name()
                ),
            ));
        }
        if self.gravity[2] != 0.0 {
            return Err(ctx.invalid(
                "simulation.gravity",
                format!(
                    "a planar scene (dimensions = 2) needs gravity in the plane z = 0, got z component {}",
                    self.gravity[2]
                ),
            ));
        }
        if self.periodic_axes().iter().any(|&(axis, _, _)| axis == 2) {
            return Err(ctx.invalid(
                "boundary.periodic",
                "a planar scene (dimensions = 2) has no periodic z axis: remove it (the plane is the section of the slab)",
            ));
        }
        if let Some(i) = self
            .fluids
            .iter()
            .position(|f| !matches!(f, FluidSpec::Block { .. }))
        {
            return Err(ctx.invalid(
                format!("fluid[{i}]"),
                "a planar scene (dimensions = 2) fills blocks only (a mesh or a cylinder has no section here)",
            ));
        }
        Ok(())
    }
}
