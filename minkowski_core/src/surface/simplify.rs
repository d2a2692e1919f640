//! Geometry-preserving simplification of an extracted surface: interior vertices of planar
//! patches, and vertices inside straight creases, are collapsed away.
//!
//! A vertex `v` is collapsed onto a neighbour `u` when `u` lies in the plane of every
//! triangle of `v`'s star that survives (so each keeps its plane), the link condition holds
//! (the mesh stays a closed 2-manifold) and no surviving triangle flips or degenerates in
//! its plane. A star in one plane collapses onto any such neighbour; a star in two planes
//! only along their common line (`u` must lie in both), where `v` lies between `u` and the
//! crease's other neighbour; a corner of three planes never. The surface is the same point
//! set: the error bound, closedness and orientation are kept. Marching tetrahedra samples a
//! flat facet with O(area / h²) triangles; plane-resolved cells come out as regions
//! triangulated once ([`super::regions`]), and what is left here for them is where a
//! region could not be merged (fanned polygons) or meets the band. Afterwards only corners
//! and the sampled (curved or chamfered) band remain.

use super::Surface;
use crate::math::Vec3;

/// Collapses never target a vertex with more incident triangles than this.
const MAX_TARGET_DEGREE: usize = 40;
/// Vertices with larger stars are left alone.
const STAR_CAP: usize = 64;
/// Rounds over the vertices next to the previous round's collapses, at most.
const MAX_ROUNDS: u32 = 8;

/// Collapse interior vertices of planar patches of `s` (see the module docs). `plane_tol`
/// is the distance within which a point counts as on a plane, `min_area` the smallest
/// triangle area kept. Returns the number of vertices removed.
pub fn merge_coplanar(s: &mut Surface, plane_tol: f64, min_area: f64) -> usize {
    let nv = s.vertices.len();
    let mut faces: Vec<[u32; 3]> = std::mem::take(&mut s.faces);
    let mut alive = vec![true; faces.len()];
    // vertex -> incident faces
    let mut inc: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for (fi, f) in faces.iter().enumerate() {
        for &v in f {
            inc[v as usize].push(fi as u32);
        }
    }
    let mut removed_v = vec![false; nv];
    let mut removed = 0usize;
    // stamp arrays: "w is a neighbour of the current v", "w was counted for the current u"
    let mut mark = vec![0u64; nv];
    let mut counted = vec![0u64; nv];
    let mut stamp = 0u64;
    // every vertex once, then again those next to a collapse (a collapse can free a
    // neighbour that was blocked), a few rounds at most
    let mut queue: Vec<usize> = (0..nv).collect();
    let mut queued = vec![0u32; nv];
    for round in 1..=MAX_ROUNDS {
        let mut next = Vec::new();
        for &v in &queue {
            if removed_v[v] || inc[v].len() < 3 {
                continue;
            }
            stamp += 1;
            let Some(u) = try_collapse(v, &s.vertices, &mut faces, &mut alive, &mut inc, (plane_tol, min_area), (&mut mark, &mut counted, stamp)) else { continue };
            removed_v[v] = true;
            removed += 1;
            for &fi in &inc[u] {
                for &w in &faces[fi as usize] {
                    if queued[w as usize] != round {
                        queued[w as usize] = round;
                        next.push(w as usize);
                    }
                }
            }
        }
        if next.is_empty() {
            break;
        }
        queue = next;
    }
    // compact
    let mut remap = vec![u32::MAX; nv];
    let mut verts = Vec::with_capacity(nv - removed);
    for (i, v) in s.vertices.iter().enumerate() {
        if !removed_v[i] {
            remap[i] = verts.len() as u32;
            verts.push(*v);
        }
    }
    s.faces = faces.iter().zip(&alive).filter(|(_, &a)| a).map(|(f, _)| [remap[f[0] as usize], remap[f[1] as usize], remap[f[2] as usize]]).collect();
    s.vertices = verts;
    removed
}

fn try_collapse(
    v: usize,
    pos: &[Vec3],
    faces: &mut [[u32; 3]],
    alive: &mut [bool],
    inc: &mut [Vec<u32>],
    tol: (f64, f64),
    scratch: (&mut [u64], &mut [u64], u64),
) -> Option<usize> {
    let (plane_tol, min_area) = tol;
    let (mark, counted, stamp) = scratch;
    if inc[v].len() > STAR_CAP {
        return None;
    }
    let mut star_buf = [0u32; STAR_CAP];
    star_buf[..inc[v].len()].copy_from_slice(&inc[v]);
    let star = &star_buf[..inc[v].len()];
    // each star triangle's unit normal (a degenerate one stops the collapse)
    let mut normals = [Vec3::ZERO; STAR_CAP];
    for (k, &fi) in star.iter().enumerate() {
        let f = faces[fi as usize];
        let n = (pos[f[1] as usize] - pos[f[0] as usize]).cross(pos[f[2] as usize] - pos[f[0] as usize]);
        let a = n.length();
        if a <= 0.0 {
            return None;
        }
        normals[k] = n / a;
    }
    // the link of v: neighbours
    let mut nbr_buf = [0u32; 3 * STAR_CAP];
    let mut nn = 0usize;
    for &fi in star {
        for &w in &faces[fi as usize] {
            if w as usize != v && !nbr_buf[..nn].contains(&w) {
                nbr_buf[nn] = w;
                nn += 1;
            }
        }
    }
    let nbrs = &nbr_buf[..nn];
    if nbrs.len() != star.len() {
        return None; // not a simple disk around v
    }
    // never onto a vertex with a huge fan (keeps every step cheap and the triangles
    // reasonably shaped)
    for &w in nbrs {
        mark[w as usize] = stamp;
    }
    for (ui, &u) in nbrs.iter().enumerate() {
        if inc[u as usize].len() > MAX_TARGET_DEGREE {
            continue;
        }
        // new star: faces of v not containing u, with v -> u; each must stay in its plane
        // (u lies in it) and none may flip or degenerate there
        let moved_off = |k: usize| (pos[u as usize] - pos[v]).dot(normals[k]).abs() > plane_tol;
        let flips = star.iter().enumerate().any(|(k, &fi)| {
            let f = faces[fi as usize];
            if f.contains(&u) {
                return false;
            }
            let g = f.map(|w| if w as usize == v { u } else { w });
            let m = (pos[g[1] as usize] - pos[g[0] as usize]).cross(pos[g[2] as usize] - pos[g[0] as usize]);
            moved_off(k) || m.dot(normals[k]) <= 2.0 * min_area
        });
        if flips {
            continue;
        }
        // link condition: u and v share exactly the two apexes of their common edge
        // (a distinct stamp per candidate u: stamp * 64 + ui never repeats for one v)
        let cstamp = stamp * 64 + ui as u64 + 1;
        let mut common = 0;
        for &fi in &inc[u as usize] {
            for &w in &faces[fi as usize] {
                if w != u && mark[w as usize] == stamp && counted[w as usize] != cstamp {
                    counted[w as usize] = cstamp;
                    common += 1;
                }
            }
        }
        if common != 2 {
            continue;
        }
        // apply
        let mut moved = Vec::new();
        for &fi in star {
            let f = faces[fi as usize];
            if f.contains(&u) {
                alive[fi as usize] = false;
                for &w in &f {
                    if w as usize != v {
                        inc[w as usize].retain(|&x| x != fi);
                    }
                }
            } else {
                faces[fi as usize] = f.map(|w| if w as usize == v { u } else { w });
                moved.push(fi);
            }
        }
        inc[u as usize].extend(moved);
        inc[v].clear();
        return Some(u as usize);
    }
    None
}
