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
        let root = self.nodes.first()?;
        let mut best = (Vec3::ZERO, f64::INFINITY);
        let mut stack = vec![(0u32, root.aabb.distance_to_point(p))];
        while let Some((n, box_distance)) = stack.pop() {
            if box_distance >= best.1 {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.is_leaf() {
                let [a, b, c] = self.tris[node.tri as usize].p;
                let q = closest_on_triangle(p, a, b, c);
                let d = (p - q).length();
                if d < best.1 {
                    best = (q, d);
                }
                continue;
            }
            let (l, r) = (node.left, node.left + 1);
            let (dl, dr) = (self.nodes[l as usize].aabb.distance_to_point(p), self.nodes[r as usize].aabb.distance_to_point(p));
            // the nearer child is popped first
            if dl <= dr {
                stack.push((r, dr));
                stack.push((l, dl));
            } else {
                stack.push((l, dl));
                stack.push((r, dr));
            }
        }
        best.1.is_finite().then_some(best)
    }
}
