//! The exact polygons of plane-resolved cells merged, plane by plane, into regions that are
//! triangulated once.
//!
//! Every cell resolved by planes gives convex polygons on the planes of its candidates; a
//! flat facet of the answer crosses many cells, so it arrives as many polygons. First every
//! polygon takes in the corners of other polygons lying on its edges (where a large cell
//! meets smaller ones: on its plane, so that the edges they share cancel below, or across
//! a crease, so that both sides of it share their vertices). Then on each plane (polygons
//! whose outward planes agree to rounding) an edge used once each way cancels; what is
//! left is the regions' boundary, and each of its loops is triangulated by ear clipping in
//! the plane with every boundary vertex kept (the neighbouring regions and the band use
//! them). A facet crossing a thousand cells thus comes out in about as many triangles as
//! its boundary has vertices, not four per cell to be collapsed afterwards.
//!
//! A plane keeps its polygons, each fanned about its centroid as before, when its boundary
//! is not simple loops around regions without holes (a vertex where two loops touch, a
//! hole, an ear not found: not simple within the weld tolerance, a loop longer than
//! [`MAX_LOOP`]), or when it shares a corner with a plane facing the other way (two sheets
//! through the same points would share diagonals). Either way the triangles cover the
//! same point set as the polygons.
//!
//! Entry point: [`triangulate`].

use super::stitch;
use crate::math::Vec3;
use crate::util::FastMap;
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
}

/// Triangles of the polygons `polys` (corners welded to indices of `vertices`, each
/// counter-clockwise about its outward normal), polygon `i` lying on the plane
/// `keys[i]`: per plane, merged into regions triangulated once where that can be done
/// (see the module documentation), else each fanned about its centroid (a vertex appended
/// to `vertices`). `tol`: the weld tolerance, within which a corner lies on another
/// polygon's edge.
pub fn triangulate(vertices: &mut Vec<Vec3>, polys: &[Vec<u32>], keys: &[PlaneKey], tol: f64) -> (Vec<[u32; 3]>, RegionStats) {
    let polys = &with_corners_on_edges(vertices, polys, tol);
    let group: Vec<[i64; 4]> = keys.iter().map(|k| group_of(k, tol)).collect();
    let mut order: Vec<usize> = (0..polys.len()).collect();
    order.sort_by_key(|&i| group[i]);
    let groups: Vec<&[usize]> = order.chunk_by(|&a, &b| group[a] == group[b]).collect();
    let verts: &[Vec3] = vertices;
    let normals: Vec<Vec3> = groups.iter().map(|g| Vec3::new(keys[g[0]][0], keys[g[0]][1], keys[g[0]][2])).collect();
    let sheets = opposite_sheets(polys, &groups, &normals);
    let merged: Vec<Option<Vec<[u32; 3]>>> = groups
        .par_iter()
        .enumerate()
        .map(|(g, group)| {
            // two sheets facing each other through the same points: triangulated the same
            // way, they would share diagonals; fanned, each keeps its own centres
            if sheets[g] {
                return None;
            }
            region_triangles(verts, group.iter().map(|&i| polys[i].as_slice()), normals[g], tol)
        })
        .collect();
    let mut faces = Vec::new();
    let mut stats = RegionStats::default();
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

/// The triangles of the regions the polygons of one plane (outward `normal`) make up, or
/// `None` when their boundary is not simple loops around regions without holes, or a loop
/// cannot be clipped.
fn region_triangles<'a>(vertices: &[Vec3], polys: impl Iterator<Item = &'a [u32]>, normal: Vec3, tol: f64) -> Option<Vec<[u32; 3]>> {
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for p in polys {
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            if a != b {
                edges.push((a, b));
            }
        }
    }
    let loops = boundary_loops(&edges)?;
    let (u, v) = plane_basis(normal);
    let mut out = Vec::new();
    for ids in loops {
        if ids.len() > MAX_LOOP {
            return None;
        }
        let pts: Vec<[f64; 2]> = ids.iter().map(|&i| vertices[i as usize]).map(|p| [p.dot(u), p.dot(v)]).collect();
        if signed_area(&pts) <= 0.0 {
            return None; // a hole (or a loop of no area)
        }
        out.extend(ear_clip(&pts, tol)?.into_iter().map(|t| t.map(|k| ids[k])));
    }
    Some(out)
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
/// used the other way); `None` when an edge is left more than once or a vertex starts
/// more than one (loops touching there).
fn boundary_loops(edges: &[(u32, u32)]) -> Option<Vec<Vec<u32>>> {
    let mut count: FastMap<(u32, u32), i32> = FastMap::default();
    for &e in edges {
        *count.entry(e).or_default() += 1;
    }
    let mut next: FastMap<u32, u32> = FastMap::default();
    let mut starts: Vec<u32> = Vec::new();
    for (&(a, b), &c) in &count {
        let left = c - count.get(&(b, a)).copied().unwrap_or(0);
        if left > 1 || (left == 1 && next.insert(a, b).is_some()) {
            return None;
        }
        if left == 1 {
            starts.push(a);
        }
    }
    starts.sort_unstable(); // a deterministic order of the loops
    let mut done: FastMap<u32, ()> = FastMap::default();
    let mut loops = Vec::new();
    for s in starts {
        if done.contains_key(&s) {
            continue;
        }
        let mut ids = vec![s];
        done.insert(s, ());
        let mut at = *next.get(&s)?;
        while at != s {
            if done.insert(at, ()).is_some() {
                return None;
            }
            ids.push(at);
            at = *next.get(&at)?;
        }
        loops.push(ids);
    }
    Some(loops)
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
    left.iter().all(|&k| t.contains(&k) || !(within(a, b, p[k]) && within(b, c, p[k]) && within(c, a, p[k])))
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
        let (faces, stats) = triangulate(&mut vertices, &polys, &keys, 1e-9);
        assert_eq!(stats, RegionStats { merged_planes: 1, fanned_planes: 0 });
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

    /// A ring of squares around a hole is a region with a hole: its polygons are fanned
    /// as they were, on their own plane, while those of another plane merge.
    #[test]
    fn a_holed_region_keeps_its_polygons() {
        let mut vertices: Vec<Vec3> = Vec::new();
        let mut id = |x: f64, y: f64, z: f64| intern(&mut vertices, Vec3::new(x, y, z));
        let mut polys = Vec::new();
        let mut keys = Vec::new();
        for x in 0..3 {
            for y in 0..3 {
                if (x, y) != (1, 1) {
                    let (x, y) = (x as f64, y as f64);
                    polys.push(vec![id(x, y, 0.0), id(x + 1.0, y, 0.0), id(x + 1.0, y + 1.0, 0.0), id(x, y + 1.0, 0.0)]);
                    keys.push(plane_key(Vec3::Z, 0.0));
                }
            }
        }
        for y in 0..2 {
            let y = y as f64;
            polys.push(vec![id(0.0, y, 5.0), id(1.0, y, 5.0), id(1.0, y + 1.0, 5.0), id(0.0, y + 1.0, 5.0)]);
            keys.push(plane_key(Vec3::Z, 5.0));
        }
        let before = vertices.len();
        let (faces, stats) = triangulate(&mut vertices, &polys, &keys, 1e-9);
        assert_eq!(stats, RegionStats { merged_planes: 1, fanned_planes: 1 });
        assert_eq!(vertices.len(), before + 8, "a centroid per fanned square");
        assert_eq!(faces.len(), 8 * 4 + 4, "{} triangles", faces.len());
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
