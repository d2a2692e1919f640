//! [`PolytopeSet`]: a union of convex polytopes with a BVH.

use crate::bvh::Bvh;
use crate::math::{Aabb, Vec3};
use crate::polytope::ConvexPolytope;

/// The union of convex primitives (for a C-obstacle: the pairwise sums).
#[derive(Clone, Debug)]
pub struct PolytopeSet {
    /// The primitives.
    pub polys: Vec<ConvexPolytope>,
    /// BVH over their boxes.
    pub bvh: Bvh,
    /// Box around all of them.
    pub aabb: Aabb,
}

impl PolytopeSet {
    /// Wrap `polys` and build the BVH.
    pub fn new(polys: Vec<ConvexPolytope>) -> Self {
        let boxes: Vec<Aabb> = polys.iter().map(|p| p.aabb).collect();
        let aabb = boxes.iter().fold(Aabb::empty(), |a, b| a.union(b));
        PolytopeSet { bvh: Bvh::build(&boxes), polys, aabb }
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.polys.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.polys.is_empty()
    }

    /// Whether `p` lies in the union (closed).
    pub fn contains_point(&self, p: Vec3) -> bool {
        let mut inside = false;
        self.bvh.for_each_at_point(p, |i| {
            if !inside && self.polys[i].contains_point(p) {
                inside = true;
            }
        });
        inside
    }

    /// Indices of the primitives containing `p`.
    pub fn containing(&self, p: Vec3) -> Vec<usize> {
        let mut out = Vec::new();
        self.bvh.for_each_at_point(p, |i| {
            if self.polys[i].contains_point(p) {
                out.push(i);
            }
        });
        out.sort_unstable();
        out
    }

    /// Signed distance to the union: outside, the exact Euclidean distance; inside, minus
    /// the largest depth of `p` in a single primitive (a lower bound on the true depth).
    pub fn signed_distance(&self, p: Vec3) -> f64 {
        let mut depth = f64::NEG_INFINITY;
        self.bvh.for_each_at_point(p, |i| {
            let s = self.polys[i].plane_distance(p);
            if s <= 0.0 {
                depth = depth.max(-s);
            }
        });
        if depth >= 0.0 {
            return -depth;
        }
        // Outside: grow the search radius until a primitive is found, then search within
        // the best distance so far.
        let mut best = f64::INFINITY;
        let mut r = self.aabb.diagonal().max(1e-300) * 1e-3 + self.aabb_distance(p);
        loop {
            self.bvh.for_each_within(p, r, |i| {
                let poly = &self.polys[i];
                if poly.plane_distance(p) < best {
                    best = best.min(poly.signed_distance(p));
                }
            });
            if best <= r || !best.is_finite() && r > 1e300 {
                return best;
            }
            if best.is_finite() {
                r = best;
            } else {
                r *= 2.0;
            }
        }
    }

    fn aabb_distance(&self, p: Vec3) -> f64 {
        self.aabb.distance_to_point(p)
    }

    /// The parameter intervals of the segment `a + t (b − a)`, `t ∈ [0, 1]`, inside the
    /// union, merged and sorted.
    pub fn segment_intervals(&self, a: Vec3, b: Vec3) -> Vec<(f64, f64)> {
        let mut iv = Vec::new();
        self.bvh.for_each_on_segment(a, b, |i| {
            if let Some(t) = self.polys[i].clip_segment(a, b) {
                iv.push(t);
            }
        });
        merge_intervals(&mut iv)
    }

    /// Whether the closed segment `a → b` misses every primitive (exact up to rounding).
    pub fn segment_is_free(&self, a: Vec3, b: Vec3) -> bool {
        let mut free = true;
        self.bvh.for_each_on_segment(a, b, |i| {
            if free && self.polys[i].clip_segment(a, b).is_some() {
                free = false;
            }
        });
        free
    }
}

/// Sort and merge overlapping or touching parameter intervals.
pub fn merge_intervals(iv: &mut [(f64, f64)]) -> Vec<(f64, f64)> {
    iv.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(iv.len());
    for &(s, e) in iv.iter() {
        match out.last_mut() {
            Some(last) if s <= last.1 + 1e-12 => last.1 = last.1.max(e),
            _ => out.push((s, e)),
        }
    }
    out
}
