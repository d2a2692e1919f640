//! Refinement of an extracted surface where it sags from the true boundary, for a source
//! that can find the boundary point a point moves to ([`crate::octree::CellSource::boundary_point`]:
//! the offsets, whose boundary is a level set of the exact distance to a mesh).
//!
//! Marching tetrahedra puts every vertex on the boundary, but a triangle is a chord: across
//! a crease of the boundary (where the offsets of two teeth of a gear meet) it cuts off the
//! crease's valley by a good part of the grid's bound, while on smooth parts it lies far
//! closer. So the error of a whole surface is set by its creases, a set of lines. Here each
//! triangle whose vertices' normals turn enough for it to sag by more than `tol` is tested
//! at its edges' midpoints and its centroid, and an edge whose ends' normals turn by much
//! also where it passes over the crease ([`on_crease`]: where their tangent planes meet,
//! moved to the boundary; a chord across a lopsided valley sags most there, not at its
//! middle). An edge that sags by more than `tol` is split (also the longest edge of a
//! triangle whose centroid does), and the triangles around it are split with it, so the
//! mesh stays closed, manifold and oriented the same way. The split point is on the crease
//! when there is one, else the midpoint's boundary point. A split that would fold a
//! triangle over is refused: a half that faces away both from the triangle and from the
//! boundary under it (a half on the far sheet of a crease sharper than a right angle turns
//! from the chord by more than a right angle, yet faces as its sheet does: that one is
//! kept); a crease point refused so is replaced by the midpoint's boundary point when that
//! folds nothing. A refused edge is flipped to the diagonal between its opposite vertices
//! instead when that sags less than half as much. What a round makes is then checked as a
//! whole, for two faults a solid check would find later without saying which split made
//! them: where a new triangle and the one across an edge of it face within 8° of opposite
//! ways (the surface folds back: a split point past a neighbour's edge, or several splits
//! of one triangle together, on a ridge a few degrees sharp; a solid check cannot tell such
//! a fold from a wrongly triangulated polygon), and where a new triangle crosses another,
//! or touches it along an edge (the triangles around a corner turned over one another
//! across a crease sharper than a right angle: on IndustReal's small gear grown by 1 mm at
//! eps 2e-3, winding number −1 in front of 20 faces). The old triangles there have their
//! crease points replaced by midpoints, or, failing that, their splits and flips given up,
//! and the round is made again. Rounds repeat on the new triangles, at a cost in triangles
//! that grows with the creases' length, not the surface's area.
//!
//! The bound the extraction stated still holds: every vertex it made is kept (the argument
//! that every boundary point lies near one holds as before), and a point of a new triangle
//! lies within the triangle's covering radius (at most its longest edge over `sqrt 3`) of a
//! vertex on the boundary, the distance changing no faster than the point moves
//! ([`SagStats::covering`] gives the largest, which the caller takes into the bound).

use super::Surface;
use crate::bvh::Bvh;
use crate::exact::crossing::triangles_meet;
use crate::math::{Aabb, Vec3};
use crate::util::{FastMap, FastSet};
use rayon::prelude::*;

/// Rounds of splitting, at most.
const MAX_ROUNDS: u32 = 8;
/// An edge of a new triangle where the two faces' normals are within this (cosine) of
/// opposite is a fold (the surface turns back within 8°): a split or flip that makes one is
/// given up, and the chord left as the extraction made it, inside its bound. A crease that
/// sharp is rarer than a fold made by a split point on the far side of a neighbour's edge,
/// and a solid check cannot tell the two apart.
const FOLD_COS: f64 = 0.99;
/// Passes of a round that give up the splits beside folds or crossings (passes that only
/// put midpoints for crease points not counted); after them, the whole round.
const MAX_FOLD_PASSES: usize = 4;
/// The refinement stops once the surface has this many times the triangles it had.
const MAX_GROWTH: usize = 3;
/// An edge whose ends' normals turn by more than this (cosine) crosses a crease: it is
/// split where the tangent planes at its ends meet ([`on_crease`]), not at its midpoint.
const CREASE_COS: f64 = 0.94;
/// ... and only when that meeting lies this share of the edge's length or more from its ends.
const CREASE_ALONG: f64 = 0.1;

/// A boundary point and the boundary's outward unit normal there.
pub type BoundaryPoint = (Vec3, Vec3);

/// Edges to split, and where.
type Splits = FastMap<(u32, u32), BoundaryPoint>;

/// A point's boundary point, given how far the point lies from some boundary point at most
/// (see [`crate::octree::CellSource::boundary_point`]).
pub type Boundary<'a> = dyn Fn(Vec3, f64) -> Option<BoundaryPoint> + Sync + 'a;

/// What [`refine_sag`] did.
#[derive(Clone, Copy, Debug, Default)]
pub struct SagStats {
    /// Rounds of splitting made.
    pub rounds: u32,
    /// Points tested (edge midpoints and centroids).
    pub tested: usize,
    /// Edges split.
    pub splits: usize,
    /// Edges flipped to the diagonal along a crease.
    pub flips: usize,
    /// Triangles whose splits and flips were given up because they folded the surface or
    /// passed it through itself.
    pub folds_refused: usize,
    /// The largest sag seen among the points tested in the last round (0 when none was).
    pub sag_left: f64,
    /// The largest covering radius of a triangle made here (what the bound must cover).
    pub covering: f64,
}

/// The key of the undirected edge `a`–`b`.
fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// The longest edge of the triangle `f` over `|b − a|`.
fn longest_edge(v: &[Vec3], f: [u32; 3]) -> (f64, (u32, u32)) {
    (0..3)
        .map(|k| {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            ((v[b as usize] - v[a as usize]).length(), edge_key(a, b))
        })
        .fold((0.0, (0, 0)), |best, e| if e.0 > best.0 { e } else { best })
}

/// Whether the triangle `f` may sag by more than `tol`: its longest edge times the angle its
/// vertices' normals turn through, over 2 (a chord across a crease of that angle sags by
/// about a quarter of it, across a smooth bend by an eighth).
/// Only triangles whose covering radius is at most `covers` are split (so that none made
/// here needs a larger bound: large flat triangles lie on their plane exactly).
fn may_sag(v: &[Vec3], normals: &[Option<Vec3>], f: [u32; 3], (tol, covers): (f64, f64)) -> bool {
    let [Some(a), Some(b), Some(c)] = f.map(|i| normals[i as usize]) else { return false };
    let least_cos = a.dot(b).min(b.dot(c)).min(c.dot(a)).clamp(-1.0, 1.0);
    let longest = longest_edge(v, f).0;
    longest / 3f64.sqrt() <= covers && longest * least_cos.acos() * 0.5 > tol
}

/// The triangles `f` is split into, given the new vertex on each of its edges that is split
/// (`mid[k]` on the edge from `f[k]` to `f[k + 1]`), in `f`'s orientation.
fn split_triangle(v: &[Vec3], f: [u32; 3], mid: [Option<u32>; 3], out: &mut Vec<[u32; 3]>) {
    let splits = mid.iter().filter(|m| m.is_some()).count();
    match splits {
        0 => out.push(f),
        1 => {
            let k = (0..3).find(|&k| mid[k].is_some()).expect("one split");
            let (a, b, c, m) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3], mid[k].expect("split"));
            out.extend([[a, m, c], [m, b, c]]);
        }
        2 => {
            // the unsplit edge is c -> a; the corner b between the two split edges is cut off
            let k = (0..3).find(|&k| mid[k].is_none()).expect("one unsplit");
            let (c, a, b) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
            let (m1, m2) = (mid[(k + 1) % 3].expect("a -> b split"), mid[(k + 2) % 3].expect("b -> c split"));
            out.push([m1, b, m2]);
            // the quad a, m1, m2, c by its shorter diagonal
            let pos = |i: u32| v[i as usize];
            if (pos(m2) - pos(a)).length() <= (pos(c) - pos(m1)).length() {
                out.extend([[a, m1, m2], [a, m2, c]]);
            } else {
                out.extend([[a, m1, c], [m1, m2, c]]);
            }
        }
        _ => {
            let [m0, m1, m2] = mid.map(|m| m.expect("all split"));
            out.extend([[f[0], m0, m2], [m0, f[1], m1], [m2, m1, f[2]], [m0, m1, m2]]);
        }
    }
}

/// The unnormalised normal of the triangle `a b c`.
fn normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a)
}

/// Whether putting the boundary point `m` on the edge `a`–`b` of the triangle `a b c`
/// folds nothing over: each half faces within a right angle of the triangle, or of the
/// boundary under the half's centroid (`under`: the normal there, `None` where it cannot
/// be found). The second is what a chord across a sharp crease needs: when `c` lies on the
/// crease, the half on the far sheet turns from the chord by more than a right angle, yet
/// faces as that sheet does.
fn split_keeps_facing([a, b, c]: [Vec3; 3], m: Vec3, under: impl Fn([Vec3; 3]) -> Option<Vec3>) -> bool {
    let n = normal(a, b, c);
    [[a, m, c], [m, b, c]].into_iter().all(|[p, q, r]| {
        let h = normal(p, q, r);
        n.dot(h) > 0.0 || under([p, q, r]).is_some_and(|at| h.dot(at) > 0.0)
    })
}

/// The boundary's normal under the centroid of the triangle `corners`, whose corners lie
/// within `off` of the boundary.
fn normal_under(boundary: &Boundary<'_>, corners: [Vec3; 3], off: f64) -> Option<Vec3> {
    let c = (corners[0] + corners[1] + corners[2]) / 3.0;
    let reach = corners.iter().map(|&p| (p - c).length()).fold(f64::INFINITY, f64::min) + off;
    boundary(c, reach).map(|(_, n)| n)
}

/// The sag of the point `x`, within `reach` of a boundary point: how far its boundary
/// point lies, and the point.
fn sag_at(boundary: &Boundary<'_>, x: Vec3, reach: f64) -> Option<(f64, BoundaryPoint)> {
    boundary(x, reach).map(|(p, n)| ((p - x).length(), (p, n)))
}

/// The boundary point on the crease the edge `e` crosses, when its ends' normals turn by
/// more than [`CREASE_COS`]: where the line the tangent planes at its ends meet in passes
/// under the edge (through the plane of the edge and the ends' mean normal), moved to the
/// boundary. `None` when the normals turn less, the line runs about along the edge, or it
/// passes off the middle of the edge.
fn on_crease(v: &[Vec3], normals: &[Option<Vec3>], (i, j): (u32, u32), (boundary, off): (&Boundary<'_>, f64)) -> Option<BoundaryPoint> {
    let (a, b) = (v[i as usize], v[j as usize]);
    let (na, nb) = (normals[i as usize]?, normals[j as usize]?);
    let cos = na.dot(nb);
    if cos > CREASE_COS {
        return None;
    }
    // x = mid + s na + t nb on both planes: the 2 x 2 system of the normals' Gram matrix
    let mid = (a + b) * 0.5;
    let (ra, rb) = (na.dot(a - mid), nb.dot(b - mid));
    let det = 1.0 - cos * cos;
    let (s, t) = ((ra - cos * rb) / det, (rb - cos * ra) / det);
    let nearest = mid + na * s + nb * t;
    // along the crease, to where it passes under the edge: the plane through the edge and
    // the ends' mean normal
    let (crease, across) = (na.cross(nb), (b - a).cross(na + nb));
    let slope = across.dot(crease);
    if slope.abs() <= CREASE_ALONG * across.length() * crease.length() {
        return None;
    }
    let x = nearest + crease * (across.dot(mid - nearest) / slope);
    let along = (x - a).dot(b - a) / (b - a).length_squared();
    if !(CREASE_ALONG..=1.0 - CREASE_ALONG).contains(&along) {
        return None;
    }
    boundary(x, (x - a).length().min((x - b).length()) + off)
}

/// How far the point `p` lies from the edge `e` (its sag under the edge, for a point on the
/// boundary under it).
fn below_edge(v: &[Vec3], (i, j): (u32, u32), p: Vec3) -> f64 {
    let (a, b) = (v[i as usize], v[j as usize]);
    let s = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
    (p - (a + (b - a) * s)).length()
}

/// One round's tests on the triangles `cands` of `faces`: the point to split each edge at
/// whose midpoint, or crease point ([`on_crease`]), sags by more than `tol` (the crease
/// point when there is one, else the midpoint's boundary point), also the longest edge of
/// a triangle whose centroid does. Records the largest sag seen. Also the midpoint's
/// boundary point of each edge split at its crease point, to split it at instead where
/// the crease point folds the surface or passes it through itself.
fn edges_to_split(
    v: &[Vec3],
    normals: &[Option<Vec3>],
    faces: &[[u32; 3]],
    cands: &[usize],
    (boundary, off): (&Boundary<'_>, f64),
    tol: f64,
    stats: &mut SagStats,
) -> (Splits, Splits) {
    let mut edges: Vec<(u32, u32)> = cands.iter().flat_map(|&fi| (0..3).map(move |k| edge_key(faces[fi][k], faces[fi][(k + 1) % 3]))).collect();
    edges.sort_unstable();
    edges.dedup();
    let at_mid: Vec<_> = edges
        .par_iter()
        .map(|&(a, b)| {
            let (a, b) = (v[a as usize], v[b as usize]);
            sag_at(boundary, (a + b) * 0.5, 0.5 * (b - a).length() + off)
        })
        .collect();
    let at_centre: Vec<_> = cands
        .par_iter()
        .map(|&fi| {
            let corners = faces[fi].map(|i| v[i as usize]);
            let c = (corners[0] + corners[1] + corners[2]) / 3.0;
            sag_at(boundary, c, corners.iter().map(|&p| (p - c).length()).fold(f64::INFINITY, f64::min) + off)
        })
        .collect();
    // an edge across a crease sags most where it passes over the crease, not at its middle
    let at_crease: Vec<Option<(f64, BoundaryPoint)>> = edges.par_iter().map(|&e| on_crease(v, normals, e, (boundary, off)).map(|p| (below_edge(v, e, p.0), p))).collect();
    stats.tested += edges.len() + cands.len();
    stats.sag_left = at_mid.iter().chain(&at_centre).chain(&at_crease).flatten().map(|s| s.0).fold(0.0, f64::max);
    let mut split: Splits = edges
        .iter()
        .zip(at_mid.iter().zip(&at_crease))
        .filter_map(|(&e, (mid, crease))| match (mid, crease) {
            (_, Some(c)) if c.0 > tol || mid.is_some_and(|m| m.0 > tol) => Some((e, c.1)),
            (Some(m), _) if m.0 > tol => Some((e, m.1)),
            _ => None,
        })
        .collect();
    let at_mid_instead: Splits = edges
        .iter()
        .zip(at_mid.iter().zip(&at_crease))
        .filter(|(e, (_, crease))| crease.is_some() && split.contains_key(e))
        .filter_map(|(&e, (mid, _))| mid.as_ref().map(|m| (e, m.1)))
        .collect();
    let mid_of: FastMap<(u32, u32), Option<(f64, BoundaryPoint)>> = edges.iter().copied().zip(at_mid).collect();
    for (&fi, centre) in cands.iter().zip(&at_centre) {
        let sags = matches!(centre, Some(s) if s.0 > tol);
        let f = faces[fi];
        if sags && !(0..3).any(|k| split.contains_key(&edge_key(f[k], f[(k + 1) % 3]))) {
            let e = longest_edge(v, f).1;
            if let Some(Some((_, p))) = mid_of.get(&e) {
                split.insert(e, *p);
            }
        }
    }
    (split, at_mid_instead)
}

/// Drop from `split` every edge next to a triangle whose covering radius is above `covers`,
/// or would be in a half of it, or which its boundary point would fold
/// ([`split_keeps_facing`]); an edge whose crease point only folds is split at its
/// midpoint's boundary point instead (`at_mid_instead`) when that folds nothing. Returns
/// the edges dropped.
fn keep_unfolded_splits(
    v: &[Vec3],
    faces: &[[u32; 3]],
    (split, at_mid_instead): (&mut Splits, &mut Splits),
    (boundary, off): (&Boundary<'_>, f64),
    covers: f64,
) -> Vec<(u32, u32)> {
    // the midpoints to fall back on, here and in the round, only where they would be kept
    let unfit = refused_splits(v, faces, at_mid_instead, (boundary, off), covers);
    at_mid_instead.retain(|e, _| !unfit.contains_key(e));
    let mut edges = Vec::new();
    for (e, only_folds) in refused_splits(v, faces, split, (boundary, off), covers) {
        if only_folds {
            if let Some(p) = at_mid_instead.remove(&e) {
                split.insert(e, p);
                continue;
            }
        }
        split.remove(&e);
        edges.push(e);
    }
    edges.sort_unstable();
    edges
}

/// The edges of `split` that [`keep_unfolded_splits`] drops, each with whether it is
/// dropped only for a fold (not for a triangle too wide).
fn refused_splits(v: &[Vec3], faces: &[[u32; 3]], split: &Splits, (boundary, off): (&Boundary<'_>, f64), covers: f64) -> FastMap<(u32, u32), bool> {
    let mut refused: FastMap<(u32, u32), bool> = FastMap::default();
    for &f in faces {
        let wide = longest_edge(v, f).0 / 3f64.sqrt() > covers;
        for k in 0..3 {
            let corners = [f[k], f[(k + 1) % 3], f[(k + 2) % 3]];
            let e = edge_key(corners[0], corners[1]);
            let Some(&m) = split.get(&e) else { continue };
            let folds = !split_keeps_facing(corners.map(|i| v[i as usize]), m.0, |half| normal_under(boundary, half, off));
            let p = corners.map(|i| v[i as usize]);
            let halves_wide = [[p[0], m.0, p[2]], [m.0, p[1], p[2]]].iter().any(|h| (0..3).any(|k| (h[k] - h[(k + 1) % 3]).length() / 3f64.sqrt() > covers));
            if folds || halves_wide || wide {
                let only_folds = refused.entry(e).or_insert(true);
                *only_folds &= !(halves_wide || wide);
            }
        }
    }
    refused
}

/// The edges of `faces`.
fn edge_set(faces: &[[u32; 3]]) -> FastSet<(u32, u32)> {
    faces.iter().flat_map(|f| (0..3).map(move |k| edge_key(f[k], f[(k + 1) % 3]))).collect()
}

/// Flip each edge of `refused` (it sags, but a split there would fold a triangle: the
/// opposite vertex of a triangle next to it lies about where the crease does) to the
/// diagonal between its two opposite vertices, when that sags less than half as much and
/// the two new triangles face the way the old ones did; a triangle flips once a round, and
/// not next to an edge `split`, and not to a diagonal longer than `sqrt 3` times `covers`.
/// Returns the triangles changed, a flipped pair after pair.
fn flip_sagging(s: &mut Surface, refused: &[(u32, u32)], split: &FastMap<(u32, u32), BoundaryPoint>, (boundary, off): (&Boundary<'_>, f64), covers: f64) -> Vec<usize> {
    let wanted: FastSet<(u32, u32)> = refused.iter().copied().collect();
    let mut around: FastMap<(u32, u32), Vec<usize>> = FastMap::default();
    for (fi, f) in s.faces.iter().enumerate() {
        for k in 0..3 {
            let e = edge_key(f[k], f[(k + 1) % 3]);
            if wanted.contains(&e) {
                around.entry(e).or_default().push(fi);
            }
        }
    }
    let mut edges = edge_set(&s.faces);
    let mut changed = Vec::new();
    let mut flipped = vec![false; s.faces.len()];
    let v = |i: u32| s.vertices[i as usize];
    let near_split = |f: [u32; 3]| (0..3).any(|k| split.contains_key(&edge_key(f[k], f[(k + 1) % 3])));
    for e in refused {
        let Some(fs) = around.get(e) else { continue };
        let [f1, f2] = fs[..] else { continue };
        if flipped[f1] || flipped[f2] || near_split(s.faces[f1]) || near_split(s.faces[f2]) {
            continue;
        }
        // f1 = a b c runs a -> b, f2 = b a d back
        let k = (0..3).find(|&k| edge_key(s.faces[f1][k], s.faces[f1][(k + 1) % 3]) == *e).expect("edge of f1");
        let (a, b, c) = (s.faces[f1][k], s.faces[f1][(k + 1) % 3], s.faces[f1][(k + 2) % 3]);
        let Some(&d) = s.faces[f2].iter().find(|&&x| x != a && x != b) else { continue };
        if c == d || edges.contains(&edge_key(c, d)) {
            continue;
        }
        let sag = |p: u32, q: u32| sag_at(boundary, (v(p) + v(q)) * 0.5, 0.5 * (v(q) - v(p)).length() + off).map(|x| x.0);
        let (Some(across), Some(along)) = (sag(a, b), sag(c, d)) else { continue };
        let was = normal(v(a), v(b), v(c)) + normal(v(b), v(a), v(d));
        let (g1, g2) = (normal(v(a), v(d), v(c)), normal(v(d), v(b), v(c)));
        let too_wide = (v(c) - v(d)).length() / 3f64.sqrt() > covers;
        if too_wide || along >= 0.5 * across || g1.dot(was) <= 0.0 || g2.dot(was) <= 0.0 || g1.dot(g2) <= 0.0 {
            continue;
        }
        s.faces[f1] = [a, d, c];
        s.faces[f2] = [d, b, c];
        edges.remove(e);
        edges.insert(edge_key(c, d));
        changed.extend([f1, f2]);
        flipped[f1] = true;
        flipped[f2] = true;
    }
    changed
}

/// Refine `s` where it sags from the boundary by more than `tol` (see the module
/// documentation), splitting only triangles whose covering radius is at most `covers`;
/// `boundary` gives a point's boundary point and normal, `None` where it cannot. Every
/// vertex of `s` must lie within `off` of the boundary.
pub fn refine_sag(s: &mut Surface, boundary: &Boundary<'_>, (tol, covers): (f64, f64), off: f64) -> SagStats {
    let mut stats = SagStats::default();
    let mut normals: Vec<Option<Vec3>> = s.vertices.par_iter().map(|&x| boundary(x, off).map(|(_, n)| n)).collect();
    let budget = s.faces.len().saturating_mul(MAX_GROWTH);
    let mut cands: Vec<usize> = (0..s.faces.len()).filter(|&fi| may_sag(&s.vertices, &normals, s.faces[fi], (tol, covers))).collect();
    while !cands.is_empty() && stats.rounds < MAX_ROUNDS && s.faces.len() < budget && !crate::deadline::cancelled() {
        let (mut split, mut at_mid_instead) = edges_to_split(&s.vertices, &normals, &s.faces, &cands, (boundary, off), tol, &mut stats);
        let refused = keep_unfolded_splits(&s.vertices, &s.faces, (&mut split, &mut at_mid_instead), (boundary, off), covers);
        let Some(round) = split_round(s, &mut normals, (&mut split, &mut at_mid_instead), (&refused, (boundary, off), covers)) else { break };
        stats.rounds += 1;
        stats.splits += split.len();
        stats.flips += round.flips;
        stats.folds_refused += round.folds_refused;
        cands.clear();
        for (fi, &old) in round.origin.iter().enumerate() {
            if round.changed[old as usize] {
                let g = s.faces[fi];
                stats.covering = stats.covering.max(longest_edge(&s.vertices, g).0 / 3f64.sqrt());
                if may_sag(&s.vertices, &normals, g, (tol, covers)) {
                    cands.push(fi);
                }
            }
        }
    }
    stats
}

/// What one round of [`refine_sag`] made: for each new face the old face it came from,
/// which old faces were split or flipped, how many pairs were flipped, and how many old
/// faces had their splits and flips given up for a fold or crossing they made.
struct Round {
    origin: Vec<u32>,
    changed: Vec<bool>,
    flips: usize,
    folds_refused: usize,
}

/// Carry out one round: flip the `refused` edges that may be ([`flip_sagging`]), split the
/// edges of `split` at their points, and where that folds the surface or passes it through
/// itself ([`folds_made`], [`crossings_made`]), again: an old face there with edges split
/// at crease points has them split at their midpoints' boundary points instead
/// (`at_mid_instead`), another has its splits and flips given up. `None` when nothing is
/// left to do (`s` unchanged).
fn split_round(
    s: &mut Surface,
    normals: &mut Vec<Option<Vec3>>,
    (split, at_mid_instead): (&mut Splits, &mut Splits),
    (refused, (boundary, off), covers): (&[(u32, u32)], (&Boundary<'_>, f64), f64),
) -> Option<Round> {
    let (saved, vertices_before) = (s.faces.clone(), s.vertices.len());
    let mut flips: Vec<[usize; 2]> = flip_sagging(s, refused, split, (boundary, off), covers).chunks_exact(2).map(|p| [p[0], p[1]]).collect();
    let mut given_up = vec![false; saved.len()];
    let (mut folds_refused, mut give_up_passes) = (0, 0);
    // each pass puts a midpoint for a crease point or gives up a face: past the passes
    // that give up, every split and flip is given up, and the pass after returns `None`
    loop {
        if split.is_empty() && flips.is_empty() {
            return None;
        }
        let mut changed = vec![false; saved.len()];
        for &fi in flips.iter().flatten() {
            changed[fi] = true;
        }
        let mut order: Vec<(u32, u32)> = split.keys().copied().collect();
        order.sort_unstable();
        let index: FastMap<(u32, u32), u32> = order.iter().enumerate().map(|(i, &e)| (e, (vertices_before + i) as u32)).collect();
        for e in &order {
            let (p, n) = split[e];
            s.vertices.push(p);
            normals.push(Some(n));
        }
        let mut faces = Vec::with_capacity(s.faces.len() + 3 * split.len());
        let mut origin = Vec::with_capacity(faces.capacity());
        for (old, &f) in s.faces.iter().enumerate() {
            let mid = [0, 1, 2].map(|k| index.get(&edge_key(f[k], f[(k + 1) % 3])).copied());
            changed[old] |= mid.iter().any(Option::is_some);
            split_triangle(&s.vertices, f, mid, &mut faces);
            origin.resize(faces.len(), old as u32);
        }
        let mut folded = folds_made(&s.vertices, &faces, &origin, &changed);
        folded.extend(crossings_made(&s.vertices, &faces, &origin, &changed));
        folded.sort_unstable();
        folded.dedup();
        if folded.is_empty() {
            s.faces = faces;
            return Some(Round { origin, changed, flips: flips.len(), folds_refused });
        }
        // undo, and leave the old faces beside the folds as they were (all, past the passes)
        s.vertices.truncate(vertices_before);
        normals.truncate(vertices_before);
        let last = give_up_passes >= MAX_FOLD_PASSES;
        let give_up: Vec<usize> = if last { (0..saved.len()).collect() } else { folded };
        let mut gave_up = false;
        for old in give_up {
            let edges = [0, 1, 2].map(|k| edge_key(saved[old][k], saved[old][(k + 1) % 3]));
            let instead: Vec<(u32, u32)> = edges.into_iter().filter(|e| split.contains_key(e) && at_mid_instead.contains_key(e)).collect();
            if !last && !instead.is_empty() {
                for e in instead {
                    split.insert(e, at_mid_instead.remove(&e).expect("an edge with a midpoint"));
                }
                continue;
            }
            folds_refused += usize::from(!given_up[old]);
            given_up[old] = true;
            gave_up = true;
            for e in edges {
                split.remove(&e);
            }
        }
        flips.retain(|&[f1, f2]| {
            let keep = !given_up[f1] && !given_up[f2];
            if !keep {
                (s.faces[f1], s.faces[f2]) = (saved[f1], saved[f2]);
            }
            keep
        });
        give_up_passes += usize::from(gave_up);
    }
}

/// The changed old faces (by `origin`, of the new `faces`) whose new triangles meet
/// another triangle of `faces` that is no neighbour along an edge (cross it, or touch it
/// along an edge: stricter than the solid check, which lets a sheet rest on another): the
/// surface passes through itself there (a split point moved across a sheet close by, or a
/// corner's triangles turned over one another; an edge's fold is [`folds_made`]'s).
/// Sorted, without repeats.
fn crossings_made(v: &[Vec3], faces: &[[u32; 3]], origin: &[u32], changed: &[bool]) -> Vec<usize> {
    let corners = |f: [u32; 3]| f.map(|i| v[i as usize]);
    let made: Vec<u32> = (0..faces.len() as u32).filter(|&fi| changed[origin[fi as usize] as usize]).collect();
    if made.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<Aabb> = made.iter().map(|&fi| Aabb::from_points(&corners(faces[fi as usize]))).collect();
    let tree = Bvh::build(&boxes);
    let scale = Aabb::from_points(v).diagonal().max(1e-300);
    let mut crossed: Vec<usize> = (0..faces.len())
        .into_par_iter()
        .flat_map_iter(|gi| {
            let g = faces[gi];
            let mut hit = Vec::new();
            tree.for_each_overlapping(&Aabb::from_points(&corners(g)), |k| {
                let fi = made[k] as usize;
                let shared = g.iter().filter(|i| faces[fi].contains(i)).count();
                if shared < 2 && (fi < gi || !changed[origin[gi] as usize]) && triangles_meet(corners(faces[fi]), corners(g), scale) {
                    hit.push(origin[fi] as usize);
                    if changed[origin[gi] as usize] {
                        hit.push(origin[gi] as usize);
                    }
                }
            });
            hit
        })
        .collect();
    crossed.sort_unstable();
    crossed.dedup();
    crossed
}

/// The old faces (by `origin`, of the new `faces`) on either side of an edge of a new
/// triangle (one whose old face is `changed`) where the surface folds back: the two faces'
/// normals within [`FOLD_COS`] of opposite. Sorted, without repeats.
fn folds_made(v: &[Vec3], faces: &[[u32; 3]], origin: &[u32], changed: &[bool]) -> Vec<usize> {
    // only faces with two corners on new triangles can be across an edge from one
    let mut on_new = vec![false; v.len()];
    for (fi, f) in faces.iter().enumerate() {
        if changed[origin[fi] as usize] {
            f.iter().for_each(|&i| on_new[i as usize] = true);
        }
    }
    let near: Vec<u32> = (0..faces.len() as u32).filter(|&fi| faces[fi as usize].iter().filter(|&&i| on_new[i as usize]).count() >= 2).collect();
    let by_edge: FastMap<(u32, u32), u32> = near
        .iter()
        .flat_map(|&fi| {
            let f = faces[fi as usize];
            (0..3).map(move |k| ((f[k], f[(k + 1) % 3]), fi))
        })
        .collect();
    let unit = |f: [u32; 3]| normal(v[f[0] as usize], v[f[1] as usize], v[f[2] as usize]).normalize_or_zero();
    let mut folded: Vec<usize> = Vec::new();
    for (fi, &f) in faces.iter().enumerate() {
        if !changed[origin[fi] as usize] {
            continue;
        }
        let n = unit(f);
        for k in 0..3 {
            let Some(&g) = by_edge.get(&(f[(k + 1) % 3], f[k])) else { continue };
            if n.dot(unit(faces[g as usize])) < -FOLD_COS {
                folded.extend([origin[fi] as usize, origin[g as usize] as usize]);
            }
        }
    }
    folded.sort_unstable();
    folded.dedup();
    folded
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The valley `z = SLOPE |x|` (solid below it, outward normal up): a point's nearest
    /// point on it, and the normal there.
    const SLOPE: f64 = 1.0;

    fn on_valley(p: Vec3) -> BoundaryPoint {
        on_valley_of(SLOPE, p)
    }

    /// [`on_valley`] for the valley `z = slope |x|`.
    fn on_valley_of(slope: f64, p: Vec3) -> BoundaryPoint {
        let sides = [Vec3::new(-slope, 0.0, 1.0).normalize(), Vec3::new(slope, 0.0, 1.0).normalize()];
        // the nearest point on each half-plane through the crease (x = 0, z = 0), clamped to it
        let on_half = |n: Vec3, sign: f64| {
            let q = p - n * p.dot(n);
            if q.x * sign >= 0.0 {
                (q, n)
            } else {
                (Vec3::new(0.0, p.y, 0.0), n)
            }
        };
        let (a, b) = (on_half(sides[0], 1.0), on_half(sides[1], -1.0));
        if (p - a.0).length() <= (p - b.0).length() {
            a
        } else {
            b
        }
    }

    /// A strip of the valley across `x` in `[-1, 1]`, `y` in `[0, len]`: vertices on it at
    /// `x` = ±1 and ±0.4 (so the crease runs through the middle of triangles), triangles
    /// wound to face up.
    fn strip(len: usize) -> Surface {
        let xs = [-1.0, -0.4, 0.4, 1.0];
        let mut s = Surface::default();
        for j in 0..=len {
            for &x in &xs {
                s.vertices.push(Vec3::new(x, j as f64 * 0.5, SLOPE * f64::abs(x)));
            }
        }
        for j in 0..len as u32 {
            for i in 0..3u32 {
                let (a, b, c, d) = (4 * j + i, 4 * j + i + 1, 4 * (j + 1) + i, 4 * (j + 1) + i + 1);
                s.faces.extend([[a, b, d], [a, d, c]]);
            }
        }
        s
    }

    /// The largest distance of sampled points of `s`'s triangles to the valley.
    fn largest_sag(s: &Surface) -> f64 {
        let mut worst: f64 = 0.0;
        for f in &s.faces {
            let [a, b, c] = f.map(|i| s.vertices[i as usize]);
            for (u, v) in [(0.33, 0.33), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5), (0.25, 0.5), (0.5, 0.25), (0.2, 0.2)] {
                let p = a + (b - a) * u + (c - a) * v;
                worst = worst.max((on_valley(p).0 - p).length());
            }
        }
        worst
    }

    /// Every edge used once each way, except along the strip's border.
    fn interior_edges_paired(s: &Surface) -> bool {
        let mut count: FastMap<(u32, u32), i32> = FastMap::default();
        for f in &s.faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                *count.entry(edge_key(a, b)).or_default() += if a < b { 1 } else { -1 };
            }
        }
        count.values().all(|&c| c.abs() <= 1)
    }

    #[test]
    fn a_chord_across_a_crease_is_refined_until_it_sags_less_than_the_tolerance() {
        let mut s = strip(6);
        let before = largest_sag(&s);
        let tol = 0.01;
        assert!(before > 20.0 * tol, "the strip's chords across the crease sag by {before}");
        let stats = refine_sag(&mut s, &|p, _| Some(on_valley(p)), (tol, 10.0), 0.0);
        let after = largest_sag(&s);
        assert!(stats.splits > 0, "{stats:?}");
        // flat sheets: the split points lie on the crease itself, so one round takes it all
        assert!(after <= tol, "still sags by {after} after {stats:?}");
        assert!(interior_edges_paired(&s), "the split strip is not one consistently wound sheet");
        // every vertex made lies on the valley, every triangle still faces up
        assert!(s.vertices.iter().all(|&v| (on_valley(v).0 - v).length() < 1e-12));
        assert!(s.faces.iter().all(|f| {
            let [a, b, c] = f.map(|i| s.vertices[i as usize]);
            normal(a, b, c).z > 0.0
        }));
        // the bound's share: no triangle made covers more than the ones it came from
        assert!(stats.covering <= 0.75, "{stats:?}");
    }

    #[test]
    fn a_chord_across_a_crease_sharper_than_a_right_angle_is_split_at_the_crease() {
        // the valley z = 2 |x| turns by 127 degrees; the triangle's corner c lies on the
        // crease, level with a, so the half of the split on b's sheet turns from the chord
        // by more than a right angle (the old test of facing refused it), yet faces up
        let slope = 2.0;
        let (a, c, b) = (Vec3::new(-1.0, 0.0, slope), Vec3::ZERO, Vec3::new(1.0, 1.0, slope));
        let mut s = Surface { vertices: vec![a, c, b], faces: vec![[0, 1, 2]], ..Surface::default() };
        assert!(normal(a, c, b).z > 0.0);
        let sag = |s: &Surface| {
            let [p, q, r] = s.faces[0].map(|i| s.vertices[i as usize]);
            s.faces
                .iter()
                .map(|f| f.map(|i| s.vertices[i as usize]))
                .flat_map(|[p, q, r]| [(p + q) * 0.5, (q + r) * 0.5, (r + p) * 0.5, (p + q + r) / 3.0])
                .chain([p, q, r])
                .map(|x| (on_valley_of(slope, x).0 - x).length())
                .fold(0.0, f64::max)
        };
        let before = sag(&s);
        let tol = 0.01;
        assert!(before > 0.3, "the chord sags by {before}");
        let stats = refine_sag(&mut s, &|p, _| Some(on_valley_of(slope, p)), (tol, 10.0), 0.0);
        assert!(stats.splits > 0, "{stats:?}");
        // the split point is the crease under the edge a-b: (0, 0.5, 0)
        assert!(s.vertices.iter().any(|v| (*v - Vec3::new(0.0, 0.5, 0.0)).length() < 1e-12), "{:?}", s.vertices);
        assert!(sag(&s) <= tol, "still sags by {} after {stats:?}", sag(&s));
        assert!(s.faces.iter().all(|f| {
            let [p, q, r] = f.map(|i| s.vertices[i as usize]);
            normal(p, q, r).z > 0.0
        }));
    }

    #[test]
    fn a_flat_surface_is_left_alone() {
        let mut s = strip(3);
        for v in &mut s.vertices {
            v.z = 0.0;
        }
        let faces = s.faces.clone();
        let stats = refine_sag(&mut s, &|p, _| Some((Vec3::new(p.x, p.y, 0.0), Vec3::Z)), (1e-6, 10.0), 0.0);
        assert_eq!((stats.splits, stats.tested), (0, 0));
        assert_eq!(s.faces, faces);
    }

    /// The unit square in the plane `z = 0`, facing up, cut along its diagonal 0–2.
    fn square() -> Surface {
        Surface { vertices: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y], faces: vec![[0, 1, 2], [0, 2, 3]], ..Default::default() }
    }

    /// One round on `s` splitting its edge 1–2 at `m` (on the plane; nothing to flip).
    fn split_right_edge_at(s: &mut Surface, m: Vec3) -> (Option<Round>, Splits) {
        let mut normals = vec![Some(Vec3::Z); s.vertices.len()];
        let mut split: Splits = [((1, 2), (m, Vec3::Z))].into_iter().collect();
        let flat = |p: Vec3, _: f64| Some((Vec3::new(p.x, p.y, 0.0), Vec3::Z));
        let round = split_round(s, &mut normals, (&mut split, &mut Splits::default()), (&[], (&flat, 0.0), 10.0));
        (round, split)
    }

    #[test]
    fn a_split_point_beside_its_edge_splits_the_triangle() {
        let mut s = square();
        let (round, split) = split_right_edge_at(&mut s, Vec3::new(1.1, 0.5, 0.0));
        let round = round.expect("a split made");
        assert_eq!((split.len(), round.folds_refused, s.faces.len()), (1, 0, 3));
        assert_eq!(round.changed, vec![true, false]);
    }

    #[test]
    fn a_split_point_past_a_neighbours_edge_is_given_up_not_folded() {
        // the half m 2 0 would face down, over the other triangle across 2–0
        let mut s = square();
        let (faces, vertices) = (s.faces.clone(), s.vertices.clone());
        let (round, split) = split_right_edge_at(&mut s, Vec3::new(-0.5, 0.5, 0.0));
        assert!(round.is_none(), "nothing left to do once the split is given up");
        assert!(split.is_empty());
        assert_eq!((s.faces, s.vertices), (faces, vertices));
    }

    #[test]
    fn a_fold_found_by_folds_made_names_the_old_faces_on_both_sides() {
        let mut s = square();
        s.vertices.push(Vec3::new(-0.5, 0.5, 0.0));
        // the old face 0 as its two halves (the second folded), the old face 1 unchanged
        let faces = [[1, 4, 0], [4, 2, 0], [0, 2, 3]];
        assert_eq!(folds_made(&s.vertices, &faces, &[0, 0, 1], &[true, false]), vec![0, 1]);
        assert!(folds_made(&s.vertices, &faces, &[0, 0, 1], &[false, false]).is_empty(), "only new triangles are asked");
    }

    #[test]
    fn a_new_triangle_crossing_another_names_its_old_face_and_neighbours_do_not_count() {
        // a new triangle on the plane z = 0 (old face 0), one piercing it (old face 1,
        // unchanged), and one sharing its edge 0-1 (old face 2, changed: neighbours)
        let v = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.2, 0.2, -1.0), Vec3::new(0.3, 0.2, 1.0), Vec3::new(0.2, 0.3, 1.0), Vec3::new(0.5, -0.5, 0.5)];
        let faces = [[0, 1, 2], [3, 4, 5], [1, 0, 6]];
        assert_eq!(crossings_made(&v, &faces, &[0, 1, 2], &[true, false, true]), vec![0]);
        assert_eq!(crossings_made(&v, &faces, &[0, 1, 2], &[true, true, false]), vec![0, 1], "both sides when both are new");
        assert!(crossings_made(&v, &faces, &[0, 1, 2], &[false, false, true]).is_empty(), "only new triangles are asked");
    }

    #[test]
    fn triangles_wider_than_the_cover_are_not_split() {
        let mut s = strip(6);
        let faces = s.faces.clone();
        let stats = refine_sag(&mut s, &|p, _| Some(on_valley(p)), (0.01, 0.1), 0.0);
        assert_eq!(stats.splits, 0);
        assert_eq!(s.faces, faces);
    }
}
