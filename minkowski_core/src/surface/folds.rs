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
//! pairing, and the triangles cover the same point set. Two kinds of outline are first
//! made simple by putting a vertex on an edge, splitting the two faces beside it (the
//! point set stays the same, up to the weld):
//!
//! - a needle, three corners on a line within the weld: its middle corner goes on the
//!   long edge, and nothing is left of the needle;
//! - an outline that crosses itself (a part of the patch facing one way, a part the
//!   other): the crossing point goes on both edges, and the outline comes apart there
//!   into loops that each turn one way.
//!
//! That runs in rounds, one vertex per edge and patch each, until no patch changes. A
//! patch whose outline is still not simple loops, or whose signed area the clipping
//! would change, is left as it is.
//!
//! Entry point: [`unfold`].

use super::regions;
use crate::math::Vec3;
use crate::polytope::point_triangle_distance2;
use crate::util::FastMap;

/// The least `−cos` of the angle between two faces' normals at a fold (within 8° of
/// opposite: a sliver's normal is rounded more than a wide face's).
const FOLD_COS: f64 = 0.99;

/// The most faces a patch takes; a larger one is left as it is (clipping is quadratic in
/// the loops' length).
const MAX_PATCH: usize = 4096;

/// The most rounds of vertices put on edges.
const MAX_ROUNDS: usize = 8;

/// Replace every patch of faces in the plane of a fold by the triangles of its net
/// cover (see the module documentation); `tol` is the weld tolerance. A patch is replaced
/// only where each vertex it alone used lies within `max_reach` of what is left of it
/// (a sheet of the answer thinner than the weld, welded into folds, is left to the
/// caller, whose bound must reach it). Returns how many patches were replaced and the
/// farthest any point of the surface moved (within `max_reach`). Vertices inside a patch
/// may be left unused; the points where an outline crossed itself are appended to
/// `vertices`.
pub fn unfold(vertices: &mut Vec<Vec3>, faces: &mut Vec<[u32; 3]>, tol: f64, max_reach: f64) -> (usize, f64) {
    let (mut replaced, mut moved) = (0, 0.0f64);
    for _ in 0..=MAX_ROUNDS {
        let round = unfold_round(vertices, faces, tol, max_reach);
        replaced += round.replaced;
        moved = moved.max(round.moved);
        if round.splits == 0 {
            break;
        }
    }
    (replaced, moved)
}

/// What one round of [`unfold`] did.
struct Round {
    replaced: usize,
    splits: usize,
    moved: f64,
}

/// An edge (as an outline runs) and the vertex to put on it.
type EdgeAt = ((u32, u32), u32);

/// What a patch becomes.
enum Cover {
    /// The triangles of what it covers once.
    Triangles(Vec<[u32; 3]>),
    /// Nothing, once the middle corner of the needle it leaves is put on the needle's long
    /// edge (as the outline runs); how far that corner is off the edge.
    Needle(EdgeAt, f64),
    /// Loops, once a point where its outline crosses itself is put on both edges.
    Crossing([EdgeAt; 2]),
}

/// One round of [`unfold`].
fn unfold_round(vertices: &mut Vec<Vec3>, faces: &mut Vec<[u32; 3]>, tol: f64, max_reach: f64) -> Round {
    let by_edge: FastMap<(u32, u32), u32> = faces.iter().enumerate().flat_map(|(i, f)| (0..3).map(move |k| ((f[k], f[(k + 1) % 3]), i as u32))).collect();
    let seeds = fold_seeds(vertices, faces, &by_edge, tol);
    let mut round = Round { replaced: 0, splits: 0, moved: 0.0 };
    if seeds.is_empty() {
        return round;
    }
    let mut uses = vec![0u32; vertices.len()];
    for &v in faces.iter().flatten() {
        uses[v as usize] += 1;
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
        match net_cover(vertices, faces, &patch, plane.0, tol) {
            Some(Cover::Triangles(tris)) => {
                if patch.iter().any(|f| split.contains_key(f)) {
                    continue; // (split for a neighbour this round: next round)
                }
                let reach = reach_of_removal(vertices, faces, &patch, &tris, &uses);
                if reach > max_reach {
                    continue;
                }
                for &f in &patch {
                    gone[f as usize] = true;
                }
                added.extend(tris);
                round.replaced += 1;
                round.moved = round.moved.max(reach);
            }
            Some(Cover::Needle(at, off)) => {
                // nothing is left of the patch: only where that may go (else, the corner on
                // the edge, the needle's edges would be used twice each way)
                let may_go = reach_of_removal(vertices, faces, &patch, &[], &uses) <= max_reach;
                if may_go && put_on_edges(&[at], &by_edge, &gone, &mut split) {
                    round.splits += 1;
                    round.moved = round.moved.max(off);
                }
            }
            Some(Cover::Crossing(at)) => {
                let recorded = put_on_edges(&at, &by_edge, &gone, &mut split);
                round.splits += 2 * usize::from(recorded);
            }
            None => {}
        }
    }
    let mut out: Vec<[u32; 3]> = Vec::with_capacity(faces.len() + added.len() + split.len());
    for (i, &f) in faces.iter().enumerate() {
        match split.get(&(i as u32)) {
            _ if gone[i] => {}
            Some(&(edge, at)) => out.extend(split_at(f, edge, at).into_iter().filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])),
            None => out.push(f),
        }
    }
    out.extend(added);
    *faces = out;
    round
}

/// Record the splits of both faces beside each edge at its vertex (`split`), unless one
/// of them is gone or split already this round (then it waits for the next); whether they
/// were recorded.
fn put_on_edges(at: &[EdgeAt], by_edge: &FastMap<(u32, u32), u32>, gone: &[bool], split: &mut FastMap<u32, EdgeAt>) -> bool {
    let beside: Option<Vec<(u32, EdgeAt)>> = at.iter().flat_map(|&((a, b), x)| [(a, b), (b, a)].map(|e| by_edge.get(&e).map(|&f| (f, ((a, b), x))))).collect();
    let Some(beside) = beside else { return false };
    let free = beside.iter().enumerate().all(|(k, (f, _))| !gone[*f as usize] && !split.contains_key(f) && !beside[..k].iter().any(|(g, _)| g == f));
    if free {
        split.extend(beside);
    }
    free
}

/// How far the vertices only the patch uses (`uses`: faces per vertex) lie from what is
/// left of it: the triangles `tris` replacing it, and its vertices that other faces keep.
/// Infinite when nothing is left (a closed flat component: no fold of the weld's).
fn reach_of_removal(vertices: &[Vec3], faces: &[[u32; 3]], patch: &[u32], tris: &[[u32; 3]], uses: &[u32]) -> f64 {
    let mut in_patch: FastMap<u32, u32> = FastMap::default();
    for &f in patch {
        for &v in &faces[f as usize] {
            *in_patch.entry(v).or_default() += 1;
        }
    }
    let kept: Vec<Vec3> = in_patch.iter().filter(|&(&v, &k)| uses[v as usize] > k).map(|(&v, _)| vertices[v as usize]).collect();
    let at = |v: u32| vertices[v as usize];
    let removed = in_patch.iter().filter(|&(&v, &k)| uses[v as usize] == k && !tris.iter().any(|t| t.contains(&v))).map(|(&v, _)| at(v));
    removed
        .map(|p| {
            let to_tris = tris.iter().map(|t| point_triangle_distance2(p, at(t[0]), at(t[1]), at(t[2])).sqrt());
            let to_kept = kept.iter().map(|&q| (q - p).length());
            to_tris.chain(to_kept).fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// The face `f`, which holds the edge `edge` one way or the other, split at `at` on it.
fn split_at(f: [u32; 3], (a, b): (u32, u32), at: u32) -> [[u32; 3]; 2] {
    let k = (0..3).find(|&k| {
        let e = (f[k], f[(k + 1) % 3]);
        e == (a, b) || e == (b, a)
    });
    let k = k.unwrap_or(0);
    let (p, q, r) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
    [[p, at, r], [at, q, r]]
}

/// The faces of fold edges to start patches from: of each pair of neighbours in one plane
/// facing opposite ways, the wider (its normal is the less rounded), widest first.
fn fold_seeds(vertices: &[Vec3], faces: &[[u32; 3]], by_edge: &FastMap<(u32, u32), u32>, tol: f64) -> Vec<u32> {
    let mut seeds: Vec<(f64, u32)> = Vec::new();
    for (i, f) in faces.iter().enumerate() {
        let (n, w) = plane_of(vertices, f);
        for k in 0..3 {
            let Some(&j) = by_edge.get(&(f[(k + 1) % 3], f[k])) else { continue };
            let g = &faces[j as usize];
            let (m, _) = plane_of(vertices, g);
            let in_plane = g.iter().all(|&v| (vertices[v as usize].dot(n) - w).abs() <= tol);
            if (i as u32) < j && n.dot(m) < -FOLD_COS && in_plane {
                let (a, b) = (twice_area(vertices, f), twice_area(vertices, g));
                seeds.push(if a >= b { (a, i as u32) } else { (b, j) });
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
        if let Some((at, off)) = needle(vertices, ids, tol) {
            return Some(Cover::Needle(at, off));
        }
    }
    let tris = regions::clip_loops(vertices, &loops, n, tol).or_else(|| regions::clip_loops(vertices, &loops, -n, tol));
    let tris = match tris {
        Some(tris) => tris,
        None => {
            if let Some((edges, t)) = first_crossing(vertices, &loops, n)? {
                let (a, b) = edges[0];
                let x = vertices.len() as u32;
                vertices.push(vertices[a as usize] + (vertices[b as usize] - vertices[a as usize]) * t);
                return Some(Cover::Crossing([(edges[0], x), (edges[1], x)]));
            }
            // loops that each turn one way, none inside another
            let mut tris = Vec::new();
            for ids in &loops {
                let facing = if loop_area(vertices, ids, n) > 0.0 { n } else { -n };
                tris.extend(regions::clip_loops(vertices, std::slice::from_ref(ids), facing, tol)?);
            }
            tris
        }
    };
    let area = |fs: &mut dyn Iterator<Item = [u32; 3]>| {
        fs.fold((0.0, 0.0), |(signed, total), f| {
            let c = cross(vertices, &f);
            (signed + c.dot(n), total + c.length())
        })
    };
    let (before, total) = area(&mut patch.iter().map(|&f| faces[f as usize]));
    let (after, _) = area(&mut tris.iter().copied());
    ((after - before).abs() <= 1e-9 * total.max(f64::MIN_POSITIVE)).then_some(Cover::Triangles(tris))
}

/// The loop `ids` as a needle: three corners, one (`at`) within `tol` of the edge between
/// the other two and between their ends; that edge (as the loop runs) and `at`, and how
/// far `at` is off it.
fn needle(vertices: &[Vec3], ids: &[u32], tol: f64) -> Option<(EdgeAt, f64)> {
    let [p0, p1, p2] = <[u32; 3]>::try_from(ids).ok()?;
    let at = |i: u32| vertices[i as usize];
    [(p0, p1, p2), (p1, p2, p0), (p2, p0, p1)].into_iter().find_map(|(a, b, c)| {
        let (ab, ac) = (at(b) - at(a), at(c) - at(a));
        let along = ac.dot(ab) / ab.length_squared();
        let off = (ac - ab * along).length();
        (along > 0.0 && along < 1.0 && off <= tol).then_some((((a, b), c), off))
    })
}

/// The first two edges of one loop that cross (in the plane of normal `n`, each end
/// strictly on its side of the other edge), and where along the first:
/// `Some(None)` when none do, `None` when edges of two loops cross.
#[allow(clippy::type_complexity)]
fn first_crossing(vertices: &[Vec3], loops: &[Vec<u32>], n: Vec3) -> Option<Option<([(u32, u32); 2], f64)>> {
    let helper = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let u = n.cross(helper).normalize();
    let v = n.cross(u);
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
        let by_edge = faces.iter().enumerate().flat_map(|(i, f)| (0..3).map(move |k| ((f[k], f[(k + 1) % 3]), i as u32))).collect();
        fold_seeds(vertices, faces, &by_edge, 1e-9).len()
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
        assert_eq!(unfold(&mut v, &mut f, 1e-9, 1.0).0, 1);
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
}
