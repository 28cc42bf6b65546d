//! Walls of boundary particles sampled from solids, and Coulomb walls: an elastic slab on
//! a tilted Coulomb floor holds below `atan μ_w` and slides above it.

use elastoplastic_granular::{
    sample_solids, Aabb, BoxSdf, Elastoplastic, ElastoplasticParams, InitialStress, Inverted,
    ParticleSet, PeriodicAxis, Plane, Solids, SolverError, Vec3, WallModel,
};
use sph_core::sampling::cubic_lattice;

/// A plane floor under a region `nx × 1 × nz` spacings: three rows of nodes below it,
/// `nx · nz` each, all with the floor's normal and model (counted by hand).
#[test]
fn a_floor_gives_three_rows_with_its_normal_and_model() {
    let s = 0.1;
    let mut p = ElastoplasticParams::<f64>::for_spacing(s, 30.0);
    p.wall_models = vec![WallModel::Coulomb(0.3)];
    p.periodic = vec![PeriodicAxis {
        axis: 2,
        lo: 0.0,
        hi: 0.4,
    }];
    p.boundary_particle_region = Some(Aabb::new(Vec3::zeros(), Vec3::new(0.5, 0.2, 0.4)).unwrap());
    let solids: Solids<f64> = vec![Box::new(Plane::new(Vec3::zeros(), Vec3::y()).unwrap())];
    let b = sample_solids(&solids, &p, 1_000).unwrap();
    // Along x: 5 + 2·3 nodes (not periodic, extended by three rows each side); along z:
    // 4 (periodic, not extended); below the floor: 3 rows.
    assert_eq!(b.len(), 11 * 4 * 3);
    for q in &b {
        assert!(q.position.y < 0.0 && q.position.y > -0.3);
        assert!(q.position.z > 0.0 && q.position.z < 0.4);
        assert_eq!(q.normal, Vec3::y());
        assert_eq!(q.model, WallModel::Coulomb(0.3));
    }
    // One more than allowed is refused, by name.
    let e = sample_solids(&solids, &p, b.len() - 1).unwrap_err();
    assert!(matches!(
        e,
        SolverError::InvalidParameter {
            name: "boundary_particles",
            ..
        }
    ));
}

/// A tank (an inverted box) and a box on its floor: nodes in the tank's walls point into
/// the tank, nodes in the box point out of it; the node inside both (the box's foot in the
/// floor) takes the nearer surface; nothing deeper than three spacings.
#[test]
fn tank_and_box_walls_point_into_the_free_side() {
    let s = 0.1;
    let mut p = ElastoplasticParams::<f64>::for_spacing(s, 30.0);
    p.wall_models = vec![WallModel::FreeSlip, WallModel::NoSlip];
    let tank = Aabb::new(Vec3::zeros(), Vec3::new(1.0, 1.0, 1.0)).unwrap();
    p.boundary_particle_region = Some(tank);
    let block = Aabb::new(Vec3::new(0.4, 0.0, 0.4), Vec3::new(0.6, 0.2, 0.6)).unwrap();
    let solids: Solids<f64> = vec![
        Box::new(Inverted(BoxSdf::new(tank).unwrap())),
        Box::new(BoxSdf::new(block).unwrap()),
    ];
    let b = sample_solids(&solids, &p, 100_000).unwrap();
    let inside = |x: &Vec3<f64>, a: &Aabb<f64>| (0..3).all(|k| x[k] > a.min[k] && x[k] < a.max[k]);
    let (mut in_box, mut in_tank) = (0, 0);
    for q in &b {
        let depth = solids
            .iter()
            .map(|sdf| -sdf.signed_distance(&q.position))
            .fold(0.0, f64::max);
        assert!(depth > 0.0 && depth <= 3.0 * s + 1e-12);
        if inside(&q.position, &block) {
            in_box += 1;
            assert_eq!(q.model, WallModel::NoSlip);
            // Out of the box: the normal points away from its centre.
            assert!(q.normal.dot(&(q.position - Vec3::new(0.5, 0.1, 0.5))) > 0.0);
        } else {
            in_tank += 1;
            assert_eq!(q.model, WallModel::FreeSlip);
            assert!(!inside(&q.position, &tank));
            // Into the tank: towards its centre.
            assert!(q.normal.dot(&(Vec3::repeat(0.5) - q.position)) > 0.0);
        }
    }
    // The box's 2 × 2 × 2 nodes all lie within three spacings of its surface.
    assert_eq!(in_box, 8);
    assert!(in_tank > 0);
}

/// An elastic slab `8s × 5s`, periodic along `x` and `z`, on a floor of boundary particles
/// of model `wall` sampled from the plane `y = 0`, under gravity tilted by `tilt_deg` along
/// `x`; returns the mean displacement along `x` after `t_s` seconds and the mean velocity
/// along `x` at `t_s − 0.2 s` and at `t_s`. Spacing 20 mm; cohesion 100 kPa keeps the slab
/// inside its cone (elastic), so only the wall can give way.
fn slab_on_tilted_floor(wall: WallModel, tilt_deg: f64, t_s: f64) -> (f64, f64, f64) {
    let s = 0.02;
    let settle = |p: &ElastoplasticParams<f64>, state: &mut ParticleSet<f64>| {
        let mut q = p.clone();
        q.common.gravity = Vec3::new(0.0, -9.81, 0.0);
        q.viscosity_alpha = 1.0;
        let solids: Solids<f64> = vec![Box::new(Plane::new(Vec3::zeros(), Vec3::y()).unwrap())];
        let mut solver = Elastoplastic::new(q, solids).unwrap();
        for _ in 0..20 {
            solver.step(state).unwrap();
        }
        state.velocities.iter_mut().for_each(|v| *v = Vec3::zeros());
        solver.save_state()
    };
    let mut p = ElastoplasticParams::<f64>::for_spacing(s, 30.0);
    p.cohesion = 1e5;
    p.common.dt = 0.02;
    let g = 9.81;
    let a = tilt_deg.to_radians();
    p.common.gravity = Vec3::new(g * a.sin(), -g * a.cos(), 0.0);
    let hi = Vec3::new(8.0 * s, 5.0 * s, 4.0 * s);
    for axis in [0, 2] {
        p.periodic.push(PeriodicAxis {
            axis,
            lo: 0.0,
            hi: hi[axis],
        });
    }
    p.wall_models = vec![wall];
    let region = Aabb::new(Vec3::zeros(), hi).unwrap();
    p.boundary_particle_region = Some(region);
    p.initial_stress = InitialStress::None;
    let solids: Solids<f64> = vec![Box::new(Plane::new(Vec3::zeros(), Vec3::y()).unwrap())];
    let x = cubic_lattice(&region, s, 10_000).unwrap();
    let mut state = ParticleSet::from_positions(x, p.common.particle_mass(), p.common.rest_density);
    let settled = settle(&p, &mut state);
    let mut solver = Elastoplastic::new(p, solids).unwrap();
    solver.restore_state(&settled, state.len()).unwrap();
    assert_eq!(solver.scheme().boundary_particles().len(), 8 * 3 * 4);
    let frames = (t_s / 0.02).round() as usize;
    let mean_vx =
        |st: &ParticleSet<f64>| st.velocities.iter().map(|v| v.x).sum::<f64>() / st.len() as f64;
    let mut travelled = 0.0;
    let mut v_early = 0.0;
    for f in 0..frames {
        let before: Vec<f64> = state.positions.iter().map(|x| x.x).collect();
        solver.step(&mut state).unwrap();
        // Unwrapped displacement: a periodic wrap moves a particle by one period.
        let period = hi.x;
        let d: f64 = state
            .positions
            .iter()
            .zip(&before)
            .map(|(x, b)| {
                let mut dx = x.x - b;
                if dx > 0.5 * period {
                    dx -= period;
                } else if dx < -0.5 * period {
                    dx += period;
                }
                dx
            })
            .sum::<f64>()
            / state.len() as f64;
        travelled += d;
        if f + 1 == frames - 10 {
            v_early = mean_vx(&state);
        }
    }
    (travelled, v_early, mean_vx(&state))
}

/// `μ_w = 0.4` (`atan μ_w` = 21.8°), the slab settled under vertical gravity first (its
/// normal stress built, velocities then zeroed) and tilted from rest: at 16.8° it holds
/// (mean displacement under half a spacing over 0.6 s; the elastic shear of the slab is
/// `ρ g H² sin θ/(2G)` ≈ 0.1 mm), at 26.8° it slides (over two spacings). Controls:
/// free-slip slides at 16.8°, no-slip holds at 26.8°. The sliding slab's acceleration is
/// printed, not checked: the wall passes at most `μ_w |t_n|` but, while sliding, less (the
/// slab's own shear stress at the wall relaxes as it slides; measured 0.69 m travelled
/// against 0.17 m for `g (sin θ − μ_w cos θ)`), so the bracket is the check.
#[test]
fn a_slab_on_a_coulomb_floor_holds_below_atan_mu_and_slides_above() {
    let mu = 0.4;
    let s = 0.02;
    let crit = f64::atan(mu).to_degrees();
    let (hold, _, _) = slab_on_tilted_floor(WallModel::Coulomb(mu), crit - 5.0, 0.6);
    let (slide, v1, v2) = slab_on_tilted_floor(WallModel::Coulomb(mu), crit + 5.0, 0.6);
    let (free, _, _) = slab_on_tilted_floor(WallModel::FreeSlip, crit - 5.0, 0.6);
    let (stuck, _, _) = slab_on_tilted_floor(WallModel::NoSlip, crit + 5.0, 0.6);
    let a = (crit + 5.0).to_radians();
    let expected = 9.81 * (a.sin() - mu * a.cos());
    let measured = (v2 - v1) / 0.2;
    eprintln!(
        "hold {hold:.5} m, slide {slide:.4} m, free {free:.4} m, no-slip {stuck:.5} m; sliding acceleration over the last 0.2 s {measured:.3} (Coulomb's {expected:.3}) m/s²"
    );
    assert!(hold.abs() < 0.5 * s, "held slab moved {hold} m");
    assert!(slide > 2.0 * s, "sliding slab moved only {slide} m");
    assert!(free > 2.0 * s, "free-slip slab moved only {free} m");
    assert!(stuck.abs() < 0.5 * s, "no-slip slab moved {stuck} m");
}
