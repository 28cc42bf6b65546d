//! Periodic axes: particles that leave `[lo, hi)` along a periodic axis re-enter at the other
//! end, and every SPH sum sees the images of the particles near the ends shifted by the
//! period (ghost particles, e.g. Monaghan 2005, *Rep. Prog. Phys.* 68:1703, §8.1). A slab
//! periodic in `z` is in plane strain without walls.
//!
//! At each neighbour search the positions are wrapped into their periods and the images of
//! every particle within `reach` (the search radius) of an end are appended after the `n`
//! particles; the neighbour lists index that extended array, and a neighbour `j ≥ n` is the
//! image `j − n`: particle `src[j − n]` shifted by `shift[j − n]`. Between searches the
//! images move with their particles.

use sph_core::{Real, Vec3};

pub use sph_solver::scene_boundary::PeriodicAxis;

/// The images of the particles near the periodic ends.
#[derive(Debug, Clone, Default)]
pub(crate) struct Images<R: Real> {
    /// The particle each image copies.
    pub src: Vec<u32>,
    /// The image's offset from its particle (m).
    pub shift: Vec<Vec3<R>>,
}

impl<R: Real> Images<R> {
    /// Neighbour `j` of lists built on `n` particles followed by the images: the particle
    /// whose values it carries and its position.
    #[inline]
    pub(crate) fn resolve(&self, j: usize, x: &[Vec3<R>]) -> (usize, Vec3<R>) {
        let n = x.len();
        if j < n {
            (j, x[j])
        } else {
            let k = self.src[j - n] as usize;
            (k, x[k] + self.shift[j - n])
        }
    }

    /// Wraps `x` into the periods of `axes`, then rebuilds the images of every particle
    /// within `reach` of an end (corners included) and writes the particles followed by
    /// their images into `extended`.
    pub(crate) fn rebuild(
        &mut self,
        x: &mut [Vec3<R>],
        axes: &[PeriodicAxis<R>],
        reach: R,
        extended: &mut Vec<Vec3<R>>,
    ) {
        for p in x.iter_mut() {
            for a in axes {
                let l = a.period();
                let c = p[a.axis];
                if c < a.lo || c >= a.hi {
                    let k = ((c - a.lo) / l).floor();
                    let mut w = c - k * l;
                    if w >= a.hi || w < a.lo {
                        w = a.lo;
                    }
                    p[a.axis] = w;
                }
            }
        }
        self.src.clear();
        self.shift.clear();
        extended.clear();
        extended.extend_from_slice(x);
        // Every combination of {−1, 0, +1} periods along the axes but all zeros.
        let combos = 3usize.pow(axes.len() as u32);
        for (i, p) in x.iter().enumerate() {
            for code in 1..combos {
                let mut shift = Vec3::zeros();
                let mut keep = true;
                let mut c = code;
                for a in axes {
                    let o = c % 3;
                    c /= 3;
                    let l = a.period();
                    match o {
                        1 if p[a.axis] < a.lo + reach => shift[a.axis] += l,
                        2 if p[a.axis] >= a.hi - reach => shift[a.axis] -= l,
                        0 => {}
                        _ => keep = false,
                    }
                }
                if keep {
                    self.src.push(i as u32);
                    self.shift.push(shift);
                    extended.push(p + shift);
                }
            }
        }
    }
}
