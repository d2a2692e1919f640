//! Exact queries on a [`ConvexPolytope`].

use super::ConvexPolytope;
use crate::math::{Aabb, Vec3};

impl ConvexPolytope {
    /// `max_k (n_k · p − d_k)`: the exact signed distance when `p` is inside (≤ 0), and a
    /// lower bound on the distance when outside.
    #[inline]
    pub fn plane_distance(&self, p: Vec3) -> f64 {
        let mut s = f64::NEG_INFINITY;
        for (n, d) in self.normals.iter().zip(&self.offsets) {
            s = s.max(n.dot(p) - d);
        }
        s
    }

    /// Whether `p` lies in the closed polytope.
    #[inline]
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.normals.iter().zip(&self.offsets).all(|(n, d)| n.dot(p) <= *d)
    }

    /// Exact signed distance to the boundary: negative inside (depth to the nearest facet
    /// plane), positive outside (Euclidean distance to the nearest boundary point, over the
    /// facets that face `p`).
    pub fn signed_distance(&self, p: Vec3) -> f64 {
        let s = self.plane_distance(p);
        if s <= 0.0 {
            return s;
        }
        let mut best = f64::INFINITY;
        for (t, &f) in self.triangles.iter().zip(&self.triangle_facet) {
            let f = f as usize;
            if self.normals[f].dot(p) - self.offsets[f] <= 0.0 {
                continue; // the nearest point lies on a facet that faces p
            }
            let d2 = point_triangle_distance2(p, self.vertices[t[0] as usize], self.vertices[t[1] as usize], self.vertices[t[2] as usize]);
            best = best.min(d2);
        }
        best.sqrt().max(s)
    }

    /// Whether the closed box lies inside the polytope (all eight corners inside).
    pub fn contains_box(&self, b: &Aabb) -> bool {
        let (c, h) = (b.center(), b.half());
        self.normals.iter().zip(&self.offsets).all(|(n, d)| n.dot(c) + n.abs().dot(h) <= *d)
    }

    /// Box–polytope overlap by separating axes restricted to the box's and the polytope's
    /// face normals. Conservative: `false` is exact (they are disjoint); `true` may, near
    /// an edge of both, be returned for a box that only nearly touches.
    pub fn overlaps_box(&self, b: &Aabb) -> bool {
        if !self.aabb.overlaps(b) {
            return false;
        }
        let (c, h) = (b.center(), b.half());
        self.normals.iter().zip(&self.offsets).all(|(n, d)| n.dot(c) - n.abs().dot(h) <= *d)
    }

    /// The parameter interval `[t0, t1] ⊆ [0, 1]` of the segment `a + t (b − a)` inside the
    /// closed polytope, or `None`. Exact up to rounding (clipping against every facet).
    pub fn clip_segment(&self, a: Vec3, b: Vec3) -> Option<(f64, f64)> {
        clip_planes(self.normals.iter().zip(&self.offsets).map(|(n, d)| (*n, *d)), a, b)
    }
}

/// Clip the segment `a → b` against half-spaces `n · x <= d`; the surviving parameter
/// interval, if any.
#[inline]
pub fn clip_planes(planes: impl Iterator<Item = (Vec3, f64)>, a: Vec3, b: Vec3) -> Option<(f64, f64)> {
    let dir = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (n, d) in planes {
        let fa = n.dot(a) - d;
        let denom = n.dot(dir);
        if denom == 0.0 {
            if fa > 0.0 {
                return None;
            }
            continue;
        }
        let t = -fa / denom;
        if denom > 0.0 {
            t1 = t1.min(t); // leaving the half-space
        } else {
            t0 = t0.max(t); // entering
        }
        if t0 > t1 {
            return None;
        }
    }
    Some((t0, t1))
}

/// Squared distance from `p` to the triangle `abc`.
pub fn point_triangle_distance2(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f64 {
    (p - closest_on_triangle(p, a, b, c)).length_squared()
}

/// The point of the triangle `abc` nearest to `p`.
pub fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    // Region tests on the barycentric coordinates (Ericson, Real-Time Collision Detection, 5.1.5).
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    a + ab * v + ac * w
}
