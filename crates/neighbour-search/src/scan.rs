//! The innermost loop shared by every fast method: one particle against a contiguous,
//! structure-of-arrays block of gathered candidates.
//!
//! On x86-64 CPUs with AVX2 (detected at run time; nothing is compiled with
//! `target-cpu=native`), eight candidates are tested per instruction sequence and the
//! indices that pass are left-packed with one permutation from a 256-entry table, without
//! a branch. Elsewhere a portable branch-free loop does the same one candidate at a time.
//! Both evaluate `(dx·dx + dy·dy) + dz·dz < h²` with the same IEEE operations in the same
//! order as [`crate::squared_distance`] (no fused multiply-add), so results are identical.

use std::any::TypeId;

use sph_core::Real;

/// Lanes processed per step; gathered blocks are padded to a multiple of this.
const LANES: usize = 8;

/// Candidates gathered for one cell.
#[derive(Debug, Clone, Default)]
pub(crate) struct Gathered<R> {
    xs: Vec<R>,
    ys: Vec<R>,
    zs: Vec<R>,
    /// Caller's index of each candidate.
    ids: Vec<u32>,
    /// Number of real (unpadded) candidates.
    len: usize,
}

impl<R: Real> Gathered<R> {
    pub fn clear(&mut self) {
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
        self.ids.clear();
        self.len = 0;
    }

    /// Appends candidates.
    #[inline]
    pub fn extend(&mut self, xs: &[R], ys: &[R], zs: &[R], ids: &[u32]) {
        append(&mut self.xs, xs);
        append(&mut self.ys, ys);
        append(&mut self.zs, zs);
        append(&mut self.ids, ids);
        self.len = self.xs.len();
    }

    /// Appends one candidate.
    #[inline]
    pub fn push(&mut self, x: R, y: R, z: R, id: u32) {
        self.xs.push(x);
        self.ys.push(y);
        self.zs.push(z);
        self.ids.push(id);
        self.len = self.xs.len();
    }

    /// Number of candidates gathered so far.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Pads to a multiple of the lane count with candidates at infinity, which fail every
    /// test (`(p − ∞)² = ∞`, never NaN for a finite `p`). Call once after gathering.
    pub fn finish(&mut self) {
        let inf = R::of_f64(f64::INFINITY);
        while self.xs.len() % LANES != 0 {
            self.xs.push(inf);
            self.ys.push(inf);
            self.zs.push(inf);
            self.ids.push(u32::MAX);
        }
    }

    /// Appends to `out` the neighbours of candidate `e` (the query particle, skipped)
    /// among all gathered candidates, in gathered order; returns how many.
    #[inline]
    pub fn neighbours_of(&mut self, e: usize, r2: R, out: &mut Vec<u32>) -> u32 {
        debug_assert!(e < self.len && self.xs.len() % LANES == 0);
        let (px, py, pz) = (self.xs[e], self.ys[e], self.zs[e]);
        // Exclude the particle itself by moving its copy to infinity for this scan.
        self.xs[e] = R::of_f64(f64::INFINITY);
        let m = self.xs.len();
        out.reserve(m);
        let before = out.len();
        // SAFETY: `out` has room for `m` more entries; every kernel writes at most
        // `found + LANES <= m` entries past `before` (m is a multiple of LANES) and
        // returns `found`, all of which it has initialised.
        let found = unsafe {
            let dst = out.as_mut_ptr().add(before);
            let f = scan(px, py, pz, &self.xs, &self.ys, &self.zs, &self.ids, r2, dst);
            out.set_len(before + f);
            f
        };
        self.xs[e] = px;
        found as u32
    }
}

/// `dst.extend_from_slice(src)` as a plain element loop: the slices here are a few cells
/// long, where a `memcpy` call per slice and a capacity check per `push` both cost more
/// than the copy itself.
#[inline(always)]
fn append<T: Copy>(dst: &mut Vec<T>, src: &[T]) {
    let old = dst.len();
    dst.reserve(src.len());
    // SAFETY: capacity for `src.len()` more elements was reserved; all of them are written
    // before the length is set.
    unsafe {
        let p = dst.as_mut_ptr().add(old);
        for (k, &v) in src.iter().enumerate() {
            p.add(k).write(v);
        }
        dst.set_len(old + src.len());
    }
}

/// Reinterprets a slice of `R` as a slice of `T` when they are the same type.
#[inline(always)]
fn same<R: 'static, T: 'static>(s: &[R]) -> Option<&[T]> {
    (TypeId::of::<R>() == TypeId::of::<T>())
        // SAFETY: R and T are the same type.
        .then(|| unsafe { std::slice::from_raw_parts(s.as_ptr() as *const T, s.len()) })
}

#[allow(clippy::too_many_arguments)]
#[inline]
unsafe fn scan<R: Real>(
    px: R,
    py: R,
    pz: R,
    xs: &[R],
    ys: &[R],
    zs: &[R],
    ids: &[u32],
    r2: R,
    out: *mut u32,
) -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt")
        {
            let p = [px.as_f64(), py.as_f64(), pz.as_f64(), r2.as_f64()];
            if let (Some(x), Some(y), Some(z)) = (same::<R, f32>(xs), same(ys), same(zs)) {
                let p = p.map(|v| v as f32); // exact: the values are f32
                return unsafe { avx2::scan_f32(p, x, y, z, ids, out) };
            }
            if let (Some(x), Some(y), Some(z)) = (same::<R, f64>(xs), same(ys), same(zs)) {
                return unsafe { avx2::scan_f64(p, x, y, z, ids, out) };
            }
        }
    }
    unsafe { scan_portable(px, py, pz, xs, ys, zs, ids, r2, out) }
}

/// The portable kernel: branch-free compaction, one candidate at a time.
#[allow(clippy::too_many_arguments)]
#[inline]
unsafe fn scan_portable<R: Real>(
    px: R,
    py: R,
    pz: R,
    xs: &[R],
    ys: &[R],
    zs: &[R],
    ids: &[u32],
    r2: R,
    out: *mut u32,
) -> usize {
    let mut found = 0;
    for t in 0..xs.len() {
        let dx = px - xs[t];
        let dy = py - ys[t];
        let dz = pz - zs[t];
        // SAFETY: found <= t < xs.len() <= capacity guaranteed by the caller.
        unsafe { *out.add(found) = ids[t] };
        found += (dx * dx + dy * dy + dz * dz < r2) as usize;
    }
    found
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    /// `LEFT_PACK[mask]` lists the set lanes of `mask` first (then zeros).
    static LEFT_PACK: [[u32; 8]; 256] = {
        let mut t = [[0u32; 8]; 256];
        let mut mask = 0;
        while mask < 256 {
            let (mut lane, mut k) = (0, 0);
            while lane < 8 {
                if mask & (1 << lane) != 0 {
                    t[mask][k] = lane as u32;
                    k += 1;
                }
                lane += 1;
            }
            mask += 1;
        }
        t
    };

    #[inline(always)]
    unsafe fn pack(mask: usize, ids: *const u32, out: *mut u32) -> usize {
        unsafe {
            let idv = _mm256_loadu_si256(ids as *const __m256i);
            let perm = _mm256_loadu_si256(LEFT_PACK[mask].as_ptr() as *const __m256i);
            _mm256_storeu_si256(out as *mut __m256i, _mm256_permutevar8x32_epi32(idv, perm));
        }
        mask.count_ones() as usize
    }

    #[target_feature(enable = "avx2,popcnt")]
    pub(super) unsafe fn scan_f32(
        p: [f32; 4],
        xs: &[f32],
        ys: &[f32],
        zs: &[f32],
        ids: &[u32],
        out: *mut u32,
    ) -> usize {
        let n = xs.len();
        assert!(n % 8 == 0 && ys.len() == n && zs.len() == n && ids.len() == n);
        let (vx, vy, vz) = (
            _mm256_set1_ps(p[0]),
            _mm256_set1_ps(p[1]),
            _mm256_set1_ps(p[2]),
        );
        let vr2 = _mm256_set1_ps(p[3]);
        let mut found = 0;
        let mut t = 0;
        while t < n {
            // SAFETY: t + 8 <= n for all four arrays; `out` has room (see caller).
            unsafe {
                let dx = _mm256_sub_ps(vx, _mm256_loadu_ps(xs.as_ptr().add(t)));
                let dy = _mm256_sub_ps(vy, _mm256_loadu_ps(ys.as_ptr().add(t)));
                let dz = _mm256_sub_ps(vz, _mm256_loadu_ps(zs.as_ptr().add(t)));
                let d2 = _mm256_add_ps(
                    _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                    _mm256_mul_ps(dz, dz),
                );
                let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(d2, vr2)) as usize;
                found += pack(mask, ids.as_ptr().add(t), out.add(found));
            }
            t += 8;
        }
        found
    }

    #[target_feature(enable = "avx2,popcnt")]
    pub(super) unsafe fn scan_f64(
        p: [f64; 4],
        xs: &[f64],
        ys: &[f64],
        zs: &[f64],
        ids: &[u32],
        out: *mut u32,
    ) -> usize {
        let n = xs.len();
        assert!(n % 8 == 0 && ys.len() == n && zs.len() == n && ids.len() == n);
        let (vx, vy, vz) = (
            _mm256_set1_pd(p[0]),
            _mm256_set1_pd(p[1]),
            _mm256_set1_pd(p[2]),
        );
        let vr2 = _mm256_set1_pd(p[3]);
        let half = |t: usize| -> usize {
            // SAFETY: t + 4 <= n (t is 0 or 4 past a multiple of 8 below n).
            unsafe {
                let dx = _mm256_sub_pd(vx, _mm256_loadu_pd(xs.as_ptr().add(t)));
                let dy = _mm256_sub_pd(vy, _mm256_loadu_pd(ys.as_ptr().add(t)));
                let dz = _mm256_sub_pd(vz, _mm256_loadu_pd(zs.as_ptr().add(t)));
                let d2 = _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)),
                    _mm256_mul_pd(dz, dz),
                );
                _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(d2, vr2)) as usize
            }
        };
        let mut found = 0;
        let mut t = 0;
        while t < n {
            let mask = half(t) | half(t + 4) << 4;
            // SAFETY: t + 8 <= n; `out` has room (see caller).
            found += unsafe { pack(mask, ids.as_ptr().add(t), out.add(found)) };
            t += 8;
        }
        found
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn both<R: Real>(pts: &[[f64; 3]], q: [f64; 3], r: f64) -> (Vec<u32>, Vec<u32>) {
        let mut g = Gathered::<R>::default();
        for (i, p) in pts.iter().enumerate() {
            g.push(R::of_f64(p[0]), R::of_f64(p[1]), R::of_f64(p[2]), i as u32);
        }
        g.push(R::of_f64(q[0]), R::of_f64(q[1]), R::of_f64(q[2]), 9999);
        let e = g.len() - 1;
        g.finish();
        let r2 = R::of_f64(r) * R::of_f64(r);
        let mut fast = Vec::new();
        g.neighbours_of(e, r2, &mut fast);
        // The portable kernel on the same data, with the query moved away as above.
        let (px, py, pz) = (g.xs[e], g.ys[e], g.zs[e]);
        g.xs[e] = R::of_f64(f64::INFINITY);
        let mut slow = vec![0u32; g.xs.len()];
        let n = unsafe {
            scan_portable(
                px,
                py,
                pz,
                &g.xs,
                &g.ys,
                &g.zs,
                &g.ids,
                r2,
                slow.as_mut_ptr(),
            )
        };
        slow.truncate(n);
        (fast, slow)
    }

    proptest! {
        /// The run-time selected kernel (AVX2 where available) equals the portable one
        /// and the direct definition, in both precisions, for any block length.
        #[test]
        fn simd_and_portable_agree(
            pts in proptest::collection::vec([-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64], 0..70),
            q in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
            r in 0.01..1.5f64,
        ) {
            let direct: Vec<u32> = pts.iter().enumerate()
                .filter(|(_, p)| {
                    let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                    d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r * r
                })
                .map(|(i, _)| i as u32)
                .collect();
            let (fast, slow) = both::<f64>(&pts, q, r);
            prop_assert_eq!(&fast, &slow);
            prop_assert_eq!(&fast, &direct);
            let (fast, slow) = both::<f32>(&pts, q, r);
            prop_assert_eq!(fast, slow);
        }
    }
}
