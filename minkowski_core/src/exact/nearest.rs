//! The point of a [`TriMesh`] nearest a query point: a depth-first walk of its BVH, the
//! nearer child first, that skips every node whose box lies farther than the best triangle
//! found so far. Exact up to the rounding of [`closest_on_triangle`].

use super::TriMesh;
use crate::math::Vec3;
use crate::polytope::closest_on_triangle;

impl TriMesh {
    /// The point of the mesh's triangles nearest `p` and its distance; `None` for a mesh
    /// with no triangle.
    pub fn nearest(&self, p: Vec3) -> Option<(Vec3, f64)> {
        self.nearest_within(p, f64::INFINITY)
    }

    /// The point of the mesh's triangles nearest `p` and its distance, when that is below
    /// `limit` (every node farther than it is skipped from the start), else `None`.
    pub fn nearest_within(&self, p: Vec3, limit: f64) -> Option<(Vec3, f64)> {
        // squared distances throughout (the limit's square a few ulps up: it must not cut
        // off a triangle within the limit), one square root at the end
        let root = self.nodes.first()?;
        let mut best = (Vec3::ZERO, limit * limit * (1.0 + 4.0 * f64::EPSILON));
        let mut stack = Vec::with_capacity(64);
        stack.push((0u32, root.aabb.distance_squared_to_point(p)));
        while let Some((n, box_distance)) = stack.pop() {
            if box_distance >= best.1 {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.is_leaf() {
                let [a, b, c] = self.tris[node.tri as usize].p;
                let q = closest_on_triangle(p, a, b, c);
                let d = (p - q).length_squared();
                if d < best.1 {
                    best = (q, d);
                }
                continue;
            }
            let (l, r) = (node.left, node.left + 1);
            let (dl, dr) = (self.nodes[l as usize].aabb.distance_squared_to_point(p), self.nodes[r as usize].aabb.distance_squared_to_point(p));
            // the nearer child is popped first
            if dl <= dr {
                stack.push((r, dr));
                stack.push((l, dl));
            } else {
                stack.push((l, dl));
                stack.push((r, dr));
            }
        }
        let distance = best.1.sqrt();
        (distance < limit).then_some((best.0, distance))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_limit_skips_what_lies_beyond_it_and_finds_what_lies_within() {
        let v: Vec<Vec3> = (0..8).map(|k| Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64)).collect();
        let f: Vec<[u32; 3]> = vec![[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]];
        let cube = TriMesh::new(v, &f, "cube").expect("a solid cube");
        let p = Vec3::new(1.5, 0.5, 2.0); // nearest the edge x = 1, z = 1, at sqrt(1.25)
        let (q, d) = cube.nearest(p).expect("a nearest point");
        assert!((q - Vec3::new(1.0, 0.5, 1.0)).length() < 1e-12 && (d - 1.25f64.sqrt()).abs() < 1e-12);
        assert_eq!(cube.nearest_within(p, 1.1), None);
        assert_eq!(cube.nearest_within(p, 1.2 + 0.05), Some((q, d)));
        assert_eq!(cube.nearest_within(p, d), None, "the limit is exclusive");
    }
}
