//! The artificial viscosity's fixed velocity scale (`viscosity_speed_m_s`): set to the
//! speed of sound it is the default viscosity bit for bit, set to another value it changes
//! the motion, and invalid values are named.

use elastoplastic_granular::{
    Aabb, BoxSdf, Elastoplastic, ElastoplasticParams, ElastoplasticScheme, Inverted, ParticleSet,
    Solids, Vec3, WallModel,
};
use sph_core::sampling::cubic_lattice;

const S: f64 = 0.01;

/// Velocities after 3 frames of a block 0.08 × 0.1 × 0.03 m released unstressed in a
/// free-slip box 0.2 m wide (it spreads, so approaching pairs feel the viscosity).
fn velocities(speed: Option<f64>) -> Vec<Vec3<f64>> {
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    p.youngs_modulus = 5.84e5;
    p.viscosity_alpha = 0.5;
    p.viscosity_speed_m_s = speed;
    p.wall_models = vec![WallModel::FreeSlip];
    let tank = Aabb::new(Vec3::zeros(), Vec3::new(0.2, 0.3, 0.03)).unwrap();
    let solids: Solids<f64> = vec![Box::new(Inverted(BoxSdf::new(tank).unwrap()))];
    let walls = Elastoplastic::volume_map_walls(solids, &p, tank, None).unwrap();
    let region = Aabb::new(Vec3::zeros(), Vec3::new(0.08, 0.1, 0.03)).unwrap();
    let x = cubic_lattice(&region, S, 100_000).unwrap();
    let mut state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    let mut solver = ElastoplasticScheme::solver(p, walls).unwrap();
    for _ in 0..3 {
        solver.step(&mut state).unwrap();
    }
    state.velocities
}

#[test]
fn the_sound_speed_as_the_fixed_scale_is_the_default_viscosity() {
    let p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
    let c = (5.84e5 / p.common.rest_density).sqrt();
    let default = velocities(None);
    assert_eq!(velocities(Some(c)), default);
    // A tenth of the speed of sound damps less: the motion differs.
    assert_ne!(velocities(Some(0.1 * c)), default);
}

#[test]
fn an_invalid_viscosity_speed_is_named() {
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut p = ElastoplasticParams::<f64>::for_spacing(S, 30.0);
        p.viscosity_speed_m_s = Some(bad);
        let err = p.validate().unwrap_err().to_string();
        assert!(err.contains("viscosity_speed_m_s"), "{bad}: {err}");
    }
}
