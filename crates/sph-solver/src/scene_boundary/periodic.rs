//! Periodic axes: the medium repeats along an axis with a period, as a scene states it
//! (`[solver] periodic = [{ axis = "z", lo = 0.0, hi = 0.03 }]`), and the ghost particles
//! that make every SPH sum see it ([`PeriodicImages`]; e.g. Monaghan 2005, *Rep. Prog.
//! Phys.* 68:1703, §8.1). A slab periodic in `z` is in plane strain without walls.
//!
//! At each neighbour search the positions are wrapped into their periods and the images of
//! every particle within `reach` (the search radius) of an end are appended after the `n`
//! particles; the neighbour lists index that extended array, and a neighbour `j ≥ n` is the
//! image `j − n`: particle `src[j − n]` shifted by `shift[j − n]`. Between searches the
//! images move with their particles.

use serde::Deserialize;
use sph_core::{Real, Vec3};

/// One periodic axis: the particles' coordinate `axis` (0 = x, 1 = y, 2 = z) lives in
/// `[lo, hi)` (m) and the medium repeats with period `hi − lo`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodicAxis<R: Real> {
    /// The axis (0 = x, 1 = y, 2 = z).
    pub axis: usize,
    /// Lower end of the period (m).
    pub lo: R,
    /// Upper end of the period (m).
    pub hi: R,
}

impl<R: Real> PeriodicAxis<R> {
    /// The period `hi − lo` (m).
    pub fn period(&self) -> R {
        self.hi - self.lo
    }
}

/// The images of the particles near the periodic ends.
#[derive(Debug, Clone, Default)]
pub struct PeriodicImages<R: Real> {
    /// The particle each image copies.
    pub src: Vec<u32>,
    /// The image's offset from its particle (m).
    pub shift: Vec<Vec3<R>>,
}

impl<R: Real> PeriodicImages<R> {
    /// Neighbour `j` of lists built on `n` particles followed by the images: the particle
    /// whose values it carries and its position.
    #[inline]
    pub fn resolve(&self, j: usize, x: &[Vec3<R>]) -> (usize, Vec3<R>) {
        let n = x.len();
        if j < n {
            (j, x[j])
        } else {
            let k = self.src[j - n] as usize;
            (k, x[k] + self.shift[j - n])
        }
    }

    /// Writes the particles `x` followed by their images into `extended` (as
    /// [`PeriodicImages::rebuild`] does, without wrapping or finding the images again): the
    /// images' positions after the particles have moved.
    pub fn refresh(&self, x: &[Vec3<R>], extended: &mut Vec<Vec3<R>>) {
        extended.clear();
        extended.extend_from_slice(x);
        extended.extend(
            self.src
                .iter()
                .zip(&self.shift)
                .map(|(&k, shift)| x[k as usize] + shift),
        );
    }

    /// The particle each entry of the particles `0..n` followed by the images stands for
    /// (`owner[j]` is [`PeriodicImages::resolve`]'s index), into `owner`.
    pub fn owners(&self, n: usize, owner: &mut Vec<u32>) {
        owner.clear();
        owner.extend(0..n as u32);
        owner.extend_from_slice(&self.src);
    }

    /// Wraps `x` into the periods of `axes`, then rebuilds the images of every particle
    /// within `reach` of an end (corners included) and writes the particles followed by
    /// their images into `extended`.
    pub fn rebuild(
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
                }
            }
        }
        self.refresh(x, extended);
    }
}

/// The offsets of a point's periodic images along `axes`: zero and `±period` along each
/// axis and their combinations (1, 3, 9 or 27 offsets, zero first).
pub fn image_offsets<R: Real>(axes: &[PeriodicAxis<R>]) -> Vec<Vec3<R>> {
    let mut out = vec![Vec3::zeros()];
    for a in axes {
        let shift = |sign: R| {
            let mut e: Vec3<R> = Vec3::zeros();
            e[a.axis] = sign * a.period();
            e
        };
        let ends = [shift(R::one()), shift(-R::one())];
        let more: Vec<Vec3<R>> = out.iter().flat_map(|o| ends.map(|e| o + e)).collect();
        out.extend(more);
    }
    out
}

/// An axis in scene files: `"x"`, `"y"` or `"z"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// `x` (0).
    X,
    /// `y` (1).
    Y,
    /// `z` (2).
    Z,
}

impl Axis {
    /// The coordinate index (0, 1, 2).
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// One periodic axis as a scene writes it: `{ axis = "z", lo = 0.0, hi = 0.03 }` (m),
/// [`PeriodicAxis`].
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeriodicSetting {
    /// The axis.
    pub axis: Axis,
    /// Lower end of the period (m).
    pub lo: f64,
    /// Upper end of the period (m).
    pub hi: f64,
}

impl PeriodicSetting {
    /// The axis as the solvers take it.
    pub fn to_axis(&self) -> PeriodicAxis<f64> {
        PeriodicAxis {
            axis: self.axis.index(),
            lo: self.lo,
            hi: self.hi,
        }
    }
}
