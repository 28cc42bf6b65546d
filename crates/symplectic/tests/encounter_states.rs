//! The encounter state of population members ([`Encounters`]): cleared when a member is
//! removed inside an encounter, written to the population table (`in_encounter`) for active
//! members only, and the switches counted (`encounters_begun`) with and without the
//! hand-back radius's hysteresis.

use symplectic::{
    outer_solar_system, BodyStates, Encounters, Ephemeris, Frame, Integrator, ParticleIntegrator,
    ParticleStatus, Population, RemovalRules, Scheme, Variant, Vec3,
};

const DAYS_PER_YEAR: f64 = 365.25;

fn ephemeris() -> Ephemeris {
    Ephemeris::new(
        outer_solar_system(Frame::EclipticJ2000),
        Integrator::S2 { step: 365.25 },
    )
    .unwrap()
}

/// The Sun and the planets (barycentric) at `t = 0`.
fn bodies_at_epoch() -> BodyStates {
    let mut bodies = BodyStates::default();
    ephemeris().bodies_at(0.0, &mut bodies).unwrap();
    bodies
}

/// Jupiter's (planet 1) barycentric state at `t = 0`, and its Hill radius
/// `|Q_J| (m_J/3m₀)^{1/3}` with `Q_J` heliocentric, as the population computes it.
fn jupiter() -> (Vec3, Vec3, f64) {
    let b = bodies_at_epoch();
    let hill = (b.positions[1] - b.positions[0]).norm() * (b.gm[1] / (3.0 * b.gm[0])).cbrt();
    (b.positions[1], b.velocities[1], hill)
}

/// A comet on Jupiter's heliocentric two-body orbit (about `G(m₀ + m_J)`), `lag_days` behind
/// it: Jupiter's heliocentric state drifted back by `lag_days`, barycentric.
fn co_orbital(lag_days: f64) -> (Vec3, Vec3) {
    let b = bodies_at_epoch();
    let mut q = b.positions[1] - b.positions[0];
    let mut v = b.velocities[1] - b.velocities[0];
    symplectic::kepler::drift(&mut q, &mut v, b.gm[0] + b.gm[1], -lag_days).unwrap();
    (q + b.positions[0], v + b.velocities[0])
}

/// A population through encounters (barycentric S2, `B₁ = 4·10⁻⁶` as the Centaur tests),
/// removed below q = 2.5 AU or beyond 100 AU unbound, first steps of one day.
fn population(states: &[(Vec3, Vec3)], encounters: Encounters) -> Population {
    let integ = ParticleIntegrator::new(Variant::Barycentric, Scheme::S2, 0.0, 4e-6).unwrap();
    let rules = RemovalRules {
        hill_factor: None,
        min_perihelion: Some(2.5),
        ejection_distance: Some(100.0),
        ..RemovalRules::default()
    };
    let ids: Vec<u64> = (0..states.len() as u64).collect();
    let mut pop = Population::new(ephemeris(), integ, rules, 0.0, 1.0, states, &ids).unwrap();
    pop.set_encounters(Some(encounters)).unwrap();
    pop
}

/// Comet 0 falls straight into Jupiter from 0.3 AU at 0.02 AU/day and ends in a collision
/// inside the encounter mode; comet 1 trails Jupiter on its orbit at about 2 Hill radii and
/// is still in the encounter mode after a year. The removed comet holds no encounter state
/// and is not flagged `in_encounter`; the other is.
#[test]
fn a_comet_removed_in_an_encounter_is_no_longer_in_it() {
    let (q_j, v_j, hill) = jupiter();
    let towards = (q_j / q_j.norm()) * 0.3;
    let falling = (q_j + towards, v_j - towards / towards.norm() * 0.02);
    // 2 Hill radii along the orbit at Jupiter's ≈ 0.0075 AU/day (checked below).
    let trailing = co_orbital(2.0 * hill / 0.0075);
    let start_ratio = (trailing.0 - q_j).norm() / hill;
    assert!(
        (1.5..2.5).contains(&start_ratio),
        "{start_ratio} Hill radii"
    );
    let mut pop = population(&[falling, trailing], Encounters::default());
    pop.advance_to(DAYS_PER_YEAR, |_| {}).unwrap();
    let [fell, trails] = pop.members() else {
        panic!("two members")
    };
    // At 0.02 AU/day from 0.3 AU the comet reaches Jupiter within 15 days, in the encounter
    // mode (it switched at its first step's end, 0.85 Hill radii from Jupiter).
    match fell.status {
        ParticleStatus::Collision { planet, time, .. } => {
            assert_eq!(planet, 1, "Jupiter");
            assert!(time < 15.0, "collision at {time} days");
        }
        ref s => panic!("expected a collision with Jupiter, got {s:?}"),
    }
    assert!(
        fell.encounter.is_none(),
        "removed, still in the encounter mode"
    );
    assert_eq!(trails.status, ParticleStatus::Active);
    assert!(
        trails.encounter.is_some(),
        "trailing Jupiter, not in an encounter"
    );
    #[cfg(feature = "parquet")]
    {
        let table = symplectic::io::population_table(&pop).unwrap();
        let flag = table
            .column_by_name("in_encounter")
            .unwrap()
            .as_any()
            .downcast_ref::<arrow_array::BooleanArray>()
            .unwrap();
        assert_eq!((flag.value(0), flag.value(1)), (false, true));
    }
}

/// A comet circling Jupiter at `radius_hill` Hill radii, retrograde, in Hill's approximation
/// (a quasi-satellite: Jupiter's semi-major axis, in its own orbit's frame `r̂` radial, `t̂`
/// along the orbit, `ĥ` normal): the epicycle `x = −A cos nt`, `y = 2A sin nt` of the linear
/// Hill equations with a vertical oscillation `z = √3 A cos nt`, whose distance
/// `√(x² + y² + z²) = 2A` is constant; `v = V_J + A n t̂` at `t = 0`, then scaled to
/// Jupiter's two-body energy (no drift along the orbit).
fn quasi_satellite(radius_hill: f64) -> (Vec3, Vec3) {
    let b = bodies_at_epoch();
    let (q_j, v_j) = (
        b.positions[1] - b.positions[0],
        b.velocities[1] - b.velocities[0],
    );
    let hill = q_j.norm() * (b.gm[1] / (3.0 * b.gm[0])).cbrt();
    let h = q_j.cross(&v_j);
    let n = h.norm() / q_j.norm_squared();
    let (r_hat, h_hat) = (q_j.normalize(), h.normalize());
    let t_hat = h_hat.cross(&r_hat);
    let a = 0.5 * radius_hill * hill;
    let q = q_j - a * r_hat + 3f64.sqrt() * a * h_hat;
    let v = v_j + a * n * t_hat;
    let mu = b.gm[0] + b.gm[1];
    let speed2 = v_j.norm_squared() + 2.0 * mu * (1.0 / q.norm() - 1.0 / q_j.norm());
    let v = v * (speed2.sqrt() / v.norm());
    (q + b.positions[0], v + b.velocities[0])
}

/// Advances `pop` (one member) to `years` in quarter years; returns the member's distance to
/// Jupiter in Hill radii at each of those synchronisations (from the ephemeris at the
/// member's own time).
fn hill_ratios(pop: &mut Population, years: f64) -> Vec<f64> {
    let mut bodies = BodyStates::default();
    let mut ratios = Vec::new();
    let mut t = 0.0;
    while t < years * DAYS_PER_YEAR {
        t += 0.25 * DAYS_PER_YEAR;
        pop.advance_to(t, |_| {}).unwrap();
        let m = &pop.members()[0];
        pop.ephemeris()
            .interpolate(m.particle.time, &mut bodies, false)
            .unwrap();
        let sun_jupiter = bodies.positions[1] - bodies.positions[0];
        let hill = sun_jupiter.norm() * (bodies.gm[1] / (3.0 * bodies.gm[0])).cbrt();
        ratios.push((m.particle.position - bodies.positions[1]).norm() / hill);
    }
    ratios
}

/// A quasi-satellite of Jupiter started at 3.2 Hill radii skims the switch radius: over
/// its first 7 years it dips below 3 R_H, rises above it (to about 3.2) and dips again,
/// not reaching 3.5 in between, then leaves. With the default hand-back radius (3.5 R_H) it switches
/// to the encounter mode once and stays in it through the skim; with the hand-back at the
/// switch radius (no hysteresis) it switches at each dip. The counts are read from the
/// member, the table's `encounters_begun` and the population's progress.
#[test]
fn a_comet_skimming_the_switch_radius_switches_once_with_hysteresis() {
    let years = 10.0;
    let comet = quasi_satellite(3.2);
    let mut with = population(&[comet], Encounters::default());
    assert_eq!(with.encounters().unwrap().hand_back_hill_factor, 3.5);
    let ratios = hill_ratios(&mut with, years);
    // The skim, from the trajectory: dips below 3 R_H that start from above it, and the
    // highest point between the first two (it rises above 3 R_H, not to 3.5).
    let dips: Vec<usize> = (1..ratios.len())
        .filter(|&k| ratios[k - 1] >= 3.0 && ratios[k] < 3.0)
        .collect();
    assert!(
        dips.len() >= 2,
        "{} dips below 3 R_H: {ratios:.2?}",
        dips.len()
    );
    let skim_high = ratios[dips[0]..dips[1]]
        .iter()
        .fold(0.0f64, |a, &b| a.max(b));
    assert!(
        (3.0..3.5).contains(&skim_high),
        "up to {skim_high} R_H between the dips: {ratios:.2?}"
    );
    let begun = |p: &Population| p.members()[0].encounters_begun;
    assert_eq!(begun(&with), 1, "with hysteresis");
    assert_eq!(with.progress().encounters_begun, 1);
    // One close encounter with Jupiter (the comet stays within twice the switch radius
    // between the dips), of one switch.
    let per = with.switches_per_encounter();
    assert_eq!(
        (per.encounters, per.switches, per.max),
        (1, 1, 1),
        "{per:?}"
    );

    let sharp = Encounters {
        hand_back_hill_factor: Encounters::default().hill_factor,
        ..Encounters::default()
    };
    let mut without = population(&[comet], sharp);
    let ratios = hill_ratios(&mut without, years);
    assert!(
        begun(&without) > 1,
        "{} switches without hysteresis",
        begun(&without)
    );
    // Still one encounter, now of several switches.
    let per = without.switches_per_encounter();
    assert_eq!(per.encounters, 1, "{per:?}");
    assert_eq!(per.max, begun(&without), "{per:?}");
    assert_eq!(per.mean(), f64::from(begun(&without)), "{per:?}");
    // The encounter is over once the comet is beyond twice the switch radius at a map
    // step's end (each ratio is at one), under way while it has not been.
    let open = without.members()[0].tally.open.map(|o| o.planet);
    let last = ratios[ratios.len() - 1];
    if last >= 2.0 * 3.0 {
        assert_eq!(open, None, "at {last} R_H: {ratios:.2?}");
    } else if ratios.iter().all(|&r| r < 2.0 * 3.0) {
        assert_eq!(open, Some(1), "{ratios:.2?}");
    }
    #[cfg(feature = "parquet")]
    {
        let table = symplectic::io::population_table(&without).unwrap();
        let column = table
            .column_by_name("encounters_begun")
            .unwrap()
            .as_any()
            .downcast_ref::<arrow_array::UInt64Array>()
            .unwrap();
        assert_eq!(column.value(0), u64::from(begun(&without)));
        for (name, value) in [
            ("planet_encounters", 1),
            ("planet_encounter_switches", begun(&without)),
            ("max_switches_per_encounter", begun(&without)),
        ] {
            let column = table
                .column_by_name(name)
                .unwrap()
                .as_any()
                .downcast_ref::<arrow_array::UInt64Array>()
                .unwrap();
            assert_eq!(column.value(0), u64::from(value), "{name}");
        }
    }
}

/// The hand-back radius is checked: finite, positive, not inside the switch radius; the
/// error names the setting.
#[test]
fn a_hand_back_radius_inside_the_switch_radius_is_refused() {
    let comet = quasi_satellite(3.2);
    let mut pop = population(&[comet], Encounters::default());
    for bad in [2.9, 0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = pop
            .set_encounters(Some(Encounters {
                hand_back_hill_factor: bad,
                ..Encounters::default()
            }))
            .unwrap_err()
            .to_string();
        assert!(e.contains("encounters.hand_back_hill_factor"), "{bad}: {e}");
    }
    let e = pop
        .set_encounters(Some(Encounters {
            hill_factor: 4.0,
            ..Encounters::default()
        }))
        .unwrap_err()
        .to_string();
    assert!(e.contains(">= encounters.hill_factor"), "{e}");
    // Equal radii: a sharp switch, allowed.
    pop.set_encounters(Some(Encounters {
        hill_factor: 4.0,
        hand_back_hill_factor: 4.0,
        ..Encounters::default()
    }))
    .unwrap();
}

/// A population saved before the hand-back radius existed (checkpoint version 1: no
/// `hand_back_hill_factor`, no `encounters_begun`) goes on as it was integrated, handed
/// back at its switch radius, and continues bit for bit as a population built that way;
/// a later version is refused by name.
#[test]
fn a_version_1_checkpoint_goes_on_without_hysteresis() {
    let dir = std::env::temp_dir().join(format!("encounter-states-v1-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("population.json");
    let comet = quasi_satellite(3.2);
    let sharp = Encounters {
        hand_back_hill_factor: Encounters::default().hill_factor,
        ..Encounters::default()
    };
    let mut straight = population(&[comet], sharp);
    straight.advance_to(10.0 * DAYS_PER_YEAR, |_| {}).unwrap();
    let mut first = population(&[comet], sharp);
    first.advance_to(2.0 * DAYS_PER_YEAR, |_| {}).unwrap();
    first.save(&path).unwrap();
    // The file as version 1 wrote it: the new fields taken out.
    let mut json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    assert_eq!(json["version"], 3);
    json["version"] = 1.into();
    let population_json = json["population"].as_object_mut().unwrap();
    population_json.remove("events").unwrap();
    let rules = population_json["rules"].as_object_mut().unwrap();
    for key in ["sun_collision", "min_distance", "max_distance"] {
        rules.remove(key).unwrap();
    }
    population_json["encounters"]
        .as_object_mut()
        .unwrap()
        .remove("hand_back_hill_factor")
        .unwrap();
    for m in population_json["members"].as_array_mut().unwrap() {
        m.as_object_mut()
            .unwrap()
            .remove("encounters_begun")
            .unwrap();
    }
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    let mut resumed = Population::load(&path).unwrap();
    assert_eq!(
        resumed.encounters(),
        Some(sharp),
        "handed back at the switch radius"
    );
    resumed.advance_to(10.0 * DAYS_PER_YEAR, |_| {}).unwrap();
    // The trajectory bit for bit (the count of switches starts at 0 in a version 1 file).
    let m = (&resumed.members()[0], &straight.members()[0]);
    assert_eq!(
        (&m.0.particle, &m.0.status, &m.0.encounter),
        (&m.1.particle, &m.1.status, &m.1.encounter)
    );
    assert_eq!(
        m.0.encounters_begun + first.members()[0].encounters_begun,
        m.1.encounters_begun
    );
    json["version"] = 4.into();
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    let e = Population::load(&path).unwrap_err().to_string();
    assert!(
        e.contains("version 4, expected") && e.contains("version 1 to 3"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A member saved in the encounter mode by a version 2 checkpoint, whose encounter state held
/// the Sun, the planets and the particle, goes on among the ephemeris' planets from the
/// particle's state; a state of neither layout ends the member with the reason named.
#[test]
fn a_version_2_encounter_state_is_converted() {
    let dir = std::env::temp_dir().join(format!("encounter-states-v2-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("population.json");
    // A quasi-satellite inside 1.5 Hill radii: in the encounter mode from its first step on.
    let mut pop = population(&[quasi_satellite(1.5)], Encounters::default());
    pop.advance_to(DAYS_PER_YEAR, |_| {}).unwrap();
    assert!(
        pop.members()[0].encounter.is_some(),
        "in the encounter mode"
    );
    pop.save(&path).unwrap();
    let mut straight = Population::load(&path).unwrap();
    straight.advance_to(1.5 * DAYS_PER_YEAR, |_| {}).unwrap();
    let mut json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    assert_eq!(json["version"], 3);
    json["version"] = 2.into();
    let state = &mut json["population"]["members"][0]["encounter"]["state"];
    let particle: Vec<f64> = state
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    // Version 2's layout: the positions of the Sun, the four planets and the particle, then
    // their velocities (the bodies' values are not read).
    let mut old = vec![0.0; 36];
    old[15..18].copy_from_slice(&particle[0..3]);
    old[33..36].copy_from_slice(&particle[3..6]);
    *state = serde_json::to_value(&old).unwrap();
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    let mut converted = Population::load(&path).unwrap();
    converted.advance_to(1.5 * DAYS_PER_YEAR, |_| {}).unwrap();
    let (a, b) = (&converted.members()[0], &straight.members()[0]);
    assert_eq!(a.status, ParticleStatus::Active);
    // The same equations for position and velocity from the same state; only `p₄` (reset to
    // −H, where the straight run carries its integrated value) enters the step control. 10⁻⁶
    // AU: far above the tolerance's 10⁻¹² per step over the half year's steps, far below the
    // astronomical units by which a body's state taken for the particle's would differ.
    let apart = (a.particle.position - b.particle.position).norm();
    assert!(apart < 1e-6, "{apart:e} AU from the straight run");
    // A state of neither layout: the member ends, the state named.
    json["population"]["members"][0]["encounter"]["state"] =
        serde_json::to_value([1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    let mut broken = Population::load(&path).unwrap();
    broken.advance_to(1.5 * DAYS_PER_YEAR, |_| {}).unwrap();
    match &broken.members()[0].status {
        ParticleStatus::IntegrationFailed { reason, .. } => {
            assert!(
                reason.contains("encounter state") && reason.contains("5 values"),
                "{reason}"
            )
        }
        other => panic!("{other:?}"),
    }
    std::fs::remove_dir_all(&dir).ok();
}
