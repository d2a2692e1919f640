//! Where the triangles of one mesh cross each other: overlapping shells, and shells that
//! pass through themselves.
//!
//! The winding number is constant in front of a face only where no other face crosses it.
//! Along a crossing segment of faces `s` and `t` the four wedges around it have winding
//! numbers `w`, `w + 1`, `w + 1` and `w + 2`, the smallest in front of both faces; so the
//! winding number is never negative when it is not in front of any face that no other face
//! crosses ([`super::TriMesh::front_windings`]) and not in the wedge in front of both faces
//! of any crossing ([`super::TriMesh::crossing_windings`]). Every region of space off the
//! surface borders a face, on a part of it that is either the whole face or borders a
//! crossing, so the two tests see every value.
//!
//! Entry point: [`super::TriMesh::crossings`].

use super::mesh::{Tri, TriMesh};
use crate::math::Vec3;
use rayon::prelude::*;

/// Pairs of subtrees [`TriMesh::overlapping_pairs`] walks in parallel.
const PAIR_TASKS: usize = 64;

/// A crossing: the two triangles and the segment where they meet.
#[derive(Clone, Copy, Debug)]
pub struct Crossing {
    /// The triangles (`s < t`).
    pub tris: [u32; 2],
    /// The ends of the segment they share.
    pub seg: [Vec3; 2],
}

impl TriMesh {
    /// Every pair of triangles that cross along a segment longer than the rounding of the
    /// mesh: not neighbours along an edge, not coplanar (coincident faces are told apart
    /// by [`TriMesh::front_windings`]), not one touching the other from one side. By a traversal of pairs of BVH nodes.
    pub fn crossings(&self) -> Vec<Crossing> {
        let verts = &self.faces;
        let scale = self.aabb.diagonal().max(1e-300);
        self.overlapping_pairs()
            .into_par_iter()
            .filter_map(|[s, t]| {
                let (fs, ft) = (verts[s as usize], verts[t as usize]);
                let shared = fs.iter().filter(|v| ft.contains(v)).count();
                if shared >= 2 {
                    return None; // neighbours along an edge
                }
                let seg = tri_tri_segment(&self.tris[s as usize], &self.tris[t as usize], scale)?;
                ((seg[1] - seg[0]).length() > 1e-9 * scale).then_some(Crossing { tris: [s, t], seg })
            })
            .collect()
    }

    /// Every pair of distinct triangles (`s < t`) whose boxes overlap, by a traversal of
    /// pairs of BVH nodes: breadth first to [`PAIR_TASKS`] pairs
    /// of subtrees, then each of those depth first, in parallel (the same pairs in the same
    /// order on any number of threads).
    fn overlapping_pairs(&self) -> Vec<[u32; 2]> {
        let mut found = Vec::new();
        let mut tasks = vec![[0u32, 0u32]];
        while !tasks.is_empty() && tasks.len() < PAIR_TASKS {
            let mut next = Vec::with_capacity(3 * tasks.len());
            for task in tasks {
                self.expand_pair(task, &mut found, &mut next);
            }
            tasks = next;
        }
        let walked: Vec<Vec<[u32; 2]>> = tasks
            .par_iter()
            .map(|&task| {
                let (mut out, mut stack) = (Vec::new(), vec![task]);
                while let Some(pair) = stack.pop() {
                    self.expand_pair(pair, &mut out, &mut stack);
                }
                out
            })
            .collect();
        found.extend(walked.into_iter().flatten());
        found
    }

    /// One step of [`TriMesh::overlapping_pairs`]: a pair of nodes whose boxes overlap
    /// gives its triangle pair (two leaves) to `found`, else its pairs of children to
    /// `next`.
    fn expand_pair(&self, [a, b]: [u32; 2], found: &mut Vec<[u32; 2]>, next: &mut Vec<[u32; 2]>) {
        let (na, nb) = (&self.nodes[a as usize], &self.nodes[b as usize]);
        if !na.aabb.overlaps(&nb.aabb) {
            return;
        }
        match (na.is_leaf(), nb.is_leaf()) {
            (true, true) => {
                if a != b {
                    found.push([na.tri.min(nb.tri), na.tri.max(nb.tri)]);
                }
            }
            _ if a == b => {
                let l = na.left;
                next.extend([[l, l], [l, l + 1], [l + 1, l + 1]]);
            }
            (false, true) => next.extend([[na.left, b], [na.left + 1, b]]),
            (true, false) => next.extend([[a, nb.left], [a, nb.left + 1]]),
            (false, false) => {
                if na.size() >= nb.size() {
                    next.extend([[na.left, b], [na.left + 1, b]]);
                } else {
                    next.extend([[a, nb.left], [a, nb.left + 1]]);
                }
            }
        }
    }

    /// The winding number in the wedge in front of both triangles of each crossing (near
    /// the middle of its segment), `None` where it could not be told.
    pub fn crossing_windings(&self, crossings: &[Crossing]) -> Vec<Option<i64>> {
        crossings.par_iter().map(|c| self.wedge_winding(c, 1.0)).collect()
    }

    /// How many crossings have the solid twice over in the wedge behind both triangles
    /// (winding number 2 or more, told): there each triangle has the solid on both of
    /// its sides, so is not all boundary (shells that overlap).
    pub fn crossings_inside(&self, crossings: &[Crossing]) -> usize {
        crossings.par_iter().filter(|c| self.wedge_winding(c, -1.0).is_some_and(|w| w >= 2)).count()
    }

    /// The winding number near the middle of the crossing's segment, in the wedge in front
    /// of both triangles when `side` is positive, behind both when negative; `None` where
    /// it could not be told, 0 where the normals are nearly opposite (no wedge).
    fn wedge_winding(&self, c: &Crossing, side: f64) -> Option<i64> {
        let scale = self.aabb.diagonal().max(1e-300);
        let (ns, nt) = (self.tris[c.tris[0] as usize].n, self.tris[c.tris[1] as usize].n);
        let bisector = ns + nt;
        if bisector.length() < 1e-3 {
            return Some(0);
        }
        let d = bisector.normalize() * side;
        let len = (c.seg[1] - c.seg[0]).length();
        let lift = (1e-7 * scale).min(1e-3 * len);
        [0.5, 0.3, 0.7].iter().find_map(|&f| self.winding(c.seg[0] + (c.seg[1] - c.seg[0]) * f + d * lift))
    }
}

/// The segment where two triangles cross, or `None` when they do not meet, lie in one
/// plane, or only touch: one lies on one side of the other's plane, meeting it along its
/// boundary (an edge of a fin lying on a face, sheets that touch along a line). A touch
/// splits neither face's sides into parts: the wedges around it are the front and the
/// back of the face that ends there, which [`TriMesh::front_windings`] tells.
fn tri_tri_segment(s: &Tri, t: &Tri, scale: f64) -> Option<[Vec3; 2]> {
    if s.n == Vec3::ZERO || t.n == Vec3::ZERO {
        return None;
    }
    let eps = 1e-12 * scale;
    let ds = t.p.map(|p| s.n.dot(p - s.p[0])); // t's corners against s's plane
    let dt = s.p.map(|p| t.n.dot(p - t.p[0])); // s's corners against t's plane
                                               // on one side of the other's plane (apart, touching it, or in it): no crossing
    let one_side = |d: [f64; 3]| d.iter().all(|&x| x >= -eps) || d.iter().all(|&x| x <= eps);
    if one_side(ds) || one_side(dt) {
        return None;
    }
    let dir = s.n.cross(t.n);
    if dir.length() < 1e-9 {
        return None; // parallel planes
    }
    let (a0, a1) = plane_cut(&s.p, dt, dir)?;
    let (b0, b1) = plane_cut(&t.p, ds, dir)?;
    // both intervals lie on the line of the two planes: their overlap
    let (lo, hi) = (a0.0.max(b0.0), a1.0.min(b1.0));
    if hi <= lo {
        return None;
    }
    let at = |x: f64, from: (f64, Vec3), to: (f64, Vec3)| {
        if to.0 - from.0 <= 0.0 {
            from.1
        } else {
            from.1 + (to.1 - from.1) * ((x - from.0) / (to.0 - from.0))
        }
    };
    Some([at(lo, a0, a1), at(hi, a0, a1)])
}

/// Where the triangle `p` (signed distances `d` of its corners to the other plane) meets
/// that plane: the two ends of the cut as `(position along dir, point)`, sorted.
fn plane_cut(p: &[Vec3; 3], d: [f64; 3], dir: Vec3) -> Option<((f64, Vec3), (f64, Vec3))> {
    let mut pts: Vec<Vec3> = Vec::with_capacity(3);
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        if d[i] == 0.0 {
            pts.push(p[i]);
        }
        if (d[i] > 0.0 && d[j] < 0.0) || (d[i] < 0.0 && d[j] > 0.0) {
            pts.push(p[i] + (p[j] - p[i]) * (d[i] / (d[i] - d[j])));
        }
    }
    let keyed: Vec<(f64, Vec3)> = pts.iter().map(|&q| (q.dot(dir), q)).collect();
    let lo = keyed.iter().copied().min_by(|x, y| x.0.total_cmp(&y.0))?;
    let hi = keyed.iter().copied().max_by(|x, y| x.0.total_cmp(&y.0))?;
    Some((lo, hi))
}
