//! The runs of `granular-repose-thesis` and their scenes: the shipped fixed-base scenes with
//! the friction angle and the cone's match set, the shifted block and the deeper slab.

use anyhow::Result;
use iisph_granular::ConeMatch;
use sph_scene::{FluidSpec, Scene, SolidSpec, SolverSpec};

use crate::helpers::repose::{self, MATCHES, THETAS};
use crate::scene_runs::shipped_scene;
use crate::Mode;

/// The 30° simple-shear heap also runs in a slab this many times deeper.
pub const WIDE_SLAB_FACTOR: f64 = 2.0;
/// The shipped scene θ = 0 runs in.
pub const LIQUID_SCENE_THETA: f64 = 20.0;
/// The sweep's 30° simple-shear heap.
pub const PLAIN_30_TAG: &str = "thesis/simple-shear/theta=30";
/// The repeat of [`PLAIN_30_TAG`] with the block shifted by half a spacing.
pub const REPEAT_TAG: &str = "thesis/repeat/simple-shear/theta=30";
/// [`PLAIN_30_TAG`] in the slab [`WIDE_SLAB_FACTOR`] times deeper.
pub const WIDE_TAG: &str = "thesis/wide/simple-shear/theta=30";

/// How a case departs from its shipped scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Variant {
    /// The scene as shipped for the mode.
    Plain,
    /// The block shifted by half a spacing along `x`.
    Shifted,
    /// The slab [`WIDE_SLAB_FACTOR`] times deeper.
    Wide,
}

/// One planned run.
pub type Plan = repose::Plan<Variant>;

/// The runs of `mode`: none in quick mode (the replay costs more than CI's quick budget);
/// in full mode the sweep under both matches, θ = 0, the repeat and the deeper slab.
pub fn plan(mode: Mode) -> Vec<Plan> {
    if mode == Mode::Quick {
        return Vec::new();
    }
    let case = |tag: &str, theta_deg: f64, cone: ConeMatch, variant: Variant| Plan {
        tag: tag.to_string(),
        theta_deg,
        cone,
        variant,
    };
    let mut p = Vec::new();
    for cone in MATCHES {
        for t in THETAS {
            let tag = format!("thesis/{}/theta={t:.0}", cone.name());
            p.push(case(&tag, t, cone, Variant::Plain));
        }
    }
    let ss = ConeMatch::SimpleShear;
    p.push(case("thesis/theta=0", 0.0, ss, Variant::Plain));
    p.push(case(REPEAT_TAG, 30.0, ss, Variant::Shifted));
    p.push(case(WIDE_TAG, 30.0, ss, Variant::Wide));
    p
}

/// The scene of a planned case: the shipped scene `granular_repose_thesis_<θ>` (θ = 0: of
/// [`LIQUID_SCENE_THETA`]) with the friction angle and the match set, and its variant applied.
pub fn scene_for(p: &Plan, mode: Mode) -> Result<Scene> {
    let scene_theta = if p.theta_deg > 0.0 {
        p.theta_deg
    } else {
        LIQUID_SCENE_THETA
    };
    let mut scene = shipped_scene(&format!("granular_repose_thesis_{scene_theta:.0}"), mode)?;
    let kind = scene.solver.kind_name();
    let SolverSpec::Granular(g) = &mut scene.solver else {
        anyhow::bail!(
            "{}: solver kind = \"{kind}\" is not the model of case {}",
            scene.source.display(),
            p.tag
        );
    };
    g.friction_angle_deg = p.theta_deg;
    g.cone_match = Some(p.cone);
    match p.variant {
        Variant::Plain => {}
        Variant::Shifted => {
            let shift = 0.5 * scene.particle_spacing;
            if let Some(FluidSpec::Block { min, max, .. }) = scene.fluids.first_mut() {
                min[0] += shift;
                max[0] += shift;
            }
        }
        Variant::Wide => widen(&mut scene, WIDE_SLAB_FACTOR),
    }
    scene.check()?;
    Ok(scene)
}

/// Deepens the slab (tank, base and block along z) by `factor`.
fn widen(scene: &mut Scene, factor: f64) {
    if let Some(t) = &mut scene.tank {
        t.max.z = t.min.z + factor * (t.max.z - t.min.z);
    }
    for solid in &mut scene.solids {
        if let SolidSpec::Box { min, max } = solid {
            max[2] = min[2] + factor * (max[2] - min[2]);
        }
    }
    for fluid in &mut scene.fluids {
        if let FluidSpec::Block { min, max, .. } = fluid {
            max[2] = min[2] + factor * (max[2] - min[2]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Quick mode runs nothing (as before the split: CI's budget); full mode the sweeps,
    /// θ = 0, the repeat and the deeper slab, each scene with the thesis model.
    #[test]
    fn the_plans_of_both_modes() {
        assert!(plan(Mode::Quick).is_empty());
        let full = plan(Mode::Full);
        let tags: Vec<&str> = full.iter().map(|p| p.tag.as_str()).collect();
        assert_eq!(
            tags,
            [
                "thesis/simple-shear/theta=20",
                "thesis/simple-shear/theta=30",
                "thesis/simple-shear/theta=40",
                "thesis/plane-strain/theta=20",
                "thesis/plane-strain/theta=30",
                "thesis/plane-strain/theta=40",
                "thesis/theta=0",
                REPEAT_TAG,
                WIDE_TAG,
            ]
        );
        for p in &full {
            let scene = scene_for(p, Mode::Full).unwrap();
            let SolverSpec::Granular(g) = &scene.solver else {
                panic!("{}: not the thesis model", p.tag);
            };
            assert_eq!(g.friction_angle_deg, p.theta_deg);
            assert_eq!(g.cone_match, Some(p.cone));
        }
    }
}
