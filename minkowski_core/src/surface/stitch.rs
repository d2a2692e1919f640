//! Joining the exact polygons of plane-resolved cells to the sampled triangles of the band.
//!
//! Where a plane-resolved cell meets a neighbour (sampled, or resolved at another size),
//! both sides trace the same segments of the same planes on their shared face, but split
//! them at different points: T-junctions. The polygons are triangulated, their corners
//! welded to vertices within a tolerance, and every edge used once (its reverse missing)
//! is split at the vertices of other such edges lying on it, the triangle becoming a fan
//! about its centroid. Nothing is moved there, so the surface is the same point set; the
//! caller checks that every edge then has its reverse exactly once (closed, manifold).
//! Where sheets of it touch, [`unzip_touching_sheets`] gives each its own vertex, moved a
//! little into it (the bound adds the move).
//!
//! Entry points: [`join`], [`open_edges`].

use super::regions::{self, PlaneKey, RegionStats};
use super::Surface;
use crate::bvh::Bvh;
use crate::math::{Aabb, Vec3};
use crate::util::{FastMap, FastSet};
use rayon::prelude::*;

/// How far, in cells, the copies of a vertex where sheets touched move apart into their
/// own sheets ([`unzip_touching_sheets`]).
pub const SHEETS_APART: f64 = 1e-3;
/// The most they move, in cells, whatever float32 would need (so the bound still shrinks
/// with the cells).
pub const SHEETS_APART_MAX: f64 = 0.05;

/// How far, in cells, a fold's faces may lie from what is left when it is replaced by
/// what it covers once ([`super::folds::unfold`]); the move counts in the planes' bound.
const FOLD_REACH: f64 = 0.05;

/// Replace the folds of the joined surface in a plane by what they cover once
/// ([`super::folds::unfold`], within [`FOLD_REACH`] cells; the weld tolerance `tol`, the
/// cell size `h`); the move and the weld count in the planes' bound. Returns how many
/// patches were replaced.
pub fn unfold(s: &mut Surface, tol: f64, h: f64) -> usize {
    // (a fold's flap reaches a few welds from what is left; a sheet thinner than the weld
    // folded into the plane reaches a cell or more, and is left to the slivers' bound)
    let (unfolded, moved) = super::folds::unfold(&mut s.vertices, &mut s.faces, tol, FOLD_REACH * h);
    if unfolded > 0 {
        // (the faces replaced were off the answer by the deviation and the weld already)
        s.planar_deviation += tol + moved;
        drop_unused_vertices(s);
    }
    unfolded
}

/// Add the convex polygons `polys` (each counter-clockwise about its outward normal) to
/// `s`, welding corners within `tol` and splitting edges at T-junctions (see the module
/// docs).
pub fn join(s: &mut Surface, polys: &[Vec<Vec3>], planes: &[PlaneKey], tol: f64, lattice: (Vec3, f64)) -> RegionStats {
    if polys.is_empty() {
        return RegionStats::default();
    }
    // the band's own open edges end where the polygons begin: weld to their vertices
    let mut grid = Grid::new(4.0 * tol);
    for (a, b) in open_edges(&s.faces) {
        for v in [a, b] {
            grid.insert(v, s.vertices[v as usize]);
        }
    }
    let band_vertices = s.vertices.len();
    let welded: Vec<Vec<u32>> = polys.iter().map(|poly| poly.iter().map(|&p| grid.weld(p, tol, &mut s.vertices)).collect()).collect();
    let (faces, stats) = regions::triangulate(&mut s.vertices, &welded, planes, tol, band_vertices);
    s.faces.extend(faces);
    // a triangle two of whose corners welded into one is a segment: no area, and its edges
    // would count as used twice
    drop_degenerate(&mut s.faces);
    if crate::deadline::cancelled() {
        return stats; // the surface is dropped
    }
    split_t_junctions(s, tol);
    if crate::deadline::cancelled() {
        return stats;
    }
    fill_face_gaps(s, tol, lattice);
    drop_degenerate(&mut s.faces);
    cancel_opposite_twins(&mut s.faces);
    // (the corners inside merged regions are no triangle's now)
    drop_unused_vertices(s);
    stats
}

/// Remove the triangles with a corner twice (segments, of no area). Returns how many went.
fn drop_degenerate(faces: &mut Vec<[u32; 3]>) -> usize {
    let before = faces.len();
    faces.retain(|f| f[0] != f[1] && f[1] != f[2] && f[2] != f[0]);
    before - faces.len()
}

/// Remove every pair of a triangle and its reverse (the same corners, facing the other
/// way): a sheet of no thickness, left where two cells' polygons or fills overlap within
/// the weld tolerance. Each edge of such a pair is used once each way by the pair itself,
/// so without it the rest of the surface keeps its edge pairing. Returns how many went.
pub fn cancel_opposite_twins(faces: &mut Vec<[u32; 3]>) -> usize {
    // key: the corners rotated to start at the smallest, and whether that order is reversed
    let canonical = |f: &[u32; 3]| {
        let r = (0..3).min_by_key(|&i| f[i]).unwrap_or(0);
        let (a, b, c) = (f[r], f[(r + 1) % 3], f[(r + 2) % 3]);
        if b < c {
            ((a, b, c), false)
        } else {
            ((a, c, b), true)
        }
    };
    let mut by_key: FastMap<(u32, u32, u32), [Vec<usize>; 2]> = FastMap::default();
    for (i, f) in faces.iter().enumerate() {
        let (k, rev) = canonical(f);
        by_key.entry(k).or_default()[rev as usize].push(i);
    }
    let mut gone = vec![false; faces.len()];
    let mut pairs = 0;
    for [fwd, back] in by_key.values() {
        for (&i, &j) in fwd.iter().zip(back) {
            gone[i] = true;
            gone[j] = true;
            pairs += 1;
        }
    }
    if pairs > 0 {
        let mut k = 0;
        faces.retain(|_| {
            k += 1;
            !gone[k - 1]
        });
    }
    pairs
}

/// Remove closed components that are slivers: at most `size` across and enclosing less
/// than `volume` (two layers of the joined surface folded onto each other, left where a
/// fill and a polygon overlap, or the two sides of a sheet thinner than the weld, welded
/// into pieces). Returns their boxes: one that lies apart from the rest held boundary no
/// other part of the surface shows (the caller takes its reach into the bound).
pub fn drop_slivers(s: &mut Surface, size: f64, volume: f64) -> Vec<Aabb> {
    let mut uf = crate::util::UnionFind::new(s.vertices.len());
    for f in &s.faces {
        uf.union(f[0] as usize, f[1] as usize);
        uf.union(f[0] as usize, f[2] as usize);
    }
    let mut parts: FastMap<usize, (f64, Aabb)> = FastMap::default();
    for f in &s.faces {
        let p = f.map(|v| s.vertices[v as usize]);
        let e = parts.entry(uf.find(f[0] as usize)).or_insert((0.0, Aabb::empty()));
        e.0 += p[0].dot(p[1].cross(p[2])) / 6.0;
        e.1 = e.1.union(&Aabb::from_points(&p));
    }
    let components = parts.len();
    let slivers: FastMap<usize, Aabb> = parts.into_iter().filter(|(_, (v, b))| v.abs() < volume && b.extent().max_element() <= size).map(|(r, (_, b))| (r, b)).collect();
    if slivers.is_empty() || slivers.len() == components {
        return Vec::new();
    }
    s.faces.retain(|f| !slivers.contains_key(&uf.find(f[0] as usize)));
    drop_unused_vertices(s);
    slivers.into_values().collect()
}

/// Remove the vertices no triangle uses (renumbering the triangles'). Returns each old
/// vertex's new number (`u32::MAX`: removed).
fn drop_unused_vertices(s: &mut Surface) -> Vec<u32> {
    let mut remap = vec![u32::MAX; s.vertices.len()];
    for f in &s.faces {
        for &v in f {
            remap[v as usize] = 0;
        }
    }
    let mut kept = Vec::with_capacity(s.vertices.len());
    for (i, &p) in s.vertices.iter().enumerate() {
        if remap[i] == 0 {
            remap[i] = kept.len() as u32;
            kept.push(p);
        }
    }
    s.vertices = kept;
    for f in &mut s.faces {
        *f = f.map(|v| remap[v as usize]);
    }
    remap
}

/// Vertices whose triangles do not form one fan (a disk) about them: where two sheets of
/// the joined surface touch at a point. On a closed surface with every edge used once each
/// way, these are what is left of a non-manifold join.
pub fn pinched_vertices(faces: &[[u32; 3]]) -> Vec<u32> {
    let Some(n) = faces.iter().flatten().max().map(|&v| v as usize + 1) else {
        return Vec::new();
    };
    // per vertex: the edges opposite it, its link's directed edges
    let corners = || faces.iter().flat_map(|f| (0..3).map(move |i| (f[i] as usize, (f[(i + 1) % 3], f[(i + 2) % 3]))));
    let (start, mut link) = buckets(n, corners);
    let mut out = Vec::new();
    for v in 0..n {
        let star = &mut link[start[v]..start[v + 1]];
        if star.is_empty() {
            continue;
        }
        star.sort_unstable();
        // follow the link from its first edge: one cycle must use all of it
        let star = &*star;
        let (mut at, mut steps) = (star[0].1, 1usize);
        while at != star[0].0 && steps <= star.len() {
            match star.binary_search_by(|e| (e.0).cmp(&at)) {
                Ok(k) => at = star[k].1,
                Err(_) => break,
            }
            steps += 1;
        }
        if at != star[0].0 || steps != star.len() {
            out.push(v as u32);
        }
    }
    out
}

/// Give each sheet its own copy of a vertex where sheets of the surface touch: two parts of
/// the sum meeting along a hair-thin edge or at a point (or coming within the weld
/// tolerance there, so their corners welded), which leaves an edge used twice each way or
/// a pinched vertex. About such a vertex the triangles fall into fans that each close
/// (the simple cycles of its link); every fan but the first gets a copy of the vertex.
/// Copies at one place would be welded into one again by any reader that joins vertices
/// by position (STL has no others): each fan's vertex moves [`SHEETS_APART`] of `h` into
/// its own fan (towards its triangles' centroids), as far as [`apart_step`] says;
/// `s.sheets_apart` records the largest move (the bound adds it). `at`:
/// the vertices to look at (the ends of open edges, or the pinched vertices when there
/// are none). Edges left open (a real hole) are left to the caller. Returns how many
/// copies were made.
pub fn unzip_touching_sheets(s: &mut Surface, mut at: Vec<u32>, h: f64) -> usize {
    at.sort_unstable();
    at.dedup();
    if at.is_empty() {
        return 0;
    }
    // the triangles about each of those vertices
    let star = stars(&s.faces, &at);
    // fans are found on the surface as unzipped so far (a hair-thin edge's second end
    // splits once its first has); directions and heights use the places as they were
    let before = s.vertices.clone();
    let mut copied_from: Vec<u32> = Vec::new();
    let mut copies = 0;
    for v in at {
        let fans = fans(&s.faces, v, &star[&v]);
        if fans.len() < 2 {
            continue;
        }
        let was = |c: u32| before[copied_from.get((c as usize).wrapping_sub(before.len())).copied().unwrap_or(c) as usize];
        let place = before[v as usize];
        let step = apart_step(place, h, star[&v].iter().map(|&t| (s.faces[t].map(was), s.faces[t].iter().position(|&c| c == v))));
        let moves: Vec<(Vec<usize>, Vec3)> = fans
            .into_iter()
            .map(|fan| {
                let into = into_fan(place, fan.iter().map(|&t| s.faces[t].map(was)));
                (fan, place + into * step)
            })
            .collect();
        for (k, (fan, moved)) in moves.into_iter().enumerate() {
            let id = if k == 0 {
                v
            } else {
                s.vertices.push(moved);
                copied_from.push(v);
                copies += 1;
                s.vertices.len() as u32 - 1
            };
            s.vertices[id as usize] = moved;
            for t in fan {
                for corner in s.faces[t].iter_mut().filter(|c| **c == v) {
                    *corner = id;
                }
            }
        }
        s.sheets_apart = s.sheets_apart.max(step);
    }
    copies
}

/// Distinct vertices closer than this, in a length unit, may be merged by a reader that
/// rounds coordinates to it when it loads a mesh (trimesh's default weld: its `tol.merge`).
pub const READER_WELD: f64 = 1e-8;

/// How far apart a coordinate of magnitude up to `x` may lie from another and a reader
/// welding by position still merge them: float32 (STL stores nothing finer) moves it by
/// at most half its step, at most `f32::EPSILON |x| / 2`, and [`READER_WELD`]'s grid by at
/// most half of that; a reader merges two vertices only when every coordinate lands on
/// the same value.
fn weld_reach(x: f64) -> f64 {
    READER_WELD + f32::EPSILON as f64 * x.abs()
}

/// Whether a reader welding by position may merge vertices at `p` and `q` ([`weld_reach`]
/// on every axis).
fn may_weld(p: Vec3, q: Vec3) -> bool {
    (0..3).all(|k| (p[k] - q[k]).abs() <= weld_reach(p[k].abs().max(q[k].abs())))
}

/// Keep distinct vertices apart to a reader that welds by position ([`may_weld`]): two
/// sheets of the surface closed over the same loop from either side (the fills of a
/// crevice's holes) meet there without sharing a vertex, and a crossing held a hair off a
/// lattice point ([`super::EDGE_CLAMP`]) lies that close to its neighbour on the next
/// edge. Such a pair joined by an edge is made one (the edge collapsed, [`collapse_edge`],
/// keeping either end) where the surface stays a closed manifold and no triangle turns
/// over; the vertices of the other pairs each move into their own triangles as
/// [`unzip_touching_sheets`] moves a copy, and a pair such moves leave within a weld (held
/// short by thin triangles about them) is pushed apart ([`push_apart`]). `s.sheets_apart`
/// grows by the longest edge collapsed plus the longest move plus the longest push (a
/// vertex may have been moved before, and a kept end may move after its collapse).
/// Returns how many vertices were collapsed or moved clear of every other.
pub fn part_coincident_vertices(s: &mut Surface, h: f64) -> usize {
    let pairs = coinciding(s);
    if pairs.is_empty() {
        return 0;
    }
    let mut star = stars(&s.faces, &pair_ends(&pairs));
    let mut gone = vec![false; s.faces.len()];
    let mut collapsed: FastSet<u32> = FastSet::default();
    let mut longest_collapse: f64 = 0.0;
    for &(u, v) in &pairs {
        if collapsed.contains(&u) || collapsed.contains(&v) {
            continue;
        }
        // either end may be kept: which one turns no triangle over depends on the side
        if let Some(gone_end) = [(u, v), (v, u)].into_iter().find_map(|(keep, drop)| collapse_edge(s, &mut star, &mut gone, keep, drop).then_some(drop)) {
            longest_collapse = longest_collapse.max((s.vertices[u as usize] - s.vertices[v as usize]).length());
            collapsed.insert(gone_end);
        }
    }
    let mut pairs = pairs;
    if !collapsed.is_empty() {
        let mut n = 0;
        s.faces.retain(|_| {
            n += 1;
            !gone[n - 1]
        });
        // a collapse moves no vertex: the pairs left are those between kept vertices,
        // numbered anew (in the same order)
        let remap = drop_unused_vertices(s);
        pairs = pairs.iter().map(|&(a, b)| (remap[a as usize], remap[b as usize])).filter(|&(a, b)| a != u32::MAX && b != u32::MAX).collect();
        star = stars(&s.faces, &pair_ends(&pairs));
    }
    let moving = pair_ends(&pairs);
    let before = s.vertices.clone();
    let mut longest_move: f64 = 0.0;
    for &v in &moving {
        let place = before[v as usize];
        let corners = |t: usize| s.faces[t].map(|c| before[c as usize]);
        let step = apart_step(place, h, star[&v].iter().map(|&t| (corners(t), s.faces[t].iter().position(|&c| c == v))));
        s.vertices[v as usize] = place + into_fan(place, star[&v].iter().map(|&t| corners(t))) * step;
        longest_move = longest_move.max(step);
    }
    let left = if moving.is_empty() { Vec::new() } else { coinciding(s) };
    let (pushed, longest_push) = push_apart(s, &left);
    s.sheets_apart += longest_collapse + longest_move + longest_push;
    collapsed.len() + moving.len().saturating_sub(pair_ends(&left).len()) + pushed
}

/// The vertices of `pairs`, each once, in order.
fn pair_ends(pairs: &[(u32, u32)]) -> Vec<u32> {
    let mut v: Vec<u32> = pairs.iter().flat_map(|&(a, b)| [a, b]).collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// Part the pairs `left` that a reader may still weld after the collapses and the moves
/// into the fans (a move held short by slivers about the vertex: a thin sheet's edge
/// eroded to a few 1e-9): one vertex of each moves away from the other, along the line
/// through them by twice the weld's reach on the axis that line runs most along, or else
/// along one axis by twice the reach (the way their difference on it points), the first
/// move that turns over no triangle about it and leaves none without area; the other
/// vertex is tried when none of the first's does. Returns how many vertices moved and the
/// longest move.
fn push_apart(s: &mut Surface, left: &[(u32, u32)]) -> (usize, f64) {
    if left.is_empty() {
        return (0, 0.0);
    }
    let star = stars(&s.faces, &pair_ends(left));
    let (mut pushed, mut longest): (usize, f64) = (0, 0.0);
    for &(u, v) in left {
        if !may_weld(s.vertices[u as usize], s.vertices[v as usize]) {
            continue; // an earlier push parted them
        }
        'pair: for (moving, other) in [(v, u), (u, v)] {
            let (p, q) = (s.vertices[moving as usize], s.vertices[other as usize]);
            let away = (p - q).normalize_or_zero();
            if away == Vec3::ZERO {
                break;
            }
            let reach = 2.0 * weld_reach(p.abs().max_element().max(q.abs().max_element()));
            let along_axes = (0..3).map(|k| (Vec3::AXES[k] * away[k].signum(), reach));
            for (dir, step) in std::iter::once((away, reach / away.abs().max_element())).chain(along_axes) {
                let to = p + dir * step;
                if !turns_over(s, &star[&moving], moving, to) {
                    s.vertices[moving as usize] = to;
                    pushed += 1;
                    longest = longest.max(step);
                    break 'pair;
                }
            }
        }
    }
    (pushed, longest)
}

/// Whether moving vertex `v` to `to` turns over a triangle of `tris` (its star) or
/// leaves one with no area.
fn turns_over(s: &Surface, tris: &[usize], v: u32, to: Vec3) -> bool {
    let at = |c: u32, moved: bool| if moved && c == v { to } else { s.vertices[c as usize] };
    let normal = |f: [u32; 3], moved: bool| (at(f[1], moved) - at(f[0], moved)).cross(at(f[2], moved) - at(f[0], moved));
    tris.iter().any(|&t| {
        let (old, new) = (normal(s.faces[t], false), normal(s.faces[t], true));
        new.length_squared() == 0.0 || old.dot(new) <= 0.0
    })
}

/// The pairs of used vertices a reader may weld ([`may_weld`]), each once, in order.
fn coinciding(s: &Surface) -> Vec<(u32, u32)> {
    let used: FastSet<u32> = s.faces.iter().flatten().copied().collect();
    let mut used: Vec<u32> = used.into_iter().collect();
    used.sort_unstable();
    let Some(bin_size) = used.iter().map(|&v| weld_reach(s.vertices[v as usize].abs().max_element())).reduce(f64::max) else {
        return Vec::new();
    };
    let bin = |p: Vec3| p.to_array().map(|x| (x / bin_size).floor() as i64);
    let mut bins: FastMap<[i64; 3], Vec<u32>> = FastMap::default();
    for &v in &used {
        bins.entry(bin(s.vertices[v as usize])).or_default().push(v);
    }
    // each pair once: a vertex looks in its own bin (at later vertices) and in the 13
    // bins after it
    let forward: Vec<[i64; 3]> = (-1..=1).flat_map(|dx| (-1..=1).flat_map(move |dy| (-1..=1).map(move |dz| [dx, dy, dz]))).filter(|d| *d > [0, 0, 0]).collect();
    let near = |v: u32| -> Vec<(u32, u32)> {
        let (p, [x, y, z]) = (s.vertices[v as usize], bin(s.vertices[v as usize]));
        let own = bins[&[x, y, z]].iter().copied().filter(|&w| w > v);
        let after = forward.iter().flat_map(|d| bins.get(&[x + d[0], y + d[1], z + d[2]]).into_iter().flatten().copied());
        own.chain(after).filter(|&w| may_weld(p, s.vertices[w as usize])).map(|w| (v.min(w), v.max(w))).collect()
    };
    let mut pairs: Vec<(u32, u32)> = used.par_iter().flat_map_iter(|&v| near(v)).collect();
    pairs.sort_unstable();
    pairs
}

/// Make `v` one with `u` when they are joined by an edge whose two triangles are the only
/// ones they share neighbours through (the link condition: the surface stays a closed
/// manifold) and no other triangle of `v` turns over or loses its area at `u`'s place.
/// `star` holds the triangles about each vertex being looked at, `gone` the triangles
/// removed; both are kept up to date.
fn collapse_edge(s: &mut Surface, star: &mut FastMap<u32, Vec<usize>>, gone: &mut [bool], u: u32, v: u32) -> bool {
    let live = |t: &usize| !gone[*t];
    let (Some(su), Some(sv)) = (star.get(&u), star.get(&v)) else { return false };
    let (su, sv): (Vec<usize>, Vec<usize>) = (su.iter().copied().filter(live).collect(), sv.iter().copied().filter(live).collect());
    let shared: Vec<usize> = sv.iter().copied().filter(|&t| s.faces[t].contains(&u)).collect();
    if shared.len() != 2 {
        return false;
    }
    let others = |tris: &[usize], me: u32| -> FastSet<u32> { tris.iter().flat_map(|&t| s.faces[t]).filter(|&c| c != me).collect() };
    let (nu, nv) = (others(&su, u), others(&sv, v));
    let opposite: Vec<u32> = shared.iter().flat_map(|&t| s.faces[t]).filter(|&c| c != u && c != v).collect();
    if nu.intersection(&nv).filter(|&&c| c != u && c != v).count() != 2 || opposite.len() != 2 || opposite[0] == opposite[1] {
        return false;
    }
    // nor may the links share an edge (a closed tetrahedron would fold flat)
    let link_edges = |tris: &[usize], me: u32| -> FastSet<(u32, u32)> {
        tris.iter()
            .map(|&t| {
                let f = s.faces[t];
                let k = f.iter().position(|&c| c == me).expect("in its star");
                let (a, b) = (f[(k + 1) % 3], f[(k + 2) % 3]);
                (a.min(b), a.max(b))
            })
            .collect()
    };
    if !link_edges(&su, u).is_disjoint(&link_edges(&sv, v)) {
        return false;
    }
    let moved: Vec<usize> = sv.iter().copied().filter(|t| !shared.contains(t)).collect();
    if turns_over(s, &moved, v, s.vertices[u as usize]) {
        return false;
    }
    for &t in &moved {
        for c in s.faces[t].iter_mut().filter(|c| **c == v) {
            *c = u;
        }
    }
    for &t in &shared {
        gone[t] = true;
    }
    star.entry(u).or_default().extend(moved);
    star.remove(&v);
    true
}

/// How far a vertex at `place` moves where sheets part: [`SHEETS_APART`] of `h`, at least
/// 16 float32 steps of its coordinates and four times [`weld_reach`], at most
/// [`SHEETS_APART_MAX`] of `h`, and less than
/// a sixth of its lowest height over the opposite edge in its triangles `star` (their
/// corners, and which is the vertex). No triangle flips: its corners each moved less than
/// a sixth of their heights over the opposite edges change its area by less than 7/12 of it.
fn apart_step(place: Vec3, h: f64, star: impl Iterator<Item = ([Vec3; 3], Option<usize>)>) -> f64 {
    let wanted = (SHEETS_APART * h).max(16.0 * f32::EPSILON as f64 * place.abs().max_element()).max(4.0 * weld_reach(place.abs().max_element())).min(SHEETS_APART_MAX * h);
    let lowest = star.map(|(p, at)| height_over_opposite_edge(p, at)).fold(f64::INFINITY, f64::min);
    wanted.min(lowest / 6.0)
}

/// The unit direction from `place` into the triangles `fan` (their corners): towards the
/// sum of their centroids; zero when that is `place`.
fn into_fan(place: Vec3, fan: impl Iterator<Item = [Vec3; 3]>) -> Vec3 {
    fan.map(|p| (p[0] + p[1] + p[2]) / 3.0 - place).fold(Vec3::ZERO, |acc, d| acc + d).normalize_or_zero()
}

/// The triangles about each of the vertices `at` (indices into `faces`).
fn stars(faces: &[[u32; 3]], at: &[u32]) -> FastMap<u32, Vec<usize>> {
    let mut star: FastMap<u32, Vec<usize>> = at.iter().map(|&v| (v, Vec::new())).collect();
    for (i, f) in faces.iter().enumerate() {
        for v in f {
            if let Some(tris) = star.get_mut(v) {
                tris.push(i);
            }
        }
    }
    star
}

/// The distance of corner `at` (0 when `None`) of the triangle with corners `p` from the
/// line through the other two.
fn height_over_opposite_edge(p: [Vec3; 3], at: Option<usize>) -> f64 {
    let i = at.unwrap_or(0);
    let (apex, x, y) = (p[i], p[(i + 1) % 3], p[(i + 2) % 3]);
    let base = (y - x).length();
    if base == 0.0 {
        return 0.0;
    }
    (x - apex).cross(y - apex).length() / base
}

/// The triangles `tris` about vertex `v` as closed fans (each a simple cycle of `v`'s link,
/// the edge opposite `v` in each triangle, walked in order); one fan when they do not all
/// fall into closed fans (an open edge, or a triangle used twice).
fn fans(faces: &[[u32; 3]], v: u32, tris: &[usize]) -> Vec<Vec<usize>> {
    // per triangle, its link edge x -> y (the corners after v, in order)
    let mut by_edge: FastMap<(u32, u32), usize> = FastMap::default();
    let mut next: FastMap<u32, Vec<u32>> = FastMap::default();
    for &t in tris {
        let f = faces[t];
        let Some(i) = f.iter().position(|&c| c == v) else { continue };
        let (x, y) = (f[(i + 1) % 3], f[(i + 2) % 3]);
        if by_edge.insert((x, y), t).is_some() {
            return vec![tris.to_vec()];
        }
        next.entry(x).or_default().push(y);
    }
    let rings = cycles(&mut next);
    let fans: Vec<Vec<usize>> = rings.iter().map(|ring| (0..ring.len()).filter_map(|i| by_edge.get(&(ring[i], ring[(i + 1) % ring.len()])).copied()).collect()).collect();
    if fans.iter().map(Vec::len).sum::<usize>() != by_edge.len() {
        return vec![tris.to_vec()];
    }
    fans
}

/// The values of `items()` (key below `n`, value) grouped by key (a counting sort): key
/// `k`'s are `values[start[k]..start[k + 1]]`. `items` is called twice (count, then place).
fn buckets<T: Copy + Default, I: Iterator<Item = (usize, T)>>(n: usize, items: impl Fn() -> I) -> (Vec<usize>, Vec<T>) {
    let mut start = vec![0usize; n + 1];
    for (k, _) in items() {
        start[k + 1] += 1;
    }
    for k in 0..n {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut values = vec![T::default(); start[n]];
    for (k, v) in items() {
        values[fill[k]] = v;
        fill[k] += 1;
    }
    (start, values)
}

/// Directed edges used by one triangle whose reverse no triangle uses, and directed edges
/// used more than once (both break a closed manifold), in order; an edge used `k > 1`
/// times is listed `k` times. Edges are bucketed by their lower vertex (a counting sort),
/// so each is compared only with the few that share it: linear in the triangles.
pub fn open_edges(faces: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let Some(n) = faces.iter().flatten().max().map(|&v| v as usize + 1) else {
        return Vec::new();
    };
    let directed = || faces.iter().flat_map(|f| (0..3).map(move |i| (f[i], f[(i + 1) % 3])));
    // per lower vertex: (upper vertex, whether the edge runs from upper to lower)
    let keyed = || directed().map(|(a, b)| (a.min(b) as usize, (u64::from(a.max(b)) << 1) | u64::from(a > b)));
    let (start, mut items) = buckets(n, keyed);
    let mut out = Vec::new();
    for lo in 0..n {
        let list = &mut items[start[lo]..start[lo + 1]];
        list.sort_unstable();
        for group in list.chunk_by(|x, y| x >> 1 == y >> 1) {
            let hi = (group[0] >> 1) as u32;
            let up = group.iter().filter(|&&x| x & 1 == 0).count(); // lo -> hi
            let down = group.len() - up; // hi -> lo
            let lo = lo as u32;
            if lo == hi {
                // an edge from a vertex to itself is its own reverse
                out.extend(std::iter::repeat_n((lo, lo), if up > 1 { up } else { 0 }));
                continue;
            }
            let listed = |uses: usize, reverse: usize| if uses > 1 || (uses == 1 && reverse == 0) { uses } else { 0 };
            out.extend(std::iter::repeat_n((lo, hi), listed(up, down)));
            out.extend(std::iter::repeat_n((hi, lo), listed(down, up)));
        }
    }
    out.sort_unstable();
    out
}

/// Split every open edge at the ends of other open edges that lie on it (within `tol`).
fn split_t_junctions(s: &mut Surface, tol: f64) {
    let open = open_edges(&s.faces);
    if open.is_empty() {
        return;
    }
    let mut ends: Vec<u32> = open.iter().flat_map(|&(a, b)| [a, b]).collect();
    ends.sort_unstable();
    ends.dedup();
    let on: FastMap<(u32, u32), Vec<u32>> = points_on_edges(&s.vertices, &open, &ends, tol).into_iter().map(|(i, pts)| (open[i], pts)).collect();
    if on.is_empty() {
        return;
    }
    let mut faces = Vec::with_capacity(s.faces.len() + 4 * on.len());
    for f in std::mem::take(&mut s.faces) {
        let edges = [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])];
        if !edges.iter().any(|e| on.contains_key(e)) {
            faces.push(f);
            continue;
        }
        let points = |e: (u32, u32)| on.get(&e).map_or(&[][..], Vec::as_slice);
        split_at_edge_points(f, [points(edges[0]), points(edges[1]), points(edges[2])], &mut faces);
    }
    s.faces = faces;
}

/// The triangle `f` with the points `on[k]` on its edge from corner `k` to corner `k + 1`
/// (in order from corner `k`) split into triangles that have them as corners, with no new
/// vertex: the edge with the most points is split at its middle one towards the opposite
/// corner, and each half is split so in turn. Both halves keep the orientation and have
/// area (the point lies inside its edge, the opposite corner off it). (A vertex at the
/// centroid, as a fan would need, lies off the surface by the triangle's sag: across a
/// crease, by a sixth of the cell.)
fn split_at_edge_points(f: [u32; 3], on: [&[u32]; 3], out: &mut Vec<[u32; 3]>) {
    let Some(k) = (0..3).filter(|&k| !on[k].is_empty()).max_by_key(|&k| on[k].len()) else {
        out.push(f);
        return;
    };
    let (a, b, c) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
    let m = on[k].len() / 2;
    let p = on[k][m];
    split_at_edge_points([a, p, c], [&on[k][..m], &[], on[(k + 2) % 3]], out);
    split_at_edge_points([p, b, c], [&on[k][m + 1..], on[(k + 1) % 3], &[]], out);
}

/// Per edge (by index in `edges`) the `points` that lie on it within `tol`, strictly
/// between its ends, in order from its first end; edges with none are left out.
pub(super) fn points_on_edges(vertices: &[Vec3], edges: &[(u32, u32)], points: &[u32], tol: f64) -> FastMap<usize, Vec<u32>> {
    let at = |v: u32| vertices[v as usize];
    let boxes: Vec<Aabb> = edges.iter().map(|&(a, b)| Aabb::from_points(&[at(a), at(b)]).inflated(tol)).collect();
    let bvh = Bvh::build(&boxes);
    // (edge, parameter, point) per point on an edge, the points in parallel (a cancelled
    // call stops asking: its surface is dropped)
    let hits: Vec<(usize, f64, u32)> = points
        .par_iter()
        .flat_map_iter(|&v| {
            let mut found = Vec::new();
            if crate::deadline::cancelled() {
                return found;
            }
            let p = at(v);
            bvh.for_each_at_point(p, |i| {
                let (a, b) = edges[i];
                if v == a || v == b || a == b {
                    return;
                }
                let (pa, d) = (at(a), at(b) - at(a));
                let t = (p - pa).dot(d) / d.length_squared();
                if t > 0.0 && t < 1.0 && (pa + d * t - p).length() <= tol {
                    found.push((i, t, v));
                }
            });
            found
        })
        .collect();
    let mut on: FastMap<usize, Vec<(f64, u32)>> = FastMap::default();
    for (i, t, v) in hits {
        on.entry(i).or_default().push((t, v));
    }
    on.into_iter()
        .map(|(i, mut pts)| {
            pts.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            (i, pts.into_iter().map(|(_, v)| v).collect())
        })
        .collect()
}

/// A lattice plane: the axis it is normal to and its index along it.
type LatticePlane = (usize, i64);

/// Close the gaps left in cell faces where a sharp edge of a plane-resolved cell leaves it
/// into a sampled cell: on the shared face the exact trace bends at the edge, the sampled
/// one cuts across, and between the two a small polygon of the face is open. Per lattice
/// plane (`lattice`: the position of lattice point 0 and the spacing), the open edges lying
/// in it form loops; each is triangulated there (ear clipping). Its points lie in a band
/// cell's face that the true boundary crosses, so within the band's bound of it; loops that
/// are not simple are left (the caller sees them open).
fn fill_face_gaps(s: &mut Surface, tol: f64, lattice: (Vec3, f64)) {
    let open = open_edges(&s.faces);
    if open.is_empty() {
        return;
    }
    let (origin, h) = lattice;
    // the lattice planes (axis, index) each vertex lies in
    let on_plane = |v: u32, axis: usize| -> Option<i64> {
        let x = (s.vertices[v as usize][axis] - origin[axis]) / h;
        let c = x.round();
        ((x - c).abs() * h <= tol).then_some(c as i64)
    };
    let mut by_plane: FastMap<LatticePlane, Vec<(u32, u32)>> = FastMap::default();
    for &(a, b) in &open {
        for axis in 0..3 {
            if let (Some(ca), Some(cb)) = (on_plane(a, axis), on_plane(b, axis)) {
                if ca == cb {
                    by_plane.entry((axis, ca)).or_default().push((a, b));
                }
            }
        }
    }
    let mut planes: Vec<(LatticePlane, Vec<(u32, u32)>)> = by_plane.into_iter().collect();
    planes.sort_unstable_by_key(|p| p.0);
    let mut filled = FastSet::default();
    let before = s.vertices.len();
    for ((axis, _), edges) in planes {
        // the fill runs each open edge backwards: b -> a
        let mut next: FastMap<u32, Vec<u32>> = FastMap::default();
        for &(a, b) in edges.iter().filter(|e| !filled.contains(*e)) {
            next.entry(b).or_default().push(a);
        }
        for ring in cycles(&mut next) {
            if let Some(tris) = ring_fill(&ring, &mut s.vertices, axis, RING_SPLITS) {
                for i in 0..ring.len() {
                    filled.insert((ring[(i + 1) % ring.len()], ring[i]));
                }
                s.faces.extend(tris);
            }
        }
    }
    if s.vertices.len() > before {
        // a ring split where it crosses itself: the faces whose open edges cross there
        // take the crossing point as a corner too
        split_t_junctions(s, tol);
    }
}

/// Most crossings [`ring_fill`] splits a ring at.
const RING_SPLITS: usize = 4;

/// Triangles filling `ring` (in order, in a plane normal to `axis`): ear clipped
/// ([`ring_triangles`]), or, for a ring that crosses itself, split where two of its edges
/// cross (a new point, appended to `vertices`) into two loops filled so in turn, up to
/// `splits` times. Each loop keeps the ring's order, so the one that turns the other way
/// faces the other way, as the edges around it ask; the two meet at the point and do not
/// overlap. `None` when that does not give a fill.
fn ring_fill(ring: &[u32], vertices: &mut Vec<Vec3>, axis: usize, splits: usize) -> Option<Vec<[u32; 3]>> {
    if let Some(tris) = ring_triangles(ring, vertices, axis) {
        return Some(tris);
    }
    if splits == 0 {
        return None;
    }
    let (i, j, t) = first_crossing(ring, vertices, axis)?;
    let n = ring.len();
    let (a, b) = (vertices[ring[i] as usize], vertices[ring[(i + 1) % n] as usize]);
    let x = vertices.len() as u32;
    vertices.push(a + (b - a) * t);
    // x -> ring[i + 1] .. ring[j] -> x, and x -> ring[j + 1] .. ring[i] -> x
    let first: Vec<u32> = std::iter::once(x).chain((i + 1..=j).map(|k| ring[k])).collect();
    let second: Vec<u32> = std::iter::once(x).chain((j + 1..n + i + 1).map(|k| ring[k % n])).collect();
    let mut out = Vec::new();
    for lobe in [first, second] {
        if lobe.len() >= 3 {
            out.extend(ring_fill(&lobe, vertices, axis, splits - 1)?);
        }
    }
    Some(out)
}

/// The first two edges of `ring` (in the plane normal to `axis`) that cross each other
/// properly, not next to each other: `(i, j, t)` with `i < j`, edge `i` (from `ring[i]` to
/// `ring[i + 1]`) crossing edge `j` at the fraction `t` of edge `i`.
fn first_crossing(ring: &[u32], vertices: &[Vec3], axis: usize) -> Option<(usize, usize, f64)> {
    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
    let p2 = |k: usize| {
        let p = vertices[ring[k % ring.len()] as usize];
        (p[u], p[w])
    };
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let n = ring.len();
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue; // neighbours through the ring's start
            }
            let (a, b, c, d) = (p2(i), p2(i + 1), p2(j), p2(j + 1));
            let (ca, cb) = (cross(c, d, a), cross(c, d, b));
            if ca * cb < 0.0 && cross(a, b, c) * cross(a, b, d) < 0.0 {
                return Some((i, j, ca / (ca - cb)));
            }
        }
    }
    None
}

/// What [`close_small_loops`] filled.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LoopsClosed {
    /// How many loops.
    pub loops: usize,
    /// The largest diameter (box diagonal) of one: how far a point of the fill may lie
    /// from its loop's vertices.
    pub diameter: f64,
}

/// Close the small holes left where the polygons of neighbouring cells or sub-cells meet
/// at a crevice or needle thinner than the weld tolerance (the two sides' corners weld to
/// different vertices, or not at all, and a few open edges ring a small hole): every
/// loop of edges used once with no reverse, at most `size` across, is filled (edges used
/// twice are sheets touching, left to [`unzip_touching_sheets`]). Each loop vertex is a
/// polygon corner (within the weld tolerance and the polygons' own deviation of the
/// boundary) or a band crossing (on it), so every point of the fill (in the loop's hull)
/// lies within the loop's diameter plus those of the boundary;
/// and the boundary lay on the polygons and band triangles already, so the fill removes
/// none of it. Each is filled by ear clipping as seen along its vector area
/// ([`clipped_in_its_plane`]), else by the fan when no triangle of it turns over
/// ([`fans_one_way`]), else left open: a loop crossing itself. Larger loops are left (the
/// caller sees them open).
pub fn close_small_loops(s: &mut Surface, size: f64) -> LoopsClosed {
    let mut out = LoopsClosed::default();
    // edges used once with no reverse: listed once (one used k > 1 times is listed k times)
    let open: Vec<(u32, u32)> = open_edges(&s.faces).chunk_by(|x, y| x == y).filter(|g| g.len() == 1).map(|g| g[0]).collect();
    if open.is_empty() {
        return out;
    }
    // the fill runs each open edge backwards: b -> a
    let mut next: FastMap<u32, Vec<u32>> = FastMap::default();
    for &(a, b) in &open {
        next.entry(b).or_default().push(a);
    }
    for ring in cycles(&mut next) {
        let corners: Vec<Vec3> = ring.iter().map(|&v| s.vertices[v as usize]).collect();
        let diameter = Aabb::from_points(&corners).diagonal();
        if diameter > size {
            continue;
        }
        let middle = corners.iter().fold(Vec3::ZERO, |acc, &p| acc + p) / corners.len() as f64;
        if let Some(tris) = clipped_in_its_plane(&ring, &s.vertices, middle) {
            s.faces.extend(tris);
        } else if fans_one_way(middle, &corners) {
            let centre = s.vertices.len() as u32;
            s.vertices.push(middle);
            for i in 0..ring.len() {
                s.faces.push([centre, ring[i], ring[(i + 1) % ring.len()]]);
            }
        } else {
            continue;
        }
        out.loops += 1;
        out.diameter = out.diameter.max(diameter);
    }
    out
}

/// The ring `ring` ear clipped as seen along its vector area (about `centre`), when that
/// view of it is simple and every triangle then faces the ring's way in 3D too (a ring
/// that bends out of its plane could turn one over): no new vertex, and a ring that is
/// not star-shaped about its centroid is filled as well.
fn clipped_in_its_plane(ring: &[u32], pos: &[Vec3], centre: Vec3) -> Option<Vec<[u32; 3]>> {
    let at = |v: u32| pos[v as usize] - centre;
    let area = (0..ring.len()).fold(Vec3::ZERO, |acc, i| acc + at(ring[i]).cross(at(ring[(i + 1) % ring.len()])));
    let normal = area.try_normalize()?;
    let u = normal.any_orthonormal_vector();
    let w = normal.cross(u);
    let tris = ear_clip(ring, |v| (at(v).dot(u), at(v).dot(w)))?;
    let faces_its_way = |t: &[u32; 3]| (at(t[1]) - at(t[0])).cross(at(t[2]) - at(t[0])).dot(normal) > 0.0;
    tris.iter().all(faces_its_way).then_some(tris)
}

/// Whether the fan about `centre` of the ring `corners` has every triangle facing the
/// ring's way (its normal on the side of the ring's vector area): a ring that crosses
/// itself, seen along that direction, fans into triangles turned over, overlapping their
/// neighbours. A simple ring not star-shaped about its centroid is declined too (left
/// open: the caller samples around it).
fn fans_one_way(centre: Vec3, corners: &[Vec3]) -> bool {
    let n = corners.len();
    let normals: Vec<Vec3> = (0..n).map(|i| (corners[i] - centre).cross(corners[(i + 1) % n] - centre)).collect();
    let area = normals.iter().fold(Vec3::ZERO, |acc, &m| acc + m);
    normals.iter().all(|m| m.dot(area) >= 0.0)
}

/// The simple cycles of the directed graph `next` (each edge used once; a walk that comes
/// back to a vertex of its own path cuts the loop there), at least three vertices each.
fn cycles(next: &mut FastMap<u32, Vec<u32>>) -> Vec<Vec<u32>> {
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut out = Vec::new();
    for start in starts {
        let mut path = vec![start];
        let mut at: FastMap<u32, usize> = FastMap::from_iter([(start, 0)]);
        while let Some(&v) = path.last() {
            let Some(w) = next.get_mut(&v).and_then(|outs| outs.pop()) else { break };
            if let Some(&i) = at.get(&w) {
                let ring: Vec<u32> = path.split_off(i + 1);
                let ring = [vec![w], ring].concat();
                for x in &ring[1..] {
                    at.remove(x);
                }
                if ring.len() >= 3 {
                    out.push(ring);
                }
            } else {
                at.insert(w, path.len());
                path.push(w);
            }
        }
    }
    out
}

/// Triangles filling the ring `ring` (in order), which lies in a plane normal to `axis`;
/// by ear clipping in that plane ([`ear_clip`]).
fn ring_triangles(ring: &[u32], pos: &[Vec3], axis: usize) -> Option<Vec<[u32; 3]>> {
    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
    ear_clip(ring, |v: u32| (pos[v as usize][u], pos[v as usize][w]))
}

/// Triangles filling the ring `ring` (in order) by ear clipping its points as `p2` puts
/// them in a plane. `None` when no ear is found, or the last triangle turns against the
/// ring: a ring crossing itself into lobes that turn opposite ways (a ring that curls over
/// itself the same way is not caught). Not the regions' clipper
/// ([`regions`]'s `ear_clip`): that one keeps corners straight to 1e-12 of their edges
/// uncut, and a crevice's gap ring, nearly straight all along, then finds no ear.
fn ear_clip(ring: &[u32], p2: impl Fn(u32) -> (f64, f64)) -> Option<Vec<[u32; 3]>> {
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let area: f64 = (0..ring.len()).map(|i| cross((0.0, 0.0), p2(ring[i]), p2(ring[(i + 1) % ring.len()]))).sum();
    let turn = area.signum();
    let mut poly: Vec<u32> = ring.to_vec();
    let mut out = Vec::with_capacity(ring.len());
    while poly.len() > 3 {
        let n = poly.len();
        let ear = (0..n).find(|&i| {
            let (a, b, c) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
            let (pa, pb, pc) = (p2(a), p2(b), p2(c));
            if cross(pa, pb, pc) * turn <= 0.0 {
                return false; // reflex or flat corner
            }
            // no other corner inside the ear
            poly.iter().all(|&q| {
                if q == a || q == b || q == c {
                    return true;
                }
                let pq = p2(q);
                !(cross(pa, pb, pq) * turn >= 0.0 && cross(pb, pc, pq) * turn >= 0.0 && cross(pc, pa, pq) * turn >= 0.0)
            })
        })?;
        out.push([poly[(ear + n - 1) % n], poly[ear], poly[(ear + 1) % n]]);
        poly.remove(ear);
    }
    // every ear turns the ring's way; the last triangle does too only when the ring is
    // simple (one crossing itself leaves a triangle turned over, overlapping its
    // neighbour): such a ring is left open
    let last = [poly[0], poly[1], poly[2]];
    if cross(p2(last[0]), p2(last[1]), p2(last[2])) * turn <= 0.0 {
        return None;
    }
    out.push(last);
    Some(out)
}

/// A hash grid of vertices for welding.
struct Grid {
    cell: f64,
    buckets: FastMap<[i64; 3], Vec<(u32, Vec3)>>,
}

impl Grid {
    fn new(cell: f64) -> Grid {
        Grid { cell, buckets: FastMap::default() }
    }

    fn key(&self, p: Vec3) -> [i64; 3] {
        let q = p / self.cell;
        [q.x.floor() as i64, q.y.floor() as i64, q.z.floor() as i64]
    }

    fn insert(&mut self, v: u32, p: Vec3) {
        let k = self.key(p);
        let b = self.buckets.entry(k).or_default();
        if !b.iter().any(|&(w, _)| w == v) {
            b.push((v, p));
        }
    }

    /// The nearest vertex within `tol` of `p`, or a new one appended to `vertices`.
    fn weld(&mut self, p: Vec3, tol: f64, vertices: &mut Vec<Vec3>) -> u32 {
        let k = self.key(p);
        // the buckets the ball of radius `tol` about `p` reaches (one, unless it is near a
        // bucket's side: the buckets are wider than `tol`)
        let reach = |axis: usize| {
            let x = p[axis] / self.cell - k[axis] as f64;
            let r = tol / self.cell;
            (if x < r { -1 } else { 0 })..=(if x > 1.0 - r { 1 } else { 0 })
        };
        let mut best: Option<(f64, u32)> = None;
        for dz in reach(2) {
            for dy in reach(1) {
                for dx in reach(0) {
                    if let Some(b) = self.buckets.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        for &(v, q) in b {
                            let d = (q - p).length();
                            if d <= tol && best.is_none_or(|(bd, _)| d < bd) {
                                best = Some((d, v));
                            }
                        }
                    }
                }
            }
        }
        if let Some((_, v)) = best {
            return v;
        }
        let v = vertices.len() as u32;
        vertices.push(p);
        self.insert(v, p);
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_next_to_two_half_squares_is_closed_after_splitting() {
        // a flat "pillow": the top is one square, the bottom two rectangles meeting in the
        // middle of the square's edges' plane: T-junctions at (0.5, 0) and (0.5, 1)
        let mut s = Surface::default();
        let v = |x: f64, y: f64| Vec3::new(x, y, 0.0);
        let top = vec![v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)];
        let left = vec![v(0.0, 0.0), v(0.0, 1.0), v(0.5, 1.0), v(0.5, 0.0)];
        let right = vec![v(0.5, 0.0), v(0.5, 1.0), v(1.0, 1.0), v(1.0, 0.0)];
        let (up, down) = (regions::plane_key(Vec3::Z, 0.0), regions::plane_key(-Vec3::Z, 0.0));
        let stats = join(&mut s, &[top, left, right], &[up, down, down], 1e-9, (Vec3::splat(0.25), 1.0));
        assert!(open_edges(&s.faces).is_empty(), "{:?}", open_edges(&s.faces));
        // top and bottom are sheets through the same points, facing each other: fanned
        // about their own centres, not merged (they would share diagonals)
        assert_eq!(stats, RegionStats { merged_planes: 0, fanned_planes: 2, straight_dropped: 0, unfolded: 0 });
    }

    #[test]
    fn a_small_hole_is_closed_by_a_fan_and_a_large_one_is_left() {
        // an open box: a unit cube without its top, whose rim is a loop 1 x 1 across
        let corners: Vec<Vec3> = (0..8).map(|c| Vec3::new((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64)).collect();
        let quads = [[0, 2, 3, 1], [0, 1, 5, 4], [1, 3, 7, 5], [3, 2, 6, 7], [2, 0, 4, 6]];
        let faces: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        let mut s = Surface { vertices: corners.clone(), faces: faces.clone(), ..Default::default() };
        assert_eq!(close_small_loops(&mut s, 1.0), LoopsClosed::default(), "the rim is sqrt(2) across");
        assert_eq!(open_edges(&s.faces).len(), 4);
        let closed = close_small_loops(&mut s, 1.5);
        assert_eq!(closed.loops, 1);
        assert!((closed.diameter - 2f64.sqrt()).abs() < 1e-12);
        assert!(open_edges(&s.faces).is_empty(), "{:?}", open_edges(&s.faces));
        // outward: the fill faces up, and the closed box encloses the unit volume
        let volume: f64 = s
            .faces
            .iter()
            .map(|f| {
                let p = f.map(|v| s.vertices[v as usize]);
                p[0].dot(p[1].cross(p[2])) / 6.0
            })
            .sum();
        assert!((volume - 1.0).abs() < 1e-12, "{volume}");
        assert_eq!((s.vertices.len(), s.faces.len()), (8, 12), "the rim ear clipped: no new vertex");
    }

    #[test]
    fn a_small_hole_not_star_shaped_about_its_centroid_is_ear_clipped() {
        // a U-shaped rim (its centroid in the U's gap, where a fan would turn triangles
        // over) under a cone from an apex above it: its edges are the only open ones
        let rim: Vec<Vec3> = [(0.0, 0.0), (3.0, 0.0), (3.0, 3.0), (2.0, 3.0), (2.0, 1.0), (1.0, 1.0), (1.0, 3.0), (0.0, 3.0)].iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect();
        let centroid = rim.iter().fold(Vec3::ZERO, |acc, &p| acc + p) / rim.len() as f64;
        assert!(!fans_one_way(centroid, &rim));
        let mut vertices = rim.clone();
        vertices.push(Vec3::new(1.5, 1.5, -2.0));
        let n = rim.len() as u32;
        let faces: Vec<[u32; 3]> = (0..n).map(|i| [n, (i + 1) % n, i]).collect();
        let mut s = Surface { vertices, faces, ..Default::default() };
        assert_eq!(close_small_loops(&mut s, 10.0).loops, 1);
        assert!(open_edges(&s.faces).is_empty(), "{:?}", open_edges(&s.faces));
        assert_eq!(s.vertices.len(), rim.len() + 1, "no new vertex");
        // the fill is the U itself: 7 units of area, every triangle facing the same way
        let fill: Vec<f64> = s.faces[rim.len()..]
            .iter()
            .map(|f| {
                let p = f.map(|v| s.vertices[v as usize]);
                (p[1] - p[0]).cross(p[2] - p[0]).z / 2.0
            })
            .collect();
        assert!(fill.iter().all(|&a| a > 0.0) || fill.iter().all(|&a| a < 0.0), "{fill:?}");
        assert!((fill.iter().sum::<f64>().abs() - 7.0).abs() < 1e-12);
    }

    /// A ring in the plane x = 0 that crosses itself: its edges (0, 1) and (2, 3) cross at
    /// (y, z) = (1.2, 0.6), leaving a large lobe turning one way and a small one the other.
    fn crossed_ring() -> Vec<Vec3> {
        [(0.0, 0.0), (2.0, 1.0), (2.0, 0.0), (0.0, 1.5)].iter().map(|&(y, z)| Vec3::new(0.0, y, z)).collect()
    }

    #[test]
    fn a_simple_ring_is_clipped_into_triangles_turning_its_way() {
        let square: Vec<Vec3> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].iter().map(|&(y, z)| Vec3::new(0.0, y, z)).collect();
        let tris = ring_triangles(&[0, 1, 2, 3], &square, 0).expect("a square is simple");
        assert_eq!(tris.len(), 2);
        for t in tris {
            let p = t.map(|v| square[v as usize]);
            assert!((p[1] - p[0]).cross(p[2] - p[0]).x > 0.0, "{t:?}");
        }
    }

    #[test]
    fn a_ring_crossing_itself_is_neither_clipped_nor_fanned() {
        // ear clipping finds an ear in the large lobe, and the triangle left is turned
        // over across the small one; a fan about the centroid turns one triangle over too
        let ring = crossed_ring();
        assert!(ring_triangles(&[0, 1, 2, 3], &ring, 0).is_none());
        let centre = ring.iter().fold(Vec3::ZERO, |acc, &p| acc + p) / 4.0;
        assert!(!fans_one_way(centre, &ring));
        let square = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        assert!(fans_one_way(Vec3::new(0.5, 0.5, 0.0), &square));
    }

    #[test]
    fn a_gap_ring_crossing_itself_is_split_where_it_crosses() {
        // the crossed ring's edges (0, 1) and (2, 3) cross at (y, z) = (1.2, 0.6): two
        // triangles meeting there, turning opposite ways as the ring does, their signed
        // areas summing to the ring's (a fan or one ear clipping would overlap them)
        let mut vertices = crossed_ring();
        let tris = ring_fill(&[0, 1, 2, 3], &mut vertices, 0, RING_SPLITS).expect("split and filled");
        assert_eq!((vertices.len(), tris.len()), (5, 2));
        assert!((vertices[4] - Vec3::new(0.0, 1.2, 0.6)).length() < 1e-12, "{:?}", vertices[4]);
        let signed: Vec<f64> = tris
            .iter()
            .map(|t| {
                let p = t.map(|v| vertices[v as usize]);
                (p[1] - p[0]).cross(p[2] - p[0]).x / 2.0
            })
            .collect();
        assert!(signed[0] * signed[1] < 0.0, "{signed:?}");
        let ring = crossed_ring();
        let shoelace: f64 = (0..4).map(|i| ring[i].y * ring[(i + 1) % 4].z - ring[i].z * ring[(i + 1) % 4].y).sum::<f64>() / 2.0;
        assert!((signed.iter().sum::<f64>() - shoelace).abs() < 1e-12);
        assert!(tris.iter().all(|t| t.contains(&4)));
    }

    #[test]
    fn a_small_hole_that_crosses_itself_is_left_open() {
        // a cone over the crossed ring from an apex off its plane: the ring's edges are
        // the only open ones; fanned, the hole would hold a triangle turned over
        let mut vertices = crossed_ring();
        vertices.push(Vec3::new(-1.0, 1.0, 0.6));
        let faces: Vec<[u32; 3]> = (0..4u32).map(|i| [4, i, (i + 1) % 4]).collect();
        let mut s = Surface { vertices, faces, ..Default::default() };
        assert_eq!(open_edges(&s.faces).len(), 4);
        assert_eq!(close_small_loops(&mut s, 10.0), LoopsClosed::default());
        assert_eq!(open_edges(&s.faces).len(), 4);
    }

    /// Two closed unit cubes (outward), the second moved by `offset`, in one surface whose
    /// coincident corners are one vertex.
    fn two_cubes(offset: Vec3) -> Surface {
        let quads = [[0, 2, 3, 1], [0, 1, 5, 4], [1, 3, 7, 5], [3, 2, 6, 7], [2, 0, 4, 6], [4, 5, 7, 6]];
        let mut s = Surface::default();
        let mut ids: FastMap<[i64; 3], u32> = FastMap::default();
        for shift in [Vec3::ZERO, offset] {
            let corner: Vec<u32> = (0..8)
                .map(|c| {
                    let p = Vec3::new((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64) + shift;
                    *ids.entry([p.x as i64, p.y as i64, p.z as i64]).or_insert_with(|| {
                        s.vertices.push(p);
                        s.vertices.len() as u32 - 1
                    })
                })
                .collect();
            s.faces.extend(quads.iter().flat_map(|q| [[corner[q[0]], corner[q[1]], corner[q[2]]], [corner[q[0]], corner[q[2]], corner[q[3]]]]));
        }
        s
    }

    /// Two closed tetrahedra with a corner at the same place but not shared (distinct
    /// vertices): each corner moves into its own tetrahedron, so float32 tells them apart,
    /// and the move is recorded.
    #[test]
    fn coincident_vertices_are_parted_into_their_own_triangles() {
        let tet = |apex_dir: f64, base: u32| -> (Vec<Vec3>, Vec<[u32; 3]>) {
            let v = vec![Vec3::ZERO, Vec3::new(1.0, 0.0, apex_dir), Vec3::new(0.0, 1.0, apex_dir), Vec3::new(1.0, 1.0, 2.0 * apex_dir)];
            let f = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]].into_iter().map(|t: [u32; 3]| t.map(|c| c + base)).collect();
            (v, f)
        };
        let (mut vertices, mut faces) = tet(1.0, 0);
        let (v2, f2) = tet(-1.0, 4);
        vertices.extend(v2);
        faces.extend(f2);
        let mut s = Surface { vertices, faces, ..Default::default() };
        let h = 0.1;
        assert_eq!(part_coincident_vertices(&mut s, h), 2);
        let (a, b) = (s.vertices[0], s.vertices[4]);
        assert!(a.to_array().map(|x| x as f32) != b.to_array().map(|x| x as f32), "{a:?} {b:?}");
        assert!(a.z > 0.0 && b.z < 0.0, "each into its own tetrahedron: {a:?} {b:?}");
        assert!(s.sheets_apart > 0.0 && s.sheets_apart <= SHEETS_APART_MAX * h);
        assert!((a - b).length() <= 2.0 * s.sheets_apart + 1e-15);
        assert_eq!(part_coincident_vertices(&mut s, h), 0, "nothing left to part");
    }

    /// A tetrahedron with an edge split a hair from its end (a crossing clamped off a
    /// lattice point): a reader would weld the two, so the short edge is collapsed and the
    /// tetrahedron is whole again.
    #[test]
    fn a_hair_short_edge_is_collapsed() {
        let o = Vec3::ONE; // (float32 does not weld near 0)
        let m = o + Vec3::new(5e-9, 0.0, 0.0); // on the edge from vertex 0 to vertex 1
        let vertices = vec![o, o + Vec3::X, o + Vec3::Y, o + Vec3::Z, m];
        // the outward tetrahedron [0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3], edge 0-1 split
        let faces = vec![[0, 2, 4], [4, 2, 1], [0, 4, 3], [4, 1, 3], [0, 3, 2], [1, 2, 3]];
        let mut s = Surface { vertices, faces, ..Default::default() };
        assert!(open_edges(&s.faces).is_empty());
        assert_eq!(part_coincident_vertices(&mut s, 0.1), 1);
        assert_eq!((s.faces.len(), s.vertices.len()), (4, 4));
        assert!(open_edges(&s.faces).is_empty() && pinched_vertices(&s.faces).is_empty());
        assert!((s.sheets_apart - 5e-9).abs() < 1e-15, "{}", s.sheets_apart);
        let at = |v: u32| s.vertices[v as usize] - o;
        let volume: f64 = s.faces.iter().map(|f| at(f[0]).dot(at(f[1]).cross(at(f[2]))) / 6.0).sum();
        assert!((volume - 1.0 / 6.0).abs() < 1e-12, "still the outward tetrahedron: {volume}");
    }

    /// An octahedron with two of its edges split a hair from an end, and a closed
    /// tetrahedron shrunk to a hair: the two splits collapse in one call; the tetrahedron's
    /// edges may not (it would fold flat), so its corners move apart instead.
    #[test]
    fn hair_short_edges_collapse_where_the_surface_stays_a_manifold() {
        let o = Vec3::new(2.0, 1.0, 1.0);
        let mut vertices: Vec<Vec3> = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].iter().map(|&d| o + d).collect();
        let mut faces: Vec<[u32; 3]> = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        // split edge 0-2 (triangles [0, 2, 4] and [2, 0, 5]) and edge 1-3 next to 0 and 1
        for (a, b) in [(0u32, 2u32), (1, 3)] {
            let m = vertices.len() as u32;
            vertices.push(vertices[a as usize] + (vertices[b as usize] - vertices[a as usize]) * 3e-9);
            let mut split = Vec::new();
            for f in &faces {
                match (0..3).find(|&k| (f[k], f[(k + 1) % 3]) == (a, b) || (f[k], f[(k + 1) % 3]) == (b, a)) {
                    Some(k) => {
                        let (p, q, r) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
                        split.extend([[p, m, r], [m, q, r]]);
                    }
                    None => split.push(*f),
                }
            }
            faces = split;
        }
        let mut s = Surface { vertices, faces, ..Default::default() };
        assert_eq!(s.faces.len(), 12);
        assert_eq!(part_coincident_vertices(&mut s, 0.1), 2);
        assert_eq!((s.faces.len(), s.vertices.len()), (8, 6));
        assert!(open_edges(&s.faces).is_empty() && pinched_vertices(&s.faces).is_empty());
        assert!(coinciding(&s).is_empty());

        let tiny = |k: usize| o + Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, (k >> 2) as f64) * 2e-9;
        let mut s = Surface { vertices: vec![tiny(0), tiny(1), tiny(2), tiny(4)], faces: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], ..Default::default() };
        let volume =
            |s: &Surface| s.faces.iter().map(|f| (s.vertices[f[0] as usize] - o).dot((s.vertices[f[1] as usize] - o).cross(s.vertices[f[2] as usize] - o)) / 6.0).sum::<f64>();
        assert!(volume(&s) > 0.0);
        // its corners cannot move into their fans by more than a sixth of their heights,
        // so they are pushed apart along its edges instead, none turning a face over
        let parted = part_coincident_vertices(&mut s, 0.1);
        assert!(parted >= 3, "{parted}");
        assert_eq!(s.faces.len(), 4, "no collapse folds the tetrahedron");
        assert!(open_edges(&s.faces).is_empty() && pinched_vertices(&s.faces).is_empty());
        assert!(coinciding(&s).is_empty(), "{:?}", s.vertices);
        assert!(volume(&s) > 0.0, "still outward: {}", volume(&s));
        let moved = (0..4).map(|k| (s.vertices[k] - [tiny(0), tiny(1), tiny(2), tiny(4)][k]).length()).fold(0.0, f64::max);
        assert!(moved > 0.0 && moved <= s.sheets_apart, "{moved} {}", s.sheets_apart);
    }

    /// A triangle with points on all three edges (two on one, one on each other) is split
    /// into triangles with those points as corners and no new vertex: all face as it did,
    /// none lacks area, they cover its area once, and their open edges are its edges'
    /// pieces between the points, each once in its direction.
    #[test]
    fn a_triangle_is_split_at_points_on_its_edges_without_a_new_vertex() {
        let mut v = vec![Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0)];
        let mut on_edge = |a: usize, b: usize, t: f64| {
            v.push(v[a] + (v[b] - v[a]) * t);
            v.len() as u32 - 1
        };
        let (p, q) = (on_edge(0, 1, 0.25), on_edge(0, 1, 0.75));
        let (r, w) = (on_edge(1, 2, 0.5), on_edge(2, 0, 0.4));
        let mut out = Vec::new();
        split_at_edge_points([0, 1, 2], [&[p, q], &[r], &[w]], &mut out);
        assert_eq!(out.len(), 5, "one triangle more per point: {out:?}");
        let normal = |f: &[u32; 3]| (v[f[1] as usize] - v[f[0] as usize]).cross(v[f[2] as usize] - v[f[0] as usize]);
        assert!(out.iter().all(|f| normal(f).z > 1e-9), "{out:?}");
        let area: f64 = out.iter().map(|f| 0.5 * normal(f).z).sum();
        assert!((area - 6.0).abs() < 1e-12, "{area}");
        assert!(out.iter().all(|f| f.iter().all(|&c| (c as usize) < v.len())));
        let mut open = open_edges(&out);
        open.sort_unstable();
        let mut pieces = vec![(0, p), (p, q), (q, 1), (1, r), (r, 2), (2, w), (w, 0)];
        pieces.sort_unstable();
        assert_eq!(open, pieces);
    }

    /// Two vertices a few 1e-9 apart among slivers (the apexes of a flat double cone, as a
    /// thin sheet's eroded edge leaves them): the push moves one away from the other along
    /// the line through them, by twice the weld's reach on its main axis, and turns no
    /// triangle over.
    #[test]
    fn vertices_among_slivers_are_pushed_apart_along_the_line_through_them() {
        let o = Vec3::new(0.005, -0.0003, 0.03);
        let (u, v) = (o, o + Vec3::new(5e-10, 8.7e-9, 5e-10));
        let far = |x: f64, y: f64, z: f64| o + Vec3::new(x, y, z) * 1e-5;
        let vertices = vec![u, v, far(-1.0, 0.0, 0.0), far(1.0, 0.0, 0.0), far(0.0, 0.001, 1.0), far(0.0, -0.001, 1.0)];
        // the double cone over the loop 2 → 4 → 3 → 5 with apexes u and v, both a hair
        // off the loop's plane: every triangle is a sliver about them
        let faces = vec![[0, 2, 4], [0, 4, 3], [0, 3, 5], [0, 5, 2], [1, 4, 2], [1, 3, 4], [1, 5, 3], [1, 2, 5]];
        let mut s = Surface { vertices, faces, ..Default::default() };
        assert!(open_edges(&s.faces).is_empty());
        assert_eq!(coinciding(&s), vec![(0, 1)]);
        let normal = |s: &Surface, f: [u32; 3]| (s.vertices[f[1] as usize] - s.vertices[f[0] as usize]).cross(s.vertices[f[2] as usize] - s.vertices[f[0] as usize]);
        let before: Vec<Vec3> = s.faces.iter().map(|&f| normal(&s, f)).collect();
        let (pushed, step) = push_apart(&mut s, &[(0, 1)]);
        assert_eq!(pushed, 1);
        assert!(coinciding(&s).is_empty(), "{:?} {:?}", s.vertices[0], s.vertices[1]);
        let (u2, v2) = (s.vertices[0], s.vertices[1]);
        assert!(u2 == u || v2 == v, "one of the two moves");
        assert!(((v2 - u2).normalize() - (v - u).normalize()).length() < 1e-6, "along the line through them");
        assert!(step > 0.0 && step <= 2.0 * 3f64.sqrt() * weld_reach(0.03), "{step}");
        for (&f, n) in s.faces.iter().zip(&before) {
            assert!(normal(&s, f).dot(*n) > 0.0, "a triangle turned over");
        }
    }

    #[test]
    fn sheets_touching_along_an_edge_or_at_a_corner_get_their_own_vertices() {
        for (offset, shared, copies) in [(Vec3::new(1.0, 1.0, 0.0), 2, 2), (Vec3::ONE, 1, 1)] {
            let mut s = two_cubes(offset);
            assert_eq!(s.vertices.len(), 16 - shared);
            let (open, pinched) = (open_edges(&s.faces), pinched_vertices(&s.faces));
            assert!(!open.is_empty() || !pinched.is_empty(), "the cubes touch: not a manifold");
            let at = open.iter().flat_map(|&(a, b)| [a, b]).chain(pinched).collect();
            let before = s.clone();
            let h = 0.5;
            assert_eq!(unzip_touching_sheets(&mut s, at, h), copies);
            assert!(open_edges(&s.faces).is_empty() && pinched_vertices(&s.faces).is_empty());
            assert_eq!(s.sheets_apart, SHEETS_APART * h);
            // the same triangles, each corner where it was or moved that far into its own
            // cube: off the plane between the cubes (x + y = 2, or x + y + z = 3)
            let step = SHEETS_APART * h;
            let off_plane = |p: Vec3| if shared == 2 { p.x + p.y - 2.0 } else { p.x + p.y + p.z - 3.0 };
            let mut moved = 0;
            for (f, g) in s.faces.iter().zip(&before.faces) {
                for (&c, &d) in f.iter().zip(g) {
                    let (now, was) = (s.vertices[c as usize], before.vertices[d as usize]);
                    assert!((now - was).length() <= step * (1.0 + 1e-12));
                    if now != was {
                        moved += 1;
                        assert!(off_plane(now).abs() > 0.5 * step, "{now} stays between the cubes");
                    }
                }
            }
            assert!(moved > 0);
        }
        // a real hole is left as it is
        let mut s = two_cubes(Vec3::new(3.0, 0.0, 0.0));
        s.faces.pop();
        let at = open_edges(&s.faces).iter().flat_map(|&(a, b)| [a, b]).collect();
        assert_eq!(unzip_touching_sheets(&mut s, at, 0.5), 0);
        assert_eq!(s.sheets_apart, 0.0);
    }

    #[test]
    fn open_edges_are_the_edges_without_one_reverse_or_used_twice() {
        // random triangles over few vertices: repeated edges, missing reverses, corners
        // welded together; against counting every directed edge
        let mut state = 7u64;
        let mut next = |m: u64| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 33) % m) as u32
        };
        for _ in 0..200 {
            let faces: Vec<[u32; 3]> = (0..1 + next(40)).map(|_| [next(9), next(9), next(9)]).collect();
            let mut uses: FastMap<(u32, u32), usize> = FastMap::default();
            for f in &faces {
                for i in 0..3 {
                    *uses.entry((f[i], f[(i + 1) % 3])).or_default() += 1;
                }
            }
            let mut expected: Vec<(u32, u32)> = uses
                .iter()
                .flat_map(|(&(a, b), &k)| {
                    let reverse = uses.get(&(b, a)).copied().unwrap_or(0);
                    let listed = if k > 1 || reverse == 0 { k } else { 0 };
                    std::iter::repeat_n((a, b), listed)
                })
                .collect();
            expected.sort_unstable();
            assert_eq!(open_edges(&faces), expected, "{faces:?}");
        }
    }

    #[test]
    fn open_edges_finds_a_missing_triangle() {
        let faces = vec![[0, 1, 2], [0, 2, 3], [0, 3, 1]];
        assert_eq!(open_edges(&faces).len(), 3, "the missing face's three edges");
        let mut closed = faces.clone();
        closed.push([1, 3, 2]);
        assert!(open_edges(&closed).is_empty());
    }
}
