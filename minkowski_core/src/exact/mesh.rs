//! [`TriMesh`]: a closed triangle mesh with a binary BVH of one triangle per leaf (so that
//! pairs of nodes of two meshes can be refined lazily, one level at a time) and an exact
//! point-in-solid test by ray parity.

use crate::error::{CoreError, CoreResult};
use crate::math::{Aabb, Vec3};
use crate::roadmap::UnionFind;
use std::collections::HashMap;

/// A BVH node: leaf when `tri != u32::MAX`, else children `left` and `left + 1`.
#[derive(Clone, Copy, Debug)]
pub struct MeshNode {
    /// Box of the node's triangles.
    pub aabb: Aabb,
    /// First child (inner nodes).
    pub left: u32,
    /// Triangle (leaves), `u32::MAX` for inner nodes.
    pub tri: u32,
}

impl MeshNode {
    /// Whether this is a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.tri != u32::MAX
    }

    /// Longest edge of the box.
    #[inline]
    pub fn size(&self) -> f64 {
        self.aabb.extent().max_element()
    }
}

/// Per-triangle data used by the pair tests.
#[derive(Clone, Copy, Debug)]
pub struct Tri {
    /// Corners.
    pub p: [Vec3; 3],
    /// Edge vectors `p1 - p0`, `p2 - p1`, `p0 - p2`.
    pub e: [Vec3; 3],
    /// Unit normal (zero for a degenerate triangle).
    pub n: Vec3,
    /// Unit in-plane edge normals `n × e_k` (zero when degenerate).
    pub m: [Vec3; 3],
}

impl Tri {
    fn new(p: [Vec3; 3]) -> Tri {
        let e = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
        let n = unit(e[0].cross(e[1]), e[0].length() * e[1].length());
        let m = [unit(n.cross(e[0]), e[0].length()), unit(n.cross(e[1]), e[1].length()), unit(n.cross(e[2]), e[2].length())];
        Tri { p, e, n, m }
    }

    /// `max_k p_k · d`.
    #[inline]
    pub fn support(&self, d: Vec3) -> f64 {
        self.p[0].dot(d).max(self.p[1].dot(d)).max(self.p[2].dot(d))
    }
}

/// `v / |v|`, or zero when `|v|` is negligible against `scale` (a product of lengths).
#[inline]
pub(crate) fn unit(v: Vec3, scale: f64) -> Vec3 {
    let l = v.length();
    if l <= 1e-12 * scale || l == 0.0 {
        Vec3::ZERO
    } else {
        v / l
    }
}

/// A closed, consistently oriented triangle mesh (outward normals) with its BVH.
#[derive(Clone, Debug)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<Vec3>,
    /// Triangles.
    pub tris: Vec<Tri>,
    /// BVH nodes; node 0 is the root.
    pub nodes: Vec<MeshNode>,
    /// Box around the mesh.
    pub aabb: Aabb,
    /// One vertex of every connected shell.
    pub anchors: Vec<Vec3>,
}

/// Ray directions for the parity test, tried in order until one meets no edge or vertex.
const RAY_DIRS: [[f64; 3]; 6] = [
    [0.577_350_269_189_625_8, 0.618_033_988_749_894_8, 0.532_088_886_237_956_1],
    [-0.381_966_011_250_105, 0.707_106_781_186_547_5, -0.595_241_580_617_241],
    [0.267_949_192_431_122_7, -0.809_016_994_374_947_4, 0.523_598_775_598_298_8],
    [-0.723_606_797_749_979, -0.223_606_797_749_979, 0.652_475_842_498_527_9],
    [0.142_857_142_857_142_85, 0.394_784_176_043_574_3, -0.907_446_052_160_137_5],
    [0.899_888_006_999_999, -0.314_159_265_358_979_3, -0.302_775_637_731_994_6],
];

impl TriMesh {
    /// Build from vertices and triangles. `what` names the mesh in errors.
    ///
    /// # Errors
    /// [`CoreError::InvalidGeometry`] when the mesh is empty, has a non-finite vertex or an
    /// index out of range, or is not closed and consistently oriented (every edge used
    /// exactly once in each direction).
    pub fn new(vertices: Vec<Vec3>, faces: &[[u32; 3]], what: &str) -> CoreResult<TriMesh> {
        let bad = |detail: String| CoreError::InvalidGeometry { what: what.into(), detail };
        if faces.is_empty() {
            return Err(bad("has no triangles".into()));
        }
        if vertices.iter().any(|v| !v.is_finite()) {
            return Err(bad("has a non-finite vertex".into()));
        }
        let nv = vertices.len() as u32;
        if let Some(f) = faces.iter().find(|f| f.iter().any(|&i| i >= nv)) {
            return Err(bad(format!("triangle {f:?} refers to a vertex beyond the {nv} given")));
        }
        let mut edges: HashMap<(u32, u32), i32> = HashMap::with_capacity(faces.len() * 3);
        for f in faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                if a == b {
                    continue;
                }
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 };
            }
        }
        let open = edges.values().filter(|&&c| c != 0).count();
        if open > 0 {
            return Err(bad(format!(
                "is not closed and consistently oriented ({open} edges are not used once in each direction); repair it first"
            )));
        }
        let tris: Vec<Tri> =
            faces.iter().map(|f| Tri::new([vertices[f[0] as usize], vertices[f[1] as usize], vertices[f[2] as usize]])).collect();
        let aabb = Aabb::from_points(&vertices);
        let nodes = build_nodes(&tris);
        // one vertex per connected shell (union-find over the triangles' corners)
        let mut shells = UnionFind::new(nv as usize);
        for f in faces {
            shells.union(f[0] as usize, f[1] as usize);
            shells.union(f[0] as usize, f[2] as usize);
        }
        let mut seen = std::collections::HashSet::new();
        let mut anchors = Vec::new();
        for f in faces {
            if seen.insert(shells.find(f[0] as usize)) {
                anchors.push(vertices[f[0] as usize]);
            }
        }
        Ok(TriMesh { vertices, tris, nodes, aabb, anchors })
    }

    /// The same mesh reflected through the origin (`-v`), still outward oriented.
    pub fn negated(&self) -> TriMesh {
        let tris: Vec<Tri> = self.tris.iter().map(|t| Tri::new([-t.p[0], -t.p[2], -t.p[1]])).collect();
        let vertices: Vec<Vec3> = self.vertices.iter().map(|v| -*v).collect();
        let aabb = Aabb::from_points(&vertices);
        let nodes = build_nodes(&tris);
        let anchors = self.anchors.iter().map(|v| -*v).collect();
        TriMesh { vertices, tris, nodes, aabb, anchors }
    }


    /// Whether `q` lies in the closed solid bounded by the mesh: the winding number along a
    /// ray (exits minus entries) is non-zero, so overlapping shells are their union and
    /// inward cavity shells are holes. A ray that passes within rounding of an edge or
    /// vertex is replaced by the next direction; a point on the surface counts as inside.
    pub fn contains(&self, q: Vec3) -> bool {
        if !self.aabb.contains_point(q) {
            return false;
        }
        let reach = 2.0 * self.aabb.diagonal() + (q - self.aabb.center()).length() + 1.0;
        let mut last = false;
        for d in RAY_DIRS {
            let d = Vec3::from_array(d).normalize();
            match self.parity(q, d, reach) {
                Parity::Surface => return true,
                Parity::Count(c) => return c != 0,
                Parity::Degenerate(c) => last = c != 0,
            }
        }
        last
    }

    fn parity(&self, q: Vec3, d: Vec3, reach: f64) -> Parity {
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
            let t = &self.tris[n.tri as usize];
            let (e1, e2) = (t.p[1] - t.p[0], t.p[2] - t.p[0]);
            let pv = d.cross(e2);
            let det = e1.dot(pv);
            let s = q - t.p[0];
            let area = e1.cross(e2).length();
            if area <= 1e-14 * scale * scale {
                continue; // a degenerate triangle bounds nothing
            }
            if det.abs() <= 1e-12 * e1.length() * e2.length() {
                // ray parallel to the plane: it matters only within the plane
                if (s.dot(e1.cross(e2)) / area).abs() <= 1e-12 * scale {
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
            if u < -tol || v < -tol || u + v > 1.0 + tol {
                continue;
            }
            if dist.abs() <= 1e-12 * scale {
                return Parity::Surface;
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
            Parity::Degenerate(count)
        } else {
            Parity::Count(count)
        }
    }
}

enum Parity {
    Surface,
    Count(i64),
    Degenerate(i64),
}

/// Median-split BVH with one triangle per leaf.
fn build_nodes(tris: &[Tri]) -> Vec<MeshNode> {
    let boxes: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(&t.p)).collect();
    let mut order: Vec<u32> = (0..tris.len() as u32).collect();
    let mut nodes = Vec::with_capacity(2 * tris.len());
    nodes.push(MeshNode { aabb: Aabb::empty(), left: 0, tri: u32::MAX });
    let mut stack = vec![(0usize, 0usize, tris.len())];
    while let Some((ni, lo, hi)) = stack.pop() {
        let aabb = order[lo..hi].iter().fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]));
        nodes[ni].aabb = aabb;
        if hi - lo == 1 {
            nodes[ni].tri = order[lo];
            continue;
        }
        let e = aabb.extent();
        let axis = if e.x >= e.y && e.x >= e.z { 0 } else if e.y >= e.z { 1 } else { 2 };
        let mid = (lo + hi) / 2;
        order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| boxes[a as usize].center()[axis].total_cmp(&boxes[b as usize].center()[axis]));
        let left = nodes.len();
        nodes.push(MeshNode { aabb: Aabb::empty(), left: 0, tri: u32::MAX });
        nodes.push(MeshNode { aabb: Aabb::empty(), left: 0, tri: u32::MAX });
        nodes[ni].left = left as u32;
        stack.push((left, lo, mid));
        stack.push((left + 1, mid, hi));
    }
    nodes
}
