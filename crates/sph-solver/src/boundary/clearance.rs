//! Lower bounds on the particles' distances to the solids, carried along their moves, so
//! that a solver calls the contact response and the divergence check's distance only where
//! they can act.
//!
//! A solid whose signed distance `φ` has the Lipschitz constant `L`
//! ([`Sdf::lipschitz_bound`]: 1 for exact distances) satisfies
//! `φ(y) ≥ φ(x) − L |y − x|`. A particle whose distance was evaluated at `x` and which then
//! moves to `y` is farther than `c = φ(x) − L |y − x| − δ` from every solid (`δ`, below,
//! covers the rounding of both evaluations and of the move). When `c` is at least the
//! contact distance, [`project_out`](super::project_out) leaves `y` unchanged (it moves a
//! position only where some solid's `φ` is below the contact distance), so skipping it gives
//! the same bits; the particle's bound becomes `c`, and the next move subtracts again.
//! A projected particle's bound is `−∞` (it is evaluated in full from then on). The check
//! for a particle deeper than `h` inside a solid is skipped where `c ≥ −h`, for the same
//! reason.
//!
//! The rounding allowance is `δ = 64 ε (1 m + |x|∞ + |y|∞)` (`ε` the precision's machine
//! epsilon): an analytic distance evaluated in a few operations on coordinates of size
//! `|x|∞` is within a few `ε |x|∞` of the exact one; the allowance takes sixty-four of them
//! and costs nothing measurable (it only makes a few particles within a hair of the
//! contact distance take the full evaluation).

use sph_core::{Real, Sdf, Vec3};

use super::Boundary;

/// Multiples of the machine epsilon (times the coordinates' size) in the rounding allowance.
const ROUNDING_ULPS: f64 = 64.0;

/// A boundary's contact response seen from the particles' distance bounds: the largest
/// Lipschitz constant of its solids and its contact distance. Only a boundary whose
/// [`Boundary::project`] is [`project_out`](super::project_out) over its solids at its
/// [`Boundary::contact_distance`] hands one out ([`Boundary::contact_guard`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactGuard<R: Real> {
    /// The largest Lipschitz constant of the solids' signed distances.
    lipschitz: R,
    /// The distance (m) the contact response keeps particles from the surfaces.
    contact_distance: R,
}

impl<R: Real> ContactGuard<R> {
    /// The guard of a contact response that projects out of `solids` to
    /// `contact_distance`; `None` when a solid declares no Lipschitz bound (then every
    /// position is evaluated in full).
    pub fn for_solids(solids: &[Box<dyn Sdf<R>>], contact_distance: R) -> Option<Self> {
        let mut lipschitz = 0.0f64;
        for s in solids {
            let l = s.lipschitz_bound()?;
            if !(l.is_finite() && l >= 0.0) {
                return None;
            }
            lipschitz = lipschitz.max(l);
        }
        Some(Self {
            lipschitz: R::of_f64(lipschitz),
            contact_distance,
        })
    }

    /// The bound at `to` of a particle whose bound at `from` is `clearance` (where it was
    /// evaluated, [`Boundary::distance`]):
    /// `clearance − L |to − from| − δ` (module docs). `+∞` stays `+∞` (no solids); NaN
    /// stays NaN (and fails every test that would skip work).
    #[inline]
    pub fn carried(&self, clearance: R, from: &Vec3<R>, to: &Vec3<R>) -> R {
        let step = (to - from).norm();
        let scale = R::one() + from.amax() + to.amax();
        let allowance = R::of_f64(ROUNDING_ULPS) * R::MACHINE_EPSILON * scale;
        clearance - self.lipschitz * step - allowance
    }

    /// The contact response of a particle moving from `from` (where its bound is
    /// `*clearance`) to `to`: `to` itself when the carried bound proves it farther than the
    /// contact distance from every solid (the bound becomes the carried one), else
    /// `boundary.project(to)` (the bound becomes `−∞`). The same bits as
    /// `boundary.project(to)` in both cases.
    #[inline]
    pub fn project(
        &self,
        boundary: &dyn Boundary<R>,
        clearance: &mut R,
        from: &Vec3<R>,
        to: Vec3<R>,
    ) -> Vec3<R> {
        let c = self.carried(*clearance, from, &to);
        if c >= self.contact_distance {
            *clearance = c;
            to
        } else {
            *clearance = R::of_f64(f64::NEG_INFINITY);
            boundary.project(to)
        }
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use sph_core::{Aabb, BoxSdf, Inverted, Sdf, Sphere, Vec3};

    use super::ContactGuard;
    use crate::boundary::{Boundary, CollisionBoundary};

    fn tank() -> CollisionBoundary<f32> {
        let aabb = Aabb::new(Vec3::new(-1.0, 0.0, -0.5), Vec3::new(1.0, 1.5, 0.5)).unwrap();
        let solids: Vec<Box<dyn Sdf<f32>>> = vec![
            Box::new(Inverted(BoxSdf::new(aabb).unwrap())),
            Box::new(Sphere::new(Vec3::new(0.3, 0.2, 0.0), 0.25).unwrap()),
        ];
        CollisionBoundary::new(solids, 0.0125).unwrap()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// A chain of moves with the guard gives the positions of a chain of full
        /// projections, bit for bit, and every carried bound is below the distance as
        /// evaluated (the oracle: `project` and `distance` at every position).
        #[test]
        fn guarded_moves_are_the_full_projections(
            start in (-1.2f32..1.2, -0.2f32..1.7, -0.7f32..0.7),
            moves in prop::collection::vec((-0.08f32..0.08, -0.08f32..0.08, -0.08f32..0.08), 1..12),
        ) {
            let b = tank();
            let guard = b.contact_guard().expect("analytic solids");
            let start = Vec3::new(start.0, start.1, start.2);
            let (mut x, mut y) = (start, start);
            let mut bound = b.distance(&x);
            for (dx, dy, dz) in moves {
                let d = Vec3::new(dx, dy, dz);
                let next = guard.project(&b, &mut bound, &x, x + d);
                let full = b.project(y + d);
                prop_assert_eq!(next, full);
                let d = b.distance(&next);
                prop_assert!(bound <= d || bound.is_nan(), "bound {} above the distance {}", bound, d);
                x = next;
                y = full;
            }
        }
    }

    /// A solid without a Lipschitz bound gives no guard.
    #[test]
    fn no_guard_without_lipschitz_bounds() {
        struct Wobbly;
        impl Sdf<f32> for Wobbly {
            fn signed_distance(&self, p: &Vec3<f32>) -> f32 {
                p.y - 0.1 * (10.0 * p.x).sin()
            }
            fn gradient(&self, _p: &Vec3<f32>) -> Vec3<f32> {
                Vec3::y()
            }
        }
        let solids: Vec<Box<dyn Sdf<f32>>> = vec![Box::new(Wobbly)];
        assert!(ContactGuard::for_solids(&solids, 0.01).is_none());
        assert!(CollisionBoundary::new(solids, 0.01)
            .unwrap()
            .contact_guard()
            .is_none());
    }
}
