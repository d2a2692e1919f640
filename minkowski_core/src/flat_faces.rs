//! The convex flat faces of a mesh: edge-connected triangles on one plane, facing the same
//! way, whose union is one convex polygon (a box's square faces, a prism's caps).
//!
//! The column over such a face (the points whose projection on its plane lies in it) is a
//! convex prism bounded by the half-planes of the face's boundary edges, so a box lies in
//! it exactly when its eight corners do — the test [`FlatFaces::over`] gives. The offset
//! source uses it to see where a triangle's neighbourhood is the face's slab even over the
//! diagonals between a face's triangles (see [`crate::offset`]).
//!
//! Entry point: [`FlatFaces::new`].

use std::collections::HashMap;

use crate::exact::TriMesh;
use crate::math::Vec3;
use crate::util::UnionFind;

/// Normals closer than this (`1 − n_a · n_b`) and heights closer than this fraction of the
/// mesh's size are one plane.
const COPLANAR: f64 = 1e-12;

/// Faces with more boundary edges than this are not tested for convexity (the test is
/// quadratic); their triangles keep their own columns.
const MAX_BOUNDARY: usize = 256;

/// Per triangle, its convex face's boundary half-planes, if it has one.
pub struct FlatFaces {
    /// Per triangle: the index of its face in `edges`, or `u32::MAX`.
    face_of: Vec<u32>,
    /// Per face: its boundary edges as `(m, q)`: inside is `(x − q) · m >= 0`.
    edges: Vec<Vec<(Vec3, Vec3)>>,
}

impl FlatFaces {
    /// The convex flat faces of `mesh` (triangles of non-convex or holed faces have none).
    pub fn new(mesh: &TriMesh) -> FlatFaces {
        let tol = COPLANAR * mesh.aabb.diagonal().max(f64::MIN_POSITIVE);
        let groups = coplanar_groups(mesh, tol);
        let mut face_of = vec![u32::MAX; mesh.tris.len()];
        let mut edges = Vec::new();
        for members in groups.into_iter().filter(|g| g.len() > 1) {
            let Some(boundary) = convex_boundary(mesh, &members, tol) else { continue };
            for &t in &members {
                face_of[t] = edges.len() as u32;
            }
            edges.push(boundary);
        }
        FlatFaces { face_of, edges }
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

/// The sets of edge-connected triangles on one plane facing one way (sliver triangles, with
/// no normal, are on their own).
fn coplanar_groups(mesh: &TriMesh, tol: f64) -> Vec<Vec<usize>> {
    let mut by_edge: HashMap<(u32, u32), usize> = HashMap::new();
    let mut uf = UnionFind::new(mesh.tris.len());
    for (t, f) in mesh.faces.iter().enumerate() {
        if mesh.tris[t].n == Vec3::ZERO {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            // the neighbour across this edge uses it the other way round
            if let Some(&u) = by_edge.get(&(b, a)) {
                let (nt, nu) = (mesh.tris[t].n, mesh.tris[u].n);
                let height = (mesh.tris[u].p[0] - mesh.tris[t].p[0]).dot(nt).abs();
                if 1.0 - nt.dot(nu) <= COPLANAR && height <= tol {
                    uf.union(t, u);
                }
            }
            by_edge.insert((a, b), t);
        }
    }
    let mut groups: HashMap<usize, Vec<usize>> = HashMap::new();
    for t in 0..mesh.tris.len() {
        groups.entry(uf.find(t)).or_default().push(t);
    }
    let mut out: Vec<Vec<usize>> = groups.into_values().collect();
    out.sort_unstable_by_key(|g| g[0]);
    out
}

/// The inward half-planes of the boundary edges of the triangles `members` (one plane),
/// when their union is one convex polygon: every corner lies inside every boundary edge.
fn convex_boundary(mesh: &TriMesh, members: &[usize], tol: f64) -> Option<Vec<(Vec3, Vec3)>> {
    let mut used: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
    for &t in members {
        let f = mesh.faces[t];
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
    fn a_fold_is_two_faces() {
        // two squares meeting at a right angle along x = 1
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0]];
        let f = [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]];
        let faces = FlatFaces::new(&mesh(&v, &f));
        assert!(faces.over(0, Vec3::new(0.5, 0.5, 1.5)) && !faces.over(2, Vec3::new(0.5, 0.5, 1.5)));
        assert!(faces.over(2, Vec3::new(2.0, 0.5, 0.5)));
    }
}
