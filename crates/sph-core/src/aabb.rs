use crate::{CoreError, Real, Vec3};

/// Axis-aligned box `[min, max]` (closed), in the simulation's length unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb<R: Real> {
    /// Lower corner.
    pub min: Vec3<R>,
    /// Upper corner.
    pub max: Vec3<R>,
}

impl<R: Real> Aabb<R> {
    /// A box from its corners; errors when a corner is not finite or `min > max` on an axis.
    pub fn new(min: Vec3<R>, max: Vec3<R>) -> Result<Self, CoreError> {
        for axis in 0..3 {
            for (v, name) in [(min[axis], "box min"), (max[axis], "box max")] {
                if !v.is_finite_value() {
                    return Err(CoreError::InvalidParameter {
                        name,
                        value: v.as_f64(),
                        reason: "corner components must be finite",
                    });
                }
            }
            if min[axis] > max[axis] {
                return Err(CoreError::InvalidParameter {
                    name: "box max",
                    value: max[axis].as_f64(),
                    reason: "max must be >= min on every axis",
                });
            }
        }
        Ok(Self { min, max })
    }

    /// Smallest box holding every point; `None` for an empty slice. Non-finite points are
    /// an error naming the first one.
    pub fn from_points(points: &[Vec3<R>]) -> Result<Option<Self>, CoreError> {
        crate::validate_finite_positions(points)?;
        let mut it = points.iter();
        let Some(first) = it.next() else {
            return Ok(None);
        };
        let (mut min, mut max) = (*first, *first);
        for p in it {
            min = min.inf(p);
            max = max.sup(p);
        }
        Ok(Some(Self { min, max }))
    }

    /// Edge lengths `max - min`.
    pub fn extent(&self) -> Vec3<R> {
        self.max - self.min
    }

    /// Centre point.
    pub fn center(&self) -> Vec3<R> {
        (self.min + self.max) * R::of_f64(0.5)
    }

    /// Volume (length³).
    pub fn volume(&self) -> R {
        let e = self.extent();
        e.x * e.y * e.z
    }

    /// `true` when `p` lies in the closed box.
    pub fn contains(&self, p: &Vec3<R>) -> bool {
        (0..3).all(|a| p[a] >= self.min[a] && p[a] <= self.max[a])
    }

    /// The box grown by `margin` on every side (shrunk for a negative margin).
    pub fn expanded(&self, margin: R) -> Self {
        let m = Vec3::repeat(margin);
        Self {
            min: self.min - m,
            max: self.max + m,
        }
    }

    /// Smallest box holding both boxes.
    pub fn union(&self, other: &Self) -> Self {
        Self {
            min: self.min.inf(&other.min),
            max: self.max.sup(&other.max),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_points_bounds_and_contains() {
        let pts = vec![Vec3::new(1.0, -2.0, 3.0), Vec3::new(-1.0, 5.0, 0.0)];
        let b = Aabb::from_points(&pts).unwrap().unwrap();
        assert_eq!(b.min, Vec3::new(-1.0, -2.0, 0.0));
        assert_eq!(b.max, Vec3::new(1.0, 5.0, 3.0));
        assert!(pts.iter().all(|p| b.contains(p)));
        assert!(!b.contains(&Vec3::new(0.0, 0.0, 3.5)));
        assert_eq!(b.volume(), 2.0 * 7.0 * 3.0);
        assert!(Aabb::<f64>::from_points(&[]).unwrap().is_none());
    }

    #[test]
    fn rejects_inverted_and_nan_boxes() {
        assert!(Aabb::new(Vec3::new(1.0f32, 0.0, 0.0), Vec3::zeros()).is_err());
        assert!(Aabb::new(Vec3::new(f64::NAN, 0.0, 0.0), Vec3::zeros()).is_err());
        let err = Aabb::from_points(&[Vec3::zeros(), Vec3::new(0.0, f64::INFINITY, 0.0)]);
        assert_eq!(
            err.unwrap_err(),
            CoreError::NonFinitePosition {
                index: 1,
                axis: 'y',
                value: f64::INFINITY
            }
        );
    }
}
