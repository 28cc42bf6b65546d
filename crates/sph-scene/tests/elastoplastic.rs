//! `[solver] kind = "elastoplastic"`: its settings, the walls of boundary particles it
//! requires, each wall's model, periodic axes against the tank; each refusal names its key.

use std::path::Path;

use sph_scene::{BoundaryModel, Scene, SolverParams, WallModel};

const BASE: &str = r#"
name = "ep"
[simulation]
precision = "f64"
particle_spacing = 0.02
duration = 0.1
frame_dt = 0.016
[solver]
kind = "elastoplastic"
substeps = 1
friction_angle_deg = 30.0
youngs_modulus = 1e6
poisson_ratio = 0.25
dilatancy_angle_deg = 5.0
cohesion = 10.0
viscosity_alpha = 0.2
viscosity_beta = 0.1
viscosity_speed_m_s = 2.5
artificial_stress_epsilon = 0.3
artificial_stress_exponent = 3.0
cfl_number = 0.15
skin = 0.004
initial_stress = "geostatic"
[boundary]
model = "particles"
periodic = [{ axis = "z", lo = 0.0, hi = 0.06 }]
[tank]
min = [0.0, 0.0, 0.0]
max = [0.6, 0.4, 0.06]
wall = { coulomb = 0.4 }
[[solid]]
kind = "box"
min = [0.2, -0.5, -0.5]
max = [0.4, 0.1, 0.56]
wall = "free-slip"
[[solid]]
kind = "sphere"
center = [0.5, 0.3, 0.03]
radius = 0.03
[[fluid]]
kind = "block"
min = [0.2, 0.1, 0.0]
max = [0.4, 0.2, 0.06]
"#;

fn parse(text: &str) -> Result<Scene, String> {
    Scene::parse_str(text, Path::new("ep.toml")).map_err(|e| e.to_string())
}

/// Every key reaches its parameter; unstated walls are no-slip; the region is the tank.
#[test]
fn every_setting_reaches_the_parameters() {
    let s = parse(BASE).unwrap();
    assert_eq!(s.boundary.model, BoundaryModel::Particles);
    let SolverParams::Elastoplastic(p) = s.solver_params::<f64>().unwrap() else {
        panic!("not elastoplastic")
    };
    assert_eq!(p.youngs_modulus, 1e6);
    assert_eq!(p.poisson_ratio, 0.25);
    assert_eq!(p.dilatancy_angle_deg, 5.0);
    assert_eq!(p.cohesion, 10.0);
    assert_eq!((p.viscosity_alpha, p.viscosity_beta), (0.2, 0.1));
    assert_eq!(p.viscosity_speed_m_s, Some(2.5));
    assert_eq!(
        (p.artificial_stress_epsilon, p.artificial_stress_exponent),
        (0.3, 3.0)
    );
    assert_eq!((p.cfl_number, p.skin), (0.15, 0.004));
    assert_eq!(
        p.initial_stress,
        elastoplastic_granular::InitialStress::Geostatic
    );
    assert_eq!(p.periodic.len(), 1);
    assert_eq!((p.periodic[0].axis, p.periodic[0].hi), (2, 0.06));
    assert_eq!(
        p.wall_models,
        vec![
            WallModel::Coulomb(0.4),
            WallModel::FreeSlip,
            WallModel::NoSlip
        ]
    );
    assert_eq!(p.boundary_particle_region, s.tank);
    // The defaults are `for_spacing`'s.
    let minimal = BASE
        .lines()
        .filter(|l| {
            ![
                "youngs",
                "poisson",
                "dilatancy",
                "cohesion",
                "viscosity",
                "artificial",
                "cfl",
                "skin",
                "initial",
            ]
            .iter()
            .any(|k| l.starts_with(k))
        })
        .collect::<Vec<_>>()
        .join("\n");
    let SolverParams::Elastoplastic(d) = parse(&minimal).unwrap().solver_params::<f64>().unwrap()
    else {
        panic!("not elastoplastic")
    };
    let mut expected = elastoplastic_granular::ElastoplasticParams::<f64>::for_spacing(0.02, 30.0);
    expected.common.dt = 0.016;
    expected.common.substeps = 1;
    expected.periodic = d.periodic.clone();
    expected.wall_models = d.wall_models.clone();
    expected.boundary_particle_region = d.boundary_particle_region;
    assert_eq!(d, expected);
}

/// Each refusal names its key.
#[test]
fn refusals_name_their_key() {
    let cases: &[(&str, &str, &str)] = &[
        (
            "model = \"particles\"",
            "model = \"volume-map\"",
            "boundary.model",
        ),
        (
            "model = \"particles\"",
            "model = \"collision\"",
            "boundary.model",
        ),
        (
            "wall = { coulomb = 0.4 }",
            "wall = { coulomb = -0.1 }",
            "tank.wall",
        ),
        (
            "wall = \"free-slip\"",
            "wall = { coulomb = 11.0 }",
            "solid[0].wall",
        ),
        ("wall = \"free-slip\"", "wall = \"sticky\"", "wall"),
        ("hi = 0.06 }", "hi = 0.05 }", "boundary.periodic"),
        (
            "youngs_modulus = 1e6",
            "youngs_modulus = -1.0",
            "solver.youngs_modulus",
        ),
        (
            "skin = 0.004",
            "skin = 0.004\nrestitution = 0.5",
            "restitution",
        ),
        // The periodic axes are the scene's: in `[solver]` they are refused with where they go.
        (
            "skin = 0.004",
            "skin = 0.004\nperiodic = []",
            "solver.periodic: the periodic axes are the scene's, not the solver's: write them under [boundary]",
        ),
    ];
    for (from, to, key) in cases {
        assert!(BASE.contains(from), "{from}");
        let e = parse(&BASE.replacen(from, to, 1)).unwrap_err();
        assert!(e.contains(key), "{to}: {e}");
    }
    // Boundary particles are the elastoplastic solver's only.
    let pbf = BASE
        .replace("kind = \"elastoplastic\"", "kind = \"pbf\"\niterations = 2")
        .lines()
        .filter(|l| {
            !l.contains("friction_angle") && !l.contains("periodic") && !l.starts_with("initial")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let pbf: String = pbf
        .lines()
        .filter(|l| {
            ![
                "youngs",
                "poisson",
                "dilatancy",
                "cohesion",
                "viscosity",
                "artificial",
                "cfl",
                "skin",
            ]
            .iter()
            .any(|k| l.starts_with(k))
        })
        .collect::<Vec<_>>()
        .join("\n");
    let e = parse(&pbf).unwrap_err();
    assert!(
        e.contains("boundary.model") && e.contains("elastoplastic"),
        "{e}"
    );
    let e = parse(&pbf.replace("model = \"particles\"", "model = \"collision\"")).unwrap_err();
    assert!(e.contains("tank.wall"), "{e}");
}

/// A moving box (`motion`): it becomes a moving wall of the parameters with its model,
/// velocity and duration, leaves the boundary's solids (it is not a contact solid) and
/// the wall models of the standing ones, and the rest criterion waits for it
/// (`motion_end_s`).
#[test]
fn a_moving_box_becomes_a_moving_wall() {
    let moving = BASE.replacen(
        "wall = \"free-slip\"",
        "wall = \"free-slip\"\nmotion = { velocity = [0.0, -0.05, 0.0], duration = 2.0 }",
        1,
    );
    let s = parse(&moving).unwrap();
    assert_eq!(s.motion_end_s(), 2.0);
    assert_eq!(s.standing_solids().collect::<Vec<_>>(), vec![1]);
    assert_eq!(
        s.build_solids::<f64>().unwrap().len(),
        2,
        "the tank and the sphere"
    );
    let SolverParams::Elastoplastic(p) = s.solver_params::<f64>().unwrap() else {
        panic!("not elastoplastic")
    };
    assert_eq!(
        p.wall_models,
        vec![WallModel::Coulomb(0.4), WallModel::NoSlip]
    );
    assert_eq!(p.moving_walls.len(), 1);
    let w = &p.moving_walls[0];
    assert_eq!((w.region.min.x, w.region.max.y), (0.2, 0.1));
    assert_eq!(w.model, WallModel::FreeSlip);
    assert_eq!((w.velocity.y, w.duration_s), (-0.05, 2.0));
    assert_eq!(parse(BASE).unwrap().motion_end_s(), 0.0);
    // Edited in code: a scene whose solids are cleared (as the experiments do) is still a
    // scene, unless a motion is left without its solid.
    let mut cleared = parse(BASE).unwrap();
    cleared.solids.clear();
    cleared.check().unwrap();
    let mut orphan = s.clone();
    orphan.solids.clear();
    let e = orphan.check().unwrap_err().to_string();
    assert!(e.contains("solid[0].motion"), "{e}");
}

/// A motion is refused, at its key, on a solid that is not a box, without walls of
/// boundary particles, with a non-finite velocity, a duration that is not positive or an
/// unknown field.
#[test]
fn bad_motions_name_their_key() {
    let motion = "motion = { velocity = [0.0, -0.05, 0.0], duration = 2.0 }";
    let sphere = BASE.replacen("radius = 0.03", &format!("radius = 0.03\n{motion}"), 1);
    let e = parse(&sphere).unwrap_err();
    assert!(e.contains("solid[1].motion") && e.contains("box"), "{e}");
    let on_box = |m: &str| {
        BASE.replacen(
            "wall = \"free-slip\"",
            &format!("wall = \"free-slip\"\n{m}"),
            1,
        )
    };
    for (m, key) in [
        (
            "motion = { velocity = [0.0, nan, 0.0], duration = 2.0 }",
            "solid[0].motion.velocity",
        ),
        (
            "motion = { velocity = [0.0, -0.05, 0.0], duration = 0.0 }",
            "solid[0].motion.duration",
        ),
        (
            "motion = { velocity = [0.0, -0.05, 0.0], duration = 2.0, spin = 1.0 }",
            "spin",
        ),
        ("motion = { velocity = [0.0, -0.05, 0.0] }", "duration"),
    ] {
        let e = parse(&on_box(m)).unwrap_err();
        assert!(e.contains(key), "{m}: {e}");
    }
    // Only walls of boundary particles move: with the collision boundary (and a solver
    // that takes it), the motion is refused at its key.
    let collision = on_box(motion).replacen("model = \"particles\"", "model = \"collision\"", 1);
    let e = parse(&collision).unwrap_err();
    assert!(e.contains("boundary.model") || e.contains("motion"), "{e}");
}

/// The `[pour]` table of `BASE`'s tank: a funnel two spacings wide, ten layers of six grains.
const POUR: &str =
    "[pour]\nmin = [0.28, 0.0, 0.0]\nmax = [0.32, 0.35, 0.06]\nvolume = 0.00048\nrate = 0.00144\n";

/// A pour reaches the solver's parameters as its `Pour`, and the scene counts its grains.
#[test]
fn a_pour_becomes_the_solvers_pour() {
    let s = parse(&format!("{BASE}{POUR}")).unwrap();
    assert_eq!(s.poured_grains(), 60);
    assert_eq!(parse(BASE).unwrap().poured_grains(), 0);
    let SolverParams::Elastoplastic(p) = s.solver_params::<f64>().unwrap() else {
        panic!("not elastoplastic")
    };
    let pour = p.pour.expect("a pour");
    assert_eq!((pour.region.min.x, pour.region.max.y), (0.28, 0.35));
    assert_eq!((pour.volume_m3, pour.rate_m3_s), (0.00048, 0.00144));
    assert_eq!(pour.layers(0.02), 10);
    assert_eq!(pour.seed, None);
    // A seed is the pour's (an ensemble of pours: one scene, seeds varied).
    let seeded = parse(&format!("{BASE}{POUR}seed = 7\n")).unwrap();
    let SolverParams::Elastoplastic(q) = seeded.solver_params::<f64>().unwrap() else {
        panic!("not elastoplastic")
    };
    assert_eq!(q.pour.expect("a pour").seed, Some(7));
    assert!(parse(&format!("{BASE}{POUR}seed = -1\n")).is_err());
    // The quick spacing halves the grains per layer's edge: the same volume, more grains.
    let fine = parse(&format!("{BASE}{POUR}").replacen(
        "particle_spacing = 0.02",
        "particle_spacing = 0.01",
        1,
    ))
    .unwrap();
    assert_eq!(fine.poured_grains(), 480);
}

/// A pour is refused, at its key: outside the tank, an empty box, a volume or a rate that
/// is not positive, an unknown field, gravity across `y`, and with a solver other than the
/// elastoplastic one (edited in code).
#[test]
fn bad_pours_name_their_key() {
    let with = |from: &str, to: &str| format!("{BASE}{}", POUR.replacen(from, to, 1));
    for (from, to, key, reason) in [
        (
            "max = [0.32, 0.35",
            "max = [0.32, 0.45",
            "pour",
            "inside the tank",
        ),
        (
            "min = [0.28",
            "min = [0.32",
            "pour.min",
            "min must be < max",
        ),
        ("volume = 0.00048", "volume = 0.0", "pour", "volume"),
        ("rate = 0.00144", "rate = -1.0", "pour", "rate"),
        (
            "rate = 0.00144",
            "rate = 0.00144\nspeed = 1.0",
            "speed",
            "unknown field",
        ),
        ("min = [0.28, 0.0", "min = [0.31, 0.0", "pour", "spacing"),
    ] {
        let e = parse(&with(from, to)).unwrap_err();
        assert!(e.contains(key) && e.contains(reason), "{to}: {e}");
    }
    let sideways = format!("{BASE}{POUR}").replacen(
        "frame_dt = 0.016",
        "frame_dt = 0.016\ngravity = [-9.81, 0.0, 0.0]",
        1,
    );
    let e = parse(&sideways).unwrap_err();
    assert!(e.contains("pour") && e.contains("gravity along −y"), "{e}");
    let mut other = parse(&format!("{BASE}{POUR}")).unwrap();
    other.solver = other.solver.with_kind(sph_scene::SolverKind::Pbf);
    other.boundary.model = BoundaryModel::Collision;
    other.walls = Default::default();
    let e = other.check().unwrap_err().to_string();
    assert!(e.contains("pour") && e.contains("elastoplastic"), "{e}");
}

/// `[simulation] dimensions = 2`: the section at `z = 0` at the scene's spacing. The block
/// fills its one layer at `z = 0` (10 × 5 grains of the 0.2 × 0.1 m block at 0.02 m), the
/// solver runs in the plane, the pour's box is the layer `|z| ≤ s/2` and its volume and
/// rate, per metre of depth, are those of a slab one spacing deep; the quick spacing cuts
/// its own section.
#[test]
fn a_planar_scene_is_the_section_at_z_0() {
    let planar = |text: &str| {
        text.replacen(
            "[boundary]\nmodel = \"particles\"\nperiodic = [{ axis = \"z\", lo = 0.0, hi = 0.06 }]",
            "[boundary]\nmodel = \"particles\"",
            1,
        )
        .replacen(
            "frame_dt = 0.016\n",
            "frame_dt = 0.016\ndimensions = 2\n",
            1,
        )
    };
    let s = parse(&planar(BASE)).unwrap();
    assert!(s.is_planar());
    let x = s.fluid_positions::<f64>().unwrap();
    assert_eq!(x.len(), 10 * 5);
    assert!(x.iter().all(|p| p.z == 0.0));
    let SolverParams::Elastoplastic(p) = s.solver_params::<f64>().unwrap() else {
        panic!("not elastoplastic")
    };
    assert_eq!(p.dimensions, sph_solver::Dimensions::Two);
    let pour_2d = POUR.replacen("volume = 0.00048", "volume = 0.0048", 1);
    let s = parse(&planar(&format!("{BASE}{pour_2d}"))).unwrap();
    let SolverParams::Elastoplastic(p) = s.solver_params::<f64>().unwrap() else {
        panic!("not elastoplastic")
    };
    let pour = p.pour.expect("a pour");
    assert_eq!((pour.region.min.z, pour.region.max.z), (-0.01, 0.01));
    assert_eq!(
        (pour.volume_m3, pour.rate_m3_s),
        (0.0048 * 0.02, 0.00144 * 0.02)
    );
    // 0.0048 m³ per metre of depth is 0.0048 m² of section; a layer of the 0.04 m wide
    // funnel is 2 grains of 0.02 × 0.02 m² (0.0008 m²): 6 layers.
    assert_eq!((pour.grains_per_layer(0.02), s.poured_grains()), (2, 12));
    let fine = parse(&planar(&format!("{BASE}{pour_2d}")).replacen(
        "particle_spacing = 0.02",
        "particle_spacing = 0.01",
        1,
    ))
    .unwrap();
    // At 0.01 m a layer is 4 grains of 0.0001 m² (0.0004 m²): 12 layers.
    assert_eq!(fine.poured_grains(), 48);
    assert!(fine
        .fluid_positions::<f64>()
        .unwrap()
        .iter()
        .all(|p| p.z == 0.0));
}

/// A planar scene is refused, at its key: with a solver that runs in 3D only, with a
/// periodic z axis, with gravity across the plane, with a cylinder of fluid, and a count
/// other than 2 or 3.
#[test]
fn planar_refusals_name_their_key() {
    let with_dims = |text: &str| {
        text.replacen(
            "frame_dt = 0.016\n",
            "frame_dt = 0.016\ndimensions = 2\n",
            1,
        )
    };
    let e = parse(&with_dims(BASE)).unwrap_err();
    assert!(
        e.contains("boundary.periodic") && e.contains("no periodic z axis"),
        "{e}"
    );
    let no_z = BASE.replacen(
        "\nperiodic = [{ axis = \"z\", lo = 0.0, hi = 0.06 }]",
        "",
        1,
    );
    let e = parse(&with_dims(&no_z).replacen(
        "frame_dt = 0.016\n",
        "frame_dt = 0.016\ngravity = [0.0, -9.81, 0.5]\n",
        1,
    ))
    .unwrap_err();
    assert!(e.contains("simulation.gravity"), "{e}");
    let e = parse(&BASE.replacen(
        "frame_dt = 0.016\n",
        "frame_dt = 0.016\ndimensions = 4\n",
        1,
    ))
    .unwrap_err();
    assert!(e.contains("dimensions must be 2 or 3, got 4"), "{e}");
    let pbf = r#"
name = "w"
[simulation]
particle_spacing = 0.02
duration = 0.1
frame_dt = 0.016
dimensions = 2
[solver]
kind = "pbf"
substeps = 2
iterations = 3
xsph_c = 0.01
[tank]
min = [0.0, 0.0, 0.0]
max = [0.6, 0.4, 0.06]
[[fluid]]
kind = "block"
min = [0.2, 0.1, 0.0]
max = [0.4, 0.2, 0.06]
"#;
    let e = parse(pbf).unwrap_err();
    assert!(
        e.contains("simulation.dimensions") && e.contains("3D only"),
        "{e}"
    );
}
