//! Which vertex sums `p ± q` of two convex pieces can be vertices of their sum: those
//! whose normal cones meet.
//!
//! `p + q` is a vertex of `conv(P) ⊕ conv(Q)` only where some direction is extreme for `p`
//! in `P` and for `q` in `Q`: their normal cones (the directions of the facets around each
//! hull vertex) meet; for `p − q`, the cone of `q` turns to its opposite. Each cone is
//! bounded by a cap on the sphere (its axis the mean of its facets' normals, its radius
//! the largest angle to one of them), and a pair is kept when the caps meet, with a small
//! slack: never fewer than the true vertices, usually a few per cent of all pairs (two
//! tessellated spheres keep about `n + m` of `n · m`). A point that is not a vertex of its
//! piece's hull, or any point when the hull cannot be built, keeps every pair.
//!
//! Entry point: [`candidate_sums`].

use crate::math::Vec3;
use crate::polytope::ConvexPolytope;
use std::collections::HashMap;

/// Angles (radians) added to the caps' radii: rounding in the hulls' normals, with room.
const SLACK: f64 = 1e-4;

/// A cap of directions: unit axis and angular radius (below a quarter turn, [`SLACK`]
/// included), kept as its cosine and sine; no axis: every direction.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cap {
    axis: Vec3,
    cos: f64,
    sin: f64,
}

const EVERY: Cap = Cap { axis: Vec3::ZERO, cos: -1.0, sin: 0.0 };

impl Cap {
    fn new(axis: Vec3, radius: f64) -> Cap {
        let r = radius + SLACK;
        Cap { axis, cos: r.cos(), sin: r.sin() }
    }

    /// Whether the caps may share a direction: the angle between their axes at most the
    /// sum of their radii (both below a quarter turn, so the sum is below a half turn and
    /// its cosine decides).
    fn meets(&self, o: &Cap) -> bool {
        self.axis == Vec3::ZERO || o.axis == Vec3::ZERO || self.axis.dot(o.axis) >= self.cos * o.cos - self.sin * o.sin
    }
}

/// The points `p + s q` (`s` = ±1) for `p` in `a` and `q` in `b` whose normal cones meet
/// (see the module documentation), given each point's cap ([`caps`]: `ca` of `a`, `cb` of
/// `b` turned by `s`); `None` when they would be all of them anyway.
pub(super) fn candidate_sums(a: &[Vec3], ca: &[Cap], b: &[Vec3], cb: &[Cap], s: f64) -> Option<Vec<Vec3>> {
    let mut out = Vec::new();
    for (p, cp) in a.iter().zip(ca) {
        for (q, cq) in b.iter().zip(cb) {
            if cp.meets(cq) {
                out.push(*p + *q * s);
            }
        }
    }
    (out.len() < a.len() * b.len() && out.len() >= 4).then_some(out)
}

/// Each point's cap, with its normals turned by `s` (−1: the cones of `−Q`).
pub(super) fn caps(points: &[Vec3], s: f64) -> Vec<Cap> {
    let Ok(hull) = ConvexPolytope::try_from_points(points, "piece") else {
        return vec![EVERY; points.len()];
    };
    // the facets around each hull vertex; a vertex of a sliver triangle (whose plane the
    // hull took from a neighbour) keeps every direction
    let scale = hull.aabb.diagonal();
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); hull.vertices.len()];
    let mut sliver = vec![false; hull.vertices.len()];
    for (t, &f) in hull.triangles.iter().zip(&hull.triangle_facet) {
        let [p0, p1, p2] = t.map(|v| hull.vertices[v as usize]);
        let thin = (p1 - p0).cross(p2 - p0).length() <= 1e-9 * scale * scale;
        for &v in t {
            sliver[v as usize] |= thin;
            if !around[v as usize].contains(&f) {
                around[v as usize].push(f);
            }
        }
    }
    let of_vertex: Vec<Cap> = around.iter().zip(&sliver).map(|(facets, &thin)| if thin { EVERY } else { cap(facets.iter().map(|&f| hull.normals[f as usize] * s)) }).collect();
    let index: HashMap<[u64; 3], usize> = hull.vertices.iter().enumerate().map(|(i, v)| (bits(*v), i)).collect();
    points.iter().map(|p| index.get(&bits(*p)).map_or(EVERY, |&i| of_vertex[i])).collect()
}

/// The cap around unit normals: their mean direction, out to the farthest.
fn cap(normals: impl Iterator<Item = Vec3> + Clone) -> Cap {
    let axis = normals.clone().fold(Vec3::ZERO, |acc, n| acc + n).normalize_or_zero();
    if axis == Vec3::ZERO {
        return EVERY;
    }
    let radius = normals.map(|n| axis.dot(n).clamp(-1.0, 1.0).acos()).fold(0.0, f64::max);
    // a cap of a quarter turn or more is not convex on the sphere: it may not hold the
    // cone its normals span
    if radius + SLACK >= std::f64::consts::FRAC_PI_2 {
        return EVERY;
    }
    Cap::new(axis, radius)
}

fn bits(v: Vec3) -> [u64; 3] {
    [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()]
}

#[cfg(test)]
#[path = "cones_tests.rs"]
mod cones_tests;
