//! The offset of a closed solid `P` by a radius, as a [`CellSource`] for the octree and
//! the surface extraction (Varadhan and Manocha's section 5.2: the boundary of the offset
//! lies on the spheres, cylinders and prisms of `P`'s vertices, edges and faces).
//!
//! Growing (`r > 0`): `O = {x : dist(x, P) <= r} = P ∪ {x : dist(x, ∂P) <= r}`.
//! Eroding (`r < 0`): `E = {x ∈ P : dist(x, ∂P) >= |r|}`.
//! A surface (open triangles, as FCL sees them) grows as its triangles do: `P` is then
//! empty and `∂P` the triangles, `O = {x : dist(x, triangles) <= r}`; it has no erosion.
//!
//! Cells are classified by exact distances to the triangles of `∂P`: a triangle is a
//! record of a cell when its `|r|`-neighbourhood may meet the cell (the distance from the
//! cell's centre minus its half-diagonal is at most `|r|`). A cell with no record meets
//! neither `∂P` nor any neighbourhood, so it lies wholly inside or outside `P` (one exact
//! winding-number test at its centre decides); a cell within `|r|` of one triangle at
//! all eight corners (the distance to a convex set is convex, so the corners bound it)
//! is wholly in the neighbourhoods. Along a segment, the part within `|r|` of a triangle
//! is one interval (the neighbourhood is convex), in closed form: the hull of the intervals
//! of the corners' balls, the edges' cylinders and the face's prism ([`near_hull`]: two
//! quadratics and a few clips, where a search along the segment took some 300 distance
//! evaluations); the offset's boundary lies at the ends of those intervals, and between
//! them a stretch is wholly inside or outside `P`.
//!
//! Flat parts come out exact ([`CellSource::plane_cut`]): a cell whose every point projects
//! into a record triangle, into the convex flat face it is part of, or into the union of
//! the records of its flat face that is not convex ([`FlatFaces`]: the cell lies in the
//! column over them), meets the neighbourhoods of that face's triangles only in its slab
//! `|n · (x − p)| <= r`, so the offset's boundary there lies on the faces of the slab
//! that cross the cell (both, in a cell wider than `2 r`). A cell where every record is
//! such a triangle is cut by those planes (at most [`MAX_PLANES`]; pieces whose two sides
//! agree are no boundary), as the exact source's flat facets are: the
//! faces of a grown box or of a gear's toothed top, the faces, edges and corners of an
//! eroded box.

use crate::exact::TriMesh;
use crate::flat_faces::{wall_meets, FlatFaces};
use crate::math::{Aabb, Vec3};
use crate::octree::{merge_sorted, CellSource, Label};
use crate::surface::planar::{Cut, MAX_PLANES};
use crate::surface::sag::BoundaryPoint;

/// Record flag: the cell lies in the triangle's column and crosses one face of its slab
/// (the face [`SLAB_FRONT`] says) or both ([`SLAB_BOTH`]); the triangle's neighbourhood
/// there is that slab.
const SLAB: u32 = 1 << 31;
/// Record flag with [`SLAB`]: the face of the slab in front of the triangle (along its
/// normal), else the one behind it.
const SLAB_FRONT: u32 = 1 << 30;
/// Record flag with [`SLAB`]: the cell crosses both faces of the slab (a cell wider than
/// twice the radius over a large flat face).
const SLAB_BOTH: u32 = 1 << 29;
/// How far, relative to the radius, a boundary point found beyond the surface point it
/// projects may lie off the boundary ([`OffsetSource::boundary_point`]): rounding only.
const BOUNDARY_POINT_TOL: f64 = 1e-9;
/// How far along a segment, as a fraction of it, the ends of a record's interval on it
/// must lie from one of its ends for that end's membership to be taken from the interval
/// ([`OffsetSource::near_interval`]): the closed form and the distance may differ by
/// rounding only nearer than that.
const END_MARGIN: f64 = 1e-4;
/// The triangle index of a record.
const INDEX: u32 = SLAB_BOTH - 1;
/// Record of no triangle: the cell misses `∂P` and lies inside `P`. A cell that misses
/// `∂P` keeps one of the two side records, so that its descendants (which miss it too)
/// take their side from it instead of casting a ray each.
const SIDE_IN: u32 = INDEX;
/// Record of no triangle: the cell misses `∂P` and lies outside `P` (see [`SIDE_IN`]).
const SIDE_OUT: u32 = INDEX - 1;

/// The side of `P` a side record gives (`Some(true)`: inside); `None` for a triangle's.
fn side_of(rec: u32) -> Option<bool> {
    match rec {
        SIDE_IN => Some(true),
        SIDE_OUT => Some(false),
        _ => None,
    }
}

/// The triangle records of `recs` (side records left out).
fn triangles(recs: &[u32]) -> impl Iterator<Item = u32> + '_ {
    recs.iter().copied().filter(|&r| side_of(r).is_none())
}

/// The offset of a closed solid by a radius (see the module documentation).
pub struct OffsetSource<'a> {
    mesh: &'a TriMesh,
    /// Per triangle, its face's planes ([`Face`]).
    faces: Vec<Face>,
    /// The flat faces the triangles make up (their columns).
    flat: FlatFaces,
    radius: f64,
    grow: bool,
    /// The box the offset lies in.
    pub aabb: Aabb,
    /// Whether the surface is refined where it sags from the offset (at its creases:
    /// [`crate::surface::sag`]); on by default.
    pub refine_creases: bool,
}

impl<'a> OffsetSource<'a> {
    /// The offset of the solid `mesh` by `r` (grown for `r > 0`, eroded for `r < 0`), or
    /// of the surface `mesh` grown by `r > 0`.
    ///
    /// # Panics
    /// When `r` is zero or not finite, or `mesh` is a surface and `r < 0` (the caller
    /// checks them).
    pub fn new(mesh: &'a TriMesh, r: f64) -> Self {
        assert!(r.is_finite() && r != 0.0, "offset radius {r}");
        assert!(mesh.solid || r > 0.0, "the erosion of a surface");
        assert!(mesh.tris.len() < SIDE_OUT as usize, "{} triangles: records address fewer than 2^29 - 2", mesh.tris.len());
        let grow = r > 0.0;
        let aabb = if grow { mesh.aabb.inflated(r * (1.0 + 1e-9)) } else { mesh.aabb };
        let faces = mesh.tris.iter().map(|t| Face::new(t.p)).collect();
        OffsetSource { mesh, faces, flat: FlatFaces::new(mesh), radius: r.abs(), grow, aabb, refine_creases: true }
    }

    /// The distance from `p` to the triangle of record `t` (flags ignored).
    fn distance(&self, t: u32, p: Vec3) -> f64 {
        let t = (t & INDEX) as usize;
        self.faces[t].distance(self.mesh.tris[t].p, p)
    }

    /// The record of triangle `t` (no flags) for `cell`, near the cell: with [`SLAB`] (and
    /// the faces) when the cell lies in its column and crosses its slab's faces; `None`
    /// when the cell lies in its column wholly outside the slab (the neighbourhood misses it).
    fn slab_record(&self, t: u32, cell: &Aabb) -> Option<u32> {
        let (face, p) = (&self.faces[t as usize], self.mesh.tris[t as usize].p);
        let over = |x: Vec3| if self.flat.has_face(t as usize) { self.flat.over(t as usize, x) } else { face.over(p, x) };
        if face.n == Vec3::ZERO || !(0..8).all(|k| over(corner(cell, k))) {
            return Some(t);
        }
        self.slab_flags(t, cell).map(|flags| t | flags)
    }

    /// The flags of the record of triangle `t` for `cell`, a cell in the column of its
    /// triangles' union ([`Self::slab_record`], [`Self::slabs_over_faces`]): [`SLAB`] (and
    /// the faces) when the cell crosses one face of its slab or both, none when it meets
    /// one only within rounding (not resolved by planes); `None` when the cell lies wholly
    /// outside the slab (the neighbourhood misses it).
    fn slab_flags(&self, t: u32, cell: &Aabb) -> Option<u32> {
        let (n, q) = (self.faces[t as usize].n, self.mesh.tris[t as usize].p[0]);
        // the heights of the corners above the triangle's plane, and the faces they cross
        let (lo, hi) = (0..8).map(|k| (corner(cell, k) - q).dot(n)).fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), z| (l.min(z), h.max(z)));
        let (front, behind) = (lo < self.radius && hi > self.radius, lo < -self.radius && hi > -self.radius);
        match (front, behind) {
            (true, false) => Some(SLAB | SLAB_FRONT),
            (false, true) => Some(SLAB),
            (true, true) => Some(SLAB | SLAB_BOTH),
            (false, false) if hi < -self.radius || lo > self.radius => None,
            _ => Some(0),
        }
    }

    /// The records of `cell` (triangle records only) that the cell leaves the column of
    /// (its own triangle's and its convex face's) get [`SLAB`] when the cell lies in the
    /// column of the records of their flat face together (a gear's toothed top, an L's
    /// cap: see [`FlatFaces`]). Over those triangles the distance to each point of the
    /// cell is its height above their plane, so their neighbourhoods there are the slab:
    /// the face's other triangles' miss the cell, not being records. Tried only when every
    /// other record has [`SLAB`] and the rest lie on at most [`MAX_PLANES`] such faces (the
    /// cell is resolved by planes only then).
    fn slabs_over_faces(&self, cell: &Aabb, recs: &mut Vec<u32>) {
        let mut faces = [u32::MAX; MAX_PLANES];
        let mut count = 0;
        for &r in recs.iter().filter(|&&r| r & SLAB == 0) {
            let Some(g) = self.flat.concave_group((r & INDEX) as usize) else { return };
            if !faces[..count].contains(&g) {
                if count == MAX_PLANES {
                    return;
                }
                faces[count] = g;
                count += 1;
            }
        }
        let corners: [Vec3; 8] = std::array::from_fn(|k| corner(cell, k));
        for &g in &faces[..count] {
            let of_face = |r: u32| self.flat.concave_group((r & INDEX) as usize) == Some(g);
            let mut members: Vec<u32> = recs.iter().filter(|&&r| of_face(r)).map(|&r| r & INDEX).collect();
            members.sort_unstable();
            if !self.column_holds(cell, &corners, &members) {
                return;
            }
            recs.retain_mut(|r| {
                if !of_face(*r) {
                    return true;
                }
                let t = *r & INDEX;
                self.slab_flags(t, cell).map(|flags| *r = t | flags).is_some()
            });
        }
    }

    /// Whether the box `cell` (with `corners`) lies in the column of the triangles
    /// `members` (sorted) of one flat face: its centre lies over one of them and it meets
    /// no wall over an edge of theirs with none of them across ([`wall_meets`]: its shadow
    /// is convex, so it holds no point of their union's boundary and lies in the union).
    fn column_holds(&self, cell: &Aabb, corners: &[Vec3; 8], members: &[u32]) -> bool {
        let face = |t: u32| (&self.faces[t as usize], self.mesh.tris[t as usize].p);
        if members.iter().any(|&t| face(t).0.n == Vec3::ZERO) || !members.iter().any(|&t| face(t).0.over(face(t).1, cell.center())) {
            return false;
        }
        members.iter().all(|&t| {
            let (f, p) = face(t);
            (0..3).all(|k| {
                let inner = self.flat.across(t as usize, k).is_some_and(|u| members.binary_search(&u).is_ok());
                inner || !wall_meets(corners, p[k], p[(k + 1) % 3], f.m[k])
            })
        })
    }

    /// The part `[s0, s1]` of `a → b` within the radius of triangle `t`, if any: the
    /// closed-form [`near_hull`] of the segment's line, clipped to it. An end that interval
    /// holds or leaves by at least [`END_MARGIN`] of the segment is as it says (the
    /// neighbourhood's boundary is that far off along the line); any other end, and both
    /// when the line misses the neighbourhood, takes its membership from
    /// [`Self::distance`], as every point query does, so that the two agree where rounding
    /// could part them.
    fn near_interval(&self, t: u32, a: Vec3, b: Vec3) -> Option<(f64, f64)> {
        let i = (t & INDEX) as usize;
        let hull = near_hull(self.mesh.tris[i].p, &self.faces[i], self.radius, a, b - a);
        let near = |s: f64, x: Vec3| match hull {
            Some((lo, hi)) if lo < s - END_MARGIN && hi > s + END_MARGIN => true,
            Some((lo, hi)) if lo > s + END_MARGIN || hi < s - END_MARGIN => false,
            _ => self.distance(t, x) <= self.radius,
        };
        let (near_a, near_b) = (near(0.0, a), near(1.0, b));
        if near_a && near_b {
            return Some((0.0, 1.0));
        }
        match (near_a, near_b, hull) {
            (true, false, Some((_, hi))) => Some((0.0, hi.clamp(0.0, 1.0))),
            (true, false, None) => Some((0.0, 0.0)),
            (false, true, Some((lo, _))) => Some((lo.clamp(0.0, 1.0), 1.0)),
            (false, true, None) => Some((1.0, 1.0)),
            (false, false, Some((lo, hi))) => {
                let (lo, hi) = (lo.max(0.0), hi.min(1.0));
                (lo <= hi).then_some((lo, hi))
            }
            _ => None,
        }
    }

    /// Whether `p`, not within the radius of the boundary, is in the offset: inside `P`
    /// (never, for a surface).
    fn inside_far(&self, p: Vec3) -> bool {
        self.mesh.solid && self.mesh.contains(p)
    }
}

impl CellSource for OffsetSource<'_> {
    fn root_records(&self) -> Vec<u32> {
        (0..self.mesh.tris.len() as u32).collect()
    }

    fn classify(&self, cell: &Aabb, cand: &[u32], _finest: bool, out: &mut Vec<u32>) -> Label {
        let centre = cell.center();
        let half = cell.half().length();
        let mut nearest = f64::INFINITY; // from the centre to a kept record
        for t in triangles(cand) {
            let t = t & INDEX;
            let d = self.distance(t, centre);
            if d - half > self.radius {
                continue;
            }
            // the distance is 1-Lipschitz (all corners within the radius when the centre is
            // within it less the half-diagonal) and convex (none is when the centre is not)
            if d + half <= self.radius || (d <= self.radius && (0..8).all(|k| self.distance(t, corner(cell, k)) <= self.radius)) {
                out.clear(); // the cell lies in one neighbourhood
                return if self.grow { Label::Full } else { Label::Empty };
            }
            if let Some(rec) = self.slab_record(t, cell) {
                out.push(rec);
                nearest = nearest.min(d);
            }
        }
        self.slabs_over_faces(cell, out);
        // the parent's side, when it missed `∂P` (then so does this cell)
        let inherited = cand.iter().rev().find_map(|&r| side_of(r));
        let side = || inherited.unwrap_or_else(|| self.inside_far(centre));
        if out.is_empty() {
            return if side() { Label::Full } else { Label::Empty };
        }
        if nearest > half {
            // no boundary triangle meets the cell: it lies on one side of `∂P`, and on the
            // side the neighbourhoods do not change (inside a grown, outside an eroded solid)
            // it is decided by that side alone
            let inside = side();
            if inside == self.grow {
                out.clear();
                return if self.grow { Label::Full } else { Label::Empty };
            }
            out.push(if inside { SIDE_IN } else { SIDE_OUT });
        }
        Label::Mixed
    }

    fn cell_contains(&self, cand: &[u32], p: Vec3) -> bool {
        // the first record within the radius decides (the nearest one need not be found);
        // the side of `P` from the cell's side record when it has one
        let side = || cand.iter().rev().find_map(|&r| side_of(r)).unwrap_or_else(|| self.inside_far(p));
        if self.grow {
            triangles(cand).any(|t| self.distance(t, p) <= self.radius) || side()
        } else {
            triangles(cand).all(|t| self.distance(t, p) >= self.radius) && side()
        }
    }

    /// Along the ray from `x`'s nearest point `q` on `∂P` through `x`, the point at the
    /// radius. A point within `reach` below the radius of a boundary point lies on the
    /// offset's side of `∂P` (outside `P` grown, inside eroded: the signed distance changes
    /// no faster than the point moves), so its distance to the triangles is its distance to
    /// that side, and `q` stays nearest along the ray up to `x`: the point is on the
    /// boundary when `x` lies at least the radius out (the chord across a crease); beyond
    /// `x` it is checked.
    fn boundary_point(&self, x: Vec3, reach: f64) -> Option<BoundaryPoint> {
        if reach >= self.radius {
            return None;
        }
        // `x` is within `reach` of a boundary point, which lies the radius from `∂P`
        let (q, d) = self.mesh.nearest_within(x, (self.radius + reach) * (1.0 + BOUNDARY_POINT_TOL))?;
        if d <= 0.0 {
            return None;
        }
        let out = (x - q) / d;
        let p = q + out * self.radius;
        if d < self.radius {
            // nothing nearer than `q` within the tolerance
            let (_, at_p) = self.mesh.nearest_within(p, self.radius * (1.0 + 2.0 * BOUNDARY_POINT_TOL))?;
            if (at_p - self.radius).abs() > BOUNDARY_POINT_TOL * self.radius {
                return None;
            }
        }
        Some((p, if self.grow { out } else { -out }))
    }

    fn has_boundary_points(&self) -> bool {
        self.refine_creases
    }

    /// The slab faces of the records, when every record has [`SLAB`] and they lie on at
    /// most [`MAX_PLANES`] planes.
    fn plane_cut(&self, own: &[u32]) -> Option<Cut> {
        let mut cut = Cut::new();
        for rec in triangles(own) {
            if rec & SLAB == 0 {
                return None;
            }
            let t = (rec & INDEX) as usize;
            let (n, p) = (self.faces[t].n, self.mesh.tris[t].p[0]);
            let tol = 1e-12 * (p.abs().max_element() + self.radius);
            let faces: &[f64] = match (rec & SLAB_BOTH != 0, rec & SLAB_FRONT != 0) {
                (true, _) => &[self.radius, -self.radius],
                (false, true) => &[self.radius],
                (false, false) => &[-self.radius],
            };
            if !faces.iter().all(|&off| cut.add(n, n.dot(p) + off, tol)) {
                return None;
            }
        }
        Some(cut)
    }

    fn boundary_intervals(&self, cand: &[u32], a: Vec3, b: Vec3, out: &mut Vec<(f64, f64)>) {
        out.clear();
        // A record is skipped when its distance at the segment's midpoint shows that no
        // point of the segment is within the radius of it, or that every point is nearer
        // the record nearest the midpoint (distances change by at most the half length
        // along it), so its interval lies in that record's: most of a cell's records are
        // skipped so. The distances at the midpoint first, then the intervals.
        let (mid, half_len) = ((a + b) * 0.5, 0.5 * (b - a).length());
        let mut at_mid = Vec::with_capacity(cand.len());
        for t in triangles(cand) {
            let d = self.distance(t, mid);
            if d + half_len <= self.radius {
                // one neighbourhood holds the whole segment: so does the union
                out.push((0.0, 1.0));
                return;
            }
            at_mid.push((t, d));
        }
        let nearest = at_mid.iter().map(|&(_, d)| d).fold(f64::INFINITY, f64::min);
        let reach = self.radius.min(nearest + half_len) + half_len;
        for &(t, d) in &at_mid {
            if d > reach {
                continue;
            }
            match self.near_interval(t, a, b) {
                Some((s0, s1)) if s0 <= 0.0 && s1 >= 1.0 => {
                    out.clear();
                    out.push((0.0, 1.0));
                    return;
                }
                Some(iv) => out.push(iv),
                None => {}
            }
        }
        merge_sorted(out);
    }

    fn solid_intervals(&self, a: Vec3, b: Vec3, sa: bool, sb: bool, bnd: &[(f64, f64)], out: &mut Vec<(f64, f64)>) {
        out.clear();
        let mut start = 0.0; // the current stretch between neighbourhood intervals
        for (k, &(s0, s1)) in bnd.iter().enumerate() {
            if s0 > start {
                let inside = if k == 0 { sa } else { self.inside_far(a + (b - a) * (0.5 * (start + s0))) };
                if inside {
                    out.push((start, s0));
                }
            }
            if self.grow {
                out.push((s0, s1));
            }
            start = s1;
        }
        if start < 1.0 {
            let last = if bnd.is_empty() { sa && sb } else { sb };
            if last {
                out.push((start, 1.0));
            }
        }
        merge_sorted(out);
    }
}

/// Below this ratio of twice its area to its longest edge squared a triangle is taken for
/// its three edges (a sliver at most 1e-9 of its length wide: its points are that close to
/// them): its normal, from a cross product of nearly parallel edges, would be rounding.
const SLIVER: f64 = 1e-9;

/// A triangle's face: unit normal `n` and unit in-plane edge normals `m[k]` (of the edge
/// from corner `k` to corner `k + 1`, pointing into the triangle); all zero for a sliver.
/// With them, for the distance, the edges `e[k]` and the inverses of their squared
/// lengths (zero for an edge of no length).
#[derive(Clone, Copy, Debug)]
pub struct Face {
    n: Vec3,
    m: [Vec3; 3],
    e: [Vec3; 3],
    inv: [f64; 3],
}

impl Face {
    /// The face of the triangle with corners `p`.
    pub fn new(p: [Vec3; 3]) -> Face {
        let e = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
        let inv = e.map(|x| if x.length_squared() > 0.0 { 1.0 / x.length_squared() } else { 0.0 });
        let cross = e[0].cross(e[1]);
        let longest = e.iter().map(|x| x.length_squared()).fold(0.0, f64::max);
        if cross.length() <= SLIVER * longest {
            return Face { n: Vec3::ZERO, m: [Vec3::ZERO; 3], e, inv };
        }
        let n = cross.normalize();
        Face { n, m: e.map(|x| n.cross(x).normalize()), e, inv }
    }

    /// Whether the point's projection on the plane lies in the triangle (`false` for a
    /// sliver).
    fn over(&self, p: [Vec3; 3], x: Vec3) -> bool {
        self.n != Vec3::ZERO && (0..3).all(|k| (x - p[k]).dot(self.m[k]) >= 0.0)
    }

    /// The distance from `x` to the triangle with corners `p`: to its plane when `x` lies
    /// over it, else to its nearest edge. That edge is one whose half-plane `x` lies
    /// outside of (the nearest point is on the boundary, where `x − q` points out of the
    /// triangle), so only those are measured; all three for a sliver.
    pub fn distance(&self, p: [Vec3; 3], x: Vec3) -> f64 {
        let sliver = self.n == Vec3::ZERO;
        let w = [x - p[0], x - p[1], x - p[2]];
        let out = [w[0].dot(self.m[0]) < 0.0, w[1].dot(self.m[1]) < 0.0, w[2].dot(self.m[2]) < 0.0];
        if !sliver && !out[0] && !out[1] && !out[2] {
            return w[0].dot(self.n).abs();
        }
        let mut least = f64::INFINITY;
        for k in 0..3 {
            if sliver || out[k] {
                let s = (w[k].dot(self.e[k]) * self.inv[k]).clamp(0.0, 1.0);
                least = least.min((w[k] - self.e[k] * s).length_squared());
            }
        }
        least.sqrt()
    }
}

/// Where the line `a + s d` (all real `s`) meets the `r`-neighbourhood of the triangle with
/// corners `p` and face `face`: `[lo, hi]` or none. That neighbourhood is convex and the union of the
/// corners' balls, the edges' finite cylinders and the prism over the face, so the hull of
/// the seven pieces' intervals (each a quadratic's or a clip's) is exactly its interval.
pub fn near_hull(p: [Vec3; 3], face: &Face, r: f64, a: Vec3, d: Vec3) -> Option<(f64, f64)> {
    let dd = d.length_squared();
    if dd == 0.0 {
        return None;
    }
    let mut hull: Option<(f64, f64)> = None;
    let mut add = |iv: Option<(f64, f64)>| {
        if let Some((lo, hi)) = iv {
            hull = Some(hull.map_or((lo, hi), |(l, h)| (l.min(lo), h.max(hi))));
        }
    };
    for k in 0..3 {
        let w = a - p[k];
        add(quadratic_below(dd, 2.0 * w.dot(d), w.length_squared() - r * r));
        let e = p[(k + 1) % 3] - p[k];
        let ee = e.length_squared();
        if ee > 0.0 {
            // perpendicular to the edge: within r of its line; along it: between its ends
            let (we, de) = (w.dot(e) / ee, d.dot(e) / ee);
            let (wp, dp) = (w - e * we, d - e * de);
            let across = quadratic_below(dp.length_squared(), 2.0 * wp.dot(dp), wp.length_squared() - r * r);
            add(across.and_then(|iv| clip(iv, we, de, 0.0)).and_then(|iv| clip(iv, -we, -de, -1.0)));
        }
    }
    let (n, m) = (face.n, face.m);
    if n != Vec3::ZERO {
        let h = (a - p[0]).dot(n);
        let mut prism = clip((f64::NEG_INFINITY, f64::INFINITY), h, d.dot(n), -r);
        prism = prism.and_then(|iv| clip(iv, -h, -d.dot(n), -r));
        for k in 0..3 {
            prism = prism.and_then(|iv| clip(iv, (a - p[k]).dot(m[k]), d.dot(m[k]), 0.0));
        }
        add(prism);
    }
    hull
}

/// `{s : A s² + B s + C <= 0}` for `A >= 0` (an interval or none; `A = 0`: all or none
/// as `C`, the case of a line parallel to a cylinder's axis).
fn quadratic_below(qa: f64, qb: f64, qc: f64) -> Option<(f64, f64)> {
    if qa <= 0.0 {
        return (qc <= 0.0).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return None;
    }
    // the root of the larger magnitude first, the other from the product (no cancellation)
    let q = -0.5 * (qb + qb.signum() * disc.sqrt());
    if q == 0.0 {
        return Some((0.0, 0.0));
    }
    let (s1, s2) = (q / qa, qc / q);
    Some((s1.min(s2), s1.max(s2)))
}

/// `iv` clipped to `{s : g0 + s g1 >= lim}`.
fn clip(iv: (f64, f64), g0: f64, g1: f64, lim: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = iv;
    let g = g0 - lim;
    if g1 == 0.0 {
        return (g >= 0.0).then_some(iv);
    }
    let s = -g / g1;
    if g1 > 0.0 {
        lo = lo.max(s);
    } else {
        hi = hi.min(s);
    }
    (lo <= hi).then_some((lo, hi))
}

fn corner(cell: &Aabb, k: usize) -> Vec3 {
    Vec3::new(if k & 1 == 0 { cell.min.x } else { cell.max.x }, if k & 2 == 0 { cell.min.y } else { cell.max.y }, if k & 4 == 0 { cell.min.z } else { cell.max.z })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::union::{approximate_solid, UnionParams};

    /// The point of segment `ab` nearest `p`.
    fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
        let ab = b - a;
        let len2 = ab.length_squared();
        if len2 == 0.0 {
            return a;
        }
        a + ab * ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    }

    fn unit_cube() -> TriMesh {
        let v: Vec<Vec3> = (0..8).map(|k| Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64)).collect();
        let f: Vec<[u32; 3]> = vec![[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]];
        TriMesh::new(v, &f, "cube").expect("a solid cube")
    }

    #[test]
    fn distances_to_a_triangle() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let dist = |x: Vec3| Face::new(p).distance(p, x);
        assert!((dist(Vec3::new(0.2, 0.2, 5.0)) - 5.0).abs() < 1e-15); // the face
        assert!((dist(Vec3::new(-1.0, -1.0, 0.0)) - 2f64.sqrt()).abs() < 1e-15); // a vertex
        assert!((dist(Vec3::new(0.5, -2.0, 0.0)) - 2.0).abs() < 1e-15); // an edge
        assert!((dist(Vec3::new(1.0, 1.0, 0.0)) - 0.5f64.sqrt()).abs() < 1e-15); // the hypotenuse
                                                                                 // a triangle with two equal corners is its edge: no NaN from 0 / 0
        let q = [Vec3::ZERO, Vec3::ZERO, Vec3::Y];
        let d = Face::new(q).distance(q, Vec3::new(-0.5, 2.0, 0.0));
        assert!((d - 5f64.sqrt() / 2.0).abs() < 1e-15, "{d}");
        // nearly collinear corners (a rounding-level area): the distance to the sliver is
        // the distance to its edges, not what a division by that area makes of it
        let (a, b) = (Vec3::new(0.06, -0.08, 0.38), Vec3::new(-0.15, -0.65, -0.96));
        let s = [a, b, a + (b - a) * 0.3];
        let x = Vec3::new(-0.08, -0.51, -0.51); // the old region code was 0.32 off here
        let edge = (closest_on_segment(x, a, b) - x).length();
        assert!((Face::new(s).distance(s, x) - edge).abs() < 1e-12);
    }

    /// The L of three unit squares (outline (0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2))
    /// fanned from (0, 0) at height `z`, facing up.
    fn l_cap(z: f64) -> TriMesh {
        let v = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]].map(|[x, y]| Vec3::new(x, y, z));
        TriMesh::surface(v.to_vec(), &[[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]], "L").expect("a surface")
    }

    #[test]
    fn cells_over_the_seams_of_a_face_that_is_not_convex_are_cut_by_its_plane() {
        let cap = l_cap(0.0);
        let src = OffsetSource::new(&cap, 0.2);
        let cube = |c: Vec3| Aabb::new(c - Vec3::splat(0.05), c + Vec3::splat(0.05));
        let records = |cell: &Aabb| {
            let mut out = Vec::new();
            let label = src.classify(cell, &src.root_records(), false, &mut out);
            (label, out)
        };
        // over the seam (0, 0) → (2, 1) between two triangles, crossing the slab's top: in
        // neither triangle's column, but in the face's
        let (label, recs) = records(&cube(Vec3::new(1.0, 0.5, 0.2)));
        assert_eq!(label, Label::Mixed);
        assert!(triangles(&recs).count() == 2 && triangles(&recs).all(|r| r & SLAB != 0 && r & SLAB_FRONT != 0), "{recs:?}");
        let cut = src.plane_cut(&recs).expect("cut by the slab's top");
        assert_eq!(cut.n, 1);
        // over the reflex corner's edge (1, 1) → (1, 2), half of it outside the L: the
        // face's column does not hold it (its neighbourhood rounds that edge)
        let (_, recs) = records(&cube(Vec3::new(1.02, 1.5, 0.2)));
        assert!(src.plane_cut(&recs).is_none(), "{recs:?}");
        // the grown cap is as a cap grown with its seams' cells sampled: the same volume
        let params = UnionParams { eps: 0.02, max_cells: 4_000_000, max_refinements: 0, simplify: false, planes: true };
        let result = approximate_solid(&src, &src.aabb, &params).expect("a surface");
        let volume = signed_volume(&result.surface.vertices, &result.surface.faces);
        // the r-neighbourhood of a flat polygon: over height z its section is the polygon
        // grown by ρ = sqrt(r² − z²) in its plane, of area A + L ρ + ρ² (5 π / 4 − 1) for
        // the L (five right convex corners add quarter discs, the reflex one takes off the
        // square where its edges' strips overlap); integrated over z in [−r, r]
        let (r, pi) = (0.2, std::f64::consts::PI);
        let exact = 2.0 * 3.0 * r + 8.0 * pi * r * r / 2.0 + (5.0 * pi / 4.0 - 1.0) * 4.0 * r.powi(3) / 3.0;
        assert!((volume - exact).abs() < 0.01 * exact, "{volume} vs {exact}");
    }

    #[test]
    fn cells_wider_than_the_slab_over_a_sheet_are_cut_by_both_its_faces() {
        // a unit square sheet (a surface) grown by 0.05: a cell 0.4 wide over its middle
        // crosses both faces of the slab, which bound the offset there
        let v = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|[x, y]| Vec3::new(x, y, 0.0));
        let sheet = TriMesh::surface(v.to_vec(), &[[0, 1, 2], [0, 2, 3]], "sheet").expect("a surface");
        let r = 0.05;
        let src = OffsetSource::new(&sheet, r);
        let cell = Aabb::new(Vec3::new(0.3, 0.3, -0.2), Vec3::new(0.7, 0.7, 0.2));
        let mut recs = Vec::new();
        assert_eq!(src.classify(&cell, &src.root_records(), false, &mut recs), Label::Mixed);
        assert!(triangles(&recs).all(|r| r & SLAB != 0 && r & SLAB_BOTH != 0), "{recs:?}");
        let cut = src.plane_cut(&recs).expect("cut by the slab's faces");
        assert_eq!(cut.n, 2);
        // the grown sheet, at a grid coarse for its thickness, has the Steiner volume
        let params = UnionParams { eps: 0.02, max_cells: 4_000_000, max_refinements: 0, simplify: true, planes: true };
        let result = approximate_solid(&src, &src.aabb, &params).expect("a surface");
        let volume = signed_volume(&result.surface.vertices, &result.surface.faces);
        let pi = std::f64::consts::PI;
        let exact = 2.0 * r + pi * 4.0 * r * r / 2.0 + 4.0 / 3.0 * pi * r.powi(3);
        assert!((volume - exact).abs() < 0.01 * exact, "{volume} vs {exact}");
    }

    #[test]
    fn membership_follows_the_distance() {
        let cube = unit_cube();
        let grown = OffsetSource::new(&cube, 0.5);
        let all = grown.root_records();
        assert!(grown.cell_contains(&all, Vec3::new(1.4, 0.5, 0.5)));
        assert!(!grown.cell_contains(&all, Vec3::new(1.6, 0.5, 0.5)));
        assert!(grown.cell_contains(&all, Vec3::new(1.3, 1.3, 0.5))); // 0.42 from the edge
        assert!(!grown.cell_contains(&all, Vec3::new(1.3, 1.3, 1.3))); // 0.52 from the corner
        let shrunk = OffsetSource::new(&cube, -0.2);
        assert!(shrunk.cell_contains(&all, Vec3::new(0.5, 0.5, 0.5)));
        assert!(!shrunk.cell_contains(&all, Vec3::new(0.1, 0.5, 0.5)));
    }

    #[test]
    fn the_grown_cube_has_the_closed_form_volume() {
        let cube = unit_cube();
        let r = 0.25;
        let src = OffsetSource::new(&cube, r);
        let params = UnionParams { eps: 0.02, max_cells: 4_000_000, max_refinements: 0, simplify: false, planes: true };
        let result = approximate_solid(&src, &src.aabb, &params).expect("a surface");
        let volume = signed_volume(&result.surface.vertices, &result.surface.faces);
        let exact = 1.0 + 6.0 * r + 3.0 * std::f64::consts::PI * r * r + 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        assert!((volume - exact).abs() < 0.03 * exact, "{volume} vs {exact}");
    }

    /// A lone triangle grows into its parallel body: by Steiner's formula for a flat convex
    /// set of area `A` and perimeter `L`, `2 A r + π L r² / 2 + 4/3 π r³`.
    #[test]
    fn a_grown_triangle_has_the_steiner_volume() {
        let v = vec![Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.3, 0.8, 0.1)];
        let tri = TriMesh::surface(v.clone(), &[[0, 1, 2]], "triangle").expect("a surface");
        let r = 0.2;
        let src = OffsetSource::new(&tri, r);
        let params = UnionParams { eps: 0.01, max_cells: 4_000_000, max_refinements: 0, simplify: true, planes: true };
        let result = approximate_solid(&src, &src.aabb, &params).expect("a surface");
        let volume = signed_volume(&result.surface.vertices, &result.surface.faces);
        let area = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length();
        let perimeter = (v[1] - v[0]).length() + (v[2] - v[1]).length() + (v[0] - v[2]).length();
        let pi = std::f64::consts::PI;
        let exact = 2.0 * area * r + 0.5 * pi * perimeter * r * r + 4.0 / 3.0 * pi * r.powi(3);
        assert!((volume - exact).abs() < 0.02 * exact, "{volume} vs {exact}");
        // its two flat sides are resolved by planes
        assert!(result.surface.planar_pieces > 0);
    }

    /// An eroded cube is resolved by its faces' slab planes everywhere: the shrunken box,
    /// its 8 corners exact to rounding, in 12 triangles after simplification.
    #[test]
    fn the_eroded_cube_is_the_exact_shrunken_box() {
        let cube = unit_cube();
        let r = 0.2;
        let src = OffsetSource::new(&cube, -r);
        let params = UnionParams { eps: 0.01, max_cells: 4_000_000, max_refinements: 0, simplify: true, planes: true };
        let result = approximate_solid(&src, &src.aabb, &params).expect("a surface");
        let s = &result.surface;
        assert!(s.planar_pieces > 0 && s.band_cells == 0, "{} pieces, {} band cells", s.planar_pieces, s.band_cells);
        assert_eq!(s.faces.len(), 12, "{} triangles", s.faces.len());
        for v in &s.vertices {
            for c in v.to_array() {
                assert!((c - r).abs() < 1e-12 || (c - (1.0 - r)).abs() < 1e-12, "vertex {v:?}");
            }
        }
        let volume = signed_volume(&s.vertices, &s.faces);
        assert!((volume - (1.0 - 2.0 * r).powi(3)).abs() < 1e-12, "{volume}");
    }

    /// A grown cube: its six faces are exact planes (their vertices lie on `x = 1 + r`
    /// etc. to rounding), joined to the sampled round edges and corners; the volume stays
    /// the closed form's within the grid's error.
    #[test]
    fn the_grown_cube_has_exact_flat_faces() {
        let cube = unit_cube();
        let r = 0.25;
        let src = OffsetSource::new(&cube, r);
        let params = UnionParams { eps: 0.02, max_cells: 4_000_000, max_refinements: 0, simplify: false, planes: true };
        let result = approximate_solid(&src, &src.aabb, &params).expect("a surface");
        let s = &result.surface;
        assert!(s.planar_pieces > 0, "no face was resolved by planes");
        assert_eq!(s.open_edges, 0);
        // every vertex over the middle of a face lies on its offset plane
        let on_face = s.vertices.iter().filter(|v| {
            let a = v.to_array();
            (0..3).any(|i| (0..3).filter(|&j| j != i).all(|j| a[j] > 0.1 && a[j] < 0.9) && (a[i] > 1.0 || a[i] < 0.0))
        });
        for v in on_face {
            let off = v.to_array().iter().map(|&c| (c - (1.0 + r)).abs().min((c + r).abs())).fold(f64::INFINITY, f64::min);
            assert!(off < 1e-12, "vertex {v:?} off its face plane by {off}");
        }
        let volume = signed_volume(&s.vertices, &s.faces);
        let exact = 1.0 + 6.0 * r + 3.0 * std::f64::consts::PI * r * r + 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        assert!((volume - exact).abs() < 0.03 * exact, "{volume} vs {exact}");
    }

    /// The closed-form interval against dense samples of the exact distance, on random
    /// triangles (degenerate ones too) and segments (some parallel to an edge or in the
    /// triangle's plane): every sample farther than 1e-9 from the interval's ends is near
    /// exactly when it lies inside it.
    #[test]
    fn the_closed_form_interval_is_where_the_distance_is_within_the_radius() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rand = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let point = |s: f64, rand: &mut dyn FnMut() -> f64| Vec3::new(rand() * s, rand() * s, rand() * s);
        let (mut met, mut missed) = (0, 0);
        for k in 0..3000 {
            let mut p = [point(1.0, &mut rand), point(1.0, &mut rand), point(1.0, &mut rand)];
            if k % 10 == 0 {
                p[2] = p[1]; // two corners the same
            } else if k % 10 == 1 {
                p[2] = p[0] + (p[1] - p[0]) * 0.3; // collinear
            }
            let v: Vec<Vec3> = p.to_vec();
            let mesh = TriMesh::surface(v, &[[0, 1, 2]], "tri").expect("a triangle");
            let src = OffsetSource {
                faces: vec![Face::new(p)],
                flat: FlatFaces::new(&mesh),
                mesh: &mesh,
                radius: 0.1 + 0.5 * rand().abs(),
                grow: true,
                aabb: mesh.aabb,
                refine_creases: true,
            };
            let a = point(1.5, &mut rand);
            let b = match k % 7 {
                0 => a + (p[1] - p[0]) * rand(),                          // parallel to an edge
                1 => a + (p[1] - p[0]) * rand() + (p[2] - p[0]) * rand(), // parallel to the face
                _ => point(1.5, &mut rand),
            };
            let iv = src.near_interval(0, a, b);
            let len = (b - a).length().max(1e-300);
            for j in 0..=400 {
                let s = j as f64 / 400.0;
                let near = src.distance(0, a + (b - a) * s) <= src.radius;
                let inside = iv.is_some_and(|(lo, hi)| lo <= s && s <= hi);
                let at_end = iv.is_some_and(|(lo, hi)| ((s - lo).abs().min((s - hi).abs())) * len < 1e-9);
                assert!(near == inside || at_end, "case {k}: s {s} near {near} interval {iv:?}");
            }
            if iv.is_some() {
                met += 1;
            } else {
                missed += 1;
            }
        }
        assert!(met > 500 && missed > 500, "{met} met, {missed} missed");
    }

    /// A small xorshift generator of numbers in `[-1, 1)` for the randomized tests.
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// The distance measuring only the edges a point lies outside of is the distance to
    /// the nearest of all three edges (or to the plane over the triangle), on random
    /// triangles, slivers among them.
    #[test]
    fn the_distance_measures_the_right_edges() {
        let mut rand = uniform(0x9e37_79b9_7f4a_7c15);
        for k in 0..20_000 {
            let mut p = [0; 3].map(|_| Vec3::new(rand(), rand(), rand()));
            if k % 7 == 0 {
                p[2] = p[0] + (p[1] - p[0]) * rand(); // collinear: a sliver
            }
            let face = Face::new(p);
            let x = Vec3::new(2.0 * rand(), 2.0 * rand(), 2.0 * rand());
            let edges = (0..3).map(|j| (closest_on_segment(x, p[j], p[(j + 1) % 3]) - x).length()).fold(f64::INFINITY, f64::min);
            let plane = face.n.dot(x - p[0]).abs();
            let reference = if face.over(p, x) { plane } else { edges };
            let d = face.distance(p, x);
            assert!((d - reference).abs() <= 1e-12, "case {k}: {d} vs {reference}");
        }
    }

    /// The segment's intervals with records skipped (by their distance at its midpoint)
    /// are the union of every record's interval, on the grown and eroded cube and a
    /// tetrahedron, for random segments of many lengths.
    #[test]
    fn skipping_records_keeps_the_union_of_the_intervals() {
        let cube = unit_cube();
        let mut rand = uniform(0x2545_f491_4f6c_dd1d);
        let mut compared = 0;
        for r in [0.3, -0.2, 0.05] {
            let src = OffsetSource::new(&cube, r);
            let all = src.root_records();
            for _ in 0..3000 {
                let a = Vec3::new(0.5 + 0.9 * rand(), 0.5 + 0.9 * rand(), 0.5 + 0.9 * rand());
                let len = 0.5 * rand().abs().powi(3);
                let b = a + Vec3::new(rand(), rand(), rand()) * len;
                let mut fast = Vec::new();
                src.boundary_intervals(&all, a, b, &mut fast);
                let mut every: Vec<(f64, f64)> = all.iter().filter_map(|&t| src.near_interval(t, a, b)).collect();
                merge_sorted(&mut every);
                if every.iter().any(|&(s0, s1)| s0 <= 0.0 && s1 >= 1.0) {
                    every = vec![(0.0, 1.0)];
                }
                assert_eq!(fast.len(), every.len(), "{a:?} → {b:?}: {fast:?} vs {every:?}");
                for (x, y) in fast.iter().zip(&every) {
                    assert!((x.0 - y.0).abs() < 1e-12 && (x.1 - y.1).abs() < 1e-12, "{fast:?} vs {every:?}");
                }
                compared += (!every.is_empty()) as usize;
            }
        }
        assert!(compared > 1000, "{compared} segments met a neighbourhood");
    }

    /// A cell that misses the boundary carries its side to its children: their labels
    /// and point answers are those a ray gives, on the grown and the eroded cube.
    #[test]
    fn side_records_answer_as_the_rays_do() {
        let cube = unit_cube();
        let mut sides = 0;
        for r in [0.1, -0.1] {
            let src = OffsetSource::new(&cube, r);
            let all = src.root_records();
            // cells of 0.1 around the cube, inside and out
            for i in 0..16 {
                for j in 0..16 {
                    for k in 0..16 {
                        let lo = Vec3::new(-0.3 + 0.1 * i as f64, -0.3 + 0.1 * j as f64, -0.3 + 0.1 * k as f64);
                        let cell = Aabb { min: lo, max: lo + Vec3::splat(0.1) };
                        let mut own = Vec::new();
                        let label = src.classify(&cell, &all, false, &mut own);
                        let side = own.iter().find_map(|&rec| side_of(rec));
                        sides += side.is_some() as usize;
                        if let Some(inside) = side {
                            assert_eq!(inside, cube.contains(cell.center()), "side of {cell:?}");
                            assert_eq!(label, Label::Mixed);
                        }
                        if label == Label::Mixed {
                            // only a MIXED cell is split
                            let child = Aabb { min: lo, max: lo + Vec3::splat(0.05) };
                            let mut grand = Vec::new();
                            let child_label = src.classify(&child, &own, false, &mut grand);
                            let mut fresh = Vec::new();
                            assert_eq!(child_label, src.classify(&child, &all, false, &mut fresh), "child of {cell:?}");
                            for q in [lo, lo + Vec3::splat(0.05), lo + Vec3::new(0.1, 0.0, 0.07)] {
                                assert_eq!(src.cell_contains(&own, q), src.cell_contains(&all, q), "{q:?}");
                            }
                        }
                    }
                }
            }
        }
        assert!(sides > 100, "{sides} cells carry a side");
    }

    fn signed_volume(v: &[Vec3], f: &[[u32; 3]]) -> f64 {
        f.iter().map(|t| v[t[0] as usize].dot(v[t[1] as usize].cross(v[t[2] as usize])) / 6.0).sum()
    }
}
