//! Witness points: cells of translations shown inside the sum by one point.
//!
//! For solids `A` and `B` and a closed box `C`, if some point `x ∈ B` has `C − x ⊂ A`,
//! every `p ∈ C` is `(p − x) + x ∈ A ⊕ B`; likewise `x ∈ A` with `C − x ⊂ B`. Unlike one
//! triangle-pair piece containing the cell, this holds where interior facets of the reduced
//! convolution cross the cell (two parts overlapping deeply, or nearly coinciding). The
//! candidates are the vertices and triangle centroids of each mesh and the points of a
//! lattice inside it; each containment is exact ([`TriMesh::contains_box`]).
//!
//! Entry point: [`Witnesses`].

use super::{ExactSource, TriMesh};
use crate::math::{Aabb, Vec3};
use rayon::prelude::*;

/// Witnesses tried first for every cell, per side and obstacle: the deepest at the query
/// point.
const FIRST: usize = 32;

/// Recent successes tried before anything else (neighbouring cells share witnesses).
const RECENT: usize = 8;

/// Surface candidates per mesh: vertices and triangle centroids, evenly spaced, at most
/// this many.
const SURFACE_CANDIDATES: usize = 4096;

/// Interior candidates: a lattice of this many points per axis over the mesh's box, those
/// inside the mesh kept.
const LATTICE: usize = 12;

/// Halvings of the cube tried when ranking a candidate by its depth.
const LEVELS: u32 = 24;

/// The witness candidates of the sums `A_k ⊕ B` of a source, ranked at a query point.
pub(super) struct Witnesses {
    /// Per obstacle `k`: `[points x of B with q − x inside A_k, points x of A_k with q − x
    /// inside B]`, deepest first.
    pools: Vec<[Vec<Vec3>; 2]>,
    /// Recent successes `(k, side, x)`, newest first.
    recent: Vec<(usize, usize, Vec3)>,
}

impl Witnesses {
    /// The candidates that lie, moved to the query point `q`, inside the other mesh, ranked
    /// by depth there (the largest cube about `q − x` inside it, halving from the source's
    /// size).
    pub(super) fn new(src: &ExactSource, q: Vec3) -> Witnesses {
        let scale = src.aabb.extent().max_element();
        let pools = src.obstacles.iter().map(|a| [ranked(&src.b, a, q, scale), ranked(a, &src.b, q, scale)]).collect();
        Witnesses { pools, recent: Vec::new() }
    }

    /// Whether a witness shows the closed box `bx` inside the sum: the recent successes,
    /// then the deepest candidates, then (`exhaustive`) every candidate whose box test
    /// passes.
    pub(super) fn show(&mut self, src: &ExactSource, bx: &Aabb, exhaustive: bool) -> bool {
        let holds = |k: usize, side: usize, x: Vec3| {
            let into = if side == 0 { &src.obstacles[k] } else { &src.b };
            let moved = Aabb::new(bx.min - x, bx.max - x);
            into.aabb.min.cmple(moved.min).all() && moved.max.cmple(into.aabb.max).all() && into.contains_box(&moved)
        };
        if let Some(i) = self.recent.iter().position(|&(k, side, x)| holds(k, side, x)) {
            let hit = self.recent.remove(i);
            self.recent.insert(0, hit);
            return true;
        }
        for (k, sides) in self.pools.iter().enumerate() {
            for (side, pool) in sides.iter().enumerate() {
                let n = if exhaustive { pool.len() } else { FIRST.min(pool.len()) };
                if let Some(&x) = pool[..n].iter().find(|&&x| holds(k, side, x)) {
                    self.recent.insert(0, (k, side, x));
                    self.recent.truncate(RECENT);
                    return true;
                }
            }
        }
        false
    }
}

/// Points of the closed solid `from`: its vertices and triangle centroids (evenly spaced,
/// [`SURFACE_CANDIDATES`] at most), and the points of a lattice over its box inside it.
fn candidates(from: &TriMesh) -> Vec<Vec3> {
    let centroids = from.tris.iter().map(|t| (t.p[0] + t.p[1] + t.p[2]) / 3.0);
    let surface: Vec<Vec3> = from.vertices.iter().copied().chain(centroids).collect();
    let step = surface.len().div_ceil(SURFACE_CANDIDATES).max(1);
    let n = LATTICE;
    let (lo, ext) = (from.aabb.min, from.aabb.extent());
    let lattice: Vec<Vec3> = (0..n * n * n)
        .into_par_iter()
        .map(|i| {
            let f = |j: usize| (j as f64 + 0.5) / n as f64;
            lo + ext * Vec3::new(f(i % n), f(i / n % n), f(i / (n * n)))
        })
        .filter(|&x| from.contains(x))
        .collect();
    surface.into_iter().step_by(step).chain(lattice).collect()
}

/// The candidates `x` of `from` with `q − x` inside the solid `into`, deepest first.
fn ranked(from: &TriMesh, into: &TriMesh, q: Vec3, scale: f64) -> Vec<Vec3> {
    let cube = |c: Vec3, r: f64| Aabb::new(c - Vec3::splat(r), c + Vec3::splat(r));
    let mut out: Vec<(u32, Vec3)> = candidates(from)
        .into_par_iter()
        .filter_map(|x| {
            let c = q - x;
            if !into.contains(c) {
                return None;
            }
            // the first halving (from the largest cube) whose cube is inside
            let (mut lo, mut hi) = (0u32, LEVELS + 1);
            while lo < hi {
                let mid = (lo + hi) / 2;
                if into.contains_box(&cube(c, scale * 0.5f64.powi(mid as i32))) {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            Some((lo, x))
        })
        .collect();
    out.sort_by_key(|&(level, _)| level);
    out.into_iter().map(|(_, x)| x).collect()
}
