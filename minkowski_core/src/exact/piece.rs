//! [`Piece`]: the convex set `T ⊕ S` of two triangles (the hull of the nine vertex sums),
//! optionally grown by the cube `[-m, m]^3`, with exact tests against points, boxes and
//! segments through its support function. No hull is built: the tests use a set of
//! directions that contains every facet normal of the (grown) piece — the two triangle
//! normals, the in-plane edge normals (for flat pieces), the nine edge × edge cross
//! products, the axes and the edge × axis cross products — so each test is exact.
//!
//! The octree's hot tests take those directions one at a time, unnormalised, and stop at
//! the first that decides ([`pair_contains_point`], [`pair_box_relation`],
//! [`pair_contains_box`]); a built [`Piece`] serves segment clips and distances, and is
//! their reference in the tests.

use super::mesh::{unit, Tri};
use crate::math::{Aabb, Vec3};
use crate::polytope::clip_planes;

/// Most directions a piece tests: 2 normals + 6 in-plane + 9 edge pairs + 3 axes + 18.
const MAX_DIRS: usize = 38;

/// The pair `T ⊕ S` grown by the cube of half-width `margin`.
pub struct Piece<'a> {
    t: &'a Tri,
    s: &'a Tri,
    margin: f64,
    dirs: [Vec3; MAX_DIRS],
    n: usize,
}

/// How a piece lies against a closed box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxRelation {
    /// They do not meet.
    Apart,
    /// They meet; the box is not inside the piece.
    Meets,
    /// The box lies inside the piece.
    Inside,
}

/// Visit the directions of [`Piece`] for `t ⊕ s` (with the axes and edge × axis products
/// when `with_axes`), one at a time and unnormalised, until `f` returns false; whether
/// every direction passed. Every test the pieces make is homogeneous in the direction, so
/// no normalisation is needed, and a test that fails early costs a few dot products.
#[inline]
fn all_dirs(t: &Tri, s: &Tri, with_axes: bool, mut f: impl FnMut(Vec3) -> bool) -> bool {
    // the axes first: the cheapest tests, and the box tests' commonest rejections
    if with_axes && ![Vec3::X, Vec3::Y, Vec3::Z].into_iter().all(&mut f) {
        return false;
    }
    let nonzero = |d: Vec3| d != Vec3::ZERO;
    if !(std::iter::once(t.n).chain(std::iter::once(s.n)).chain(t.m).chain(s.m).filter(|&d| nonzero(d)).all(&mut f)) {
        return false;
    }
    for et in &t.e {
        for es in &s.e {
            let d = et.cross(*es);
            // the same cut-off as `unit(…, 1e3 |et| |es|)`
            if d.length_squared() > 1e-18 * et.length_squared() * es.length_squared() && !f(d) {
                return false;
            }
        }
    }
    if with_axes {
        for a in [Vec3::X, Vec3::Y, Vec3::Z] {
            for e in t.e.iter().chain(&s.e) {
                let d = e.cross(a);
                if d.length_squared() > 1e-18 * e.length_squared() && !f(d) {
                    return false;
                }
            }
        }
    }
    true
}

/// `(min, max)` of `x · d` over `t ⊕ s ⊕ [-m, m]^3`: minus the support of `-d`, and the
/// support of `d`, from the six corner products.
#[inline]
fn pair_range(t: &Tri, s: &Tri, m: f64, d: Vec3) -> (f64, f64) {
    let (a0, a1, a2) = (t.p[0].dot(d), t.p[1].dot(d), t.p[2].dot(d));
    let (b0, b1, b2) = (s.p[0].dot(d), s.p[1].dot(d), s.p[2].dot(d));
    let g = m * (d.x.abs() + d.y.abs() + d.z.abs());
    (a0.min(a1).min(a2) + b0.min(b1).min(b2) - g, a0.max(a1).max(a2) + b0.max(b1).max(b2) + g)
}

/// Whether `p` lies in the closed `t ⊕ s` grown by the cube of half-width `m`: the
/// directions of [`Piece`], one at a time and unnormalised, so a far point costs a few
/// dot products and no piece is built.
#[inline]
pub fn pair_contains_point(t: &Tri, s: &Tri, m: f64, p: Vec3) -> bool {
    // the axes and edge × axis products always: two degenerate (segment) triangles on
    // parallel lines have no normal and no edge × edge product to separate a point
    all_dirs(t, s, true, |d| {
        let x = p.dot(d);
        let (lo, hi) = pair_range(t, s, m, d);
        lo <= x && x <= hi
    })
}

/// How the closed `t ⊕ s` grown by the cube of half-width `m` lies against the closed box
/// `b` (separating axes for meeting, every facet direction for inside; exact), as
/// [`Piece::overlaps_box`] and [`Piece::contains_box`] would say (unnormalised directions
/// may round otherwise only at exact ties), stopping at the first separating direction.
#[inline]
pub fn pair_box_relation(t: &Tri, s: &Tri, m: f64, b: &Aabb) -> BoxRelation {
    // the axes against the box's own bounds first, as `Piece::overlaps_box` (centre ±
    // half could round past them)
    let lo_hi = |k: usize| {
        let (tk, sk) = (t.p.map(|p| p[k]), s.p.map(|p| p[k]));
        let lo = tk[0].min(tk[1]).min(tk[2]) + sk[0].min(sk[1]).min(sk[2]) - m;
        (lo, tk[0].max(tk[1]).max(tk[2]) + sk[0].max(sk[1]).max(sk[2]) + m)
    };
    if (0..3).any(|k| {
        let (lo, hi) = lo_hi(k);
        hi < b.min[k] || lo > b.max[k]
    }) {
        return BoxRelation::Apart;
    }
    let (c, h) = (b.center(), b.half());
    let mut inside = true;
    let meets = all_dirs(t, s, true, |d| {
        let (x, r) = (c.dot(d), h.dot(d.abs()));
        let (lo, hi) = pair_range(t, s, m, d);
        inside &= x + r <= hi && lo <= x - r;
        hi >= x - r && lo <= x + r
    });
    match (meets, inside) {
        (false, _) => BoxRelation::Apart,
        (true, false) => BoxRelation::Meets,
        (true, true) => BoxRelation::Inside,
    }
}

/// Whether the closed `t ⊕ s` grown by the cube of half-width `m` contains the closed box
/// `b`, as [`Piece::contains_box`] would say, stopping at the first direction that shows a
/// corner outside.
#[inline]
pub fn pair_contains_box(t: &Tri, s: &Tri, m: f64, b: &Aabb) -> bool {
    let (c, h) = (b.center(), b.half());
    all_dirs(t, s, true, |d| {
        let (x, r) = (c.dot(d), h.dot(d.abs()));
        let (lo, hi) = pair_range(t, s, m, d);
        x + r <= hi && lo <= x - r
    })
}

impl<'a> Piece<'a> {
    /// The piece of `t` and `s`. `with_axes`: also the directions a box or the margin
    /// cube needs (box tests, or any test with a margin).
    pub fn new(t: &'a Tri, s: &'a Tri, margin: f64, with_axes: bool) -> Piece<'a> {
        let mut dirs = [Vec3::ZERO; MAX_DIRS];
        let mut n = 0;
        let mut push = |d: Vec3| {
            if d != Vec3::ZERO {
                dirs[n] = d;
                n += 1;
            }
        };
        push(t.n);
        push(s.n);
        for k in 0..3 {
            push(t.m[k]);
            push(s.m[k]);
        }
        for et in &t.e {
            for es in &s.e {
                push(unit(et.cross(*es), 1e3 * et.length() * es.length()));
            }
        }
        if with_axes || margin > 0.0 {
            for a in [Vec3::X, Vec3::Y, Vec3::Z] {
                push(a);
                for e in t.e.iter().chain(&s.e) {
                    push(unit(e.cross(a), 1e3 * e.length()));
                }
            }
        }
        Piece { t, s, margin, dirs, n }
    }

    /// The support function `max_{x ∈ piece} x · d`.
    #[inline]
    pub fn support(&self, d: Vec3) -> f64 {
        self.t.support(d) + self.s.support(d) + self.margin * (d.x.abs() + d.y.abs() + d.z.abs())
    }

    /// `max_d (d · p − h(d))` over the piece's directions (both signs): positive outside
    /// (a lower bound on the distance), minus the smallest facet-plane depth inside.
    pub fn separation(&self, p: Vec3) -> f64 {
        let mut s = f64::NEG_INFINITY;
        for &d in &self.dirs[..self.n] {
            let x = p.dot(d);
            s = s.max(x - self.support(d)).max(-x - self.support(-d));
        }
        s
    }

    /// Whether `p` lies in the closed piece.
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.dirs[..self.n].iter().all(|&d| {
            let x = p.dot(d);
            x <= self.support(d) && -x <= self.support(-d)
        })
    }

    /// Whether the closed piece meets the closed box `b` (separating axes; exact).
    pub fn overlaps_box(&self, b: &Aabb) -> bool {
        debug_assert!(self.n >= 3);
        let (c, h) = (b.center(), b.half());
        for a in 0..3 {
            // the axes first: the cheapest rejections
            let mut d = Vec3::ZERO;
            d[a] = 1.0;
            if self.support(d) < b.min[a] || -self.support(-d) > b.max[a] {
                return false;
            }
        }
        self.dirs[..self.n].iter().all(|&d| {
            let (x, r) = (c.dot(d), h.dot(d.abs()));
            self.support(d) >= x - r && -self.support(-d) <= x + r
        })
    }

    /// Whether the closed piece contains the closed box `b`.
    pub fn contains_box(&self, b: &Aabb) -> bool {
        let (c, h) = (b.center(), b.half());
        self.dirs[..self.n].iter().all(|&d| {
            let (x, r) = (c.dot(d), h.dot(d.abs()));
            x + r <= self.support(d) && -x + r <= self.support(-d)
        })
    }

    /// The parameter interval of the segment `a → b` inside the closed piece.
    pub fn clip(&self, a: Vec3, b: Vec3) -> Option<(f64, f64)> {
        // every direction and its opposite, as half-spaces `x · d <= support(d)`
        let planes = self.dirs[..self.n].iter().flat_map(|&d0| [d0, -d0]).map(|d| (d, self.support(d)));
        clip_planes(planes, a, b)
    }
}
