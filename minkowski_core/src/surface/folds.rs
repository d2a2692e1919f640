//! Folds in a plane: where the joined surface turns back onto itself within one plane.
//!
//! Two triangles that share an edge, lie in one plane and face opposite ways overlap: the
//! surface folds back there, covering part of the plane once each way. That bounds
//! nothing, but no clean solid has it (a solid check sees faces facing opposite ways
//! overlap). It is left where regions of one plane facing opposite ways meet, each
//! triangulated on its own, and their corners are welded.
//!
//! Each connected patch of faces lying in the plane of a fold (every corner within the
//! weld of it) is replaced by the triangulation of its net cover. Its triangles' edges,
//! an edge used both ways cancelling, leave the boundary loops of what it covers once,
//! which are ear-clipped facing the way they turn ([`super::regions`]). The loops are the
//! patch's own edges toward the rest of the surface, so its neighbours keep their
//! pairing. Two kinds of outline are dealt with first:
//!
//! - a needle, an edge and a chain of corners running back along it within the weld:
//!   nothing is covered; the patch goes, and the face across the needle's long edge takes
//!   the chain's corners instead, fanned from its far corner over them (T-junctions: the
//!   surface moves by no more than the weld);
//! - an outline that crosses itself (a part of the patch facing one way, a part the
//!   other): the crossing point is put on both edges (the faces beside each split there,
//!   nothing moved), and the outline comes apart there into loops that each turn one way,
//!   in the next round.
//!
//! A patch is replaced only where each of its faces lies within a reach (a few welds, in
//! the caller's bound) of one piece of what is left of it: a new triangle or an edge of
//! its outline (a sheet of the answer thinner than the weld, folded into the plane, is
//! left to the caller, whose bound must reach it), and only where no new edge is one the
//! rest of the surface already has. A patch whose outline is still not simple loops, or
//! whose loops nest but do not clip, is left as it is.
//!
//! Entry point: [`unfold`].

use super::regions;
use crate::math::Vec3;
use crate::polytope::point_triangle_distance2;
use crate::util::{faces_by_edge, FastMap};

/// The least `−cos` of the angle between two faces' normals at a fold (within 8° of
/// opposite: a sliver's normal is rounded more than a wide face's).
const FOLD_COS: f64 = 0.99;

/// The most faces a patch takes; a larger one is left as it is (clipping is quadratic in
/// the loops' length).
const MAX_PATCH: usize = 4096;

/// The most rounds of crossing points put on edges.
const MAX_ROUNDS: usize = 8;

/// The most (face, piece) pairs [`reach_of_removal`] measures; a patch needing more is
/// left as it is.
const MAX_REACH_PAIRS: usize = 1 << 22;

/// Replace every patch of faces in the plane of a fold by the triangles of its net cover
/// (see the module documentation); `tol` is the weld tolerance, `max_reach` how far a
/// removed face may lie from what is left. Returns how many patches were replaced, and
/// the farthest a removed face lay from what is left or a needle's corner from its edge.
/// Vertices inside a patch may be left unused; crossing points are appended to
/// `vertices`.
pub fn unfold(vertices: &mut Vec<Vec3>, faces: &mut Vec<[u32; 3]>, tol: f64, max_reach: f64) -> (usize, f64) {
    let (mut replaced, mut moved) = (0, 0.0f64);
    for _ in 0..MAX_ROUNDS {
        if crate::deadline::cancelled() {
            break;
        }
        let round = unfold_round(vertices, faces, tol, max_reach);
        replaced += round.replaced;
        moved = moved.max(round.moved);
        if round.splits == 0 && round.deferred == 0 {
            break;
        }
    }
    (replaced, moved)
}

/// What one round of [`unfold`] did: patches replaced, crossing points put on edges,
/// patches left for the next round (a face of theirs split for a neighbour), and the
/// farthest move.
#[derive(Default)]
struct Round {
    replaced: usize,
    splits: usize,
    deferred: usize,
    moved: f64,
}

/// An edge (as an outline runs) and the vertex to put on it.
type EdgeAt = ((u32, u32), u32);

/// What a patch becomes.
enum Cover {
    /// The triangles of what it covers once, and its outline's edges.
    Triangles(Vec<[u32; 3]>, Vec<(u32, u32)>),
    /// Nothing: the needle's long edge (as the outline runs), the chain of its corners to
    /// put on that edge, and how far the farthest is off it.
    Needle((u32, u32), Vec<u32>, f64),
    /// Loops, once the point where the outline crosses itself is put on both edges.
    Crossing([EdgeAt; 2]),
}

/// One round of [`unfold`].
fn unfold_round(vertices: &mut Vec<Vec3>, faces: &mut Vec<[u32; 3]>, tol: f64, max_reach: f64) -> Round {
    let by_edge = faces_by_edge(faces);
    let seeds = fold_seeds(vertices, faces, &by_edge, tol);
    let mut round = Round::default();
    if seeds.is_empty() {
        return round;
    }
    let mut taken = vec![false; faces.len()];
    // per face: gone (replaced), or split at a vertex on one of its edges
    let mut gone = vec![false; faces.len()];
    let mut split: FastMap<u32, EdgeAt> = FastMap::default();
    let mut added: Vec<[u32; 3]> = Vec::new();
    for seed in seeds {
        if taken[seed as usize] {
            continue;
        }
        let plane = plane_of(vertices, &faces[seed as usize]);
        let patch = grow_patch(vertices, faces, &by_edge, seed, plane, tol, &mut taken);
        if patch.len() > MAX_PATCH {
            continue;
        }
        let in_patch: FastMap<u32, ()> = patch.iter().map(|&f| (f, ())).collect();
        let busy = |f: &u32| gone[*f as usize] || split.contains_key(f);
        match net_cover(vertices, faces, &patch, plane.0, tol) {
            Some(Cover::Triangles(tris, outline)) => {
                if patch.iter().any(busy) {
                    round.deferred += 1;
                    continue;
                }
                let reach = reach_of_removal(vertices, faces, &patch, &tris, &outline);
                if reach > max_reach || !fits(&tris, &by_edge, &in_patch) {
                    continue;
                }
                for &f in &patch {
                    gone[f as usize] = true;
                }
                added.extend(tris);
                round.replaced += 1;
                round.moved = round.moved.max(reach);
            }
            Some(Cover::Needle((a, b), chain, off)) => {
                // the face across the long edge is fanned over the chain's corners: the
                // fan's new edges to its far corner must be new to the surface
                let Some(&across) = by_edge.get(&(b, a)) else { continue };
                if patch.iter().any(busy) || busy(&across) {
                    round.deferred += 1;
                    continue;
                }
                let halves = fan_along(faces[across as usize], (a, b), &chain);
                let reach = reach_of_removal(vertices, faces, &patch, &[], &[(a, b)]).max(off);
                let mut replaced = in_patch;
                replaced.insert(across, ());
                if reach > max_reach || !fits(&halves, &by_edge, &replaced) {
                    continue;
                }
                for &f in &patch {
                    gone[f as usize] = true;
                }
                gone[across as usize] = true;
                added.extend(halves);
                round.replaced += 1;
                round.moved = round.moved.max(reach);
            }
            Some(Cover::Crossing(at)) => {
                if put_on_edges(&at, &by_edge, &gone, &mut split) {
                    round.splits += 2;
                } else {
                    round.deferred += 1;
                }
            }
            None => {}
        }
    }
    let mut out: Vec<[u32; 3]> = Vec::with_capacity(faces.len() + added.len() + split.len());
    for (i, &f) in faces.iter().enumerate() {
        match split.get(&(i as u32)) {
            _ if gone[i] => {}
            Some(&(edge, at)) => out.extend(split_at(f, edge, at)),
            None => out.push(f),
        }
    }
    out.extend(added);
    *faces = out;
    round
}

/// Whether the triangles `tris`, replacing the faces `replaced`, keep every directed edge
/// used once: none of their edges is one a face that stays already has, and where a face
/// that stays has its reverse, that is an edge the replaced faces had too (an outline's).
fn fits(tris: &[[u32; 3]], by_edge: &FastMap<(u32, u32), u32>, replaced: &FastMap<u32, ()>) -> bool {
    let stays = |e: &(u32, u32)| by_edge.get(e).is_some_and(|f| !replaced.contains_key(f));
    let was_replaced = |e: &(u32, u32)| by_edge.get(e).is_some_and(|f| replaced.contains_key(f));
    tris.iter().flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3]))).all(|(x, y)| !stays(&(x, y)) && (!stays(&(y, x)) || was_replaced(&(x, y))))
}

/// Record the splits of both faces beside each edge at its (new) vertex (`split`), unless
/// one of them is gone or split already this round; whether they were recorded.
fn put_on_edges(at: &[EdgeAt], by_edge: &FastMap<(u32, u32), u32>, gone: &[bool], split: &mut FastMap<u32, EdgeAt>) -> bool {
    let beside: Option<Vec<(u32, EdgeAt)>> = at.iter().flat_map(|&((a, b), x)| [(a, b), (b, a)].map(|e| by_edge.get(&e).map(|&f| (f, ((a, b), x))))).collect();
    let Some(beside) = beside else { return false };
    let free = beside.iter().enumerate().all(|(k, (f, _))| !gone[*f as usize] && !split.contains_key(f) && !beside[..k].iter().any(|(g, _)| g == f));
    if free {
        split.extend(beside);
    }
    free
}

/// The face `f`, which holds the edge `b → a`, fanned from its far corner over the
/// `chain` of corners put on that edge (from `b` towards `a`).
fn fan_along(f: [u32; 3], (a, b): (u32, u32), chain: &[u32]) -> Vec<[u32; 3]> {
    let k = (0..3).find(|&k| (f[k], f[(k + 1) % 3]) == (b, a));
    debug_assert!(k.is_some(), "the face {f:?} has no edge {b} -> {a}");
    let r = f[(k.unwrap_or(0) + 2) % 3];
    let path: Vec<u32> = std::iter::once(b).chain(chain.iter().copied()).chain(std::iter::once(a)).collect();
    path.windows(2).map(|w| [w[0], w[1], r]).collect()
}

/// The face `f`, which holds the edge `(a, b)` one way or the other, split at `at` on it.
fn split_at(f: [u32; 3], (a, b): (u32, u32), at: u32) -> [[u32; 3]; 2] {
    let holds_ab = (0..3).any(|k| (f[k], f[(k + 1) % 3]) == (a, b));
    let halves = if holds_ab { fan_along(f, (b, a), &[at]) } else { fan_along(f, (a, b), &[at]) };
    [halves[0], halves[1]]
}

/// How far the patch's faces lie from what is left of it: the largest, over its faces, of
/// the least over the pieces left (the triangles `tris`, the outline's edges) of the
/// farthest corner from the piece (distance to a convex piece is convex, so the whole
/// face lies that close to it). Infinite when nothing is left, or when that would take
/// more than [`MAX_REACH_PAIRS`] measures.
fn reach_of_removal(vertices: &[Vec3], faces: &[[u32; 3]], patch: &[u32], tris: &[[u32; 3]], outline: &[(u32, u32)]) -> f64 {
    if patch.len() * (tris.len() + outline.len()) > MAX_REACH_PAIRS {
        return f64::INFINITY;
    }
    let at = |v: u32| vertices[v as usize];
    let to_tri = |p: Vec3, t: &[u32; 3]| point_triangle_distance2(p, at(t[0]), at(t[1]), at(t[2])).sqrt();
    let to_edge = |p: Vec3, &(a, b): &(u32, u32)| point_segment_distance(p, at(a), at(b));
    patch
        .iter()
        .map(|&f| {
            let corners = faces[f as usize].map(at);
            let far = |d: &dyn Fn(Vec3) -> f64| corners.iter().map(|&p| d(p)).fold(0.0, f64::max);
            let by_tris = tris.iter().map(|t| far(&|p| to_tri(p, t)));
            let by_edges = outline.iter().map(|e| far(&|p| to_edge(p, e)));
            by_tris.chain(by_edges).fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

fn point_segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 { ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
    (p - (a + ab * t)).length()
}

/// The faces of fold edges to start patches from: of each pair of neighbours facing
/// opposite ways, both within `tol` of the wider one's plane, the wider (its normal is
/// the less rounded), widest first.
fn fold_seeds(vertices: &[Vec3], faces: &[[u32; 3]], by_edge: &FastMap<(u32, u32), u32>, tol: f64) -> Vec<u32> {
    // (each face's plane and area once: a face is asked about from each of its edges)
    let planes: Vec<(Vec3, f64)> = faces.iter().map(|f| plane_of(vertices, f)).collect();
    let areas: Vec<f64> = faces.iter().map(|f| twice_area(vertices, f)).collect();
    let mut seeds: Vec<(f64, u32)> = Vec::new();
    for (i, f) in faces.iter().enumerate() {
        for k in 0..3 {
            let Some(&j) = by_edge.get(&(f[(k + 1) % 3], f[k])) else { continue };
            let (i, j) = (i as u32, j);
            if j <= i || planes[i as usize].0.dot(planes[j as usize].0) >= -FOLD_COS {
                continue;
            }
            let wide = if areas[j as usize] > areas[i as usize] { j } else { i };
            let (n, w) = planes[wide as usize];
            if f.iter().chain(&faces[j as usize]).all(|&v| (vertices[v as usize].dot(n) - w).abs() <= tol) {
                seeds.push((areas[wide as usize], wide));
            }
        }
    }
    seeds.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    seeds.into_iter().map(|(_, i)| i).collect()
}

/// The faces reached from `seed` across edges to faces with every corner within `tol` of
/// `plane`, each marked `taken` (a walk stops after [`MAX_PATCH`] and one more face).
fn grow_patch(vertices: &[Vec3], faces: &[[u32; 3]], by_edge: &FastMap<(u32, u32), u32>, seed: u32, (n, w): (Vec3, f64), tol: f64, taken: &mut [bool]) -> Vec<u32> {
    let in_plane = |f: &[u32; 3]| f.iter().all(|&v| (vertices[v as usize].dot(n) - w).abs() <= tol);
    taken[seed as usize] = true;
    let mut patch = vec![seed];
    let mut next = 0;
    while next < patch.len() && patch.len() <= MAX_PATCH {
        let f = faces[patch[next] as usize];
        next += 1;
        for k in 0..3 {
            let Some(&j) = by_edge.get(&(f[(k + 1) % 3], f[k])) else { continue };
            if !taken[j as usize] && in_plane(&faces[j as usize]) {
                taken[j as usize] = true;
                patch.push(j);
            }
        }
    }
    patch
}

/// What the patch becomes, or `None` (see the module documentation).
fn net_cover(vertices: &mut Vec<Vec3>, faces: &[[u32; 3]], patch: &[u32], n: Vec3, tol: f64) -> Option<Cover> {
    let loops = regions::region_loops(vertices, patch.iter().map(|&f| faces[f as usize].as_slice()), n)?;
    if let [ids] = loops.as_slice() {
        if let Some((edge, chain, off)) = needle(vertices, ids, tol) {
            return Some(Cover::Needle(edge, chain, off));
        }
    }
    let outline: Vec<(u32, u32)> = loops.iter().flat_map(|ids| (0..ids.len()).map(move |k| (ids[k], ids[(k + 1) % ids.len()]))).collect();
    // one way: regions with their holes, clipped facing the way the loops' total turns
    let facing = if loops.iter().map(|ids| loop_area(vertices, ids, n)).sum::<f64>() >= 0.0 { n } else { -n };
    if let Some(tris) = regions::clip_loops(vertices, &loops, facing, tol) {
        return Some(Cover::Triangles(tris, outline));
    }
    if let Some((edges, t)) = first_crossing(vertices, &loops, n)? {
        let (a, b) = edges[0];
        let x = vertices.len() as u32;
        vertices.push(vertices[a as usize] + (vertices[b as usize] - vertices[a as usize]) * t);
        return Some(Cover::Crossing([(edges[0], x), (edges[1], x)]));
    }
    // loops that each turn one way, none inside another
    if nested(vertices, &loops, n) {
        return None;
    }
    let mut tris = Vec::new();
    for ids in &loops {
        let facing = if loop_area(vertices, ids, n) > 0.0 { n } else { -n };
        tris.extend(regions::clip_loops(vertices, std::slice::from_ref(ids), facing, tol)?);
    }
    Some(Cover::Triangles(tris, outline))
}

/// Whether a corner of one loop lies inside another (in the plane of normal `n`).
fn nested(vertices: &[Vec3], loops: &[Vec<u32>], n: Vec3) -> bool {
    let (u, v) = basis(n);
    let at = |i: u32| [vertices[i as usize].dot(u), vertices[i as usize].dot(v)];
    loops.iter().enumerate().any(|(i, outer)| loops.iter().enumerate().any(|(j, inner)| i != j && inner.iter().any(|&c| !outer.contains(&c) && regions::inside(outer, at(c), &at))))
}

/// Two unit vectors spanning the plane of normal `n`.
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let helper = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let u = n.cross(helper).normalize();
    (u, n.cross(u))
}

/// The loop `ids` as a needle: an edge `a → b` of it, the rest of it (from `b` back to
/// `a`) running back along that edge strictly between its ends, each corner within `tol`
/// of it. The edge, those corners from `b` on, and how far the farthest is off the edge.
fn needle(vertices: &[Vec3], ids: &[u32], tol: f64) -> Option<((u32, u32), Vec<u32>, f64)> {
    let n = ids.len();
    if n < 3 {
        return None;
    }
    let at = |i: u32| vertices[i as usize];
    (0..n).find_map(|k| {
        let (a, b) = (ids[k], ids[(k + 1) % n]);
        let ab = at(b) - at(a);
        let chain: Vec<u32> = (2..n).map(|j| ids[(k + j) % n]).collect();
        let (mut last, mut off) = (1.0, 0.0f64);
        for &c in &chain {
            let ac = at(c) - at(a);
            let along = ac.dot(ab) / ab.length_squared();
            if !(along > 0.0 && along < last) {
                return None;
            }
            (last, off) = (along, off.max((ac - ab * along).length()));
        }
        (off <= tol).then_some(((a, b), chain, off))
    })
}

/// The first two edges of one loop that cross (in the plane of normal `n`, each end
/// strictly on its side of the other edge), and where along the first:
/// `Some(None)` when none do, `None` when edges of two loops cross.
#[allow(clippy::type_complexity)]
fn first_crossing(vertices: &[Vec3], loops: &[Vec<u32>], n: Vec3) -> Option<Option<([(u32, u32); 2], f64)>> {
    let (u, v) = basis(n);
    let at = |i: u32| [vertices[i as usize].dot(u), vertices[i as usize].dot(v)];
    let edges: Vec<(usize, (u32, u32))> = loops.iter().enumerate().flat_map(|(l, ids)| (0..ids.len()).map(move |i| (l, (ids[i], ids[(i + 1) % ids.len()])))).collect();
    let orient = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
    let strict = |x: f64, y: f64| (x > 0.0 && y < 0.0) || (x < 0.0 && y > 0.0);
    for (k, &(l, (a, b))) in edges.iter().enumerate() {
        let (p, q) = (at(a), at(b));
        for &(l2, (c, d)) in &edges[k + 1..] {
            let (r, s) = (at(c), at(d));
            let (p_side, q_side) = (orient(r, s, p), orient(r, s, q));
            if !(strict(orient(p, q, r), orient(p, q, s)) && strict(p_side, q_side)) {
                continue;
            }
            if l2 != l {
                return None;
            }
            return Some(Some(([(a, b), (c, d)], p_side / (p_side - q_side))));
        }
    }
    Some(None)
}

/// Twice the signed area of the loop `ids` about `n`.
fn loop_area(vertices: &[Vec3], ids: &[u32], n: Vec3) -> f64 {
    let o = vertices[ids[0] as usize];
    (1..ids.len().saturating_sub(1)).map(|k| (vertices[ids[k] as usize] - o).cross(vertices[ids[k + 1] as usize] - o).dot(n)).sum()
}

/// The face's unit normal `n` and offset `w` (`n · x = w` on its plane; zero for a
/// face of no area).
fn plane_of(vertices: &[Vec3], f: &[u32; 3]) -> (Vec3, f64) {
    let n = cross(vertices, f).normalize_or_zero();
    (n, n.dot(vertices[f[0] as usize]))
}

fn cross(vertices: &[Vec3], f: &[u32; 3]) -> Vec3 {
    let p = f.map(|v| vertices[v as usize]);
    (p[1] - p[0]).cross(p[2] - p[0])
}

fn twice_area(vertices: &[Vec3], f: &[u32; 3]) -> f64 {
    cross(vertices, f).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every directed edge used once and its reverse once.
    fn closed(faces: &[[u32; 3]]) -> bool {
        let mut count: FastMap<(u32, u32), i32> = FastMap::default();
        for f in faces {
            for k in 0..3 {
                *count.entry((f[k], f[(k + 1) % 3])).or_default() += 1;
            }
        }
        count.iter().all(|(&(a, b), &c)| c == 1 && count.get(&(b, a)) == Some(&1))
    }

    fn folds(vertices: &[Vec3], faces: &[[u32; 3]]) -> usize {
        fold_seeds(vertices, faces, &faces_by_edge(faces), 1e-9).len()
    }

    /// `(signed area about +z, area)` of the faces on `z = height`.
    fn areas_at(vertices: &[Vec3], faces: &[[u32; 3]], height: f64) -> (f64, f64) {
        let on = |f: &&[u32; 3]| f.iter().all(|&v| (vertices[v as usize].z - height).abs() < 1e-12);
        faces.iter().filter(on).fold((0.0, 0.0), |(s, a), f| (s + cross(vertices, f).z / 2.0, a + twice_area(vertices, f) / 2.0))
    }

    /// A unit cube whose top is fanned about its centre `c`, one fan triangle cut at a
    /// point `d` just across its edge `5 → c` (inside the next one): the triangle `(d, 5,
    /// c)` faces down and folds onto its neighbour `(5, 7, c)`.
    fn cube_with_a_folded_top() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut v: Vec<Vec3> = (0..8).map(|k| Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64)).collect();
        let mut f: Vec<[u32; 3]> = vec![[0, 2, 3], [0, 3, 1], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]];
        let (c, d) = (8, 9);
        v.extend([Vec3::new(0.5, 0.5, 1.0), Vec3::new(0.8, 0.35, 1.0)]);
        f.extend([[4, 5, d], [d, 5, c], [4, d, c], [5, 7, c], [7, 6, c], [6, 4, c]]);
        (v, f)
    }

    #[test]
    fn a_fold_on_a_face_is_replaced_by_what_it_covers() {
        let (mut v, mut f) = cube_with_a_folded_top();
        assert!(closed(&f));
        assert_eq!(folds(&v, &f), 3, "(d, 5, c) against each neighbour");
        assert_eq!(unfold(&mut v, &mut f, 1e-9, 1.0).0, 1);
        assert!(closed(&f));
        assert_eq!(folds(&v, &f), 0);
        // the top covers the unit square once, facing up
        let (signed, area) = areas_at(&v, &f, 1.0);
        assert!((signed - 1.0).abs() < 1e-12 && (area - 1.0).abs() < 1e-12, "{signed} {area}");
        crate::exact::TriMesh::new(v, &f, "unfolded cube").expect("a solid");
    }

    /// A bow tie on `z = 0` (corners `(0, 0) → (2, 1.5) → (2, 0) → (0, 1)`, its outline
    /// crossing itself at `(0.8, 0.6)`) as two triangles sharing the diagonal `0 – 2`, one
    /// facing down (area 1.5) and one up (area 1), closed by a roof of two apexes `t`
    /// and `s` above.
    fn bow_tie_under_a_roof() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (t, s) = (4, 5);
        let v = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 1.5, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.5, 0.5, 1.0), Vec3::new(0.5, 0.5, 1.5)];
        let f = vec![[0, 1, 2], [0, 2, 3], [1, 0, t], [2, 1, t], [3, 2, s], [0, 3, s], [t, 0, s], [t, s, 2]];
        (v, f)
    }

    #[test]
    fn an_outline_crossing_itself_comes_apart_at_the_crossing() {
        let (mut v, mut f) = bow_tie_under_a_roof();
        assert!(closed(&f));
        assert_eq!(folds(&v, &f), 1);
        assert_eq!(areas_at(&v, &f, 0.0), (-0.5, 2.5));
        // (what goes, about the diagonal's middle, lies some 0.6 from what is left)
        assert_eq!(unfold(&mut v, &mut f, 1e-9, 10.0).0, 1);
        assert!(closed(&f));
        assert_eq!(folds(&v, &f), 0);
        // the crossing is a vertex; the lobes (0.4 up, 0.9 down) no longer overlap
        assert!(v.iter().any(|p| (*p - Vec3::new(0.8, 0.6, 0.0)).length() < 1e-12));
        let (signed, area) = areas_at(&v, &f, 0.0);
        assert!((signed + 0.5).abs() < 1e-12 && (area - 1.3).abs() < 1e-12, "{signed} {area}");
    }

    /// A needle fold under a roof: on `z = 0`, `(B, E, A)` facing up, `(E, B, C)` and
    /// `(C, A, E)` facing down, what they cover once the needle `A → B → C` (`C` within
    /// `1e-12` of the edge `A – B`), its edges paired by a roof of two apexes `T` and `S`.
    fn needle_under_a_roof() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (a, b, c, e, t, s) = (0, 1, 2, 3, 4, 5);
        let v = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.5, 1e-12, 0.0), Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.5, 0.3, 1.0), Vec3::new(0.5, -0.3, 1.0)];
        let f = vec![[b, e, a], [e, b, c], [c, a, e], [b, a, s], [c, b, t], [a, c, t], [s, a, t], [b, s, t]];
        (v, f)
    }

    #[test]
    fn a_needle_left_by_a_fold_becomes_a_vertex_on_an_edge() {
        // E, which only the fold uses, lies 0.5 from what is left (A, B and C): farther
        // than a reach of 0.1 allows, so the fold stays as it was
        let (mut v, mut f) = needle_under_a_roof();
        let (replaced, moved) = unfold(&mut v, &mut f, 1e-9, 0.1);
        assert_eq!((replaced, moved), (0, 0.0));
        assert_eq!((v, f), needle_under_a_roof());
        let (mut v, mut f) = needle_under_a_roof();
        assert!(closed(&f));
        assert!(folds(&v, &f) >= 1);
        assert_eq!(unfold(&mut v, &mut f, 1e-9, 1.0).0, 1);
        assert!(closed(&f));
        // nothing is left on the plane: the roof's face over A – B is split at C
        assert_eq!(areas_at(&v, &f, 0.0), (0.0, 0.0));
        let (a, b, c, s) = (0, 1, 2, 5);
        assert_eq!(f.len(), 6, "{f:?}");
        assert!(f.contains(&[b, c, s]) && f.contains(&[c, a, s]), "{f:?}");
    }

    #[test]
    fn a_needle_of_a_chain_of_corners_puts_them_all_on_the_edge_across() {
        // as the needle under a roof, with three corners (C3, C2, C1, within 1e-12 of the
        // edge A – B) running back from B to A: the fan of a sliver's loop over corners
        // that all lie on one line
        let (a, b, c1, c2, c3, e, t, s) = (0, 1, 2, 3, 4, 5, 6, 7);
        let mut v = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.25, 1e-12, 0.0),
            Vec3::new(0.5, -1e-12, 0.0),
            Vec3::new(0.75, 1e-12, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(0.5, 0.3, 1.0),
            Vec3::new(0.5, -0.3, 1.0),
        ];
        let mut f = vec![[b, e, a], [e, b, c3], [c3, c2, e], [c2, c1, e], [c1, a, e], [b, a, s], [c3, b, t], [c2, c3, t], [c1, c2, t], [a, c1, t], [s, a, t], [b, s, t]];
        assert!(closed(&f) && folds(&v, &f) >= 1);
        assert_eq!(unfold(&mut v, &mut f, 1e-9, 1.0).0, 1);
        assert!(closed(&f));
        assert_eq!(areas_at(&v, &f, 0.0), (0.0, 0.0));
        assert_eq!(f.len(), 10, "{f:?}");
        for piece in [[b, c3, s], [c3, c2, s], [c2, c1, s], [c1, a, s]] {
            assert!(f.contains(&piece), "{piece:?} in {f:?}");
        }
    }

    /// A tetrahedron on the corner `corner`, pointing along `dir` (outward).
    fn tetrahedron_at(v: &mut Vec<Vec3>, f: &mut Vec<[u32; 3]>, corner: u32, dir: Vec3) {
        let p = v[corner as usize];
        let o = v.len() as u32;
        let side = dir.cross(Vec3::Z).normalize() * 0.2;
        v.extend([p + dir * 0.5 + side, p + dir * 0.5 - side, p + dir * 0.4 + Vec3::Z * 0.3]);
        let mut tet = [[corner, o, o + 1], [corner, o + 1, o + 2], [corner, o + 2, o], [o, o + 2, o + 1]];
        let volume: f64 = tet.iter().map(|t| v[t[0] as usize].dot(v[t[1] as usize].cross(v[t[2] as usize]))).sum();
        if volume < 0.0 {
            for t in tet.iter_mut() {
                t.swap(1, 2);
            }
        }
        f.extend(tet);
    }

    #[test]
    fn a_doubled_sheet_far_from_what_is_left_stays() {
        // a unit square on z = 0 twice, fanned differently each way, its corners held by
        // four tetrahedra: the net cover is nothing, its middle 0.5 from anything left
        let (a, b, c, d) = (0, 1, 2, 3);
        let mut v = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let mut f = vec![[a, b, c], [a, c, d], [a, d, b], [b, d, c]];
        for (k, dir) in [(a, Vec3::new(-1.0, -1.0, 0.0)), (b, Vec3::new(1.0, -1.0, 0.0)), (c, Vec3::new(1.0, 1.0, 0.0)), (d, Vec3::new(-1.0, 1.0, 0.0))] {
            tetrahedron_at(&mut v, &mut f, k, dir.normalize());
        }
        assert!(closed(&f) && folds(&v, &f) > 0);
        let before = f.clone();
        assert_eq!(unfold(&mut v, &mut f, 1e-9, 0.05), (0, 0.0));
        assert_eq!(f, before);
    }

    /// A unit quad on z = 0 (corners numbered as given) under two roofs sharing its
    /// diagonal `x – z`, its bottom fanned about its centre facing down, one fan triangle
    /// cut at a point across its edge: a fold, whose net cover is the quad.
    fn quad_under_two_roofs(y: u32, x: u32, z: u32, w: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut v = vec![Vec3::ZERO; 4];
        v[x as usize] = Vec3::new(0.0, 0.0, 0.0);
        v[y as usize] = Vec3::new(1.0, 0.0, 0.0);
        v[z as usize] = Vec3::new(1.0, 1.0, 0.0);
        v[w as usize] = Vec3::new(0.0, 1.0, 0.0);
        let (t1, t2, c, d) = (4, 5, 6, 7);
        v.extend([Vec3::new(0.67, 0.33, 1.0), Vec3::new(0.33, 0.67, 1.0), Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.3, 0.4, 0.0)]);
        let mut f = vec![[x, y, t1], [y, z, t1], [z, x, t1], [z, w, t2], [w, x, t2], [x, z, t2]];
        f.extend([[y, x, d], [d, x, c], [y, d, c], [x, w, c], [w, z, c], [z, y, c]]);
        (v, f)
    }

    #[test]
    fn a_new_diagonal_the_surface_already_has_is_not_made() {
        // the quad clipped along x – z would use that edge a second time each way
        for ids in [(0, 1, 2, 3), (1, 0, 3, 2), (3, 0, 1, 2), (2, 3, 0, 1)] {
            let (mut v, mut f) = quad_under_two_roofs(ids.0, ids.1, ids.2, ids.3);
            assert!(closed(&f), "{ids:?}");
            unfold(&mut v, &mut f, 1e-9, 1.0);
            assert!(closed(&f), "{ids:?}: {f:?}");
        }
    }

    #[test]
    fn a_fold_is_found_whichever_face_comes_first() {
        // a sliver 3° off the plane of the wide face it folds onto
        let v = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.5, 0.01, 0.0005), Vec3::new(0.5, 0.8, 0.0)];
        let (sliver, wide) = ([0, 1, 2], [1, 0, 3]);
        for (faces, seed) in [(vec![sliver, wide], 1), (vec![wide, sliver], 0)] {
            assert_eq!(fold_seeds(&v, &faces, &faces_by_edge(&faces), 1e-3), vec![seed], "{faces:?}");
        }
    }
}
