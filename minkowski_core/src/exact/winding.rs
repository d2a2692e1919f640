//! The exact winding number of a closed [`TriMesh`], and the test that makes one a solid.
//!
//! A closed mesh (every edge used once in each direction) has an integer winding number
//! `w(q)` at every point `q` off its surface: the signed count of its faces crossed by any
//! ray from `q`, `+1` where the ray leaves through a face (along its normal), `−1` where it
//! enters. `w` is `0` far away and grows by one across each face, from its front (the side
//! the normal points to) to its back.
//!
//! The mesh bounds a *solid* — the set `{w ≥ 1}`, with every face either on its boundary
//! facing out or inside it — exactly when `w` is never negative: each value of `w` is the
//! front or the back value of some face, so that holds when every face has `w ≥ 0` just in
//! front of it ([`TriMesh::front_windings`]). A face with `w = −1` in front has the solid
//! in front and nothing behind: it is inverted (an inside-out shell, or a part of a shell
//! glued to another with the wrong side out). Shells that overlap are their union (`w = 2`
//! in the overlap is inside); a cavity shell (wound inward, inside a body) is a hole.
//!
//! Entry points: [`TriMesh::winding`], [`TriMesh::contains`], [`TriMesh::front_windings`].

use super::mesh::TriMesh;
use crate::math::Vec3;
use rayon::prelude::*;

/// Ray directions, tried in order until one meets no edge or vertex.
const RAY_DIRS: [[f64; 3]; 6] = [
    [0.577_350_269_189_625_8, 0.618_033_988_749_894_8, 0.532_088_886_237_956_1],
    [-0.381_966_011_250_105, 0.707_106_781_186_547_5, -0.595_241_580_617_241],
    [0.267_949_192_431_122_7, -0.809_016_994_374_947_4, 0.523_598_775_598_298_8],
    [-0.723_606_797_749_979, -0.223_606_797_749_979, 0.652_475_842_498_527_9],
    [0.142_857_142_857_142_85, 0.394_784_176_043_574_3, -0.907_446_052_160_137_5],
    [0.899_888_006_999_999, -0.314_159_265_358_979_3, -0.302_775_637_731_994_6],
];

/// Barycentric sample points of a face for [`TriMesh::front_windings`], tried in order
/// until one lies on no other face.
const FACE_SAMPLES: [[f64; 3]; 5] = [[1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], [0.6, 0.25, 0.15], [0.15, 0.6, 0.25], [0.25, 0.15, 0.6], [0.45, 0.1, 0.45]];

/// Heights above a face's centre, in mesh diagonals, at which its front winding number is
/// asked when every sample point on it lies on another face (coincident faces of bodies
/// that share a plane): far below any feature a solid can have, far above the rounding
/// with which a point is "on" a face.
const FRONT_LIFTS: [f64; 2] = [1e-9, 1e-7];

/// Twice a needle's area, in roundings of its largest coordinate times its longest
/// edge, below which its normal is noise ([`TriMesh::is_degenerate`]): each edge is off
/// by up to a rounding of the coordinates, so their cross product by about twice that
/// times an edge's length.
const NEEDLE_ROUNDINGS: f64 = 16.0;

/// What one ray saw.
enum Ray {
    /// The origin lies on a face (within rounding).
    Surface,
    /// The signed crossing count.
    Count(i64),
    /// The ray passed within rounding of an edge or vertex, or along a face; the count so
    /// far is unreliable.
    Degenerate(i64),
}

impl TriMesh {
    /// The winding number at `q`, or `None` when `q` lies on the surface (within rounding).
    ///
    /// # Panics
    /// In debug builds, when the mesh is not closed (the winding number is not defined).
    pub fn winding(&self, q: Vec3) -> Option<i64> {
        debug_assert!(self.closed, "the winding number of an open mesh");
        if !self.aabb.contains_point(q) {
            return Some(0);
        }
        let mut last = 0;
        for d in RAY_DIRS {
            match self.ray(q, Vec3::from_array(d).normalize(), u32::MAX) {
                Ray::Surface => return None,
                Ray::Count(c) => return Some(c),
                Ray::Degenerate(c) => last = c,
            }
        }
        Some(last)
    }

    /// Whether `q` lies in the closed solid bounded by the mesh: on the surface or where
    /// the winding number is not zero (overlapping shells are their union, cavity shells
    /// holes).
    ///
    /// # Panics
    /// In debug builds, when the mesh is no solid.
    pub fn contains(&self, q: Vec3) -> bool {
        debug_assert!(self.solid, "containment in a surface");
        self.winding(q).is_none_or(|w| w != 0)
    }

    /// The parity of the number of faces a ray from `q` crosses (`true`: odd), or `None`
    /// when `q` lies on a face or every ray passed within rounding of an edge. For a
    /// surface closed mod 2 (every edge, vertices welded, used an even number of times:
    /// see [`super::shells`]) it is the same for every ray, constant off the surface, and
    /// changes across it; orientation does not matter.
    pub fn parity(&self, q: Vec3) -> Option<bool> {
        if !self.aabb.contains_point(q) {
            return Some(false);
        }
        RAY_DIRS.iter().find_map(|&d| match self.ray(q, Vec3::from_array(d).normalize(), u32::MAX) {
            Ray::Count(c) => Some(Some(c.rem_euclid(2) == 1)),
            Ray::Surface => Some(None),
            Ray::Degenerate(_) => None,
        })?
    }

    /// The winding number just in front of every face (on the side its normal points to):
    /// at points on the face, or just above it where those lie on other faces (bodies that
    /// share a plane); `None` where it could not be told. Degenerate faces get `Some(0)`:
    /// they bound nothing, and rays pass through them ([`TriMesh::is_degenerate`]), so
    /// the side a rounding-noise normal points to is no front. The mesh
    /// bounds a solid when no value is negative (see the module documentation). Parallel.
    pub fn front_windings(&self) -> Vec<Option<i64>> {
        debug_assert!(self.closed, "the winding number of an open mesh");
        (0..self.tris.len()).into_par_iter().map(|i| self.front_winding(i)).collect()
    }

    fn front_winding(&self, i: usize) -> Option<i64> {
        let t = &self.tris[i];
        if t.n == Vec3::ZERO || self.is_degenerate(t) {
            return Some(0);
        }
        let centre = t.p[0] * FACE_SAMPLES[0][0] + t.p[1] * FACE_SAMPLES[0][1] + t.p[2] * FACE_SAMPLES[0][2];
        let on_face = FACE_SAMPLES.iter().map(|w| t.p[0] * w[0] + t.p[1] * w[1] + t.p[2] * w[2]);
        // a face lying on another (two bodies sharing a plane) is told just in front of it
        let scale = self.aabb.diagonal();
        let lifted = FRONT_LIFTS.iter().map(|&h| centre + t.n * (h * scale));
        for q in on_face.chain(lifted) {
            if let Some(w) = self.winding_from(q, t.n, i as u32) {
                return Some(w);
            }
        }
        None
    }

    /// The winding number at `q`, by rays on the side of `n`, ignoring face `skip`; `None`
    /// when `q` lies on another face.
    fn winding_from(&self, q: Vec3, n: Vec3, skip: u32) -> Option<i64> {
        let mut last = 0;
        for g in RAY_DIRS {
            // a generic direction on the front side (d · n > 0.7)
            let d = (n + Vec3::from_array(g) * 0.3).normalize();
            match self.ray(q, d, skip) {
                Ray::Surface => return None,
                Ray::Count(c) => return Some(c),
                Ray::Degenerate(c) => last = c,
            }
        }
        Some(last)
    }

    /// Whether a face is degenerate: twice its area is below `1e-14` of the squared
    /// diagonal, or below what rounding its corners' coordinates can make of the cross
    /// product of its edges (a needle whose corners lie on a line up to that rounding has
    /// a unit normal pointing anywhere). It bounds nothing: rays pass through it and it
    /// has no front.
    pub(crate) fn is_degenerate(&self, t: &super::mesh::Tri) -> bool {
        let scale = self.aabb.diagonal().max(1e-300);
        let twice_area = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).length();
        let magnitude = t.p.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
        let longest = t.e.iter().map(|e| e.length()).fold(0.0, f64::max);
        twice_area <= 1e-14 * scale * scale || twice_area <= NEEDLE_ROUNDINGS * f64::EPSILON * magnitude * longest
    }

    /// Cast the ray `q + s d`, `s > 0`, against every face but `skip`.
    fn ray(&self, q: Vec3, d: Vec3, skip: u32) -> Ray {
        let reach = 2.0 * self.aabb.diagonal() + (q - self.aabb.center()).length() + 1.0;
        let far = q + d * reach;
        let scale = self.aabb.diagonal().max(1e-300);
        let mut count = 0i64;
        let mut degenerate = false;
        let mut stack = vec![0u32];
        while let Some(ni) = stack.pop() {
            let n = &self.nodes[ni as usize];
            if !n.aabb.overlaps_segment(q, far) {
                continue;
            }
            if !n.is_leaf() {
                stack.push(n.left);
                stack.push(n.left + 1);
                continue;
            }
            if n.tri == skip {
                continue;
            }
            let t = &self.tris[n.tri as usize];
            let (e1, e2) = (t.p[1] - t.p[0], t.p[2] - t.p[0]);
            let pv = d.cross(e2);
            let det = e1.dot(pv);
            let s = q - t.p[0];
            // (a degenerate face is passed through: asked only where it would count)
            if det.abs() <= 1e-12 * e1.length() * e2.length() {
                // ray parallel to the plane: it matters only within the plane
                let normal = e1.cross(e2);
                if !self.is_degenerate(t) && (s.dot(normal) / normal.length()).abs() <= 1e-12 * scale {
                    degenerate = true;
                }
                continue;
            }
            let inv = 1.0 / det;
            let u = s.dot(pv) * inv;
            let qv = s.cross(e1);
            let v = d.dot(qv) * inv;
            let dist = e2.dot(qv) * inv;
            let tol = 1e-9;
            if u < -tol || v < -tol || u + v > 1.0 + tol || self.is_degenerate(t) {
                continue;
            }
            if dist.abs() <= 1e-12 * scale {
                return Ray::Surface;
            }
            if dist < 0.0 {
                continue;
            }
            if u <= tol || v <= tol || u + v >= 1.0 - tol {
                degenerate = true;
                continue;
            }
            // det = −d · n: negative when the ray leaves through an outward face
            count += if det < 0.0 { 1 } else { -1 };
        }
        if degenerate {
            Ray::Degenerate(count)
        } else {
            Ray::Count(count)
        }
    }
}
