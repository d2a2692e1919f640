//! Face adjacency of octree leaves: two leaves are adjacent when their closed boxes share a
//! face region of positive area. Leaves differ in size, so a leaf's face meets either one
//! leaf at least as large or several smaller ones; both are found by walking the lattice
//! through the [`LeafIndex`].

use super::index::LeafIndex;
use crate::math::{Aabb, Vec3};
use crate::octree::Octree;
use rayon::prelude::*;

/// A leaf across a face of another.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    /// The neighbouring leaf.
    pub leaf: usize,
    /// Axis of the shared face's normal (0 x, 1 y, 2 z).
    pub axis: u8,
    /// `true` when the neighbour lies on the positive side along `axis`.
    pub positive: bool,
    /// Centre of the shared face rectangle (the smaller leaf's face): the portal.
    pub portal: Vec3,
}

/// A pair of face-adjacent leaves, reported once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adjacency {
    /// One leaf (the smaller, or the lower one when equal in size).
    pub a: u32,
    /// The other leaf.
    pub b: u32,
    /// Axis of the shared face's normal.
    pub axis: u8,
    /// Centre of the shared face rectangle.
    pub portal: Vec3,
}

/// Centre of the face of cell `(level, corner)` normal to `axis`, on its upper side when
/// `upper`.
#[inline]
pub(crate) fn face_center(oct: &Octree, level: u8, corner: [u32; 3], axis: usize, upper: bool) -> Vec3 {
    let s = (1u64 << level) as f64;
    let mut c = [0.0f64; 3];
    for k in 0..3 {
        c[k] = corner[k] as f64
            + if k == axis {
                if upper {
                    s
                } else {
                    0.0
                }
            } else {
                0.5 * s
            };
    }
    oct.origin + Vec3::new(c[0], c[1], c[2]) * oct.h
}

/// The finest cell just across the face of `(level, ijk)` normal to `axis` (on the upper
/// side when `upper`), or `None` outside the root.
#[inline]
fn across(ijk: [u32; 3], level: u8, axis: usize, upper: bool, depth: u8) -> Option<[u32; 3]> {
    let mut q = ijk;
    if upper {
        let x = ijk[axis] as u64 + (1u64 << level);
        if x >= 1u64 << depth {
            return None;
        }
        q[axis] = x as u32;
    } else {
        if ijk[axis] == 0 {
            return None;
        }
        q[axis] = ijk[axis] - 1;
    }
    Some(q)
}

/// Every leaf sharing a face region of positive area with leaf `id`, appended to `out`,
/// with the centre of the shared face (6 directions; a face meets one leaf at least as
/// large or several smaller ones).
pub fn neighbors(oct: &Octree, index: &LeafIndex, id: usize, out: &mut Vec<Neighbor>) {
    let leaf = &oct.leaves[id];
    let (l, ijk) = (leaf.level, leaf.ijk);
    for axis in 0..3usize {
        for upper in [false, true] {
            let Some(q) = across(ijk, l, axis, upper, oct.depth) else { continue };
            if let Some(n) = index.containing_cell(q, l) {
                out.push(Neighbor { leaf: n, axis: axis as u8, positive: upper, portal: face_center(oct, l, ijk, axis, upper) });
                continue;
            }
            // The same-size cell across is subdivided: collect its leaves on our side.
            let s = 1u32 << l;
            let mut block = ijk;
            block[axis] = if upper { ijk[axis] + s } else { ijk[axis] - s };
            collect_face(oct, index, l, block, axis, upper, upper, out);
        }
    }
}

/// Leaves inside cell `(level, corner)` that touch its face normal to `axis` on the lower
/// side (`low_side`) or the upper side; `positive` is recorded in the neighbours.
#[allow(clippy::too_many_arguments)]
fn collect_face(oct: &Octree, index: &LeafIndex, level: u8, corner: [u32; 3], axis: usize, low_side: bool, positive: bool, out: &mut Vec<Neighbor>) {
    if let Some(n) = index.get(level, corner) {
        out.push(Neighbor { leaf: n, axis: axis as u8, positive, portal: face_center(oct, level, corner, axis, !low_side) });
        return;
    }
    if level == 0 {
        return; // not a tiling (cannot happen for an octree's leaves)
    }
    let half = 1u32 << (level - 1);
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    for du in [0, half] {
        for dv in [0, half] {
            let mut c = corner;
            c[u] += du;
            c[v] += dv;
            if !low_side {
                c[axis] += half;
            }
            collect_face(oct, index, level - 1, c, axis, low_side, positive, out);
        }
    }
}

/// All pairs of face-adjacent leaves that both pass `keep`, each pair once, in the order of
/// their first leaf (parallel over leaves; deterministic).
pub fn face_adjacency(oct: &Octree, index: &LeafIndex, keep: impl Fn(usize) -> bool + Sync) -> Vec<Adjacency> {
    (0..oct.leaves.len())
        .into_par_iter()
        .flat_map_iter(|u| {
            let mut out = Vec::new();
            if keep(u) {
                let leaf = &oct.leaves[u];
                let (l, ijk) = (leaf.level, leaf.ijk);
                for axis in 0..3usize {
                    for upper in [false, true] {
                        let Some(q) = across(ijk, l, axis, upper, oct.depth) else { continue };
                        // Report a pair from its smaller leaf (from the lower one when the
                        // sizes are equal); smaller neighbours report themselves.
                        if let Some(v) = index.containing_cell(q, l) {
                            let lv = oct.leaves[v].level;
                            if (lv > l || upper) && keep(v) {
                                out.push(Adjacency { a: u as u32, b: v as u32, axis: axis as u8, portal: face_center(oct, l, ijk, axis, upper) });
                            }
                        }
                    }
                }
            }
            out.into_iter()
        })
        .collect()
}

/// The rectangle shared by the closed boxes of leaves `a` and `b` (as a box that is flat
/// along the face normal), or `None` when they do not share a face region of positive area.
pub fn shared_face(oct: &Octree, a: usize, b: usize) -> Option<Aabb> {
    let (la, lb) = (&oct.leaves[a], &oct.leaves[b]);
    let (sa, sb) = (1u64 << la.level, 1u64 << lb.level);
    let mut lo = [0u64; 3];
    let mut hi = [0u64; 3];
    let mut flat = 0;
    for k in 0..3 {
        let (a0, b0) = (la.ijk[k] as u64, lb.ijk[k] as u64);
        lo[k] = a0.max(b0);
        hi[k] = (a0 + sa).min(b0 + sb);
        if lo[k] > hi[k] {
            return None;
        }
        if lo[k] == hi[k] {
            flat += 1;
        }
    }
    if flat != 1 {
        return None;
    }
    let p = |c: [u64; 3]| oct.origin + Vec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * oct.h;
    Some(Aabb::new(p(lo), p(hi)))
}
