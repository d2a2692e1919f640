//! The flat faces of a mesh: edge-connected triangles on one plane, facing the same way
//! (a box's square faces, a prism's caps, a gear's toothed top).
//!
//! The column over a convex face (the points whose projection on its plane lies in it) is a
//! convex prism bounded by the half-planes of the face's boundary edges, so a box lies in
//! it exactly when its eight corners do — the test [`FlatFaces::over`] gives. Over a face
//! that is not convex, a box lies in the column of some of its triangles exactly when its
//! shadow holds a point over one of them and meets none of the walls over their union's
//! boundary edges ([`FlatFaces::across`] tells those: no triangle of the face across them
//! among the ones taken; [`wall_meets`] is the wall test, conservative). The offset source
//! uses both to see where a triangle's neighbourhood is the face's slab even over the edges
//! between a face's triangles (see [`crate::offset`]).
//!
//! Entry point: [`FlatFaces::new`].

use std::collections::HashMap;

use crate::exact::shells::weld;
use crate::exact::TriMesh;
use crate::math::Vec3;
use crate::util::UnionFind;

/// Normals closer than this (`1 − n_a · n_b`) and heights closer than this fraction of the
/// mesh's size are one plane.
const COPLANAR: f64 = 1e-12;

/// Faces with more boundary edges than this are not tested for convexity (the test is
/// quadratic); their triangles keep their own columns.
const MAX_BOUNDARY: usize = 256;

/// Per triangle, its flat face, and that face's boundary half-planes when it is convex.
pub struct FlatFaces {
    /// Per triangle: the index of its convex face in `edges`, or `u32::MAX`.
    face_of: Vec<u32>,
    /// Per convex face: its boundary edges as `(m, q)`: inside is `(x − q) · m >= 0`.
    edges: Vec<Vec<(Vec3, Vec3)>>,
    /// Per triangle: its flat face of more than one triangle, or `u32::MAX`.
    group: Vec<u32>,
    /// Per triangle and edge `k` (from corner `k` to `k + 1`): the triangle of its flat face
    /// across that edge, or `u32::MAX` on the face's boundary.
    across: Vec<[u32; 3]>,
}

impl FlatFaces {
    /// The flat faces of `mesh` and, of the convex ones, their columns' half-planes
    /// (triangles of non-convex or holed faces have none: [`FlatFaces::concave_group`]).
    pub fn new(mesh: &TriMesh) -> FlatFaces {
        let tol = COPLANAR * mesh.aabb.diagonal().max(f64::MIN_POSITIVE);
        let faces = welded_faces(mesh);
        let (groups, mut across) = coplanar_groups(mesh, &faces, tol);
        let mut face_of = vec![u32::MAX; mesh.tris.len()];
        let mut group = vec![u32::MAX; mesh.tris.len()];
        let mut edges = Vec::new();
        for (g, members) in groups.into_iter().filter(|g| g.len() > 1).enumerate() {
            for &t in &members {
                group[t] = g as u32;
            }
            let Some(boundary) = convex_boundary(mesh, &faces, &members, tol) else { continue };
            for &t in &members {
                face_of[t] = edges.len() as u32;
            }
            edges.push(boundary);
        }
        for (t, sides) in across.iter_mut().enumerate() {
            for u in sides.iter_mut().filter(|u| **u != u32::MAX) {
                if group[*u as usize] != group[t] {
                    *u = u32::MAX; // (joined by a non-manifold edge only)
                }
            }
        }
        FlatFaces { face_of, edges, group, across }
    }

    /// The flat face of more than one triangle that triangle `t` is part of, when it is not
    /// convex (a convex one's column is [`FlatFaces::over`]'s).
    pub fn concave_group(&self, t: usize) -> Option<u32> {
        (self.group[t] != u32::MAX && self.face_of[t] == u32::MAX).then_some(self.group[t])
    }

    /// The triangle of `t`'s flat face across its edge `k` (from corner `k` to `k + 1`).
    pub fn across(&self, t: usize, k: usize) -> Option<u32> {
        let u = self.across[t][k];
        (u != u32::MAX).then_some(u)
    }

    /// Whether triangle `t` belongs to a convex face of more than one triangle.
    pub fn has_face(&self, t: usize) -> bool {
        self.face_of[t] != u32::MAX
    }

    /// Whether `x` projects into the convex face of triangle `t` (closed); `false` when `t`
    /// has none.
    pub fn over(&self, t: usize, x: Vec3) -> bool {
        match self.edges.get(self.face_of[t] as usize) {
            Some(face) => face.iter().all(|&(m, q)| (x - q).dot(m) >= 0.0),
            None => false,
        }
    }
}

/// The mesh's faces with vertices at one position made one ([`weld`]): a triangle
/// soup, as OMPL.app ships its environments, repeats each vertex per triangle, and its
/// faces are joined only where the positions are the same.
fn welded_faces(mesh: &TriMesh) -> Vec<[u32; 3]> {
    let id = weld(&mesh.vertices);
    mesh.faces.iter().map(|f| f.map(|v| id[v as usize])).collect()
}

/// The sets of edge-connected triangles (`faces`, welded) on one plane facing one way
/// (sliver triangles, with no normal, are on their own), and per triangle and edge the
/// triangle joined to it there.
fn coplanar_groups(mesh: &TriMesh, faces: &[[u32; 3]], tol: f64) -> (Vec<Vec<usize>>, Vec<[u32; 3]>) {
    let mut by_edge: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
    let mut uf = UnionFind::new(mesh.tris.len());
    let mut across = vec![[u32::MAX; 3]; mesh.tris.len()];
    for (t, f) in faces.iter().enumerate() {
        if mesh.tris[t].n == Vec3::ZERO {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            // the neighbour across this edge uses it the other way round
            if let Some(&(u, j)) = by_edge.get(&(b, a)) {
                let (nt, nu) = (mesh.tris[t].n, mesh.tris[u].n);
                let height = (mesh.tris[u].p[0] - mesh.tris[t].p[0]).dot(nt).abs();
                if 1.0 - nt.dot(nu) <= COPLANAR && height <= tol {
                    uf.union(t, u);
                    across[t][k] = u as u32;
                    across[u][j] = t as u32;
                }
            }
            by_edge.insert((a, b), (t, k));
        }
    }
    let mut groups: HashMap<usize, Vec<usize>> = HashMap::new();
    for t in 0..mesh.tris.len() {
        groups.entry(uf.find(t)).or_default().push(t);
    }
    let mut out: Vec<Vec<usize>> = groups.into_values().collect();
    out.sort_unstable_by_key(|g| g[0]);
    (out, across)
}

/// Whether the box with corners `corners` may meet the wall over the edge `a → b` of a flat
/// face (the points `a + s (b − a) + u n`, `s` in `[0, 1]`, `u` any, `n` the face's normal),
/// `m` the edge's in-plane normal: the box reaches both sides of the wall's plane (or
/// touches it) and overlaps the edge's extent along it. Conservative: `true` near the
/// edge's ends when the box passes beside them.
pub fn wall_meets(corners: &[Vec3; 8], a: Vec3, b: Vec3, m: Vec3) -> bool {
    let len = (b - a).length();
    if len == 0.0 {
        return false;
    }
    let along = (b - a) / len;
    let (mut across_lo, mut across_hi, mut along_lo, mut along_hi) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &x in corners {
        let w = x - a;
        let (c, l) = (w.dot(m), w.dot(along));
        (across_lo, across_hi) = (across_lo.min(c), across_hi.max(c));
        (along_lo, along_hi) = (along_lo.min(l), along_hi.max(l));
    }
    across_lo <= 0.0 && across_hi >= 0.0 && along_hi >= 0.0 && along_lo <= len
}

/// The inward half-planes of the boundary edges of the triangles `members` (one plane),
/// when their union is one convex polygon: every corner lies inside every boundary edge.
fn convex_boundary(mesh: &TriMesh, faces: &[[u32; 3]], members: &[usize], tol: f64) -> Option<Vec<(Vec3, Vec3)>> {
    let mut used: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
    for &t in members {
        let f = faces[t];
        for k in 0..3 {
            used.insert((f[k], f[(k + 1) % 3]), (t, k));
        }
    }
    let boundary: Vec<(Vec3, Vec3)> = used.iter().filter(|(&(a, b), _)| !used.contains_key(&(b, a))).map(|(_, &(t, k))| (mesh.tris[t].m[k], mesh.tris[t].p[k])).collect();
    if boundary.len() < 3 || boundary.len() > MAX_BOUNDARY {
        return None;
    }
    let corners = members.iter().flat_map(|&t| mesh.tris[t].p);
    let convex = corners.clone().all(|x| boundary.iter().all(|&(m, q)| (x - q).dot(m) >= -tol));
    convex.then_some(boundary)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(v: &[[f64; 3]], f: &[[u32; 3]]) -> TriMesh {
        TriMesh::surface(v.iter().map(|&p| Vec3::from_array(p)).collect(), f, "test").expect("a mesh")
    }

    #[test]
    fn a_square_of_two_triangles_is_one_convex_face() {
        let m = mesh(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2], [0, 2, 3]]);
        let faces = FlatFaces::new(&m);
        assert!(faces.has_face(0) && faces.has_face(1));
        // over the diagonal: in neither triangle's column alone, but in the square's
        assert!(faces.over(0, Vec3::new(0.5, 0.5, 3.0)) && faces.over(1, Vec3::new(0.9, 0.1, -2.0)));
        assert!(!faces.over(0, Vec3::new(1.1, 0.5, 0.0)));
    }

    #[test]
    fn an_l_shaped_face_is_not_convex() {
        // an L of three squares (six triangles) in the plane z = 0
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [2.0, 1.0, 0.0], [0.0, 2.0, 0.0], [1.0, 2.0, 0.0]];
        let f = [[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6]];
        let faces = FlatFaces::new(&mesh(&v, &f));
        assert!((0..6).all(|t| !faces.has_face(t)));
        assert!(!faces.over(0, Vec3::new(1.5, 1.5, 0.0)));
    }

    #[test]
    fn an_l_shaped_face_tells_the_triangles_across_its_inner_edges() {
        // an L of three unit squares fanned from (0, 0): the fan's inner edges join its
        // triangles, its outline has none across
        let v = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 2.0, 0.0]];
        let f = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]];
        let faces = FlatFaces::new(&mesh(&v, &f));
        assert!((0..4).all(|t| faces.concave_group(t) == Some(0)));
        assert_eq!((faces.across(0, 2), faces.across(1, 0)), (Some(1), Some(0))); // over 0 → 2
        assert_eq!((faces.across(0, 0), faces.across(1, 1), faces.across(3, 1)), (None, None, None));
        // a convex face has no concave group
        let square = FlatFaces::new(&mesh(&v[..4], &[[0, 1, 2], [0, 2, 3]]));
        assert!(square.concave_group(0).is_none() && square.has_face(0));
    }

    #[test]
    fn a_wall_is_met_by_boxes_across_it_within_its_edge() {
        let corners = |c: Vec3, h: f64| -> [Vec3; 8] {
            std::array::from_fn(|k| c + Vec3::new(if k & 1 == 0 { -h } else { h }, if k & 2 == 0 { -h } else { h }, if k & 4 == 0 { -h } else { h }))
        };
        // the wall over the edge (0, 0, 0) → (1, 0, 0), inside towards +y
        let (a, b, m) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert!(wall_meets(&corners(Vec3::new(0.5, 0.0, 7.0), 0.1), a, b, m)); // high above it
        assert!(!wall_meets(&corners(Vec3::new(0.5, 0.2, 0.0), 0.1), a, b, m)); // beside it
        assert!(!wall_meets(&corners(Vec3::new(1.2, 0.0, 0.0), 0.1), a, b, m)); // past its end
        assert!(wall_meets(&corners(Vec3::new(1.05, 0.0, 0.0), 0.1), a, b, m)); // over its end
    }

    #[test]
    fn a_soup_of_unshared_corners_makes_the_same_faces() {
        // the square of two triangles, each with its own copies of the corners
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let faces = FlatFaces::new(&mesh(&v, &[[0, 1, 2], [3, 4, 5]]));
        assert!(faces.has_face(0) && faces.has_face(1));
        assert!(faces.over(0, Vec3::new(0.5, 0.5, 3.0)));
        assert_eq!((faces.across(0, 2), faces.across(1, 0)), (Some(1), Some(0)));
    }

    #[test]
    fn a_fold_is_two_faces() {
        // two squares meeting at a right angle along x = 1
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0]];
        let f = [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]];
        let faces = FlatFaces::new(&mesh(&v, &f));
        assert!(faces.over(0, Vec3::new(0.5, 0.5, 1.5)) && !faces.over(2, Vec3::new(0.5, 0.5, 1.5)));
        assert!(faces.over(2, Vec3::new(2.0, 0.5, 0.5)));
    }
}
