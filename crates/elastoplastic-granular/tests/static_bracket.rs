//! The static bracket: a slope cut in a settled layer holds a few degrees below the
//! slope the cone allows a material that has not flowed, and fails a few degrees above.
//!
//! The physics (docs/elastoplastic-granular.md, "The slope a heap should stand at" and
//! "For a flank that forms by flowing, the reduction is exact"). Bui, Fukagawa, Sako &
//! Ohno (2008), "Lagrangian meshfree particles method (SPH) for large deformation and
//! failure flows of geomaterial using elastic–plastic soil constitutive model", *Int. J.
//! Numer. Anal. Methods Geomech.* 32:1537–1570, use the Drucker–Prager cone
//! `f = √J2 + α_φ I1 − k_c`. In plane strain with `s_zz` = 0 and `c` = 0 a stress on the
//! cone has `τ_max = p sin φ_m`, `sin φ_m = 3 α_φ`: the in-plane Mohr–Coulomb angle of
//! the cone. A slope formed without flowing (a wedge cut in a layer at rest under its
//! geostatic stress) stands by limit equilibrium up to `asin(3 α_φ)`
//! (`ConeMatch::max_stable_slope_deg`). With a non-associated flow rule (`ψ` = 0) a
//! flank that forms by flowing comes to rest lower, at `atan(3 α_φ)` (Davis 1968's
//! reduced strength, exact for steady shear parallel to the surface:
//! `ConeMatch::predicted_repose_angle_deg`), the angle of repose, NOT the bracket's
//! angle. Under the default plane-strain associated match (Bui's `α_φ = tan φ/√(9 +
//! 12 tan² φ)`) at φ = 30° they are 28.71° and 25.66°; under the simple-shear match
//! (`α_φ = tan φ/3`) 35.26° and 30°.
//!
//! Set-up (`heap::cut_slope`): spacing 20 mm, a trapezoidal mound 0.2 m high on a base
//! 0.8 m wide, periodic along `x` (1.2 m) and across a slab three spacings deep (plane
//! strain without walls), a no-slip floor of three rows of boundary particles, the
//! geostatic stress of each column at the start; `E` = 5.84·10⁵ Pa (a tenth of the
//! default, as the docs' runs), `ψ` = 0, `c` = 0, other parameters the defaults. Each
//! case runs 2 s (125 frames).
//!
//! The criteria are those of the static bracket: a slope holds when no grain has moved
//! (in-plane, from its start) half a spacing — none has left its lattice site — and fails
//! when one has moved more than two spacings — a slip beyond where elastic settlement
//! and the staircase surface's corner grains reach. The margin of ±4° is twice the
//! spacing error of the flanks measured at this spacing (2.14° at 20 mm for the drained
//! heaps: `docs/elastoplastic-granular.md`).

mod common;
use common::heap::{cut_slope, SlopeSetup};
use elastoplastic_granular::{ConeMatch, ElastoplasticParams};

const S: f64 = 0.02;
const PHI_DEG: f64 = 30.0;
/// 2 s of frames of 0.016 s.
const FRAMES: usize = 125;

/// The largest in-plane displacement (in spacings) of a grain of the mound with flanks at
/// `max_stable_slope_deg(φ) + offset_deg` over 2 s.
fn largest_displacement(cone_match: ConeMatch, offset_deg: f64) -> f64 {
    let mut p = ElastoplasticParams::<f64>::for_spacing(S, PHI_DEG);
    p.youngs_modulus = 5.84e5;
    p.cone_match = cone_match;
    let setup = SlopeSetup {
        period_x_m: 1.2,
        base_width_m: 0.8,
        height_m: 0.2,
        slope_deg: cone_match.max_stable_slope_deg(PHI_DEG) + offset_deg,
        slab_depth_m: 3.0 * S,
    };
    let (mut solver, mut state) = cut_slope(p, setup).unwrap();
    let start = state.positions.clone();
    // ids[k]: the index at the start of the grain now at k (the solver reorders them).
    let mut ids: Vec<usize> = (0..state.len()).collect();
    let mut largest = 0.0f64;
    for _ in 0..FRAMES {
        solver.step(&mut state).unwrap();
        if let Some(perm) = solver.last_permutation() {
            ids = perm.iter().map(|&o| ids[o as usize]).collect();
        }
        for (x, &i) in state.positions.iter().zip(&ids) {
            let d = x - start[i];
            largest = largest.max(d.x.hypot(d.y) / S);
        }
    }
    println!(
        "{cone_match:?}, slope {:.2}°: largest displacement {largest:.2} spacings",
        setup.slope_deg
    );
    largest
}

#[test]
fn a_settled_slope_four_degrees_below_the_cones_angle_holds_default_match() {
    let d = largest_displacement(ConeMatch::PlaneStrainAssociated, -4.0);
    assert!(d < 0.5, "largest displacement {d} spacings");
}

#[test]
fn a_settled_slope_four_degrees_above_the_cones_angle_fails_default_match() {
    let d = largest_displacement(ConeMatch::PlaneStrainAssociated, 4.0);
    assert!(d > 2.0, "largest displacement {d} spacings");
}

#[test]
fn a_settled_slope_four_degrees_below_the_cones_angle_holds_simple_shear_match() {
    // 31.26°: above the 30° repose angle of this match, which a slope that has not
    // flowed may exceed.
    let d = largest_displacement(ConeMatch::SimpleShear, -4.0);
    assert!(d < 0.5, "largest displacement {d} spacings");
}

#[test]
fn a_settled_slope_four_degrees_above_the_cones_angle_fails_simple_shear_match() {
    let d = largest_displacement(ConeMatch::SimpleShear, 4.0);
    assert!(d > 2.0, "largest displacement {d} spacings");
}
