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
//! boundary contact are never reflex, so their facets are in the set.) On CAD parts,
//! whose flat faces are triangulated into many coplanar triangles, this removes most
//! facets (two 60-triangle plates: from 4950 to a few hundred).

use super::mesh::TriMesh;
use crate::math::{Aabb, Vec3};
use crate::polytope::clip_planes;
use rayon::prelude::*;
use std::collections::HashMap;

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
        for i in 0..k {
            e[i] = self.p[(i + 1) % k] - self.p[i];
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
        for i in 0..k {
            q[i] = self.p[i] - c;
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
    fn flat_planes(&self) -> Option<([(Vec3, f64); 6], usize)> {
        let k = self.n as usize;
        let (e0, e1) = (self.p[1] - self.p[0], self.p[2] - self.p[1]);
        let n = e0.cross(e1);
        let nl = n.length();
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
    /// Edges that can be locally extreme and are not flat: (a, b, n1, n2).
    edges: Vec<(u32, u32, Vec3, Vec3)>,
    /// Normals of the triangles around each vertex.
    fan: Vec<Vec<Vec3>>,
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
    for (fi, f) in faces.iter().enumerate() {
        for &v in f {
            fan[v as usize].push(m.tris[fi].n);
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
    for (&(a, b), &f1) in &half {
        if a > b {
            continue;
        }
        let Some(&f2) = half.get(&(b, a)) else { continue };
        let (n1, n2) = (m.tris[f1].n, m.tris[f2].n);
        if n1 == Vec3::ZERO || n2 == Vec3::ZERO {
            edges.push((a, b, Vec3::ZERO, Vec3::ZERO)); // degenerate neighbour: keep, unknown arc
            continue;
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
        edges.push((a, b, n1, n2));
    }
    edges.sort_unstable_by_key(|e| (e.0, e.1));
    Topo { verts, ring, faces, edges, fan }
}

/// Whether vertex `v` of `t` can be locally extreme in direction `d` (unit), and is not
/// inside a planar region facing `d`.
#[inline]
fn extreme(t: &Topo, v: u32, d: Vec3) -> bool {
    if t.fan[v as usize].iter().all(|&n| same_normal(n, d)) {
        return false;
    }
    let p = t.verts[v as usize];
    t.ring[v as usize].iter().all(|&w| {
        let e = t.verts[w as usize] - p;
        d.dot(e) <= TOL * e.length()
    })
}

/// Whether the Gauss arcs `[n1, n2]` and `[m1, m2]` can share a direction.
fn arcs_meet(n1: Vec3, n2: Vec3, m1: Vec3, m2: Vec3) -> bool {
    if n1 == Vec3::ZERO || m1 == Vec3::ZERO {
        return true;
    }
    let on_arc = |x: Vec3, a: Vec3, b: Vec3| -> bool {
        let p = a.cross(b);
        if p.length() <= TOL {
            return (x - a).length() <= 1e-6; // a point arc
        }
        x.dot(p).abs() <= 1e-6 * p.length() && a.cross(x).dot(p) >= -TOL && x.cross(b).dot(p) >= -TOL
    };
    let (pa, pb) = (n1.cross(n2), m1.cross(m2));
    if pa.length() <= TOL {
        return on_arc(n1, m1, m2);
    }
    if pb.length() <= TOL {
        return on_arc(m1, n1, n2);
    }
    let c = pa.cross(pb);
    if c.length() <= 1e-9 * pa.length() * pb.length() {
        return true; // the same great circle: conservatively yes
    }
    let c = c.normalize();
    [c, -c].iter().any(|&x| on_arc(x, n1, n2) && on_arc(x, m1, m2))
}

/// The reduced convolution facets of `a` (obstacle `k`) and `b`.
pub fn convolution(a: &TriMesh, b: &TriMesh, k: u32) -> Vec<Facet> {
    let (ta, tb) = (topo(a), topo(b));
    let tri = |t: &TriMesh, i: usize| t.tris[i];
    let mut out: Vec<Facet> = (0..ta.faces.len())
        .into_par_iter()
        .flat_map_iter(|i| {
            let t = tri(a, i);
            let tb = &tb;
            (0..tb.verts.len() as u32)
                .filter(move |&v| t.n != Vec3::ZERO && extreme(tb, v, t.n))
                .map(move |v| {
                    let q = tb.verts[v as usize];
                    Facet { p: [t.p[0] + q, t.p[1] + q, t.p[2] + q, Vec3::ZERO], n: 3, k }
                })
        })
        .collect();
    out.par_extend((0..tb.faces.len()).into_par_iter().flat_map_iter(|j| {
        let s = tri(b, j);
        let ta = &ta;
        (0..ta.verts.len() as u32).filter(move |&u| s.n != Vec3::ZERO && extreme(ta, u, s.n)).map(move |u| {
            let q = ta.verts[u as usize];
            Facet { p: [s.p[0] + q, s.p[1] + q, s.p[2] + q, Vec3::ZERO], n: 3, k }
        })
    }));
    out.par_extend(ta.edges.par_iter().flat_map_iter(|&(a0, a1, n1, n2)| {
        let tb = &tb;
        let (p0, p1) = (ta.verts[a0 as usize], ta.verts[a1 as usize]);
        let e = p1 - p0;
        tb.edges.iter().filter_map(move |&(b0, b1, m1, m2)| {
            let (q0, q1) = (tb.verts[b0 as usize], tb.verts[b1 as usize]);
            let g = q1 - q0;
            if e.cross(g).length() <= 1e-9 * e.length() * g.length() {
                return None; // parallel edges sum to a segment on other facets' borders
            }
            arcs_meet(n1, n2, m1, m2).then(|| Facet { p: [p0 + q0, p1 + q0, p1 + q1, p0 + q1], n: 4, k })
        })
    }));
    out
}
