//! The settings of a volume map's construction and their checks.

use sph_core::grid::SampledGrid;

use crate::SolverError;

/// How `Ψ` is interpolated between grid nodes (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interpolation {
    /// Trilinear blend of each node's tangent-plane model plus second-order correction
    /// (`O(cell³)` where the nodes' corrections are smooth, exact for flat walls). Stores
    /// 56 bytes per band node.
    #[default]
    NodePlanes,
    /// `Ψ = Ψ_plane(φ(x)) + C(x)` with `C` trilinear on a dense [`f64`] grid (`O(cell)` near
    /// medial axes of `φ`, e.g. near tank edges).
    TrilinearCorrection,
}

/// Build options of a volume map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeMapOptions {
    /// Grid cells per support radius (1..=64; default 4: spacing `h/4`).
    pub cells_per_support: usize,
    /// Gauss–Legendre points in `cos θ` about the node normal (1..=256; default 16).
    pub polar_directions: usize,
    /// Uniform azimuths (1..=1024; default 32).
    pub azimuth_directions: usize,
    /// Samples of `φ` along each ray before the sign-change search (1..=256; default 8).
    pub ray_samples: usize,
    /// Largest grid (nodes) a single solid may use (8..=2²⁶, the limit of
    /// [`SampledGrid::MAX_NODES`]; default 2²⁵ ≈ 3.4e7).
    pub max_nodes: usize,
    /// Interpolation scheme (default [`Interpolation::NodePlanes`]).
    pub interpolation: Interpolation,
}

impl Default for VolumeMapOptions {
    fn default() -> Self {
        Self {
            cells_per_support: 4,
            polar_directions: 16,
            azimuth_directions: 32,
            ray_samples: 8,
            max_nodes: 1 << 25,
            interpolation: Interpolation::NodePlanes,
        }
    }
}

impl VolumeMapOptions {
    pub(super) fn validate(&self) -> Result<(), SolverError> {
        let checks: [(&'static str, usize, usize, usize, &'static str); 5] = [
            (
                "cells_per_support",
                self.cells_per_support,
                1,
                64,
                "must be in 1..=64",
            ),
            (
                "polar_directions",
                self.polar_directions,
                1,
                256,
                "must be in 1..=256",
            ),
            (
                "azimuth_directions",
                self.azimuth_directions,
                1,
                1024,
                "must be in 1..=1024",
            ),
            (
                "ray_samples",
                self.ray_samples,
                1,
                256,
                "must be in 1..=256",
            ),
            (
                "max_nodes",
                self.max_nodes,
                8,
                SampledGrid::<f64>::MAX_NODES,
                "must be in 8..=2^26",
            ),
        ];
        for (name, v, lo, hi, reason) in checks {
            if v < lo || v > hi {
                return Err(invalid(name, v as f64, reason));
            }
        }
        Ok(())
    }
}

pub(crate) fn invalid(name: &'static str, value: f64, reason: &'static str) -> SolverError {
    SolverError::InvalidParameter {
        solver: "volume map",
        name,
        value,
        reason,
    }
}
