//! Invalid input is rejected with errors naming the culprit; divergence is reported as
//! `BlowUp`, never written as NaN.

mod common;

use pbf::{Pbf, PbfParams, SolverError, Vec3};
use sph_core::CoreError;

fn param_error(p: PbfParams<f64>) -> &'static str {
    let e = p.validate().unwrap_err();
    assert!(Pbf::new(p, vec![]).is_err());
    match e {
        SolverError::InvalidParameter { name, .. } => name,
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn invalid_parameters_are_named() {
    let ok = PbfParams::<f64>::default();
    ok.validate().unwrap();
    type Setter = Box<dyn Fn(&mut PbfParams<f64>)>;
    let cases: Vec<(&str, Setter)> = vec![
        (
            "support_radius",
            Box::new(|p| p.common.support_radius = 0.0),
        ),
        (
            "support_radius",
            Box::new(|p| p.common.support_radius = -0.05),
        ),
        (
            "support_radius",
            Box::new(|p| p.common.support_radius = f64::NAN),
        ),
        (
            "support_radius",
            Box::new(|p| p.common.support_radius = p.common.particle_spacing),
        ),
        (
            "support_radius",
            Box::new(|p| p.common.support_radius = 100.0 * p.common.particle_spacing),
        ),
        ("dt", Box::new(|p| p.common.dt = 0.0)),
        ("dt", Box::new(|p| p.common.dt = f64::NAN)),
        ("dt", Box::new(|p| p.common.dt = f64::INFINITY)),
        ("rest_density", Box::new(|p| p.common.rest_density = -1.0)),
        (
            "particle_spacing",
            Box::new(|p| p.common.particle_spacing = f64::NAN),
        ),
        ("solver_iterations", Box::new(|p| p.solver_iterations = 0)),
        ("substeps", Box::new(|p| p.common.substeps = 0)),
        ("cfm_epsilon", Box::new(|p| p.cfm_epsilon = 0.0)),
        ("scorr_k", Box::new(|p| p.scorr_k = -0.1)),
        ("scorr_n", Box::new(|p| p.scorr_n = 0)),
        ("scorr_delta_q", Box::new(|p| p.scorr_delta_q = 1.0)),
        (
            "vorticity_epsilon",
            Box::new(|p| p.vorticity_epsilon = f64::NAN),
        ),
        ("xsph_c", Box::new(|p| p.xsph_c = 1.5)),
        (
            "gravity",
            Box::new(|p| p.common.gravity.y = f64::NEG_INFINITY),
        ),
        (
            "mean_compression_tolerance",
            Box::new(|p| p.mean_compression_tolerance = Some(0.0)),
        ),
        (
            "mean_compression_tolerance",
            Box::new(|p| p.mean_compression_tolerance = Some(f64::NAN)),
        ),
        (
            "min_solver_iterations",
            Box::new(|p| {
                p.mean_compression_tolerance = Some(1e-3);
                p.min_solver_iterations = p.solver_iterations + 1;
            }),
        ),
        (
            "min_solver_iterations",
            Box::new(|p| {
                p.mean_compression_tolerance = Some(1e-3);
                p.min_solver_iterations = 0;
            }),
        ),
    ];
    for (name, set) in cases {
        let mut p = ok.clone();
        set(&mut p);
        assert_eq!(param_error(p), name);
    }
    let mut p = ok.clone();
    p.common.support_radius = -1.0;
    let msg = p.validate().unwrap_err().to_string();
    assert!(
        msg.contains("support_radius") && msg.contains("-1"),
        "{msg}"
    );
}

#[test]
fn nan_position_names_the_particle() {
    let (p, state, solids) = common::dam_break::<f64>();
    let mut solver = Pbf::new(p, solids).unwrap();
    common::assert_nan_position_rejected(&mut solver, state);
}

#[test]
fn bad_velocity_mass_and_lengths_are_named() {
    let (p, state, solids) = common::dam_break::<f32>();
    let mut solver = Pbf::new(p, solids).unwrap();
    let mut s = state.clone();
    s.velocities[11].x = f32::INFINITY;
    assert!(matches!(
        solver.step(&mut s),
        Err(SolverError::InvalidState(CoreError::NonFiniteVelocity {
            index: 11,
            ..
        }))
    ));
    let mut s = state.clone();
    s.masses[3] = 0.0;
    assert!(matches!(
        solver.step(&mut s),
        Err(SolverError::InvalidMass { index: 3, .. })
    ));
    let mut s = state.clone();
    s.masses.pop();
    assert!(matches!(
        solver.step(&mut s),
        Err(SolverError::InvalidState(CoreError::LengthMismatch { .. }))
    ));
    let e = solver
        .evaluate_constraints(&[Vec3::zeros(), Vec3::new(f32::NAN, 0.0, 0.0)], &[1.0, 1.0])
        .unwrap_err();
    assert!(matches!(
        e,
        SolverError::InvalidState(CoreError::NonFinitePosition { index: 1, .. })
    ));
}

/// A time step so large that the predicted positions overflow: `BlowUp`, naming the step,
/// and the state keeps its last finite values.
#[test]
fn huge_dt_is_a_blow_up_not_nan() {
    // f32: Δt² g = 2.5e39 · 9.81 overflows.
    let (mut p, mut state, solids) = common::dam_break::<f32>();
    let mut solver = Pbf::new(p.clone(), solids).unwrap();
    solver.step(&mut state).unwrap();
    p.common.dt = 1e20;
    solver.set_params(p).unwrap();
    let before = common::bits(&state);
    match solver.step(&mut state) {
        Err(SolverError::BlowUp {
            step: 1, reason, ..
        }) => assert!(reason.contains("not finite"), "{reason}"),
        other => panic!("expected BlowUp, got {other:?}"),
    }
    assert_eq!(common::bits(&state), before);
    assert!(state
        .positions
        .iter()
        .chain(&state.velocities)
        .all(|v| v.iter().all(|c| c.is_finite())));

    // f64, from the start: dt = 1e160 s.
    let (mut p, mut state, solids) = common::dam_break::<f64>();
    p.common.dt = 1e160;
    let mut solver = Pbf::new(p, solids).unwrap();
    let e = solver.step(&mut state).unwrap_err();
    assert!(matches!(e, SolverError::BlowUp { step: 0, .. }), "{e:?}");
    assert!(e.to_string().contains("blow-up in step 0"), "{e}");
    assert!(state
        .positions
        .iter()
        .all(|v| v.iter().all(|c| c.is_finite())));
}

/// Contradictory solids leave particles deep inside one of them: reported as `BlowUp`
/// instead of silently accepted.
#[test]
fn particle_deep_inside_a_solid_is_a_blow_up() {
    use sph_core::{Aabb, BoxSdf, Inverted, Plane};
    let (p, mut state, mut solids) = common::dam_break::<f64>();
    let h = p.common.support_radius;
    // A floor at y = 0.3 m (free above), resolved first, and, resolved last, a second tank
    // whose top is at y = 2 h = 0.1 m (free below): no position satisfies both, and the
    // last projection leaves every particle about 0.2 m (> h) inside the floor.
    solids.insert(
        0,
        Box::new(Plane::new(Vec3::new(0.0, 0.3, 0.0), Vec3::new(0.0, 1.0, 0.0)).unwrap()),
    );
    let low = Aabb::new(Vec3::new(-1.0, -1.0, -1.0), Vec3::new(1.0, 2.0 * h, 1.0)).unwrap();
    solids.push(Box::new(Inverted(BoxSdf::new(low).unwrap())));
    let mut solver = Pbf::new(p, solids).unwrap();
    let e = solver.step(&mut state).unwrap_err();
    match &e {
        SolverError::BlowUp { reason, .. } => assert!(reason.contains("inside solid"), "{reason}"),
        other => panic!("{other:?}"),
    }
}

/// No particles: a step is a no-op with zero statistics.
#[test]
fn empty_state_steps() {
    let (p, _, solids) = common::dam_break::<f64>();
    let mut solver = Pbf::new(p, solids).unwrap();
    let mut state = pbf::ParticleSet::new();
    let st = solver.step(&mut state).unwrap();
    assert_eq!(st.kinetic_energy, 0.0);
    assert_eq!(st.max_density_ratio, 0.0);
    assert_eq!(st.substeps, 4);
    assert!(state.is_empty());
}
