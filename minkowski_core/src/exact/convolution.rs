//! The reduced convolution of two closed meshes: the flat facets `T + v` (face of `A`,
//! vertex of `B`), `u + S` and `e ⊕ g` (edge pairs, parallelograms) whose features can be
//! extreme in a common direction. Every boundary point of `A ⊕ B` lies on one of them
//! (a boundary point is a contact of `A` and `p − B` with disjoint interiors, where both
//! are locally extreme in a common direction), so the facets are the only boundary
//! candidates the octree needs — a surface, where the triangle-pair pieces fill a shell.
//!
//! The compatibility tests are conservative (a tolerance admits borderline pairs), so the
//! facet set can only grow: extra facets cost time, never correctness.
//!
//! Features inside a planar region are left out: a flat edge (its two triangles coplanar,
//! up to the rounding of their normals) and a vertex whose triangles all face the contact
//! direction. A contact there is a contact of the planar region `P` (of one mesh) with a
//! feature or planar region `Q` of the other; the contact set `P ∩ (p − Q)` is a polygon
//! or segment whose corners are corners of `P`, corners of `Q` or crossings of their
//! border edges, so `p` also lies on a facet of border features. (Border features in a
//! boundary contact are never reflex, so their facets are in the set.)
//!
//! Face–face contacts are collapsed further: a facet whose two features lie in planar
//! regions `P` (of `A`) and `Q` (of `B`) of one normal, both convex polygons, is a subset
//! of `P ⊕ Q`, itself a convex polygon in `A ⊕ B`; such facets give way to that polygon,
//! once per region pair. Only containment is used, so no contact is lost, and the
//! polygon lies in the sum (facets grown by a margin serve as membership witnesses).
//! On CAD parts, whose flat faces are triangulated into several coplanar triangles, this
//! removes most facets: the two 60-triangle plates of the pegs-and-holes assembly (five
//! boxes each) have 3600 facets without it and 309 with it.
//!
//! Where a mesh holds several outward shells (overlapping or touching bodies exported as
//! one mesh; no cavities), each convex shell `K` is a part of the solid: a face, vertex or
//! edge of another shell inside `K` that `K` reaches beyond in the contact direction is
//! not locally extreme for the solid, so its facet is left out ([`Parts`]): the faces of
//! one bar inside another give none. (Every point in the relative interior of such a
//! facet is an interior point of `A ⊕ B`; the sum is a regular closed set, so its boundary
//! stays covered by the rest.) The pegs-and-holes plates then have 218 facets.

use super::gauss::{arc_distance, DirGrid};
use super::mesh::TriMesh;
use crate::math::{Aabb, Vec3};
use crate::polytope::clip_planes;
use crate::util::UnionFind;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Angular tolerance of the compatibility tests.
const TOL: f64 = 1e-9;

/// Normals this close (`|n1 × n2|`, same side) make a flat edge or a flat vertex: inside a
/// planar region, up to the rounding of the normals themselves. Facets of such features
/// are covered by the region's border facets, so they are left out (see [`convolution`]).
const FLAT: f64 = 1e-13;

/// A flat convex polygon (3 or 4 corners) of the convolution, grown by a cube of half-width
/// `margin` in the tests.
#[derive(Clone, Copy, Debug)]
pub struct Facet {
    /// Corners (the fourth unused for triangles).
    pub p: [Vec3; 4],
    /// Number of corners.
    pub n: u8,
    /// Obstacle the facet belongs to.
    pub k: u32,
}

/// The half-spaces `(d, w)` (`d · x <= w`) of a flat facet, and how many of the six are
/// used: what [`Facet::contains_point`] and [`Facet::clip`] test without a margin.
pub type FlatPlanes = ([(Vec3, f64); 6], usize);

/// Test directions of a facet: its normal, its in-plane edge normals, the axes and edge ×
/// axis — every facet normal of the facet grown by a cube and of facet − box.
struct Dirs {
    d: [Vec3; 20],
    n: usize,
    /// Rounding slack added to every support value: a flat facet's slabs have zero width,
    /// and nearly parallel directions (the normal and an edge × axis) would otherwise cut
    /// a crossing segment down to nothing.
    slack: f64,
}

impl Facet {
    /// Rounding slack of the facet's tests: `1e-12` of its largest coordinate (a flat
    /// facet has zero thickness, so every test is thickened by it).
    #[inline]
    fn slack(&self) -> f64 {
        1e-12 * self.p[..self.n as usize].iter().fold(1e-300f64, |acc, q| acc.max(q.abs().max_element()))
    }

    /// Box of the facet grown by `m`.
    pub fn aabb(&self, m: f64) -> Aabb {
        Aabb::from_points(&self.p[..self.n as usize]).inflated(m)
    }

    #[inline]
    fn support(&self, d: Vec3, m: f64) -> f64 {
        let mut s = self.p[0].dot(d);
        for q in &self.p[1..self.n as usize] {
            s = s.max(q.dot(d));
        }
        s + m * (d.x.abs() + d.y.abs() + d.z.abs())
    }

    /// The test directions (unit; ones negligible against the edge lengths are left out,
    /// as rounding noise).
    fn dirs(&self) -> Dirs {
        let k = self.n as usize;
        let mut out = Dirs { d: [Vec3::ZERO; 20], n: 0, slack: self.slack() };
        let mut push = |d: Vec3, scale2: f64| {
            if d.length_squared() > 1e-24 * scale2 && d.length_squared() > 0.0 {
                out.d[out.n] = d.normalize();
                out.n += 1;
            }
        };
        let mut e = [Vec3::ZERO; 4];
        for (i, ei) in e[..k].iter_mut().enumerate() {
            *ei = self.p[(i + 1) % k] - self.p[i];
        }
        let l2 = [e[0].length_squared(), e[1].length_squared(), e[2].length_squared()];
        let normal = e[0].cross(e[1]);
        let nl2 = l2[0] * l2[1];
        push(normal, nl2);
        let distinct = if k == 4 { 2 } else { 3 }; // a parallelogram has two edge directions
        if normal.length_squared() > 1e-24 * nl2 {
            for i in 0..distinct {
                push(normal.cross(e[i]), normal.length_squared() * l2[i]);
            }
        }
        for a in [Vec3::X, Vec3::Y, Vec3::Z] {
            push(a, 1.0);
            for i in 0..distinct {
                push(e[i].cross(a), 1e6 * l2[i]);
            }
        }
        out
    }

    /// Whether the facet grown by `m` meets the closed box `b`: separating axes of the
    /// flat polygon and the box grown by `m` (and a rounding slack) — the box's axes, the
    /// polygon's normal and its edges × the axes, unnormalised (the tests are homogeneous).
    pub fn overlaps_box(&self, b: &Aabb, m: f64) -> bool {
        let k = self.n as usize;
        let c = b.center();
        let mut q = [Vec3::ZERO; 4];
        for (qi, &p) in q[..k].iter_mut().zip(&self.p[..k]) {
            *qi = p - c;
        }
        let q = &q[..k];
        let h = b.half() + Vec3::splat(m + self.slack());
        for a in 0..3 {
            let (lo, hi) = q.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x[a]), hi.max(x[a])));
            if lo > h[a] || hi < -h[a] {
                return false;
            }
        }
        let separates = |d: Vec3| {
            let (lo, hi) = q.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x.dot(d)), hi.max(x.dot(d))));
            let r = h.dot(d.abs());
            lo > r || hi < -r
        };
        let (e0, e1) = (q[1] - q[0], q[2] - q[1]);
        if separates(e0.cross(e1)) {
            return false;
        }
        let edges = if k == 4 { [e0, e1, Vec3::ZERO] } else { [e0, e1, q[0] - q[2]] };
        for e in edges {
            for d in [Vec3::new(0.0, e.z, -e.y), Vec3::new(-e.z, 0.0, e.x), Vec3::new(e.y, -e.x, 0.0)] {
                if separates(d) {
                    return false;
                }
            }
        }
        true
    }

    /// The half-spaces of the flat facet (no margin) thickened by the rounding slack: its
    /// plane from both sides and its edges; `None` for a degenerate facet.
    #[inline]
    pub(crate) fn flat_planes(&self) -> Option<FlatPlanes> {
        let k = self.n as usize;
        let (e0, e1) = (self.p[1] - self.p[0], self.p[2] - self.p[1]);
        let n = e0.cross(e1);
        let nl = n.length();
        #[allow(clippy::neg_cmp_op_on_partial_ord)] // a NaN length must fail (degenerate facet)
        if !(nl > 1e-12 * e0.length() * e1.length()) {
            return None;
        }
        let nu = n / nl;
        let slack = self.slack();
        let w = nu.dot(self.p[0]);
        let mut out = [(Vec3::ZERO, 0.0); 6];
        out[0] = (nu, w + slack);
        out[1] = (-nu, -w + slack);
        for i in 0..k {
            let e = self.p[(i + 1) % k] - self.p[i];
            let o = e.cross(nu); // outward in the plane: the corners run counter-clockwise about n
            let l = o.length();
            if l == 0.0 {
                continue; // a zero-length edge bounds nothing
            }
            let o = o / l;
            out[2 + i] = (o, o.dot(self.p[i]) + slack);
        }
        Some((out, 2 + k))
    }

    /// `max_d (d · p − h(d))` over the facet's directions: a lower bound on the distance
    /// from `p` to the facet grown by `m` when positive.
    pub fn separation(&self, p: Vec3, m: f64) -> f64 {
        let dirs = self.dirs();
        let mut s = f64::NEG_INFINITY;
        for &d in &dirs.d[..dirs.n] {
            let x = p.dot(d);
            s = s.max(x - self.support(d, m)).max(-x - self.support(-d, m));
        }
        s
    }

    /// Whether `p` lies in the facet grown by `m`.
    pub fn contains_point(&self, p: Vec3, m: f64) -> bool {
        if m == 0.0 {
            if let Some((pl, n)) = self.flat_planes() {
                return pl[..n].iter().all(|&(d, w)| d.dot(p) <= w);
            }
        }
        let dirs = self.dirs();
        let m = m + dirs.slack;
        dirs.d[..dirs.n].iter().all(|&d| {
            let x = p.dot(d);
            x <= self.support(d, m) && -x <= self.support(-d, m)
        })
    }

    /// The parameter interval of `a → b` in the facet grown by `m`.
    pub fn clip(&self, a: Vec3, b: Vec3, m: f64) -> Option<(f64, f64)> {
        if m == 0.0 {
            if let Some((pl, n)) = self.flat_planes() {
                return clip_planes(pl[..n].iter().copied(), a, b);
            }
        }
        let dirs = self.dirs();
        let m = m + dirs.slack;
        // every direction and its opposite, as half-spaces `x · d <= support(d)`
        let planes = dirs.d[..dirs.n].iter().flat_map(|&d0| [d0, -d0]).map(|d| (d, self.support(d, m)));
        clip_planes(planes, a, b)
    }
}

/// Local structure of a mesh: vertex rings and edges with their Gauss-map arcs.
struct Topo {
    /// Distinct vertex positions (welded by index).
    verts: Vec<Vec3>,
    /// Neighbours of each vertex.
    ring: Vec<Vec<u32>>,
    /// Per triangle: vertex indices.
    faces: Vec<[u32; 3]>,
    /// Edges that can be locally extreme and are not flat: (a, b, n1, n2) and the
    /// triangles (f1, f2) with those normals.
    edges: Vec<(u32, u32, Vec3, Vec3, u32, u32)>,
    /// Normals of the triangles around each vertex.
    fan: Vec<Vec<Vec3>>,
    /// The triangles around each vertex (parallel to `fan`).
    fan_faces: Vec<Vec<u32>>,
    /// Planar region of each triangle.
    region: Vec<u32>,
    /// Border corners of each planar region that is a convex polygon (`None` otherwise).
    convex: Vec<Option<Vec<Vec3>>>,
    /// Unit normal of each planar region (its first triangle's).
    normal: Vec<Vec3>,
    /// Convex parts of the solid (see [`Parts`]).
    parts: Parts,
    /// Triangles whose normal direction a convex part extends beyond: no face contact.
    shadowed: Vec<bool>,
}

impl Topo {
    /// The convex planar region of triangle `f`, if its region is one.
    #[inline]
    fn convex_region(&self, f: u32) -> Option<u32> {
        let r = self.region[f as usize];
        self.convex[r as usize].is_some().then_some(r)
    }

    /// A convex planar region with unit normal `d` among the (unshadowed) triangles at
    /// vertex `v`.
    #[inline]
    fn convex_region_at(&self, v: u32, d: Vec3) -> Option<u32> {
        let (fan, faces) = (&self.fan[v as usize], &self.fan_faces[v as usize]);
        fan.iter().zip(faces).filter(|(&n, &f)| same_normal(n, d) && !self.shadowed[f as usize]).find_map(|(_, &f)| self.convex_region(f))
    }

    /// Whether vertex `v` can make a contact in direction `d`: locally extreme, and no
    /// convex part of the solid reaching beyond it.
    #[inline]
    fn contact(&self, v: u32, d: Vec3) -> bool {
        extreme(self, v, d) && !self.parts.shadowed(&[v], &self.verts, d)
    }
}

#[inline]
fn same_normal(n1: Vec3, n2: Vec3) -> bool {
    n1 != Vec3::ZERO && n1.dot(n2) > 0.0 && n1.cross(n2).length() <= FLAT
}

fn topo(m: &TriMesh) -> Topo {
    // weld corners by exact position (the mesh was built from an indexed face list)
    let mut id: HashMap<[u64; 3], u32> = HashMap::new();
    let mut verts = Vec::new();
    let mut faces = Vec::with_capacity(m.tris.len());
    for t in &m.tris {
        let mut f = [0u32; 3];
        for (c, p) in t.p.iter().enumerate() {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            f[c] = *id.entry(key).or_insert_with(|| {
                verts.push(*p);
                (verts.len() - 1) as u32
            });
        }
        faces.push(f);
    }
    let mut ring: Vec<Vec<u32>> = vec![Vec::new(); verts.len()];
    let mut fan: Vec<Vec<Vec3>> = vec![Vec::new(); verts.len()];
    let mut fan_faces: Vec<Vec<u32>> = vec![Vec::new(); verts.len()];
    for (fi, f) in faces.iter().enumerate() {
        for &v in f {
            fan[v as usize].push(m.tris[fi].n);
            fan_faces[v as usize].push(fi as u32);
        }
    }
    let mut half: HashMap<(u32, u32), usize> = HashMap::new();
    for (fi, f) in faces.iter().enumerate() {
        for c in 0..3 {
            let (a, b) = (f[c], f[(c + 1) % 3]);
            if !ring[a as usize].contains(&b) {
                ring[a as usize].push(b);
            }
            if !ring[b as usize].contains(&a) {
                ring[b as usize].push(a);
            }
            half.insert((a, b), fi);
        }
    }
    let mut edges = Vec::new();
    let mut regions = UnionFind::new(faces.len());
    for (&(a, b), &f1) in &half {
        if a > b {
            continue;
        }
        let Some(&f2) = half.get(&(b, a)) else { continue };
        let (n1, n2) = (m.tris[f1].n, m.tris[f2].n);
        if n1 == Vec3::ZERO || n2 == Vec3::ZERO {
            // degenerate neighbour: keep, unknown arc
            edges.push((a, b, Vec3::ZERO, Vec3::ZERO, f1 as u32, f2 as u32));
            continue;
        }
        if same_normal(n1, n2) {
            regions.union(f1, f2); // one planar region
        }
        // reflex when the far corner of f2 lies above f1's plane
        let far = faces[f2].iter().copied().find(|&v| v != a && v != b).unwrap_or(a);
        let len = (verts[b as usize] - verts[a as usize]).length().max((verts[far as usize] - verts[a as usize]).length());
        if n1.dot(verts[far as usize] - verts[a as usize]) > TOL * len {
            continue; // reflex: never locally extreme
        }
        if same_normal(n1, n2) {
            continue; // flat: inside a planar region
        }
        edges.push((a, b, n1, n2, f1 as u32, f2 as u32));
    }
    edges.sort_unstable_by_key(|e| (e.0, e.1));
    // planar regions, numbered in the order of their first triangle (deterministic)
    let mut id_of_root = vec![u32::MAX; faces.len()];
    let mut region = Vec::with_capacity(faces.len());
    let mut members: Vec<Vec<u32>> = Vec::new();
    for f in 0..faces.len() as u32 {
        let r = regions.find(f as usize);
        if id_of_root[r] == u32::MAX {
            id_of_root[r] = members.len() as u32;
            members.push(Vec::new());
        }
        members[id_of_root[r] as usize].push(f);
        region.push(id_of_root[r]);
    }
    let convex = members.iter().map(|ms| convex_border(&verts, &faces, m, ms)).collect();
    let normal = members.iter().map(|ms| m.tris[ms[0] as usize].n).collect();
    let parts = Parts::new(&verts, &faces, m);
    let shadowed = faces.iter().enumerate().map(|(i, f)| m.tris[i].n != Vec3::ZERO && parts.shadowed(f, &verts, m.tris[i].n)).collect();
    Topo { verts, ring, faces, edges, fan, fan_faces, region, convex, normal, parts, shadowed }
}

/// Shells of at most this many triangles are tried as convex parts of the solid.
const MAX_PART: usize = 512;

/// The convex shells of a mesh (overlapping or touching bodies exported as one mesh),
/// which show where the solid extends beyond a feature: a feature inside a convex part
/// `K ⊂ A` that `K` extends beyond in direction `d` (`h_K(d) > d · x` at its points) is
/// not locally extreme in `d` for the solid (the segment to `K`'s farther point stays in
/// `K`), so it makes no contact in that direction.
struct Parts {
    /// Distinct corners of each convex part.
    corners: Vec<Vec<Vec3>>,
    /// The parts holding each (welded) vertex.
    at: Vec<Vec<u32>>,
    /// Rounding margin for "extends beyond".
    inner: f64,
}

impl Parts {
    fn new(verts: &[Vec3], faces: &[[u32; 3]], m: &TriMesh) -> Parts {
        let scale = verts.iter().fold(0.0f64, |acc, v| acc.max(v.abs().max_element())).max(1e-300);
        let mut parts = Parts { corners: Vec::new(), at: vec![Vec::new(); verts.len()], inner: 1e-12 * scale };
        // shells: triangles joined across edges that are used once in each direction (not
        // across a corner or an edge where more shells meet: those are distinct bodies)
        let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
        for f in faces {
            for c in 0..3 {
                *uses.entry((f[c], f[(c + 1) % 3])).or_insert(0) += 1;
            }
        }
        let manifold = |a: u32, b: u32| uses.get(&(a, b)) == Some(&1) && uses.get(&(b, a)) == Some(&1);
        let mut half: HashMap<(u32, u32), usize> = HashMap::new();
        for (i, f) in faces.iter().enumerate() {
            for c in 0..3 {
                half.insert((f[c], f[(c + 1) % 3]), i);
            }
        }
        let mut joined = UnionFind::new(faces.len());
        for (&(a, b), &i) in &half {
            if let Some(&j) = half.get(&(b, a)) {
                if manifold(a, b) {
                    joined.union(i, j);
                }
            }
        }
        let mut shell_of_root: HashMap<usize, usize> = HashMap::new();
        let mut shells: Vec<Vec<usize>> = Vec::new();
        let mut shell_of = vec![0usize; faces.len()];
        for (i, slot) in shell_of.iter_mut().enumerate() {
            let r = joined.find(i);
            let k = *shell_of_root.entry(r).or_insert_with(|| {
                shells.push(Vec::new());
                shells.len() - 1
            });
            shells[k].push(i);
            *slot = k;
        }
        if shells.len() < 2 {
            return parts; // one shell: it is the solid, whose features the tests already see
        }
        // a part must lie in the solid: with every shell outward (positive volume) and
        // not passing through itself, each adds 0 or 1 to the winding number, so the solid
        // is their union; an inward shell (a cavity) or one that crosses itself can cut a
        // hole into a part, and then no part is used at all
        let volume = |tris: &Vec<usize>| tris.iter().map(|&t| m.tris[t].p[0].dot(m.tris[t].p[1].cross(m.tris[t].p[2]))).sum::<f64>();
        let self_crossing = m.crossing.iter().any(|&[s, t]| shell_of[s as usize] == shell_of[t as usize]);
        if self_crossing || shells.iter().any(|t| volume(t) <= 0.0) {
            return parts;
        }
        // vertices by x, so each part scans only those within its box's x range
        let mut by_x: Vec<u32> = (0..verts.len() as u32).collect();
        by_x.sort_unstable_by(|&a, &b| verts[a as usize].x.total_cmp(&verts[b as usize].x));
        for tris in shells.iter().filter(|t| (4..=MAX_PART).contains(&t.len())) {
            let mut planes: Vec<(Vec3, f64)> = Vec::new();
            for &t in tris {
                let tri = &m.tris[t];
                let w = tri.n.dot(tri.p[0]);
                if tri.n != Vec3::ZERO && !planes.iter().any(|&(q, v)| same_normal(q, tri.n) && (v - w).abs() <= 1e-12 * scale) {
                    planes.push((tri.n, w));
                }
            }
            let mut own: Vec<u32> = tris.iter().flat_map(|&t| faces[t]).collect();
            own.sort_unstable();
            own.dedup();
            let corners: Vec<Vec3> = own.iter().map(|&v| verts[v as usize]).collect();
            let convex = planes.len() >= 4 && planes.iter().all(|&(q, w)| corners.iter().all(|c| q.dot(*c) <= w + 1e-9 * scale));
            if !convex {
                continue;
            }
            let id = parts.corners.len() as u32;
            let bx = Aabb::from_points(&corners);
            let lo = by_x.partition_point(|&v| verts[v as usize].x < bx.min.x);
            let hi = by_x.partition_point(|&v| verts[v as usize].x <= bx.max.x);
            for &v in &by_x[lo..hi] {
                let p = verts[v as usize];
                // in the closed part (exactly, in floating point: no tolerance outward); not
                // the part's own corners, whose features the tolerant tests admitted on
                // purpose (a convex shell reaches beyond its own features only by those
                // tolerances)
                if own.binary_search(&v).is_err() && bx.contains_point(p) && planes.iter().all(|&(q, w)| q.dot(p) <= w) {
                    parts.at[v as usize].push(id);
                }
            }
            parts.corners.push(corners);
        }
        parts
    }

    /// Whether a part holding all of `vs` extends beyond them in direction `d` (they all
    /// lie at one height along `d`: a face and its normal, or a single vertex).
    fn shadowed(&self, vs: &[u32], verts: &[Vec3], d: Vec3) -> bool {
        let Some((&first, rest)) = vs.split_first() else { return false };
        let h = d.dot(verts[first as usize]) + self.inner;
        self.at[first as usize].iter().filter(|k| rest.iter().all(|&v| self.at[v as usize].contains(k))).any(|&k| self.corners[k as usize].iter().any(|c| d.dot(*c) > h))
    }
}

/// An orthonormal basis `(u, w)` of the plane normal to the unit `n`.
fn plane_basis(n: Vec3) -> (Vec3, Vec3) {
    let a = if n.x.abs() < 0.6 { Vec3::X } else { Vec3::Y };
    let u = n.cross(a).normalize();
    (u, n.cross(u))
}

/// The border corners (counter-clockwise about the normal) of a planar region, when the
/// region is a convex polygon: its triangles (welded corners `faces`, all of one normal)
/// use each directed edge once, the edges used in one direction only form one closed
/// loop, the loop turns left at every corner (or runs straight on) once around, and the
/// triangles' areas add up to the loop's. Then the triangles tile the polygon (their
/// winding number about any point inside is the loop's, 1), so the polygon is exactly
/// the region. `None` otherwise.
fn convex_border(verts: &[Vec3], faces: &[[u32; 3]], m: &TriMesh, members: &[u32]) -> Option<Vec<Vec3>> {
    let n = m.tris[members[0] as usize].n;
    if n == Vec3::ZERO {
        return None;
    }
    let mut directed: HashSet<(u32, u32)> = HashSet::with_capacity(3 * members.len());
    let mut area = 0.0;
    for &f in members {
        let t = &m.tris[f as usize];
        area += 0.5 * t.e[0].cross(t.e[1]).length();
        let c = faces[f as usize];
        for i in 0..3 {
            let e = (c[i], c[(i + 1) % 3]);
            if e.0 == e.1 || !directed.insert(e) {
                return None;
            }
        }
    }
    let mut next: HashMap<u32, u32> = HashMap::new();
    for &(a, b) in &directed {
        if !directed.contains(&(b, a)) && next.insert(a, b).is_some() {
            return None; // two border edges leave one corner
        }
    }
    let start = *next.keys().min()?;
    let mut ring = vec![start];
    let mut v = start;
    loop {
        v = *next.get(&v)?;
        if v == start {
            break;
        }
        if ring.len() >= next.len() {
            return None;
        }
        ring.push(v);
    }
    if ring.len() != next.len() || ring.len() < 3 {
        return None; // several loops (holes, or pieces)
    }
    let (u, w) = plane_basis(n);
    let q: Vec<(f64, f64)> = ring.iter().map(|&i| (verts[i as usize].dot(u), verts[i as usize].dot(w))).collect();
    let k = q.len();
    let mut turning = 0.0;
    let mut twice_area = 0.0;
    for i in 0..k {
        let (p0, p1, p2) = (q[i], q[(i + 1) % k], q[(i + 2) % k]);
        let (e1, e2) = ((p1.0 - p0.0, p1.1 - p0.1), (p2.0 - p1.0, p2.1 - p1.1));
        let cross = e1.0 * e2.1 - e1.1 * e2.0;
        let dot = e1.0 * e2.0 + e1.1 * e2.1;
        let l = (e1.0.hypot(e1.1)) * (e2.0.hypot(e2.1));
        if l.is_nan() || l <= 0.0 || cross < -1e-12 * l {
            return None; // a repeated corner, or a right turn: not convex
        }
        turning += cross.atan2(dot);
        twice_area += p0.0 * p1.1 - p1.0 * p0.1;
    }
    let tau = 2.0 * std::f64::consts::PI;
    if (turning - tau).abs() > 1e-6 || (0.5 * twice_area - area).abs() > 1e-9 * area {
        return None;
    }
    Some(ring.iter().map(|&i| verts[i as usize]).collect())
}

/// The facets of `P ⊕ Q` for two convex planar polygons of one normal `n` (corners of
/// each given): the convex hull of the corner sums, in the plane, as a fan of triangles.
fn polygon_sum(p: &[Vec3], q: &[Vec3], n: Vec3, k: u32, out: &mut Vec<Facet>) {
    let (u, w) = plane_basis(n);
    // `+ 0.0` turns -0 into +0: the sort must be numeric for the chain to be a hull
    let mut pts: Vec<(f64, f64, Vec3)> = p.iter().flat_map(|&a| q.iter().map(move |&b| a + b)).map(|x| (x.dot(u) + 0.0, x.dot(w) + 0.0, x)).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup_by(|a, b| a.0 == b.0 && a.1 == b.1);
    if pts.len() < 3 {
        return;
    }
    // Andrew's monotone chain, collinear points dropped
    let turn = |o: &(f64, f64, Vec3), a: &(f64, f64, Vec3), b: &(f64, f64, Vec3)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let mut hull: Vec<(f64, f64, Vec3)> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let base = hull.len();
        for j in 0..pts.len() {
            let x = pts[if pass == 0 { j } else { pts.len() - 1 - j }];
            while hull.len() >= base + 2 && turn(&hull[hull.len() - 2], &hull[hull.len() - 1], &x) <= 0.0 {
                hull.pop();
            }
            hull.push(x);
        }
        hull.pop(); // the chain's last point starts the other chain
    }
    for i in 1..hull.len().saturating_sub(1) {
        out.push(Facet { p: [hull[0].2, hull[i].2, hull[i + 1].2, Vec3::ZERO], n: 3, k });
    }
}

/// Whether vertex `v` of `t` can be locally extreme in direction `d` (unit), and is not
/// inside a planar region facing `d`. (A vertex whose ring edges all lie across `d`, with
/// every triangle facing away from `d`, sits in a flat patch with the solid on the `d`
/// side: never extreme in `d`, though its edges alone cannot tell.)
#[inline]
fn extreme(t: &Topo, v: u32, d: Vec3) -> bool {
    let fan = &t.fan[v as usize];
    if fan.iter().all(|&n| same_normal(n, d)) {
        return false;
    }
    let p = t.verts[v as usize];
    let mut across = true;
    let below = t.ring[v as usize].iter().all(|&w| {
        let e = t.verts[w as usize] - p;
        let (x, tol) = (d.dot(e), TOL * e.length());
        across &= x.abs() <= tol;
        x <= tol
    });
    below && !(across && fan.iter().all(|&n| n.dot(d) < 0.0))
}

/// Whether the Gauss arc `[n1, n2]` of an edge is unknown: a degenerate neighbour, or a
/// knife edge (normals nearly opposite, so the half circle between them has no reliable
/// pole). Such an edge can meet any arc.
#[inline]
fn unknown_arc(n1: Vec3, n2: Vec3) -> bool {
    n1 == Vec3::ZERO || n2 == Vec3::ZERO || (n1.dot(n2) < 0.0 && n1.cross(n2).length() <= TOL)
}

/// Where two Gauss arcs meet.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Meet {
    No,
    /// In this one direction (unit).
    At(Vec3),
    /// Somewhere (an unknown arc, a point arc, or overlapping arcs of one circle).
    Somewhere,
}

/// Whether (and where) the Gauss arcs `[n1, n2]` and `[m1, m2]` can share a direction.
fn arcs_meet(n1: Vec3, n2: Vec3, m1: Vec3, m2: Vec3) -> Meet {
    let yes = |b: bool| if b { Meet::Somewhere } else { Meet::No };
    if unknown_arc(n1, n2) || unknown_arc(m1, m2) {
        return Meet::Somewhere;
    }
    let on_arc = |x: Vec3, a: Vec3, b: Vec3| -> bool {
        let p = a.cross(b);
        if p.length() <= TOL {
            return (x - a).length() <= 1e-6; // a point arc (not a knife: see above)
        }
        // on the circle, between the ends (loosely for short arcs), and on the arc's side
        // of the sphere (the end tests alone also pass the points opposite a short arc)
        x.dot(p).abs() <= 1e-6 * p.length() && a.cross(x).dot(p) >= -TOL && x.cross(b).dot(p) >= -TOL && x.dot(a + b) >= -TOL
    };
    let (pa, pb) = (n1.cross(n2), m1.cross(m2));
    if pa.length() <= TOL {
        return yes(on_arc(n1, m1, m2));
    }
    if pb.length() <= TOL {
        return yes(on_arc(m1, n1, n2));
    }
    let c = pa.cross(pb);
    if c.length() <= 1e-9 * pa.length() * pb.length() {
        // the same great circle: the arcs meet when they overlap, so an end of one lies
        // on the other
        return yes(on_arc(m1, n1, n2) || on_arc(m2, n1, n2) || on_arc(n1, m1, m2) || on_arc(n2, m1, m2));
    }
    let c = c.normalize();
    let hits: Vec<Vec3> = [c, -c].into_iter().filter(|&x| on_arc(x, n1, n2) && on_arc(x, m1, m2)).collect();
    match hits[..] {
        [] => Meet::No,
        [x] => Meet::At(x),
        _ => Meet::Somewhere,
    }
}

/// The vertices of `t` bucketed by the directions they can be extreme in: a cell lists
/// a vertex unless some ring edge `e` is too close to the cell for any direction `d` of
/// it to pass [`extreme`]'s `d · ê <= TOL` (a necessary condition, edge by edge).
fn vertex_grid(t: &Topo) -> DirGrid {
    let lim_angle = TOL.acos();
    DirGrid::build(t.verts.len(), |g, v| {
        let p = t.verts[v as usize];
        let e: Vec<Vec3> = t.ring[v as usize].iter().map(|&w| t.verts[w as usize] - p).filter(|e| e.length() > 0.0).map(Vec3::normalize).collect();
        if e.is_empty() {
            return None;
        }
        Some(g.cells(|cap| {
            let lim = (lim_angle - cap.rho).max(0.0).cos();
            e.iter().all(|&e| cap.c.dot(e) <= lim)
        }))
    })
}

/// How far beyond its Gauss arc [`arcs_meet`] can find a meeting point of an edge: its
/// circle tolerance, and its end tolerance (`TOL` against an unnormalised pole).
fn arc_slack(n1: Vec3, n2: Vec3) -> f64 {
    let pl = n1.cross(n2).length();
    1e-5 + if pl > TOL { 2.0 * TOL / pl } else { 0.0 }
}

/// The non-flat edges of `t` bucketed by their Gauss arcs (grown by [`arc_slack`]).
fn edge_grid(t: &Topo) -> DirGrid {
    DirGrid::build(t.edges.len(), |g, i| {
        let (_, _, n1, n2, _, _) = t.edges[i as usize];
        if unknown_arc(n1, n2) {
            return None;
        }
        let slack = arc_slack(n1, n2);
        Some(g.cells(|cap| arc_distance(cap.c, n1, n2) <= cap.rho + slack))
    })
}

/// A facet of the reduced convolution, or the pair of convex planar regions (of `a`, of
/// `b`, one normal) whose sum contains it.
enum Part {
    Facet(Facet),
    Regions(u32, u32),
}

/// The reduced convolution facets of `a` (obstacle `k`) and `b`.
///
/// A facet whose features lie in convex planar regions `P` of `a` and `Q` of `b` of one
/// normal (a face–face contact) is contained in `P ⊕ Q`, a convex polygon in `A ⊕ B`: such
/// facets are replaced by the polygon (a fan of triangles), once per region pair. On
/// parts made of boxes this replaces every facet: a box pair then has its six faces.
pub fn convolution(a: &TriMesh, b: &TriMesh, k: u32) -> Vec<Facet> {
    convolution_by(a, b, k, true, usize::MAX, None).expect("no facet budget")
}

/// [`convolution`], giving up once more than `budget` facets were found (they are
/// estimated to need more memory than allowed): `Err(facets found so far)`. With `near`,
/// only the facets whose boxes meet that box are kept (and counted).
pub fn convolution_within(a: &TriMesh, b: &TriMesh, k: u32, budget: usize, near: Option<&Aabb>) -> Result<Vec<Facet>, usize> {
    convolution_by(a, b, k, true, budget, near)
}

/// [`convolution_within`] with the candidates looked up on direction grids (`grid`), or
/// every feature against every other (a reference for the tests).
fn convolution_by(a: &TriMesh, b: &TriMesh, k: u32, grid: bool, budget: usize, near: Option<&Aabb>) -> Result<Vec<Facet>, usize> {
    let kept = |f: &Facet| near.is_none_or(|r| f.aabb(0.0).overlaps(r));
    let wanted = |part: &Part| match part {
        Part::Facet(f) => kept(f),
        Part::Regions(..) => true, // their polygons are filtered once made
    };
    // whether a facet spanning `bx` moved by the box `[lo, hi]` can meet `near` (asked
    // before the costlier contact tests)
    let reach = |bx: &Aabb, lo: Vec3, hi: Vec3| near.is_none_or(|r| Aabb::new(bx.min + lo, bx.max + hi).overlaps(r));
    let found = AtomicUsize::new(0);
    let room = || found.load(Ordering::Relaxed) <= budget && !crate::deadline::cancelled(); // (a cancelled call drops what it finds)
    let bump = |_: &Part| {
        found.fetch_add(1, Ordering::Relaxed);
    };
    let (ta, tb) = (topo(a), topo(b));
    let (va, vb, eb) = (vertex_grid(&ta), vertex_grid(&tb), edge_grid(&tb));
    let tri = |t: &TriMesh, i: usize| t.tris[i];
    let candidates = |g: &DirGrid, n: Vec3, all: usize| match (n == Vec3::ZERO, grid) {
        (true, _) => Vec::new(),
        (false, true) => g.at(n),
        (false, false) => (0..all as u32).collect(),
    };
    let mut parts: Vec<Part> = (0..ta.faces.len())
        .into_par_iter()
        .take_any_while(|_| room())
        .flat_map_iter(|i| {
            let t = tri(a, i);
            let tb = &tb;
            let ra = ta.convex_region(i as u32);
            let n = if ta.shadowed[i] { Vec3::ZERO } else { t.n }; // no face contact
            let tbox = Aabb::from_points(&t.p);
            let near_v = move |v: u32| reach(&tbox, tb.verts[v as usize], tb.verts[v as usize]);
            candidates(&vb, n, tb.verts.len()).into_iter().filter(move |&v| near_v(v) && tb.contact(v, t.n)).map(move |v| match ra.zip(tb.convex_region_at(v, t.n)) {
                Some((ra, rb)) => Part::Regions(ra, rb),
                None => {
                    let q = tb.verts[v as usize];
                    Part::Facet(Facet { p: [t.p[0] + q, t.p[1] + q, t.p[2] + q, Vec3::ZERO], n: 3, k })
                }
            })
        })
        .filter(wanted)
        .inspect(bump)
        .collect();
    parts.par_extend(
        (0..tb.faces.len())
            .into_par_iter()
            .take_any_while(|_| room())
            .flat_map_iter(|j| {
                let s = tri(b, j);
                let ta = &ta;
                let rb = tb.convex_region(j as u32);
                let n = if tb.shadowed[j] { Vec3::ZERO } else { s.n };
                let sbox = Aabb::from_points(&s.p);
                let near_u = move |u: u32| reach(&sbox, ta.verts[u as usize], ta.verts[u as usize]);
                candidates(&va, n, ta.verts.len()).into_iter().filter(move |&u| near_u(u) && ta.contact(u, s.n)).map(move |u| match ta.convex_region_at(u, s.n).zip(rb) {
                    Some((ra, rb)) => Part::Regions(ra, rb),
                    None => {
                        let q = ta.verts[u as usize];
                        Part::Facet(Facet { p: [s.p[0] + q, s.p[1] + q, s.p[2] + q, Vec3::ZERO], n: 3, k })
                    }
                })
            })
            .filter(wanted)
            .inspect(bump),
    );
    parts.par_extend(
        ta.edges
            .par_iter()
            .take_any_while(|_| room())
            .flat_map_iter(|&(a0, a1, n1, n2, f1, f2)| {
                let (tb, ta) = (&tb, &ta);
                let (p0, p1) = (ta.verts[a0 as usize], ta.verts[a1 as usize]);
                let e = p1 - p0;
                let near: Vec<u32> = if !grid || unknown_arc(n1, n2) {
                    (0..tb.edges.len() as u32).collect()
                } else {
                    let slack = arc_slack(n1, n2);
                    eb.gather(&eb.cells(|cap| arc_distance(cap.c, n1, n2) <= cap.rho + slack))
                };
                let ebox = Aabb::from_points(&[p0, p1]);
                near.into_iter().filter_map(move |j| {
                    let (b0, b1, m1, m2, g1, g2) = tb.edges[j as usize];
                    let (q0, q1) = (tb.verts[b0 as usize], tb.verts[b1 as usize]);
                    if !reach(&ebox, q0.min(q1), q0.max(q1)) {
                        return None;
                    }
                    let g = q1 - q0;
                    if e.cross(g).length() <= 1e-9 * e.length() * g.length() {
                        return None; // parallel edges sum to a segment on other facets' borders
                    }
                    // both edges on the border of convex regions of one normal: in their sum
                    for (n, f) in [(n1, f1), (n2, f2)] {
                        for (m, g) in [(m1, g1), (m2, g2)] {
                            if same_normal(n, m) && !ta.shadowed[f as usize] && !tb.shadowed[g as usize] {
                                if let Some(r) = ta.convex_region(f).zip(tb.convex_region(g)) {
                                    return Some(Part::Regions(r.0, r.1));
                                }
                            }
                        }
                    }
                    let facet = Part::Facet(Facet { p: [p0 + q0, p1 + q0, p1 + q1, p0 + q1], n: 4, k });
                    match arcs_meet(n1, n2, m1, m2) {
                        Meet::No => None,
                        // one contact direction: none when a convex part reaches beyond either edge
                        Meet::At(x) if ta.parts.shadowed(&[a0, a1], &ta.verts, x) || tb.parts.shadowed(&[b0, b1], &tb.verts, x) => None,
                        _ => Some(facet),
                    }
                })
            })
            .filter(wanted)
            .inspect(bump),
    );
    if found.load(Ordering::Relaxed) > budget {
        return Err(found.load(Ordering::Relaxed));
    }
    let mut out = Vec::with_capacity(parts.len());
    let mut pairs = Vec::new();
    for part in parts {
        match part {
            Part::Facet(f) => out.push(f),
            Part::Regions(ra, rb) => pairs.push((ra, rb)),
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    for (ra, rb) in pairs {
        if let (Some(p), Some(q)) = (&ta.convex[ra as usize], &tb.convex[rb as usize]) {
            let from = out.len();
            polygon_sum(p, q, ta.normal[ra as usize], k, &mut out);
            if near.is_some() {
                let mut fan = out.split_off(from);
                fan.retain(kept);
                out.extend(fan);
            }
        }
        if out.len() > budget {
            return Err(out.len());
        }
    }
    Ok(out)
}

/// The reduced convolution found by testing every feature pair (no direction grids).
#[cfg(test)]
pub(crate) fn convolution_scan(a: &TriMesh, b: &TriMesh) -> Vec<Facet> {
    convolution_by(a, b, 0, false, usize::MAX, None).expect("no facet budget")
}

/// Per planar region of `m`: its number of border corners when it is a convex polygon.
#[cfg(test)]
pub(crate) fn planar_regions(m: &TriMesh) -> Vec<Option<usize>> {
    topo(m).convex.iter().map(|c| c.as_ref().map(Vec::len)).collect()
}
