//! Directions bucketed on a cube map: the reduced convolution looks up the features whose
//! normal cone or Gauss arc can contain a direction, instead of testing every feature
//! against every other (`O(n + m + pairs)` work where a scan is `O(n · m)`).
//!
//! Each cell of the map is a spherical quadrilateral (a square of a cube face, projected
//! from the centre) held as a cap: its centre direction and an angular radius reaching
//! its corners. A feature is listed in every cell whose cap its direction set may meet;
//! the tests are necessary conditions, so a list can hold extra features (the exact test
//! runs on them afterwards) but never misses one.

use crate::math::Vec3;
use rayon::prelude::*;

/// Coarse cells per cube-face side, and fine cells per coarse side.
const COARSE: usize = 4;
const FINE: usize = 4;
const SIDE: usize = COARSE * FINE;

/// Angle added to every cap radius against rounding.
const PAD: f64 = 1e-7;

/// A cell as a cap: unit centre and angular radius.
#[derive(Clone, Copy, Debug)]
pub struct Cap {
    pub c: Vec3,
    pub rho: f64,
}

/// The direction of `(u, v)` on cube face `f` (axis `f / 2`, side `+` for even `f`).
fn on_face(f: usize, u: f64, v: f64) -> Vec3 {
    let a = f / 2;
    let mut p = [0.0; 3];
    p[a] = if f.is_multiple_of(2) { 1.0 } else { -1.0 };
    p[(a + 1) % 3] = u;
    p[(a + 2) % 3] = v;
    Vec3::from_array(p).normalize()
}

/// The cap of the square `[u0, u1] × [v0, v1]` of face `f`.
fn cap(f: usize, u0: f64, u1: f64, v0: f64, v1: f64) -> Cap {
    let c = on_face(f, 0.5 * (u0 + u1), 0.5 * (v0 + v1));
    let rho = [(u0, v0), (u1, v0), (u0, v1), (u1, v1)].iter().map(|&(u, v)| angle(c, on_face(f, u, v))).fold(0.0f64, f64::max);
    Cap { c, rho: rho + PAD }
}

/// The angle between unit vectors.
#[inline]
pub fn angle(a: Vec3, b: Vec3) -> f64 {
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// Features listed per fine cell of the cube map.
pub struct DirGrid {
    coarse: Vec<Cap>,
    fine: Vec<Cap>,
    lists: Vec<Vec<u32>>,
    /// Features whose direction set is unknown (degenerate): candidates everywhere.
    always: Vec<u32>,
}

impl DirGrid {
    fn caps(n: usize) -> Vec<Cap> {
        let step = 2.0 / n as f64;
        let mut out = Vec::with_capacity(6 * n * n);
        for f in 0..6 {
            for i in 0..n {
                for j in 0..n {
                    let (u0, v0) = (-1.0 + i as f64 * step, -1.0 + j as f64 * step);
                    out.push(cap(f, u0, u0 + step, v0, v0 + step));
                }
            }
        }
        out
    }

    /// The fine cells whose caps pass `meets` (a coarse cell first: its fine cells only
    /// when it passes), in index order.
    pub fn cells(&self, meets: impl Fn(&Cap) -> bool) -> Vec<u32> {
        let mut out = Vec::new();
        for (ci, cc) in self.coarse.iter().enumerate() {
            if !meets(cc) {
                continue;
            }
            let (f, rest) = (ci / (COARSE * COARSE), ci % (COARSE * COARSE));
            let (i0, j0) = ((rest / COARSE) * FINE, (rest % COARSE) * FINE);
            for i in i0..i0 + FINE {
                for j in j0..j0 + FINE {
                    let fi = f * SIDE * SIDE + i * SIDE + j;
                    if meets(&self.fine[fi]) {
                        out.push(fi as u32);
                    }
                }
            }
        }
        out
    }

    /// A grid over `n` features: `cells_of(id)` gives the fine cells feature `id` may
    /// meet, or `None` when it may meet any direction.
    pub fn build(n: usize, cells_of: impl Fn(&DirGrid, u32) -> Option<Vec<u32>> + Sync) -> DirGrid {
        let mut g = DirGrid { coarse: Self::caps(COARSE), fine: Self::caps(SIDE), lists: Vec::new(), always: Vec::new() };
        let per: Vec<Option<Vec<u32>>> = (0..n as u32).into_par_iter().map(|id| cells_of(&g, id)).collect();
        let mut lists = vec![Vec::new(); g.fine.len()];
        for (id, cells) in per.into_iter().enumerate() {
            match cells {
                Some(cells) => cells.into_iter().for_each(|c| lists[c as usize].push(id as u32)),
                None => g.always.push(id as u32),
            }
        }
        g.lists = lists;
        g
    }

    /// The fine cell holding direction `d` (non-zero).
    pub fn locate(d: Vec3) -> u32 {
        let ad = d.abs();
        let a = if ad.x >= ad.y && ad.x >= ad.z {
            0
        } else if ad.y >= ad.z {
            1
        } else {
            2
        };
        let f = 2 * a + usize::from(d[a] < 0.0);
        let idx = |x: f64| (((x / ad[a] + 1.0) * 0.5 * SIDE as f64) as usize).min(SIDE - 1);
        (f * SIDE * SIDE + idx(d[(a + 1) % 3]) * SIDE + idx(d[(a + 2) % 3])) as u32
    }

    /// The features that may contain direction `d`: those of its cell and the ones
    /// listed everywhere (each once; ascending).
    pub fn at(&self, d: Vec3) -> Vec<u32> {
        let mut out = self.lists[Self::locate(d) as usize].clone();
        out.extend_from_slice(&self.always);
        out.sort_unstable();
        out
    }

    /// The features listed in any of `cells`, or everywhere (each once; ascending).
    pub fn gather(&self, cells: &[u32]) -> Vec<u32> {
        let mut out: Vec<u32> = cells.iter().flat_map(|&c| self.lists[c as usize].iter().copied()).collect();
        out.extend_from_slice(&self.always);
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// A lower bound on the angle from `c` to the great-circle arc from `n1` to `n2` (unit,
/// less than a half-turn apart; a point when they nearly coincide).
pub fn arc_distance(c: Vec3, n1: Vec3, n2: Vec3) -> f64 {
    let ends = angle(c, n1).min(angle(c, n2));
    let p = n1.cross(n2);
    let pl = p.length();
    if pl <= 1e-6 {
        return (ends - angle(n1, n2)).max(0.0);
    }
    let p = p / pl;
    let h = c.dot(p);
    let q = c - p * h;
    let ql = q.length();
    if ql <= 1e-12 {
        return std::f64::consts::FRAC_PI_2 - PAD; // c is a pole of the circle
    }
    let q = q / ql;
    if n1.cross(q).dot(p) >= 0.0 && q.cross(n2).dot(p) >= 0.0 {
        h.abs().clamp(0.0, 1.0).asin()
    } else {
        ends
    }
}
