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
//! A face whose edge lies in another's plane, the face on one side of it, touches the
//! other there. Where the face across that edge is on the same side (a V resting on the
//! other), or in the plane, the sheet turns back: it splits no face's sides into parts,
//! and the wedges around it are the front and back of the faces that end there. Where the
//! face across is on the other side, the sheet passes through along that edge: a
//! crossing, as one through the faces' insides is.
//!
//! Entry point: [`super::TriMesh::crossings`].

use super::mesh::{Tri, TriMesh};
use crate::math::Vec3;
use crate::util::{faces_by_edge, FastMap};
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
    /// by [`TriMesh::front_windings`]), not one touching the other from one side unless
    /// the sheet goes on through it there ([`TriMesh::passes_through`]). By a traversal of
    /// pairs of BVH nodes.
    pub fn crossings(&self) -> Vec<Crossing> {
        let verts = &self.faces;
        let scale = self.aabb.diagonal().max(1e-300);
        let met: Vec<([u32; 2], Meeting)> = self
            .overlapping_pairs()
            .into_par_iter()
            .filter_map(|[s, t]| {
                let (fs, ft) = (verts[s as usize], verts[t as usize]);
                let shared = fs.iter().filter(|v| ft.contains(v)).count();
                if shared >= 2 {
                    return None; // neighbours along an edge
                }
                let meeting = meeting(&self.tris[s as usize], &self.tris[t as usize], scale)?;
                let seg = meeting.segment();
                ((seg[1] - seg[0]).length() > 1e-9 * scale).then_some(([s, t], meeting))
            })
            .collect();
        // (the faces across the touching edges, only where there are touches)
        let by_edge: FastMap<(u32, u32), u32> = if met.iter().any(|(_, m)| matches!(m, Meeting::Touch { .. })) { faces_by_edge(verts) } else { FastMap::default() };
        met.into_iter()
            .filter_map(|(tris, meeting)| match meeting {
                Meeting::Crossing(seg) => Some(Crossing { tris, seg }),
                Meeting::Touch { seg, edges } => {
                    let through = edges.iter().flatten().any(|&(who, edge)| self.passes_through(tris[who], edge, tris[1 - who], &by_edge, scale));
                    through.then_some(Crossing { tris, seg })
                }
            })
            .collect()
    }

    /// Whether the sheet of face `f`, which touches face `other`'s plane along its edge
    /// `edge` (corners `edge` and `edge + 1`) from one side, goes on through it there: the
    /// face across that edge lies on the plane's other side (a V of the two on one side
    /// is a touch; one lying in the plane is a coincident face).
    fn passes_through(&self, f: u32, edge: usize, other: u32, by_edge: &FastMap<(u32, u32), u32>, scale: f64) -> bool {
        let face = self.faces[f as usize];
        let (a, b) = (face[edge], face[(edge + 1) % 3]);
        let Some(&g) = by_edge.get(&(b, a)) else { return true }; // (an open mesh: counted)
        let o = &self.tris[other as usize];
        let side = |v: u32| o.n.dot(self.vertices[v as usize] - o.p[0]);
        let beyond = |fc: [u32; 3]| fc.into_iter().find(|&v| v != a && v != b).map_or(0.0, side);
        let (here, there) = (beyond(face), beyond(self.faces[g as usize]));
        let eps = 1e-12 * scale;
        (here > eps && there < -eps) || (here < -eps && there > eps)
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

/// Whether the triangles `s` and `t` (corners) meet along a segment longer than the
/// rounding of a mesh of size `scale`: they cross, or one touches the other along an
/// edge. Triangles in one plane, or meeting only at a corner, do not.
pub fn triangles_meet(s: [Vec3; 3], t: [Vec3; 3], scale: f64) -> bool {
    meeting(&Tri::new(s), &Tri::new(t), scale).is_some_and(|m| {
        let seg = m.segment();
        (seg[1] - seg[0]).length() > 1e-9 * scale
    })
}

/// How two triangles that meet along a segment meet.
enum Meeting {
    /// Each passes through the other's plane.
    Crossing([Vec3; 2]),
    /// One or both lie on one side of the other's plane, along the segment, each with an
    /// edge in that plane: `(which of the two, the edge's first corner)`.
    Touch { seg: [Vec3; 2], edges: [Option<(usize, usize)>; 2] },
}

impl Meeting {
    fn segment(&self) -> [Vec3; 2] {
        match self {
            Meeting::Crossing(seg) | Meeting::Touch { seg, .. } => *seg,
        }
    }
}

/// Where two triangles meet along a segment, or `None` when they do not, lie in one
/// plane, or meet only where a corner of one touches the other's plane.
fn meeting(s: &Tri, t: &Tri, scale: f64) -> Option<Meeting> {
    if s.n == Vec3::ZERO || t.n == Vec3::ZERO {
        return None;
    }
    let eps = 1e-12 * scale;
    let ds = t.p.map(|p| s.n.dot(p - s.p[0])); // t's corners against s's plane
    let dt = s.p.map(|p| t.n.dot(p - t.p[0])); // s's corners against t's plane
    let side = |d: [f64; 3]| (d.iter().all(|&x| x > eps) || d.iter().all(|&x| x < -eps), d.iter().all(|&x| x.abs() <= eps));
    let ((apart_s, flat_s), (apart_t, flat_t)) = (side(ds), side(dt));
    if apart_s || apart_t || flat_s || flat_t {
        return None;
    }
    // one on one side of the other's plane, an edge in it
    let touching = |d: [f64; 3]| {
        let one_side = d.iter().all(|&x| x >= -eps) || d.iter().all(|&x| x <= eps);
        (0..3).find(|&k| d[k].abs() <= eps && d[(k + 1) % 3].abs() <= eps).filter(|_| one_side)
    };
    let edges = [touching(dt).map(|k| (0, k)), touching(ds).map(|k| (1, k))];
    let seg = segment_of(s, t, ds, dt)?;
    Some(if edges.iter().any(Option::is_some) { Meeting::Touch { seg, edges } } else { Meeting::Crossing(seg) })
}

/// The segment of the line of the two planes that lies in both triangles (`ds`, `dt`:
/// each one's corners against the other's plane), or `None`.
fn segment_of(s: &Tri, t: &Tri, ds: [f64; 3], dt: [f64; 3]) -> Option<[Vec3; 2]> {
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
