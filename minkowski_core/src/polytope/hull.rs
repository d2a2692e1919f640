//! Building a [`ConvexPolytope`] from points.

use crate::error::{CoreError, CoreResult};
use crate::math::{Aabb, Vec3};
use crate::util::{FastMap, UnionFind};

/// Points this close to a facet's plane, relative to the hull's diagonal, count as on it
/// (coplanar triangles are merged into one facet within it).
pub const PLANE_TOL_REL: f64 = 1e-9;

/// A closed convex polytope `{x : n_k · x <= d_k for all k}`.
///
/// Facet planes have unit outward normals; coplanar hull triangles are merged into one
/// plane, so `normals.len()` is the number of true facets. The boundary triangulation is
/// kept for exact point–polytope distances.
#[derive(Clone, Debug)]
pub struct ConvexPolytope {
    /// Hull vertices.
    pub vertices: Vec<Vec3>,
    /// Unit outward facet normals.
    pub normals: Vec<Vec3>,
    /// Facet offsets: the facet plane is `n · x = d`.
    pub offsets: Vec<f64>,
    /// Boundary triangles (indices into `vertices`, outward winding).
    pub triangles: Vec<[u32; 3]>,
    /// Facet (plane) index of each triangle.
    pub triangle_facet: Vec<u32>,
    /// Bounding box.
    pub aabb: Aabb,
}

impl ConvexPolytope {
    /// The convex hull of `points`.
    ///
    /// # Errors
    /// [`CoreError::NonFinite`] for NaN or inf, [`CoreError::Degenerate`] for fewer than
    /// four points or points that span no volume.
    pub fn try_from_points(points: &[Vec3], what: &str) -> CoreResult<Self> {
        if points.iter().any(|p| !p.is_finite()) {
            return Err(CoreError::NonFinite { what: what.to_string() });
        }
        if points.len() < 4 {
            return Err(CoreError::Degenerate { what: what.to_string(), detail: format!("{} points", points.len()) });
        }
        let bbox = Aabb::from_points(points);
        let scale = bbox.diagonal();
        if scale.is_nan() || scale <= 0.0 {
            return Err(CoreError::Degenerate { what: what.to_string(), detail: "all points coincide".into() });
        }
        // parry's quickhull may panic on degenerate input: contain that here.
        let hull = std::panic::catch_unwind(|| parry3d_f64::transformation::try_convex_hull(points));
        let (verts, tris) = match hull {
            Ok(Ok(h)) => h,
            Ok(Err(e)) => return Err(CoreError::Degenerate { what: what.to_string(), detail: format!("hull failed: {e}") }),
            Err(_) => return Err(CoreError::Degenerate { what: what.to_string(), detail: "hull failed (flat or degenerate points)".into() }),
        };
        Self::from_hull(verts, tris, scale, what)
    }

    /// The convex hull of `points`.
    ///
    /// # Panics
    /// When [`ConvexPolytope::try_from_points`] fails.
    pub fn from_points(points: &[Vec3]) -> Self {
        Self::try_from_points(points, "points").expect("convex hull")
    }

    fn from_hull(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>, scale: f64, what: &str) -> CoreResult<Self> {
        let degenerate = |detail: &str| CoreError::Degenerate { what: what.to_string(), detail: detail.to_string() };
        if triangles.len() < 4 {
            return Err(degenerate("fewer than 4 hull facets"));
        }
        // Orient every triangle outward: the hull's interior point is the vertex mean.
        let centre = vertices.iter().fold(Vec3::ZERO, |a, v| a + *v) / vertices.len() as f64;
        let mut tris = triangles;
        let mut volume = 0.0;
        let mut tri_n = Vec::with_capacity(tris.len());
        for t in tris.iter_mut() {
            let (a, b, c) = (vertices[t[0] as usize], vertices[t[1] as usize], vertices[t[2] as usize]);
            let mut n = (b - a).cross(c - a);
            if n.dot(a - centre) < 0.0 {
                t.swap(1, 2);
                n = -n;
            }
            volume += n.dot(a - centre) / 6.0;
            tri_n.push(n);
        }
        #[allow(clippy::neg_cmp_op_on_partial_ord)] // a NaN volume must fail (degenerate hull)
        if !(volume > 1e-12 * scale * scale * scale) {
            return Err(degenerate("zero volume (all points in a plane)"));
        }
        // Merge coplanar neighbouring triangles into facets (union–find over shared edges).
        let plane_tol = PLANE_TOL_REL * scale;
        let unit: Vec<Vec3> = tri_n.iter().map(|n| n.normalize_or_zero()).collect();
        let off: Vec<f64> = tris.iter().zip(&unit).map(|(t, n)| n.dot(vertices[t[0] as usize])).collect();
        let mut facets = UnionFind::new(tris.len());
        let mut edge_owner: FastMap<(u32, u32), usize> = FastMap::with_capacity_and_hasher(tris.len() * 2, Default::default());
        let mut adjacent: Vec<(usize, usize)> = Vec::with_capacity(tris.len() * 3 / 2);
        for (ti, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = if a < b { (a, b) } else { (b, a) };
                if let Some(&other) = edge_owner.get(&key) {
                    adjacent.push((ti, other));
                } else {
                    edge_owner.insert(key, ti);
                }
            }
        }
        // sliver triangles (near-coplanar hull points) have no reliable plane: they join a
        // neighbouring facet afterwards instead of forming (or bridging) facets
        let deg: Vec<bool> = tri_n.iter().map(|n| n.length() <= 1e-12 * scale * scale).collect();
        let coplanar = |i: usize, j: usize| -> bool {
            // same plane when each triangle's vertices lie on the other's plane
            !deg[i] && !deg[j] && unit[i].dot(unit[j]) > 1.0 - 1e-10 && tris[j].iter().all(|&v| (unit[i].dot(vertices[v as usize]) - off[i]).abs() <= plane_tol)
        };
        for &(i, j) in &adjacent {
            if coplanar(i, j) {
                facets.union(i, j);
            }
        }
        // One plane per facet: area-weighted normal, offset as the max over the facet's vertices
        // (so every hull vertex satisfies n·v <= d exactly).
        let mut facet_of_root: FastMap<usize, u32> = FastMap::default();
        let mut normals: Vec<Vec3> = Vec::new();
        let mut triangle_facet = vec![u32::MAX; tris.len()];
        for ti in 0..tris.len() {
            if deg[ti] {
                continue;
            }
            let r = facets.find(ti);
            let f = *facet_of_root.entry(r).or_insert_with(|| {
                normals.push(Vec3::ZERO);
                (normals.len() - 1) as u32
            });
            normals[f as usize] += tri_n[ti];
            triangle_facet[ti] = f;
        }
        // slivers take the facet of a neighbour (repeated for chains of slivers)
        loop {
            let mut changed = false;
            for &(i, j) in &adjacent {
                for (a, b) in [(i, j), (j, i)] {
                    if triangle_facet[a] == u32::MAX && triangle_facet[b] != u32::MAX {
                        triangle_facet[a] = triangle_facet[b];
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        if triangle_facet.contains(&u32::MAX) {
            return Err(degenerate("zero-area facet"));
        }
        for n in normals.iter_mut() {
            *n = n.normalize_or_zero();
        }
        if normals.contains(&Vec3::ZERO) {
            return Err(degenerate("zero-area facet"));
        }
        // Offsets: the support over all hull vertices, so every plane is a supporting plane
        // even when rounding in the hull left a tilted sliver facet (then the polytope is a
        // hair larger than the hull, never smaller).
        let offsets = supports(&vertices, &normals, &tris, &triangle_facet);
        let aabb = Aabb::from_points(&vertices);
        Ok(ConvexPolytope { vertices, normals, offsets, triangles: tris, triangle_facet, aabb })
    }

    /// Volume (exact for the hull).
    pub fn volume(&self) -> f64 {
        let c = self.vertices[0];
        self.triangles
            .iter()
            .map(|t| {
                let (a, b, d) = (self.vertices[t[0] as usize], self.vertices[t[1] as usize], self.vertices[t[2] as usize]);
                (a - c).dot((b - c).cross(d - c)) / 6.0
            })
            .sum()
    }
}

/// Per facet normal `n`, `max_v n · v` over all `vertices`: the same value as a scan over
/// every vertex, found by a branch and bound over a BVH of the vertices from the facet's
/// own vertices (a box's bound, `Σ_k max(n_k lo_k, n_k hi_k)` summed in the dot product's
/// order, is never below the rounded `n · v` of a point in it: rounding is monotone).
fn supports(vertices: &[Vec3], normals: &[Vec3], tris: &[[u32; 3]], triangle_facet: &[u32]) -> Vec<f64> {
    let mut best = vec![f64::NEG_INFINITY; normals.len()];
    for (t, &f) in tris.iter().zip(triangle_facet) {
        for &v in t {
            best[f as usize] = best[f as usize].max(normals[f as usize].dot(vertices[v as usize]));
        }
    }
    let boxes: Vec<Aabb> = vertices.iter().map(|&v| Aabb::new(v, v)).collect();
    let bvh = crate::bvh::Bvh::build(&boxes);
    for (n, b) in normals.iter().zip(best.iter_mut()) {
        let bound = |bx: &Aabb| (n.x * bx.min.x).max(n.x * bx.max.x) + (n.y * bx.min.y).max(n.y * bx.max.y) + (n.z * bx.min.z).max(n.z * bx.max.z);
        let top = std::cell::Cell::new(*b);
        bvh.for_each_where(|bx| bound(bx) > top.get(), |i| top.set(top.get().max(n.dot(vertices[i]))));
        *b = top.get();
    }
    best
}
