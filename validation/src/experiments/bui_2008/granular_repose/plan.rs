//! The runs of `granular-repose` and their scenes: the shipped poured scenes with the friction
//! angle and the cone's match set, and the coarse (spacing and modulus) variants.

use anyhow::Result;
use elastoplastic_granular::ConeMatch;
use sph_scene::{Scene, SolverParams, SolverSpec};

use crate::helpers::repose::{self, MATCHES, THETAS};
use crate::scene_runs::shipped_scene;
use crate::Mode;

/// The shipped scene θ = 0 runs in (a period of 1.6 m: the poured layer 0.1 m deep).
pub const LIQUID_SCENE_THETA: f64 = 40.0;
/// The factor on Young's modulus of the modulus check.
pub const STIFF_FACTOR: f64 = 10.0;
/// Full mode's 30° simple-shear heap at the quick spacing (the spacing and modulus checks'
/// coarse heap).
pub const COARSE_TAG: &str = "coarse/simple-shear/theta=30";
/// The modulus check's stiff heap.
pub const STIFF_TAG: &str = "stiff/simple-shear/theta=30";
/// The sweep's 30° simple-shear heap (quick mode's coarse heap).
pub const PLAIN_30_TAG: &str = "simple-shear/theta=30";

/// How a case departs from its shipped scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Variant {
    /// The scene as shipped for the mode.
    Plain,
    /// At the quick spacing, with the scene's viscosity velocity scale held
    /// (`viscosity_speed_m_s`, the scene's or else the speed of sound of its modulus) and the
    /// modulus times `factor` (1: the spacing check's coarse heap).
    Coarse {
        /// The factor on Young's modulus.
        modulus_factor: f64,
    },
}

/// Pours of each case in quick mode: as many as the experiment's time allows: two (a quick
/// pour costs about 40 s of one core, the 40° and stiff heaps two to four times that; with
/// two pours per case the experiment takes about as long as its single pours did before the
/// explicit step was bounded by the P-wave speed; `docs/elastoplastic-granular.md`).
pub const POURS_QUICK: u64 = 2;
/// Pours of each case in full mode: eight, the ensemble's size the standards ask of a
/// result that scatters.
pub const POURS_FULL: u64 = 8;

/// One pour of a case: how the case departs from its shipped scene and the pour's seed
/// (`[pour] seed`; pours of different seeds are the case's ensemble).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Poured {
    /// How the case departs from its shipped scene.
    pub variant: Variant,
    /// The pour's seed (`None`: the shipped scene's pour, for θ = 0's single run).
    pub seed: Option<u64>,
}

/// One planned run.
pub type Plan = repose::Plan<Poured>;

/// The case of a run's tag: the tag without its `/pour=K` suffix.
pub fn case_of(tag: &str) -> &str {
    tag.rsplit_once("/pour=").map_or(tag, |(case, _)| case)
}

/// The runs of `mode`: the sweep under both matches and the stiff heap (both modes), full
/// mode's coarse heap of the spacing check, each an ensemble of [`POURS_QUICK`] or
/// [`POURS_FULL`] pours of seeds 1, 2, …, tagged `<case>/pour=<seed>`; θ = 0 one pour (a
/// flatness check, no angle).
pub fn plan(mode: Mode) -> Vec<Plan> {
    let pours = mode.pick(POURS_QUICK, POURS_FULL);
    let ensemble = |case: String, theta_deg: f64, cone: ConeMatch, variant: Variant| {
        (1..=pours).map(move |seed| Plan {
            tag: format!("{case}/pour={seed}"),
            theta_deg,
            cone,
            variant: Poured {
                variant,
                seed: Some(seed),
            },
        })
    };
    let mut p = Vec::new();
    for cone in MATCHES {
        for t in THETAS {
            let case = format!("{}/theta={t:.0}", cone.name());
            p.extend(ensemble(case, t, cone, Variant::Plain));
        }
    }
    let ss = ConeMatch::SimpleShear;
    p.push(Plan {
        tag: "theta=0".into(),
        theta_deg: 0.0,
        cone: ss,
        variant: Poured {
            variant: Variant::Plain,
            seed: None,
        },
    });
    let stiff = Variant::Coarse {
        modulus_factor: STIFF_FACTOR,
    };
    p.extend(ensemble(STIFF_TAG.into(), 30.0, ss, stiff));
    if mode == Mode::Full {
        // Quick mode's own 30° heaps are the coarse heaps (the viscosity's velocity scale
        // defaults to the sound speed of `E`).
        let coarse = Variant::Coarse {
            modulus_factor: 1.0,
        };
        p.extend(ensemble(COARSE_TAG.into(), 30.0, ss, coarse));
    }
    p
}

/// The scene of a planned case: the shipped poured scene of its θ (θ = 0: of
/// [`LIQUID_SCENE_THETA`], with the density re-initialisation on; a coarse variant at the
/// quick spacing) with the friction angle and the match set, and its variant applied.
pub fn scene_for(p: &Plan, mode: Mode) -> Result<Scene> {
    let scene_theta = if p.theta_deg > 0.0 {
        p.theta_deg
    } else {
        LIQUID_SCENE_THETA
    };
    let mode = match p.variant.variant {
        Variant::Coarse { .. } => Mode::Quick,
        Variant::Plain => mode,
    };
    let mut scene = shipped_scene(&format!("granular_repose_poured_{scene_theta:.0}"), mode)?;
    let kind = scene.solver.kind_name();
    let SolverSpec::Elastoplastic(e) = &mut scene.solver else {
        anyhow::bail!(
            "{}: solver kind = \"{kind}\" is not the model of case {}",
            scene.source.display(),
            p.tag
        );
    };
    e.friction_angle_deg = p.theta_deg;
    e.cone_match = Some(p.cone);
    if p.theta_deg == 0.0 {
        // The granular liquid separates from its sloshing surface: with the continuity
        // equation alone a separated grain's density collapses and its next contact blows
        // the run up (the crate's `angle_sweep` test holds the control).
        e.density_reinit_interval_s = Some(elastoplastic_granular::DENSITY_REINIT_INTERVAL_S);
    }
    if let (Some(seed), Some(pour)) = (p.variant.seed, scene.pour.as_mut()) {
        pour.seed = Some(seed);
    }
    if let Variant::Coarse { modulus_factor } = p.variant.variant {
        let SolverParams::Elastoplastic(params) = scene.solver_params::<f64>()? else {
            anyhow::bail!("{}: not elastoplastic", scene.source.display());
        };
        let viscosity_speed = params.viscosity_speed();
        let modulus = params.youngs_modulus;
        if let SolverSpec::Elastoplastic(e) = &mut scene.solver {
            e.viscosity_speed_m_s = Some(viscosity_speed);
            e.youngs_modulus = Some(modulus_factor * modulus);
        }
    }
    scene.check()?;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::helpers::repose::steps_to_cap;

    /// The stiff pours are the quick plan's longest by the explicit steps to the cap, so
    /// they start first: `10 E` takes about `√10` times the steps of `E` (the step is
    /// `C_p h / c_p`, `c_p ∝ √E`); the other cases alike.
    #[test]
    fn the_stiff_pours_take_the_most_steps() {
        let plans = plan(Mode::Quick);
        let steps = |p: &Plan| steps_to_cap(&scene_for(p, Mode::Quick).unwrap());
        let (stiff, other): (Vec<&Plan>, Vec<&Plan>) =
            plans.iter().partition(|p| p.tag.starts_with(STIFF_TAG));
        let least_stiff = stiff.iter().map(|p| steps(p)).fold(f64::INFINITY, f64::min);
        let most_other = other.iter().map(|p| steps(p)).fold(0.0, f64::max);
        let ratio = least_stiff / most_other;
        // √10 = 3.16, each frame's steps rounded up to a whole number (about 20 and 61).
        assert!((2.8..3.4).contains(&ratio), "stiff / other steps {ratio}");
    }

    /// Quick mode runs the two sweeps, θ = 0 and the stiff heap (CI's budget); full mode adds
    /// the coarse heap; each case but θ = 0 is an ensemble of pours of seeds 1..n.
    #[test]
    fn the_plans_of_both_modes() {
        let cases = |m| {
            let mut c: Vec<(String, usize, Vec<Option<u64>>)> = Vec::new();
            for p in plan(m) {
                let case = case_of(&p.tag).to_string();
                match c.iter_mut().find(|(k, _, _)| *k == case) {
                    Some((_, n, seeds)) => {
                        *n += 1;
                        seeds.push(p.variant.seed);
                    }
                    None => c.push((case, 1, vec![p.variant.seed])),
                }
            }
            c
        };
        let quick = [
            "simple-shear/theta=20",
            "simple-shear/theta=30",
            "simple-shear/theta=40",
            "plane-strain/theta=20",
            "plane-strain/theta=30",
            "plane-strain/theta=40",
            "theta=0",
            STIFF_TAG,
        ];
        let mut full = quick.to_vec();
        full.push(COARSE_TAG);
        for (mode, names, pours) in [
            (Mode::Quick, quick.to_vec(), POURS_QUICK),
            (Mode::Full, full, POURS_FULL),
        ] {
            let got = cases(mode);
            let got_names: Vec<&str> = got.iter().map(|(c, _, _)| c.as_str()).collect();
            assert_eq!(got_names, names);
            for (case, n, seeds) in &got {
                if case == "theta=0" {
                    assert_eq!((*n, seeds.as_slice()), (1, &[None][..]));
                } else {
                    let expected: Vec<Option<u64>> = (1..=pours).map(Some).collect();
                    assert_eq!(seeds, &expected, "{case}");
                }
            }
        }
    }

    #[test]
    fn a_pours_seed_reaches_its_scene() {
        for p in plan(Mode::Quick) {
            let scene = scene_for(&p, Mode::Quick).unwrap();
            let seed = scene.pour.as_ref().and_then(|pour| pour.seed);
            match p.variant.seed {
                Some(s) => assert_eq!(seed, Some(s), "{}", p.tag),
                None => assert_eq!(seed, None, "{}", p.tag),
            }
        }
    }

    #[test]
    fn scenes_carry_the_model_and_the_variant() {
        for p in plan(Mode::Quick) {
            let scene = scene_for(&p, Mode::Quick).unwrap();
            let SolverSpec::Elastoplastic(e) = &scene.solver else {
                panic!("{}: not elastoplastic", p.tag);
            };
            assert_eq!(e.friction_angle_deg, p.theta_deg);
            assert_eq!(e.cone_match, Some(p.cone));
        }
    }
}
