//! Particle sampling of simple shapes.

use crate::{Aabb, CoreError, Real, Vec3};

/// Points of a simple cubic lattice filling `region` at `spacing` (absolute length): the
/// first point sits half a spacing inside the lower corner, as fluid blocks are sampled in
/// SPlisHSPlasH, so a block of edge `n · spacing` holds `n³` particles. Errors when the
/// spacing is not finite and positive or the lattice would exceed `max_points`.
pub fn cubic_lattice<R: Real>(
    region: &Aabb<R>,
    spacing: R,
    max_points: usize,
) -> Result<Vec<Vec3<R>>, CoreError> {
    if !(spacing.is_finite_value() && spacing > R::zero()) {
        return Err(CoreError::InvalidParameter {
            name: "lattice spacing",
            value: spacing.as_f64(),
            reason: "must be finite and > 0",
        });
    }
    let e = region.extent();
    let counts: [usize; 3] = std::array::from_fn(|a| {
        let c = (e[a] / spacing).as_f64();
        // Round to the nearest count, so that an edge of n spacings gives n points despite
        // rounding; at least one point per axis.
        (c + 1e-9).floor().max(1.0) as usize
    });
    let total = counts.iter().map(|&c| c as f64).product::<f64>();
    if total > max_points as f64 {
        return Err(CoreError::InvalidParameter {
            name: "lattice point count",
            value: total,
            reason: "exceeds the allowed maximum",
        });
    }
    let half = spacing * R::of_f64(0.5);
    let mut out = Vec::with_capacity(total as usize);
    for i in 0..counts[0] {
        for j in 0..counts[1] {
            for k in 0..counts[2] {
                let f = |n: usize, a: usize| region.min[a] + half + spacing * R::of_f64(n as f64);
                out.push(Vec3::new(f(i, 0), f(j, 1), f(k, 2)));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_of_n_spacings_has_n_cubed_points() {
        let b = Aabb::new(Vec3::new(-1.95, 0.05, -0.5), Vec3::new(-0.95, 1.05, 0.5)).unwrap();
        let pts = cubic_lattice(&b, 0.025f64, 1 << 20).unwrap();
        assert_eq!(pts.len(), 40 * 40 * 40);
        assert!(pts.iter().all(|p| b.contains(p)));
        assert!(cubic_lattice(&b, 0.0, 10).is_err());
        assert!(cubic_lattice(&b, 0.001, 10).is_err());
    }
}
