//! The exact polygons of plane-resolved cells merged, plane by plane, into regions that are
//! triangulated once.
//!
//! Every cell resolved by planes gives convex polygons on the planes of its candidates; a
//! flat facet of the answer crosses many cells, so it arrives as many polygons. First every
//! polygon takes in the corners of other polygons lying on its edges (where a large cell
//! meets smaller ones: on its plane, so that the edges they share cancel below, or across
//! a crease, so that both sides of it share their vertices). Then on each plane (polygons
//! whose outward planes agree to rounding) an edge used once each way cancels; what is
//! left is the regions' boundary. A straight edge of the answer between two regions is split
//! at every cell wall it crosses; both regions leave those vertices out of their outlines
//! (the band's vertices, and those of fanned planes, stay: others use them). Each loop is
//! then triangulated by ear clipping in the plane: where loops touch at a vertex, each
//! region keeps its own; a hole (a clockwise loop) is first joined to the loop around it
//! by a bridge there and back. A facet crossing a thousand cells thus comes out in about as
//! many triangles as it has corners, not four per cell to be collapsed afterwards.
//!
//! A plane keeps its polygons, each fanned about its centroid as before, when its boundary
//! is not simple loops (an edge left twice, regions overlapping at a vertex, a loop through
//! a vertex twice — a hole touching the loop around it —, a hole in no loop, no ear found
//! even to rounding, a loop longer than [`MAX_LOOP`] with its holes bridged in), or when
//! it shares a corner with a plane facing the other way (two sheets through the same
//! points would share diagonals). Either way the triangles cover the same point set as the
//! polygons.
//!
//! Entry point: [`triangulate`].

use super::stitch;
use crate::math::Vec3;
use crate::util::{FastMap, FastSet};
use rayon::prelude::*;

/// An outward plane `(n, w)` (`n · x = w` on it) as recorded by a cell: grouped with the
/// planes within rounding of it by [`triangulate`].
pub type PlaneKey = [f64; 4];

/// The key of the outward plane `(n, w)`.
pub fn plane_key(n: Vec3, w: f64) -> PlaneKey {
    [n.x, n.y, n.z, w]
}

/// Normals whose components agree to this many steps are one plane's (the same facet's
/// plane is computed from different triangles in different cells, a few roundings apart).
const NORMAL_STEP: f64 = 1e-9;

/// The group of the plane `k`: its normal and offset quantized (the offset to steps of
/// `tol`, the weld tolerance); planes within rounding of each other fall into one group
/// unless a step boundary lies between them (then they stay two regions, which is safe).
fn group_of(k: &PlaneKey, tol: f64) -> [i64; 4] {
    let q = |x: f64, step: f64| (x / step).round() as i64;
    [q(k[0], NORMAL_STEP), q(k[1], NORMAL_STEP), q(k[2], NORMAL_STEP), q(k[3], tol)]
}

/// Loops longer than this are not clipped (the clipping is quadratic in their length);
/// their plane's polygons are fanned.
const MAX_LOOP: usize = 4096;

/// What [`triangulate`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RegionStats {
    /// Planes whose polygons were merged into regions.
    pub merged_planes: usize,
    /// Planes whose polygons were fanned one by one instead.
    pub fanned_planes: usize,
    /// Vertices found inside straight creases, left out of the regions' outlines (but
    /// where a shortened outline could not be clipped: [`triangulate`]).
    pub straight_dropped: usize,
    /// Patches of faces where the joined surface folded back in one plane, replaced by
    /// what they cover once ([`super::folds`]; counted by the extraction, after the loops
    /// left open are closed).
    pub unfolded: usize,
}

/// Triangles of the polygons `polys` (corners welded to indices of `vertices`, each
/// counter-clockwise about its outward normal), polygon `i` lying on the plane
/// `keys[i]`: per plane, merged into regions triangulated once where that can be done
/// (see the module documentation), else each fanned about its centroid (a vertex appended
/// to `vertices`). `tol`: the weld tolerance, within which a corner lies on another
/// polygon's edge. Vertices below `kept` (the band's) stay in the outlines; others inside
/// straight creases between two merged regions are left out of both
/// ([`straight_crease_vertices`]).
pub fn triangulate(vertices: &mut Vec<Vec3>, polys: &[Vec<u32>], keys: &[PlaneKey], tol: f64, kept: usize) -> (Vec<[u32; 3]>, RegionStats) {
    let polys = &with_corners_on_edges(vertices, polys, tol);
    let group: Vec<[i64; 4]> = keys.iter().map(|k| group_of(k, tol)).collect();
    let mut order: Vec<usize> = (0..polys.len()).collect();
    order.sort_by_key(|&i| group[i]);
    let groups: Vec<&[usize]> = order.chunk_by(|&a, &b| group[a] == group[b]).collect();
    let verts: &[Vec3] = vertices;
    let normals: Vec<Vec3> = groups.iter().map(|g| Vec3::new(keys[g[0]][0], keys[g[0]][1], keys[g[0]][2])).collect();
    let sheets = opposite_sheets(polys, &groups, &normals);
    let loops: Vec<Option<Vec<Vec<u32>>>> = groups
        .par_iter()
        .enumerate()
        .map(|(g, group)| {
            // two sheets facing each other through the same points: triangulated the same
            // way, they would share diagonals; fanned, each keeps its own centres
            if sheets[g] {
                return None;
            }
            region_loops(verts, group.iter().map(|&i| polys[i].as_slice()), normals[g])
        })
        .collect();
    let mut stats = RegionStats::default();
    // the band's vertices (the polygons' corners welded to them) and the fanned polygons'
    // corners stay
    let fanned: FastSet<u32> = groups.iter().zip(&loops).filter(|(_, l)| l.is_none()).flat_map(|(g, _)| g.iter().flat_map(|&i| polys[i].iter().copied())).collect();
    let straight = straight_crease_vertices(verts, &loops, tol, |v| (v as usize) < kept || fanned.contains(&v));
    let merged: Vec<Option<Vec<[u32; 3]>>> = loops
        .par_iter()
        .enumerate()
        .map(|(g, whole)| {
            let whole = whole.as_ref()?;
            let short: Vec<Vec<u32>> = whole.iter().map(|ids| ids.iter().copied().filter(|v| !straight.contains(v)).collect()).collect();
            // (should a shortened loop not clip, the whole one is tried: where that clips,
            // the stitch splits the neighbour's edges at the vertices it kept; where it does
            // not, the plane is fanned, its polygons keeping them too)
            clip_loops(verts, &short, normals[g], tol).or_else(|| clip_loops(verts, whole, normals[g], tol))
        })
        .collect();
    stats.straight_dropped = straight.len();
    let mut faces = Vec::new();
    for (group, tris) in groups.iter().zip(merged) {
        match tris {
            Some(tris) => {
                stats.merged_planes += 1;
                faces.extend(tris);
            }
            None => {
                stats.fanned_planes += 1;
                for &i in *group {
                    fan(vertices, &polys[i], &mut faces);
                }
            }
        }
    }
    (faces, stats)
}

/// Per group, whether a polygon of it shares a corner with one of a group facing the other
/// way (within [`OPPOSITE`]): two sheets of the surface touching there (a part of no
/// thickness, or one thinner than the weld).
fn opposite_sheets(polys: &[Vec<u32>], groups: &[&[usize]], normals: &[Vec3]) -> Vec<bool> {
    let mut users: FastMap<u32, Vec<u32>> = FastMap::default();
    for (g, group) in groups.iter().enumerate() {
        for &i in *group {
            for &v in &polys[i] {
                let list = users.entry(v).or_default();
                if list.last() != Some(&(g as u32)) {
                    list.push(g as u32);
                }
            }
        }
    }
    let mut out = vec![false; groups.len()];
    for list in users.values() {
        for (k, &a) in list.iter().enumerate() {
            for &b in &list[k + 1..] {
                let (na, nb) = (normals[a as usize], normals[b as usize]);
                if na.dot(nb) < -(1.0 - OPPOSITE) * na.length() * nb.length() {
                    out[a as usize] = true;
                    out[b as usize] = true;
                }
            }
        }
    }
    out
}

/// How far from exactly opposite (`1 + cos` of the angle) two planes count as facing each
/// other.
const OPPOSITE: f64 = 1e-6;

/// The polygon `ids` fanned about its centroid (appended to `vertices`).
fn fan(vertices: &mut Vec<Vec3>, ids: &[u32], faces: &mut Vec<[u32; 3]>) {
    let c = ids.iter().fold(Vec3::ZERO, |acc, &v| acc + vertices[v as usize]) / ids.len() as f64;
    let centre = vertices.len() as u32;
    vertices.push(c);
    for i in 0..ids.len() {
        let (a, b) = (ids[i], ids[(i + 1) % ids.len()]);
        if a != b {
            faces.push([centre, a, b]);
        }
    }
}

/// The boundary loops of the regions the polygons of one plane (outward `normal`) make
/// up: counter-clockwise around regions, clockwise around holes; `None` when they are not
/// simple loops ([`boundary_loops`]), a loop is longer than [`MAX_LOOP`] or has no area.
pub(super) fn region_loops<'a>(vertices: &[Vec3], polys: impl Iterator<Item = &'a [u32]>, normal: Vec3) -> Option<Vec<Vec<u32>>> {
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for p in polys {
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            if a != b {
                edges.push((a, b));
            }
        }
    }
    let (u, v) = plane_basis(normal);
    let loops = boundary_loops(&edges, |a, b| {
        let d = vertices[b as usize] - vertices[a as usize];
        d.dot(v).atan2(d.dot(u))
    })?;
    let short = loops.iter().all(|ids| ids.len() <= MAX_LOOP);
    let areas_nonzero = loops.iter().all(|ids| signed_area(&ids.iter().map(|&i| in_plane(vertices, i, (u, v))).collect::<Vec<_>>()) != 0.0);
    (short && areas_nonzero).then_some(loops)
}

/// Vertex `i` in the plane's coordinates `(u, v)`.
fn in_plane(vertices: &[Vec3], i: u32, (u, v): (Vec3, Vec3)) -> [f64; 2] {
    let p = vertices[i as usize];
    [p.dot(u), p.dot(v)]
}

/// The triangles of the loops of one plane (outward `normal`) by ear clipping (within the
/// weld tolerance `tol`, else to rounding), holes joined to the loops around them first
/// ([`with_holes_bridged`]), or `None` when that cannot be done.
pub(super) fn clip_loops(vertices: &[Vec3], loops: &[Vec<u32>], normal: Vec3, tol: f64) -> Option<Vec<[u32; 3]>> {
    if loops.iter().any(|ids| ids.len() < 3) {
        return None; // (a sliver region whose sides were all straight creases)
    }
    let basis = plane_basis(normal);
    let pos = |i: u32| in_plane(vertices, i, basis);
    let mut out = Vec::new();
    for ids in with_holes_bridged(loops, pos)? {
        if ids.len() > MAX_LOOP {
            return None;
        }
        let pts: Vec<[f64; 2]> = ids.iter().map(|&i| pos(i)).collect();
        // two corners just over the weld apart can stand within it of each other's edges:
        // not simple within the weld, the loop may still be simple to rounding
        let tris = ear_clip(&pts, tol).or_else(|| ear_clip(&pts, 0.0))?;
        out.extend(tris.into_iter().map(|t| t.map(|k| ids[k])));
    }
    Some(out)
}

/// The loops of one plane as polygons to clip: each counter-clockwise (outer) loop with
/// the clockwise ones (holes) inside it joined in, each by a bridge there and back from its
/// rightmost vertex to a vertex of the outer loop it sees (Eberly's construction; holes
/// taken rightmost first, so the ray from each meets only the loop and the holes already
/// joined). `None` when a hole lies in no outer loop, or its ray meets nothing.
fn with_holes_bridged(loops: &[Vec<u32>], pos: impl Fn(u32) -> [f64; 2]) -> Option<Vec<Vec<u32>>> {
    let area = |ids: &[u32]| signed_area(&ids.iter().map(|&i| pos(i)).collect::<Vec<_>>());
    let (outers, holes): (Vec<&Vec<u32>>, Vec<&Vec<u32>>) = loops.iter().partition(|ids| area(ids) > 0.0);
    if holes.is_empty() {
        return Some(loops.to_vec());
    }
    let mut inner: Vec<Vec<&Vec<u32>>> = vec![Vec::new(); outers.len()];
    for hole in holes {
        // the smallest outer loop around a vertex of the hole it does not share
        let around = |o: &Vec<u32>| hole.iter().find(|v| !o.contains(v)).is_some_and(|&v| inside(o, pos(v), &pos));
        let k = (0..outers.len()).filter(|&k| around(outers[k])).min_by(|&a, &b| area(outers[a]).total_cmp(&area(outers[b])))?;
        inner[k].push(hole);
    }
    let rightmost = |ids: &[u32]| (0..ids.len()).max_by(|&a, &b| pos(ids[a]).partial_cmp(&pos(ids[b])).unwrap_or(std::cmp::Ordering::Equal)).unwrap_or(0);
    let mut out = Vec::with_capacity(outers.len());
    for (outer, mut holes) in outers.into_iter().zip(inner) {
        holes.sort_by(|a, b| pos(b[rightmost(b)]).partial_cmp(&pos(a[rightmost(a)])).unwrap_or(std::cmp::Ordering::Equal));
        let mut poly = outer.clone();
        for hole in holes {
            let m = rightmost(hole);
            let j = bridge_end(&poly, pos(hole[m]), &pos)?;
            let hole_from_m = (0..=hole.len()).map(|k| hole[(m + k) % hole.len()]);
            let joined: Vec<u32> = poly[..=j].iter().copied().chain(hole_from_m).chain(poly[j..].iter().copied()).collect();
            poly = joined;
        }
        out.push(poly);
    }
    Some(out)
}

/// Whether `q` lies inside the loop `ids` (crossings of the ray to `+x`).
pub(super) fn inside(ids: &[u32], q: [f64; 2], pos: &impl Fn(u32) -> [f64; 2]) -> bool {
    let mut odd = false;
    for i in 0..ids.len() {
        let (a, b) = (pos(ids[i]), pos(ids[(i + 1) % ids.len()]));
        if (a[1] > q[1]) != (b[1] > q[1]) && q[0] < a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) {
            odd = !odd;
        }
    }
    odd
}

/// The corner of the counter-clockwise polygon `poly` that the point `m` inside it sees
/// (Eberly): the end of larger `x` of the first edge the ray from `m` to `+x` meets going up
/// (where the ray leaves the polygon), unless corners lie in the triangle of `m`, that
/// meeting point and that end; then of those, the one nearest the ray's direction. A
/// corner the polygon passes twice (an earlier bridge's end) is taken where `m` lies in
/// its angle.
fn bridge_end(poly: &[u32], m: [f64; 2], pos: &impl Fn(u32) -> [f64; 2]) -> Option<usize> {
    let n = poly.len();
    let mut hit: Option<(f64, usize)> = None; // (x where the ray meets the edge, its corner)
    for i in 0..n {
        let (a, b) = (pos(poly[i]), pos(poly[(i + 1) % n]));
        if !(a[1] <= m[1] && m[1] <= b[1] && a[1] < b[1]) {
            continue;
        }
        let x = a[0] + (m[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
        if x < m[0] || hit.is_some_and(|(hx, _)| hx <= x) {
            continue;
        }
        let end = if x == a[0] && m[1] == a[1] {
            i
        } else if x == b[0] && m[1] == b[1] || a[0] <= b[0] {
            (i + 1) % n
        } else {
            i
        };
        hit = Some((x, end));
    }
    let (x, end) = hit?;
    let (i_pt, p) = ([x, m[1]], pos(poly[end]));
    if i_pt == p {
        return the_copy_around(poly, end, m, pos);
    }
    // corners strictly inside the triangle m, i_pt, p hide p: take the one at the least
    // angle to the ray (the nearest of those)
    let tri = if orient(m, i_pt, p) > 0.0 { [m, i_pt, p] } else { [m, p, i_pt] };
    let strictly_in = |q: [f64; 2]| (0..3).all(|k| orient(tri[k], tri[(k + 1) % 3], q) > 0.0);
    let key = |q: [f64; 2]| {
        let d = [q[0] - m[0], q[1] - m[1]];
        ((d[1].abs()).atan2(d[0]), d[0] * d[0] + d[1] * d[1])
    };
    let best = (0..n).filter(|&k| k != end && strictly_in(pos(poly[k]))).min_by(|&a, &b| key(pos(poly[a])).partial_cmp(&key(pos(poly[b]))).unwrap_or(std::cmp::Ordering::Equal));
    the_copy_around(poly, best.unwrap_or(end), m, pos)
}

/// Of the places the polygon passes corner `poly[k]`, the one whose angle (inside the
/// counter-clockwise polygon, between the edges in and out there) holds `m`; `None` when
/// none does.
fn the_copy_around(poly: &[u32], k: usize, m: [f64; 2], pos: &impl Fn(u32) -> [f64; 2]) -> Option<usize> {
    let n = poly.len();
    (0..n).filter(|&j| poly[j] == poly[k]).find(|&j| {
        let (a, p, b) = (pos(poly[(j + n - 1) % n]), pos(poly[j]), pos(poly[(j + 1) % n]));
        let (left_in, left_out) = (orient(a, p, m) >= 0.0, orient(p, b, m) >= 0.0);
        if orient(a, p, b) >= 0.0 {
            left_in && left_out // a convex corner: left of both edges
        } else {
            left_in || left_out // a reflex one: left of either
        }
    })
}

/// Relative distance (of the run's length and its ends' coordinates) within which a vertex
/// lies on the straight line between the ends of its run: rounding of the exact planes'
/// intersections, far below any feature.
const ON_LINE: f64 = 1e-10;

/// The vertices of the loops `loops` (per plane; `None`: a plane not merged) that lie
/// inside a straight crease between two regions, which both regions can leave out of their
/// outlines: each is a vertex of exactly two loops, between the same two neighbours in both
/// (in opposite order), not `pinned` (a vertex the band or a fanned polygon uses), and in
/// a run of such vertices whose every vertex lies on the line between the run's ends, in
/// order along it. A straight edge of the answer crossing many cells is split at every
/// cell wall; its outlines keep only its ends. The point set does not change.
fn straight_crease_vertices(vertices: &[Vec3], loops: &[Option<Vec<Vec<u32>>>], tol: f64, pinned: impl Fn(u32) -> bool) -> FastSet<u32> {
    // per vertex: its (previous, next) in each loop it is on (up to three kept)
    let mut seen: FastMap<u32, Vec<(u32, u32)>> = FastMap::default();
    for ids in loops.iter().flatten().flatten() {
        for (i, &v) in ids.iter().enumerate() {
            let (prev, next) = (ids[(i + ids.len() - 1) % ids.len()], ids[(i + 1) % ids.len()]);
            let list = seen.entry(v).or_default();
            if list.len() < 3 {
                list.push((prev, next));
            }
        }
    }
    let in_crease = |v: u32| match seen.get(&v).map(Vec::as_slice) {
        Some(&[(p1, n1), (p2, n2)]) => p1 == n2 && n1 == p2 && p1 != n1 && !pinned(v),
        _ => false,
    };
    // runs of such vertices between two others (anchors); the same run, with the same
    // anchors, is on both loops, and is judged the same way from either
    let mut out = FastSet::default();
    for ids in loops.iter().flatten().flatten() {
        let n = ids.len();
        let anchors: Vec<usize> = (0..n).filter(|&i| !in_crease(ids[i])).collect();
        for (k, &a) in anchors.iter().enumerate() {
            let b = anchors[(k + 1) % anchors.len()];
            let run: Vec<u32> = (1..(b + n - a) % n).map(|j| ids[(a + j) % n]).collect();
            if !run.is_empty() && on_segment(vertices, ids[a], ids[b], &run, tol) {
                out.extend(run);
            }
        }
    }
    out
}

/// Whether every vertex of `run` lies on the segment from `a` to `b` (within [`ON_LINE`],
/// and within the weld tolerance `weld`, the stitch's, far from the origin),
/// strictly between them and in order from `a`. The segment is measured from its end of
/// smaller index, so the answer is the same from both loops the run is on (there it runs
/// from `b` to `a`, reversed).
fn on_segment(vertices: &[Vec3], a: u32, b: u32, run: &[u32], weld: f64) -> bool {
    let (lo, hi) = (a.min(b), a.max(b));
    let (p, q) = (vertices[lo as usize], vertices[hi as usize]);
    let d = q - p;
    let len2 = d.dot(d);
    let tol = (ON_LINE * (len2.sqrt() + p.abs().max_element().max(q.abs().max_element()))).min(weld);
    if len2 <= tol * tol {
        return false;
    }
    let params: Option<Vec<f64>> = run
        .iter()
        .map(|&v| {
            let x = vertices[v as usize] - p;
            let t = x.dot(d) / len2;
            ((x - d * t).length() <= tol && t > 0.0 && t < 1.0).then_some(t)
        })
        .collect();
    let Some(params) = params else { return false };
    // from `a` towards `b`: rising along `lo → hi` when `a` is `lo`
    params.windows(2).all(|w| if a == lo { w[0] < w[1] } else { w[0] > w[1] })
}

/// The polygons with the corners of others that lie on their edges (within `tol`) put in,
/// in order along each edge: where a large cell's polygon meets smaller cells' polygons,
/// on its plane (so that the edges it shares with them cancel) or across a crease (so that
/// the triangles on either side of it share their vertices).
fn with_corners_on_edges(vertices: &[Vec3], polys: &[Vec<u32>], tol: f64) -> Vec<Vec<u32>> {
    let edges: Vec<(u32, u32)> = polys.iter().flat_map(|p| (0..p.len()).map(move |i| (p[i], p[(i + 1) % p.len()]))).collect();
    let mut corners: Vec<u32> = polys.iter().flatten().copied().collect();
    corners.sort_unstable();
    corners.dedup();
    let on = stitch::points_on_edges(vertices, &edges, &corners, tol);
    let mut out = Vec::with_capacity(polys.len());
    let mut e = 0usize;
    for p in polys {
        let mut ids = Vec::with_capacity(p.len());
        for &a in p {
            ids.push(a);
            ids.extend(on.get(&e).into_iter().flatten());
            e += 1;
        }
        ids.dedup();
        if ids.len() > 1 && ids[0] == ids[ids.len() - 1] {
            ids.pop();
        }
        out.push(ids);
    }
    out
}

/// The loops of the edges left when each edge used both ways cancels (as often as it is
/// used the other way); `None` when an edge is left more than once. Where loops touch at a
/// vertex (it starts several edges left), each edge arriving there goes on by the edge
/// leaving it first clockwise from where it came from (`angle(a, b)`: the direction of
/// `a → b` in the plane, counter-clockwise about the outward normal): the loops of regions
/// touching at a corner stay apart, each around its own region.
fn boundary_loops(edges: &[(u32, u32)], angle: impl Fn(u32, u32) -> f64) -> Option<Vec<Vec<u32>>> {
    let mut count: FastMap<(u32, u32), i32> = FastMap::default();
    for &e in edges {
        *count.entry(e).or_default() += 1;
    }
    let mut next: FastMap<u32, Vec<u32>> = FastMap::default();
    let mut left_edges: Vec<(u32, u32)> = Vec::new();
    for (&(a, b), &c) in &count {
        let left = c - count.get(&(b, a)).copied().unwrap_or(0);
        if left > 1 {
            return None;
        }
        if left == 1 {
            next.entry(a).or_default().push(b);
            left_edges.push((a, b));
        }
    }
    left_edges.sort_unstable(); // a deterministic order of the loops
                                // where several edges leave a vertex: the one each arriving edge goes on by (distinct,
                                // else the regions overlap there)
    let mut turn: FastMap<(u32, u32), u32> = FastMap::default();
    for &(p, at) in &left_edges {
        let out = &next[&at];
        if out.len() > 1 {
            turn.insert((p, at), first_clockwise(angle(at, p), out, |w| angle(at, w))?);
        }
    }
    let mut taken: FastSet<(u32, u32)> = FastSet::default();
    for (&(_, at), &to) in &turn {
        if !taken.insert((at, to)) {
            return None;
        }
    }
    let mut used: FastSet<(u32, u32)> = FastSet::default();
    let mut loops = Vec::new();
    for &start in &left_edges {
        if used.contains(&start) {
            continue;
        }
        let (mut ids, mut e) = (Vec::new(), start);
        loop {
            if !used.insert(e) {
                return None;
            }
            ids.push(e.0);
            let to = match turn.get(&e) {
                Some(&to) => to,
                None => *next.get(&e.1)?.first()?,
            };
            e = (e.1, to);
            if e == start {
                break;
            }
        }
        loops.push(ids);
    }
    // a vertex twice in one loop (the walk passed a touching corner it started at) is not
    // a simple loop
    for ids in &loops {
        let mut sorted = ids.clone();
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return None;
        }
    }
    Some(loops)
}

/// Of the candidates, the one whose direction (`dir`) comes first turning clockwise from
/// the direction `back` (towards where the walk came from).
fn first_clockwise(back: f64, candidates: &[u32], dir: impl Fn(u32) -> f64) -> Option<u32> {
    let tau = std::f64::consts::TAU;
    candidates.iter().map(|&w| (w, (back - dir(w)).rem_euclid(tau))).filter(|&(_, turn)| turn > 0.0).min_by(|a, b| a.1.total_cmp(&b.1)).map(|(w, _)| w)
}

/// Two unit vectors spanning the plane of normal `n`, with `u × v` along `n`.
fn plane_basis(n: Vec3) -> (Vec3, Vec3) {
    let n = n.normalize();
    let helper = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let u = n.cross(helper).normalize();
    (u, n.cross(u))
}

/// Twice the signed area of the 2D loop (positive: counter-clockwise).
fn signed_area(p: &[[f64; 2]]) -> f64 {
    (0..p.len()).map(|i| cross(p[i], p[(i + 1) % p.len()])).sum()
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// `(b − a) × (c − a)`: positive when `a, b, c` turn counter-clockwise.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Relative size below which a turn counts as straight (to rounding).
const STRAIGHT: f64 = 1e-12;

/// The triangles (corner positions in `p`) of the counter-clockwise simple polygon `p`,
/// by ear clipping: a corner is cut off when it stands clear of the line through its
/// neighbours by more than `tol` (a corner welded onto a straight run, within `tol` of it,
/// is part of the run: cut off, it would leave a sliver) and no other corner lies in its
/// triangle or within `tol` of it; `None` when no corner can be (a polygon not simple
/// within `tol`). Straight corners are kept until an ear takes them.
fn ear_clip(p: &[[f64; 2]], tol: f64) -> Option<Vec<[usize; 3]>> {
    let mut left: Vec<usize> = (0..p.len()).collect();
    let mut out = Vec::with_capacity(p.len().saturating_sub(2));
    let mut i = 0usize;
    let mut tried = 0usize;
    while left.len() > 3 {
        let m = left.len();
        let (a, b, c) = (left[(i + m - 1) % m], left[i % m], left[(i + 1) % m]);
        if is_ear(p, &left, [a, b, c], tol) {
            out.push([a, b, c]);
            left.remove(i % m);
            i = (i + m - 2) % (m - 1); // back to the corner before: it may be an ear now
            tried = 0;
        } else {
            i = (i + 1) % m;
            tried += 1;
            if tried > m {
                return None;
            }
        }
    }
    let last = [left[0], left[1], left[2]];
    stands_clear(p, last, tol).then(|| out.push(last))?;
    Some(out)
}

fn distance(x: [f64; 2], y: [f64; 2]) -> f64 {
    (x[0] - y[0]).hypot(x[1] - y[1])
}

/// Whether the middle corner of `t` turns left and stands clear of the line through the
/// other two by more than `tol` (and by more than rounding).
fn stands_clear(p: &[[f64; 2]], [a, b, c]: [usize; 3], tol: f64) -> bool {
    let ac = distance(p[a], p[c]);
    orient(p[a], p[b], p[c]) > (STRAIGHT * distance(p[a], p[b]) * ac).max(tol * ac)
}

/// Whether the corner `t[1]` (between `t[0]` and `t[2]`) of the polygon of corners `left`
/// is an ear: it stands clear ([`stands_clear`]) and no other corner lies in the triangle
/// or within `tol` outside it.
fn is_ear(p: &[[f64; 2]], left: &[usize], t: [usize; 3], tol: f64) -> bool {
    if !stands_clear(p, t, tol) {
        return false;
    }
    let [a, b, c] = t.map(|k| p[k]);
    let within = |x: [f64; 2], y: [f64; 2], q: [f64; 2]| orient(x, y, q) >= -tol * distance(x, y);
    // (a corner at one of the triangle's own, as a bridge's ends are twice, does not hide it)
    left.iter().all(|&k| t.contains(&k) || [a, b, c].contains(&p[k]) || !(within(a, b, p[k]) && within(b, c, p[k]) && within(c, a, p[k])))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The index of `p` in `vertices`, appended if it is not there.
    fn intern(vertices: &mut Vec<Vec3>, p: Vec3) -> u32 {
        match vertices.iter().position(|&q| q == p) {
            Some(i) => i as u32,
            None => {
                vertices.push(p);
                vertices.len() as u32 - 1
            }
        }
    }

    /// Unit squares of a 2x2 grid and a 2x2 square beside them on `z = 0` (facing up),
    /// its side split at the grid's corner there only in the grid's polygons: one region,
    /// an outline of 9 corners (five straight), triangulated once into 7 triangles.
    #[test]
    fn squares_on_a_plane_become_one_region() {
        let mut vertices: Vec<Vec3> = Vec::new();
        let mut id = |x: f64, y: f64| intern(&mut vertices, Vec3::new(x, y, 0.0));
        let mut polys = Vec::new();
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            polys.push(vec![id(x, y), id(x + 1.0, y), id(x + 1.0, y + 1.0), id(x, y + 1.0)]);
        }
        polys.push(vec![id(2.0, 0.0), id(4.0, 0.0), id(4.0, 2.0), id(2.0, 2.0)]); // T-junction at (2, 1)
        let keys = vec![plane_key(Vec3::Z, 0.0); polys.len()];
        let before = vertices.len();
        let (faces, stats) = triangulate(&mut vertices, &polys, &keys, 1e-9, 0);
        assert_eq!(stats, RegionStats { merged_planes: 1, fanned_planes: 0, straight_dropped: 0, unfolded: 0 });
        assert_eq!(vertices.len(), before, "no centroid added");
        // the outline: (0,0) (1,0) (2,0) (4,0) (4,2) (2,2) (1,2) (0,2) (0,1): 7 triangles
        assert_eq!(faces.len(), 7, "{faces:?}");
        let area: f64 = faces.iter().map(|f| (vertices[f[1] as usize] - vertices[f[0] as usize]).cross(vertices[f[2] as usize] - vertices[f[0] as usize]).z / 2.0).sum();
        assert!((area - 8.0).abs() < 1e-12, "area {area}");
        assert!(faces.iter().all(|f| (vertices[f[1] as usize] - vertices[f[0] as usize]).cross(vertices[f[2] as usize] - vertices[f[0] as usize]).z > 0.0), "all face up");
        // interior (1, 1) is no corner of any triangle
        let centre = vertices.iter().position(|&q| q == Vec3::new(1.0, 1.0, 0.0)).expect("a grid corner") as u32;
        assert!(faces.iter().all(|f| !f.contains(&centre)));
    }

    /// Two planes meeting in a straight crease along y (the top `z = 0` and the side
    /// `x = 2` of a box's edge), each made of unit squares: the crease's two inner vertices
    /// are in both outlines between the same neighbours, and both leave them out, so the
    /// crease is one edge, used once each way; a vertex the band uses (below `kept`) stays.
    #[test]
    fn straight_crease_vertices_are_left_out_of_both_regions() {
        for kept in [0usize, 1] {
            let mut vertices: Vec<Vec3> = vec![Vec3::new(2.0, 1.0, 0.0)]; // the band's, when kept = 1
            let mut id = |x: f64, y: f64, z: f64| intern(&mut vertices, Vec3::new(x, y, z));
            let (mut polys, mut keys) = (Vec::new(), Vec::new());
            for k in 0..3 {
                let y = k as f64;
                for x in [0.0, 1.0] {
                    polys.push(vec![id(x, y, 0.0), id(x + 1.0, y, 0.0), id(x + 1.0, y + 1.0, 0.0), id(x, y + 1.0, 0.0)]);
                    keys.push(plane_key(Vec3::Z, 0.0));
                }
                polys.push(vec![id(2.0, y, -1.0), id(2.0, y + 1.0, -1.0), id(2.0, y + 1.0, 0.0), id(2.0, y, 0.0)]);
                keys.push(plane_key(Vec3::X, 2.0));
            }
            let (faces, stats) = triangulate(&mut vertices, &polys, &keys, 1e-9, kept);
            assert_eq!(stats, RegionStats { merged_planes: 2, fanned_planes: 0, straight_dropped: 2 - kept, unfolded: 0 }, "kept {kept}");
            let used = |p: Vec3| faces.iter().any(|f| f.iter().any(|&v| vertices[v as usize] == p));
            assert_eq!(used(Vec3::new(2.0, 1.0, 0.0)), kept == 1);
            assert!(!used(Vec3::new(2.0, 2.0, 0.0)));
            // outlines of 10 − 2 + kept and 8 − 2 + kept corners
            assert_eq!(faces.len(), 8 + 6 - 4 + 2 * kept, "{faces:?}");
            // every edge on the crease is used once each way
            let mut count: FastMap<(u32, u32), i32> = FastMap::default();
            for f in &faces {
                for i in 0..3 {
                    *count.entry((f[i], f[(i + 1) % 3])).or_default() += 1;
                }
            }
            let on_crease = |v: u32| vertices[v as usize].x == 2.0 && vertices[v as usize].z == 0.0;
            for (&(a, b), &c) in &count {
                if on_crease(a) && on_crease(b) {
                    assert_eq!((c, count.get(&(b, a)).copied()), (1, Some(1)), "crease edge {a}-{b}");
                }
            }
        }
    }

    /// A run lies on its segment only in order along it and within rounding of the line.
    #[test]
    fn a_run_on_a_segment() {
        let v = vec![Vec3::ZERO, Vec3::new(3.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 1e-6, 0.0)];
        assert!(on_segment(&v, 0, 1, &[2, 3], 1e-9));
        assert!(on_segment(&v, 1, 0, &[3, 2], 1e-9), "either way round");
        assert!(!on_segment(&v, 0, 1, &[3, 2], 1e-9), "out of order");
        assert!(!on_segment(&v, 0, 1, &[2, 4], 1e-9), "off the line");
        assert!(!on_segment(&v, 0, 2, &[3], 1e-9), "past the end");
    }

    /// Two squares of one plane touching at a corner, and a square touching an L of three
    /// at its outer corner: each region keeps its own loop (the edge arriving at the
    /// shared corner goes on by the first edge clockwise), so the planes merge.
    #[test]
    fn regions_touching_at_a_corner_keep_their_own_loops() {
        let mut vertices: Vec<Vec3> = Vec::new();
        let mut id = |x: f64, y: f64| intern(&mut vertices, Vec3::new(x, y, 0.0));
        let square = |id: &mut dyn FnMut(f64, f64) -> u32, x: f64, y: f64| vec![id(x, y), id(x + 1.0, y), id(x + 1.0, y + 1.0), id(x, y + 1.0)];
        let polys = vec![square(&mut id, 0.0, 0.0), square(&mut id, 1.0, 1.0)];
        let keys = vec![plane_key(Vec3::Z, 0.0); 2];
        let (faces, stats) = triangulate(&mut vertices, &polys, &keys, 1e-9, 0);
        assert_eq!((stats.merged_planes, stats.fanned_planes, faces.len()), (1, 0, 4), "{faces:?}");
        let mut vertices: Vec<Vec3> = Vec::new();
        let mut id = |x: f64, y: f64| intern(&mut vertices, Vec3::new(x, y, 0.0));
        let polys: Vec<Vec<u32>> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (2.0, 1.0)].iter().map(|&(x, y)| square(&mut id, x, y)).collect();
        let keys = vec![plane_key(Vec3::Z, 0.0); polys.len()];
        let (faces, stats) = triangulate(&mut vertices, &polys, &keys, 1e-9, 0);
        assert_eq!((stats.merged_planes, stats.fanned_planes), (1, 0));
        let area: f64 = faces.iter().map(|f| (vertices[f[1] as usize] - vertices[f[0] as usize]).cross(vertices[f[2] as usize] - vertices[f[0] as usize]).z / 2.0).sum();
        assert!((area - 4.0).abs() < 1e-12, "area {area}");
    }

    /// A square region with two square holes (a ring of cells around each, as a face of a
    /// grate's sum meets the band there): one region, its holes bridged in, triangulated
    /// once with every triangle facing up and the area of the square less the holes'.
    #[test]
    fn a_region_with_holes_is_bridged_and_clipped_once() {
        let mut vertices: Vec<Vec3> = Vec::new();
        let mut id = |x: f64, y: f64| intern(&mut vertices, Vec3::new(x, y, 0.0));
        let mut polys = Vec::new();
        for x in 0..7 {
            for y in 0..5 {
                if (x, y) != (1, 2) && (x, y) != (5, 2) {
                    let (x, y) = (x as f64, y as f64);
                    polys.push(vec![id(x, y), id(x + 1.0, y), id(x + 1.0, y + 1.0), id(x, y + 1.0)]);
                }
            }
        }
        let keys = vec![plane_key(Vec3::Z, 0.0); polys.len()];
        let before = vertices.len();
        let (faces, stats) = triangulate(&mut vertices, &polys, &keys, 1e-9, 0);
        assert_eq!((stats.merged_planes, stats.fanned_planes), (1, 0));
        assert_eq!(vertices.len(), before, "no centroid added");
        let area = |f: &[u32; 3]| (vertices[f[1] as usize] - vertices[f[0] as usize]).cross(vertices[f[2] as usize] - vertices[f[0] as usize]).z / 2.0;
        assert!(faces.iter().all(|f| area(f) > 0.0), "all face up");
        let total: f64 = faces.iter().map(area).sum();
        assert!((total - 33.0).abs() < 1e-12, "area {total}");
        // an outline of 24 corners (the open boundary keeps its straight ones) and two holes
        // of 4: n + 2 h − 2 triangles
        assert_eq!(faces.len(), 24 + 4 + 4 + 2 * 2 - 2, "{} triangles", faces.len());
        // every edge used once each way, but the outline's and the holes'
        let mut count: FastMap<(u32, u32), i32> = FastMap::default();
        for f in &faces {
            for i in 0..3 {
                *count.entry((f[i], f[(i + 1) % 3])).or_default() += 1;
            }
        }
        let single = count.keys().filter(|&&(a, b)| !count.contains_key(&(b, a))).count();
        assert_eq!(single, 24 + 4 + 4, "outline edges");
    }

    /// A loop from a sum's facet whose two corners lie just over the weld apart, one of them
    /// reflex by less than the weld: not simple within the weld, so that clipping fails;
    /// simple to rounding, it is clipped exactly, every triangle turning left.
    #[test]
    fn a_loop_simple_only_to_rounding_is_clipped_exactly() {
        let p = [
            [-1.4039817539349981, -2.640148344701439],
            [-1.395154729323091, -2.657850309921108],
            [-1.3951618469542844, -2.657867447885093],
            [-1.3906043119398677, -2.6669758458512143],
            [-1.3795774163759644, -2.6516718645166524],
        ];
        let tol = 1.8335362345687105e-05;
        assert!(ear_clip(&p, tol).is_none());
        let (vertices, ids): (Vec<Vec3>, Vec<u32>) = p.iter().enumerate().map(|(i, q)| (Vec3::new(q[0], q[1], 0.0), i as u32)).unzip();
        let tris = clip_loops(&vertices, &[ids], Vec3::Z, tol).expect("clipped to rounding");
        assert_eq!(tris.len(), 3);
        let area = |t: &[u32; 3]| orient(p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
        assert!(tris.iter().all(|t| area(t) > 0.0));
        assert!((tris.iter().map(area).sum::<f64>() - signed_area(&p)).abs() < 1e-15);
    }

    /// Random regions of jittered grid cells with holes of one to four cells (apart from
    /// each other and from the outline): every plane merges, its triangles turning left and
    /// covering the cells' area. Bridges then often end at earlier bridges' ends, where
    /// the polygon passes a corner twice: a bridge from the wrong copy of it crosses the
    /// polygon, and the plane could not be clipped.
    #[test]
    fn jittered_regions_with_holes_are_clipped_once() {
        const N: usize = 10;
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for case in 0..200 {
            let mut vertices: Vec<Vec3> = Vec::new();
            for i in 0..=N {
                for j in 0..=N {
                    vertices.push(Vec3::new(i as f64 + 0.6 * next() - 0.3, j as f64 + 0.6 * next() - 0.3, 0.0));
                }
            }
            let id = |i: usize, j: usize| (i * (N + 1) + j) as u32;
            let mut removed: Vec<(usize, usize)> = Vec::new();
            for _ in 0..4 {
                let pick = |x: f64| 1 + (x * (N - 2) as f64) as usize % (N - 2);
                let mut blob = vec![(pick(next()), pick(next()))];
                for _ in 0..(next() * 4.0) as usize {
                    let (a, b) = blob[(next() * blob.len() as f64) as usize % blob.len()];
                    let c = [(a + 1, b), (a - 1, b), (a, b + 1), (a, b - 1)][(next() * 4.0) as usize % 4];
                    if (1..N - 1).contains(&c.0) && (1..N - 1).contains(&c.1) && !blob.contains(&c) {
                        blob.push(c);
                    }
                }
                let near = |&(a, b): &(usize, usize)| removed.iter().any(|&(x, y)| x.abs_diff(a) <= 1 && y.abs_diff(b) <= 1);
                if !blob.iter().any(near) {
                    removed.extend(blob);
                }
            }
            let polys: Vec<Vec<u32>> = (0..N)
                .flat_map(|i| (0..N).map(move |j| (i, j)))
                .filter(|c| !removed.contains(c))
                .map(|(i, j)| vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
                .collect();
            let area_in = |vertices: &[Vec3], ids: &[u32]| signed_area(&ids.iter().map(|&v| [vertices[v as usize].x, vertices[v as usize].y]).collect::<Vec<_>>()) / 2.0;
            let expected: f64 = polys.iter().map(|p| area_in(&vertices, p)).sum();
            let keys = vec![plane_key(Vec3::Z, 0.0); polys.len()];
            let (faces, stats) = triangulate(&mut vertices, &polys, &keys, 1e-9, 0);
            let area = |ids: &[u32]| area_in(&vertices, ids);
            assert_eq!((stats.merged_planes, stats.fanned_planes), (1, 0), "case {case}: {} cells removed", removed.len());
            assert!(faces.iter().all(|f| area(f) > 0.0), "case {case}: a triangle turns right");
            let total: f64 = faces.iter().map(|f| area(f)).sum();
            assert!((total - expected).abs() < 1e-9 * expected, "case {case}: {total} vs {expected}");
        }
    }

    /// Ear clipping a comb-like polygon with straight runs: `n − 2` triangles, all turning
    /// left, their area the polygon's.
    #[test]
    fn ear_clipping_covers_a_comb() {
        let mut p: Vec<[f64; 2]> = vec![[0.0, 0.0]];
        for k in 0..10 {
            let x = k as f64;
            p.extend([[x + 0.25, 0.0], [x + 0.5, 0.0], [x + 0.5, 1.0], [x + 0.75, 1.0], [x + 0.75, 0.0]]);
        }
        p.extend([[10.0, 0.0], [10.0, -1.0], [5.0, -1.0], [0.0, -1.0]]);
        p.reverse(); // counter-clockwise
        let tris = ear_clip(&p, 1e-9).expect("a simple polygon");
        assert_eq!(tris.len(), p.len() - 2);
        let area: f64 = tris.iter().map(|t| orient(p[t[0]], p[t[1]], p[t[2]]) / 2.0).sum();
        assert!((area - signed_area(&p) / 2.0).abs() < 1e-12, "{area}");
        assert!(tris.iter().all(|t| orient(p[t[0]], p[t[1]], p[t[2]]) > 0.0));
    }
}
