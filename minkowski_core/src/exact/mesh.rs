//! [`TriMesh`]: a triangle mesh with a binary BVH of one triangle per leaf (so that pairs of
//! nodes of two meshes can be refined lazily, one level at a time). A closed one (a
//! candidate solid) also has the exact winding number of [`super::winding`].

use super::crossing::Crossing;
use crate::error::{CoreError, CoreResult};
use crate::math::{Aabb, Vec3};
use crate::util::UnionFind;
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
    pub(crate) fn new(p: [Vec3; 3]) -> Tri {
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

/// A triangle mesh with its BVH: closed and consistently oriented (outward normals, from
/// [`TriMesh::new`]) or any set of triangles (a surface, from [`TriMesh::surface`]).
#[derive(Clone, Debug)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<Vec3>,
    /// Triangles.
    pub tris: Vec<Tri>,
    /// Their vertex indices.
    pub faces: Vec<[u32; 3]>,
    /// The pairs of triangles that cross each other (see [`super::crossing`]); filled for
    /// solids only.
    pub crossing: Vec<[u32; 2]>,
    /// BVH nodes; node 0 is the root.
    pub nodes: Vec<MeshNode>,
    /// Box around the mesh.
    pub aabb: Aabb,
    /// One vertex of every connected shell (vertex-connected component).
    pub anchors: Vec<Vec3>,
    /// Whether every edge is used once in each direction (then the winding number is
    /// defined off the surface).
    pub closed: bool,
    /// Whether it bounds a solid (closed, winding number never negative: see
    /// [`super::winding`]); only then may [`TriMesh::contains`] be asked.
    pub solid: bool,
}

/// A closed mesh's winding numbers ([`TriMesh::checked_windings`]): just in front of each
/// triangle, in the wedge in front of both triangles of each crossing (`None`: untold), and
/// the solid it bounds, or why it bounds none.
pub struct Windings {
    /// Per triangle.
    pub fronts: Vec<Option<i64>>,
    /// Per crossing of two triangles.
    pub wedges: Vec<Option<i64>>,
    /// How many crossings have the solid on both sides of both triangles
    /// ([`TriMesh::crossings_inside`]).
    pub crossings_inside: usize,
    /// The solid, or the error saying why the mesh is none.
    pub solid: CoreResult<TriMesh>,
}

impl TriMesh {
    /// A solid from vertices and triangles. `what` names the mesh in errors.
    ///
    /// # Errors
    /// [`CoreError::InvalidGeometry`] when the mesh is empty, has a non-finite vertex or an
    /// index out of range, is not closed and consistently oriented (every edge used
    /// exactly once in each direction), or is closed but no solid: its winding number is
    /// negative somewhere (inverted faces or shells; [`TriMesh::front_windings`]).
    pub fn new(vertices: Vec<Vec3>, faces: &[[u32; 3]], what: &str) -> CoreResult<TriMesh> {
        TriMesh::checked_windings(vertices, faces, what)?.solid
    }

    /// The closed mesh's winding numbers in front of its triangles and at its crossings,
    /// and the solid it is when none is negative or untold (else the error
    /// [`TriMesh::new`] gives): the windings computed once, for a caller that reports
    /// them too.
    ///
    /// # Errors
    /// [`CoreError::InvalidGeometry`] when the mesh is empty, has a non-finite vertex or an
    /// index out of range, or is not closed and consistently oriented.
    pub fn checked_windings(vertices: Vec<Vec3>, faces: &[[u32; 3]], what: &str) -> CoreResult<Windings> {
        check_arrays(&vertices, faces, what)?;
        TriMesh::check_closed(faces, what)?;
        let mesh = TriMesh { closed: true, ..TriMesh::surface(vertices, faces, what)? };
        let crossings = mesh.crossings();
        Ok(mesh.windings_with(&crossings, what))
    }

    /// [`TriMesh::checked_windings`] of this closed mesh, its `crossings` found.
    pub(crate) fn windings_with(self, crossings: &[Crossing], what: &str) -> Windings {
        debug_assert!(self.closed, "the winding number of an open mesh");
        let mut mesh = self;
        let fronts = mesh.front_windings();
        let wedges = mesh.crossing_windings(crossings);
        let crossings_inside = mesh.crossings_inside(crossings);
        let negative = |ws: &[Option<i64>]| ws.iter().filter(|w| w.is_some_and(|w| w < 0)).count();
        let unknown = |ws: &[Option<i64>]| ws.iter().filter(|w| w.is_none()).count();
        let (inverted, inverted_wedges) = (negative(&fronts), negative(&wedges));
        let untold = unknown(&fronts) + unknown(&wedges);
        let solid = if inverted + inverted_wedges + untold > 0 {
            Err(CoreError::InvalidGeometry {
                what: what.into(),
                detail: format!(
                    "is closed but bounds no solid: {inverted} of {} triangles, and {inverted_wedges} of {} crossings of triangles, have the inside in front of them (winding number below 0: inverted faces or shells), and {untold} places could not be told; repair it or use it as a surface",
                    fronts.len(),
                    crossings.len()
                ),
            })
        } else {
            mesh.crossing = crossings.iter().map(|c| c.tris).collect();
            mesh.solid = true;
            Ok(mesh)
        };
        Windings { fronts, wedges, crossings_inside, solid }
    }

    /// Whether every edge of `faces` is used once in each direction.
    ///
    /// # Errors
    /// [`CoreError::InvalidGeometry`] saying how many edges are not.
    pub fn check_closed(faces: &[[u32; 3]], what: &str) -> CoreResult<()> {
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
            return Err(CoreError::InvalidGeometry {
                what: what.into(),
                detail: format!("is not closed and consistently oriented ({open} edges are not used once in each direction); repair it first"),
            });
        }
        Ok(())
    }

    /// Any set of triangles (open, overlapping, inconsistently wound: a *surface*, as FCL
    /// sees a mesh). It has no inside: [`TriMesh::contains`] must not be asked.
    ///
    /// # Errors
    /// [`CoreError::InvalidGeometry`] when the mesh is empty, has a non-finite vertex or an
    /// index out of range.
    pub fn surface(vertices: Vec<Vec3>, faces: &[[u32; 3]], what: &str) -> CoreResult<TriMesh> {
        check_arrays(&vertices, faces, what)?;
        let nv = vertices.len();
        let tris: Vec<Tri> = faces.iter().map(|f| Tri::new([vertices[f[0] as usize], vertices[f[1] as usize], vertices[f[2] as usize]])).collect();
        let aabb = Aabb::from_points(&vertices);
        let nodes = build_nodes(&tris);
        // one vertex per connected shell (union-find over the triangles' corners)
        let mut shells = UnionFind::new(nv);
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
        Ok(TriMesh { vertices, tris, faces: faces.to_vec(), crossing: Vec::new(), nodes, aabb, anchors, closed: false, solid: false })
    }

    /// The same mesh reflected through the origin (`-v`), still outward oriented.
    pub fn negated(&self) -> TriMesh {
        let tris: Vec<Tri> = self.tris.iter().map(|t| Tri::new([-t.p[0], -t.p[2], -t.p[1]])).collect();
        let vertices: Vec<Vec3> = self.vertices.iter().map(|v| -*v).collect();
        let aabb = Aabb::from_points(&vertices);
        let nodes = build_nodes(&tris);
        let anchors = self.anchors.iter().map(|v| -*v).collect();
        let faces = self.faces.iter().map(|f| [f[0], f[2], f[1]]).collect();
        TriMesh { vertices, tris, faces, crossing: self.crossing.clone(), nodes, aabb, anchors, closed: self.closed, solid: self.solid }
    }

    /// Whether a triangle meets the closed box `b` (separating axes, with the rounding
    /// slack of [`super::Facet::overlaps_box`]: touching counts).
    pub fn meets_box(&self, b: &Aabb) -> bool {
        let mut stack = vec![0u32];
        while let Some(ni) = stack.pop() {
            let n = &self.nodes[ni as usize];
            if !n.aabb.overlaps(b) {
                continue;
            }
            if !n.is_leaf() {
                stack.extend([n.left, n.left + 1]);
                continue;
            }
            let t = &self.tris[n.tri as usize];
            let tri = super::Facet { p: [t.p[0], t.p[1], t.p[2], Vec3::ZERO], n: 3, k: 0 };
            if tri.overlaps_box(b, 0.0) {
                return true;
            }
        }
        false
    }

    /// Whether the solid contains the closed box `b`: no triangle meets it and its centre
    /// is inside.
    pub fn contains_box(&self, b: &Aabb) -> bool {
        debug_assert!(self.solid, "containment in a surface");
        !self.meets_box(b) && self.contains(b.center())
    }
}

/// Non-empty, finite, indices in range.
fn check_arrays(vertices: &[Vec3], faces: &[[u32; 3]], what: &str) -> CoreResult<()> {
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
    Ok(())
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
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
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
