//! The elastoplastic solver from a scene: walls of boundary particles from the tank and the
//! solids, each solid's wall model, a periodic axis, the geostatic start; a run resumed
//! from a checkpoint repeats the uninterrupted one bit for bit, stress and plastic strain
//! included.

use std::path::PathBuf;

use sph_scene::Scene;
use sph_sim::observe::{RestCriterion, RestObserver};
use sph_sim::{run_frames, RunPlan, SceneSim};

/// A block on a no-slip box in a tank open along `z` (periodic), its floor and ends
/// Coulomb; spacing 20 mm.
const SCENE: &str = r#"
name = "ep_tiny"
[simulation]
precision = "f64"
particle_spacing = 0.02
duration = 0.096
frame_dt = 0.016
[solver]
kind = "elastoplastic"
substeps = 1
friction_angle_deg = 30.0
youngs_modulus = 5.84e5
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
wall = "no-slip"
[[fluid]]
kind = "block"
min = [0.2, 0.1, 0.0]
max = [0.4, 0.24, 0.06]
"#;

fn scene(test: &str) -> Scene {
    let dir = std::env::temp_dir().join(format!("sph-sim-ep-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path: PathBuf = dir.join("ep_tiny.toml");
    std::fs::write(&path, SCENE).unwrap();
    Scene::load(&path).unwrap()
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn a_resumed_elastoplastic_scene_repeats_the_uninterrupted_run() {
    let scene = scene("resume");
    let mut whole = SceneSim::<f64>::new(&scene).unwrap();
    assert_eq!(whole.solver().name(), "elastoplastic");
    let mut first = SceneSim::<f64>::new(&scene).unwrap();
    for _ in 0..3 {
        whole.advance().unwrap();
        first.advance().unwrap();
    }
    let c = first.checkpoint();
    // The checkpoint carries the stress (6 per particle) and the plastic strain.
    let n = first.state.len();
    let stress = c.solver.array("stress").expect("stress saved");
    assert_eq!(stress.len(), 6 * n);
    assert!(
        stress.iter().any(|&s| s < 0.0),
        "a geostatic block is compressed"
    );
    assert_eq!(c.solver.array("plastic_strain").map(<[f64]>::len), Some(n));
    let mut resumed = SceneSim::<f64>::new(&scene).unwrap();
    resumed.restore(c).unwrap();
    for _ in 0..3 {
        whole.advance().unwrap();
        resumed.advance().unwrap();
    }
    let flat = |s: &SceneSim<f64>| {
        let st = &s.state;
        let mut v: Vec<f64> = st.positions.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
        v.extend(st.velocities.iter().flat_map(|p| [p.x, p.y, p.z]));
        v.extend(&st.densities);
        v
    };
    assert_eq!(bits(&flat(&whole)), bits(&flat(&resumed)));
    let (a, b) = (whole.solver().save_state(), resumed.solver().save_state());
    for name in ["stress", "plastic_strain"] {
        assert_eq!(
            bits(a.array(name).unwrap()),
            bits(b.array(name).unwrap()),
            "{name}"
        );
    }
    assert_eq!(whole.ids, resumed.ids);
    // The output frame carries the stress (as a full tensor) and the plastic strain.
    let path = std::env::temp_dir().join(format!("sph-sim-ep-frame-{}.vtk", std::process::id()));
    whole.write_vtk(&path).unwrap();
    let vtk = vtkio::Vtk::import(&path).unwrap();
    std::fs::remove_file(&path).ok();
    let vtkio::model::DataSet::PolyData { pieces, .. } = vtk.data else {
        panic!("not poly data")
    };
    let vtkio::model::Piece::Inline(p) = &pieces[0] else {
        panic!("not inline")
    };
    let field = |name: &str| -> Vec<f32> {
        p.data
            .point
            .iter()
            .find_map(|x| match x {
                vtkio::model::Attribute::DataArray(d) if d.name == name => {
                    d.data.clone().cast_into::<f32>()
                }
                _ => None,
            })
            .unwrap_or_else(|| panic!("no {name} in the frame"))
    };
    let n = whole.state.len();
    let (tensor, eps) = (field("stress"), field("plastic_strain"));
    assert_eq!((tensor.len(), eps.len()), (9 * n, n));
    let stress = a.array("stress").unwrap();
    for i in [0, n / 2, n - 1] {
        // σ_yy is the tensor's centre entry
        assert_eq!(tensor[9 * i + 4], stress[6 * i + 1] as f32, "particle {i}");
        assert_eq!(eps[i], a.array("plastic_strain").unwrap()[i] as f32);
    }
}

/// A bed periodic along `x` (0.4 m) on a plate with a slot `|x| < 0.06 m` over a channel
/// with free-slip walls, closed by a no-slip trapdoor (`motion`) lowered at 5 cm/s for
/// 0.2 s; spacing 20 mm, 300 grains.
const TRAPDOOR: &str = r#"
name = "ep_trapdoor"
[simulation]
precision = "f64"
particle_spacing = 0.02
duration = 0.32
frame_dt = 0.016
[solver]
kind = "elastoplastic"
substeps = 1
friction_angle_deg = 30.0
cone_match = "simple-shear"
youngs_modulus = 5.84e5
initial_stress = "geostatic"
[boundary]
model = "particles"
periodic = [{ axis = "x", lo = 0.0, hi = 0.4 }, { axis = "z", lo = 0.0, hi = 0.06 }]
[tank]
min = [0.0, -0.3, 0.0]
max = [0.4, 0.3, 0.06]
[[solid]]
kind = "box"
min = [0.06, -0.06, -0.5]
max = [0.34, 0.0, 0.56]
[[solid]]
kind = "box"
min = [0.06, -0.3, -0.5]
max = [0.34, 0.0, 0.56]
wall = "free-slip"
[[solid]]
kind = "box"
min = [-0.06, -0.06, -0.5]
max = [0.06, 0.0, 0.56]
motion = { velocity = [0.0, -0.05, 0.0], duration = 0.2 }
[[fluid]]
kind = "block"
min = [0.0, 0.0, 0.0]
max = [0.4, 0.1, 0.06]
"#;

/// A scene's moving box carries the grains over it down and stops by itself: after 0.32 s
/// the grains that stood over the trapdoor have descended by about its travel, 10 mm (at
/// least half of it, no more than 1.5 times: they follow it with their elastic lag, a few
/// of them from the slot's edges slower), the grains over the plate's middle not at all
/// (under 1 mm), and the rest criterion's wait is the door's 0.2 s.
#[test]
fn a_trapdoor_in_a_scene_lowers_the_grains_over_it() {
    let dir = std::env::temp_dir().join(format!("sph-sim-ep-door-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("ep_trapdoor.toml");
    std::fs::write(&path, TRAPDOOR).unwrap();
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.motion_end_s(), 0.2);
    let mut sim = SceneSim::<f64>::new(&scene).unwrap();
    let start: Vec<_> = sim.state.positions.clone();
    let over_door: Vec<usize> = (0..start.len())
        .filter(|&i| start[i].x < 0.04 || start[i].x > 0.36)
        .collect();
    let middle: Vec<usize> = (0..start.len())
        .filter(|&i| (start[i].x - 0.2).abs() < 0.05)
        .collect();
    while sim.time_s < scene.duration_s - 1e-9 {
        sim.advance().unwrap();
    }
    // Follow each grain by its id (the solver reorders them).
    let now: Vec<_> = {
        let mut by_id = vec![sim.state.positions[0]; start.len()];
        for (k, &id) in sim.ids.iter().enumerate() {
            by_id[id as usize] = sim.state.positions[k];
        }
        by_id
    };
    let mean_drop =
        |set: &[usize]| set.iter().map(|&i| start[i].y - now[i].y).sum::<f64>() / set.len() as f64;
    let (door, plate) = (mean_drop(&over_door), mean_drop(&middle));
    eprintln!("over the door {door:.5} m, over the plate {plate:.5} m");
    assert!(door > 0.005 && door < 0.015, "over the door: {door} m");
    assert!(plate.abs() < 0.001, "over the plate: {plate} m");
}

/// A pour onto a bare floor: a tank 0.4 m long, periodic along `x` and `z`, no grains at the
/// start, a funnel two spacings wide pouring 20 layers of six grains (spacing 20 mm) falling
/// due at 30 layers a second, placed one each fourth frame (a layer waits 1.1 √(s/g) =
/// 49.7 ms after the one before it).
const POURED: &str = r#"
name = "ep_poured"
[simulation]
precision = "f64"
particle_spacing = 0.02
duration = 1.4
frame_dt = 0.016
[solver]
kind = "elastoplastic"
substeps = 1
friction_angle_deg = 30.0
cone_match = "simple-shear"
youngs_modulus = 5.84e5
[boundary]
model = "particles"
periodic = [{ axis = "x", lo = 0.0, hi = 0.4 }, { axis = "z", lo = 0.0, hi = 0.06 }]
[tank]
min = [0.0, 0.0, 0.0]
max = [0.4, 0.5, 0.06]
[pour]
min = [0.18, 0.0, 0.0]
max = [0.22, 0.45, 0.06]
volume = 0.00096
rate = 0.00144
"#;

/// The scene's pour adds its grains in the one frame loop: the ids number them in the order
/// poured, the rest criterion samples the heap only once the last layer is in, and a run
/// resumed from a checkpoint taken in the middle of the pour repeats the uninterrupted one
/// bit for bit.
#[test]
fn a_scene_pours_its_grains_and_resumes_in_the_middle_of_the_pour() {
    let dir = std::env::temp_dir().join(format!("sph-sim-ep-pour-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("ep_poured.toml");
    std::fs::write(&path, POURED).unwrap();
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.poured_grains(), 120);
    let mut whole = SceneSim::<f64>::new(&scene).unwrap();
    assert_eq!((whole.initial_particles(), whole.state.len()), (0, 0));
    let mut rest = RestObserver::new(RestCriterion::default());
    let plan = RunPlan::next(&whole, 20);
    run_frames(&mut whole, &plan, &mut [&mut rest]).unwrap();
    // 20 frames: a layer at the starts of frames 0, 4, 8, 12 and 16 (due every 33 ms, each
    // waiting 49.7 ms after the one before it): 5 layers.
    assert_eq!(whole.state.len(), 30);
    assert!(!whole.pour_finished());
    assert!(rest.samples.is_empty() && rest.verdict.is_none());
    let mut sorted = whole.ids.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, (0..30).collect::<Vec<u32>>());
    let c = whole.checkpoint();
    let mut resumed = SceneSim::<f64>::new(&scene).unwrap();
    resumed.restore(c).unwrap();
    let plan = RunPlan::next(&whole, 60);
    run_frames(&mut whole, &plan, &mut [&mut rest]).unwrap();
    run_frames(&mut resumed, &plan, &mut []).unwrap();
    assert!(whole.pour_finished() && whole.state.len() == 120);
    assert!(!rest.samples.is_empty(), "sampled after the last layer");
    let flat = |s: &SceneSim<f64>| {
        let st = &s.state;
        let mut v: Vec<f64> = st.positions.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
        v.extend(st.velocities.iter().flat_map(|p| [p.x, p.y, p.z]));
        v
    };
    assert_eq!(bits(&flat(&whole)), bits(&flat(&resumed)));
    assert_eq!(whole.ids, resumed.ids);
    // A checkpoint with more grains than the scene pours is refused.
    let mut bad = whole.checkpoint();
    bad.ids.push(120);
    bad.state.push(
        sph_core::Vec3::new(0.2, 0.3, 0.01),
        sph_core::Vec3::zeros(),
        1.0,
        1.0,
    );
    let mut fresh = SceneSim::<f64>::new(&scene).unwrap();
    let e = fresh.restore(bad).unwrap_err();
    assert!(e.contains("pours 120 more"), "{e}");
}
