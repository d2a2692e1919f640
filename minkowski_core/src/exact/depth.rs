//! The nearest boundary point of the exact source to a query point: penetration depth
//! (the point inside) and separation distance (outside), as a proved interval.
//!
//! Two facts about the reduced-convolution facets ([`super::convolution`]) carry it:
//!
//! * every boundary point of the solid lies on a facet (the facets are a superset of the
//!   boundary), so no boundary point is nearer to `p` than the nearest facet;
//! * every facet lies in the solid (it is a subset of a triangle-pair piece, a contact).
//!
//! Outside the solid, the nearest solid point is a boundary point, so the distance is
//! exactly the smallest point–facet distance (both facts). Inside, the depth — the
//! distance from `p` to the nearest point not in the solid, which lies on the boundary —
//! is at least the distance to the nearest facet, but interior facets can lie nearer. The
//! search then goes best first over octree cells around `p`, each keyed by a lower bound
//! on the distance from `p` to any boundary point in it: the larger of its box distance and
//! its nearest candidate facet's distance. Cells FULL by exact tests (no facet and the
//! centre inside, one piece containing the cell, a vertex nested for the whole cell, or a
//! *witness*: a point `x` of one mesh with the cell, moved by `−x`, inside the other, see
//! [`super::witness`]) hold no point outside and are dropped; an EMPTY cell (no facet, centre outside)
//! is outside as a whole, and its nearest point is an upper bound; so is the nearest point
//! of a MIXED cell that the exact point query puts outside. The lower bound is the
//! smallest key left, and the search stops when the gap is within the tolerance.
//!
//! Entry points: [`ExactSource::try_depth`], [`Depth`], [`facet_nearest`].

use super::convolution::Facet;
use super::verify::octants;
use super::witness::Witnesses;
use super::ExactSource;
use crate::error::{CoreError, CoreResult};
use crate::math::{Aabb, Vec3};
use crate::octree::{CellSource, Label};
use rayon::prelude::*;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Facets tried, nearest first, for a point just beyond their nearest point before the
/// cell search.
const FIRST_FACETS: usize = 64;

/// Cells are split no smaller than this fraction of the tolerance.
const MIN_CELL_PER_TOL: f64 = 1.0 / 8.0;

/// What [`ExactSource::try_depth`] found about the query point `p`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Depth {
    /// Whether `p` lies in the closed solid.
    pub inside: bool,
    /// Proved lower bound on the distance from `p` to the boundary.
    pub lower: f64,
    /// Upper bound: `|point - p|`.
    pub upper: f64,
    /// Inside: a point proved outside the solid at distance `upper` from `p`. Outside: the
    /// nearest point of the solid (on a facet).
    pub point: Vec3,
    /// Whether `upper - lower` is within the tolerance asked for (false: the cell budget or
    /// the smallest cell size stopped the search first).
    pub converged: bool,
    /// Cells classified.
    pub cells: usize,
    /// Facets the exact point query was asked about, nearest first.
    pub facets_tried: usize,
    /// MIXED cells of the smallest size (an eighth of the tolerance) left unresolved: no
    /// exact test showed them inside; when not converged and this is not 0, they held the
    /// lower bound down.
    pub smallest_cells: usize,
}

/// A cell of the search, ordered by its key (smallest first in the heap).
struct Cell {
    key: f64,
    bx: Aabb,
    cand: Vec<u32>,
}

impl PartialEq for Cell {
    fn eq(&self, o: &Self) -> bool {
        self.key.total_cmp(&o.key) == Ordering::Equal
    }
}
impl Eq for Cell {}
impl PartialOrd for Cell {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Cell {
    fn cmp(&self, o: &Self) -> Ordering {
        o.key.total_cmp(&self.key)
    }
}

/// The nearest point to `p` of the closed segment `a → b`.
fn segment_nearest(a: Vec3, b: Vec3, p: Vec3) -> Vec3 {
    let d = b - a;
    let l2 = d.length_squared();
    if l2 <= 0.0 {
        return a;
    }
    a + d * ((p - a).dot(d) / l2).clamp(0.0, 1.0)
}

/// The nearest point to `p` of the facet (a flat convex polygon, corners in order): the
/// projection onto its plane when it falls inside, else the nearest point of its edges.
pub fn facet_nearest(f: &Facet, p: Vec3) -> Vec3 {
    let c = &f.p[..f.n as usize];
    let k = c.len();
    let normal = (c[1] - c[0]).cross(c[2] - c[1]);
    let scale = (c[1] - c[0]).length_squared() * (c[2] - c[1]).length_squared();
    if normal.length_squared() > 1e-24 * scale {
        let n = normal.normalize();
        let q = p - n * (p - c[0]).dot(n);
        if (0..k).all(|i| (c[(i + 1) % k] - c[i]).cross(q - c[i]).dot(n) >= 0.0) {
            return q;
        }
    }
    let mut best = c[0];
    for i in 0..k {
        let q = segment_nearest(c[i], c[(i + 1) % k], p);
        if (q - p).length_squared() < (best - p).length_squared() {
            best = q;
        }
    }
    best
}

/// How far beyond the box [`Search::box_exit`] steps.
fn exit_step(bx: &Aabb, p: Vec3, tol: f64) -> f64 {
    tol * 0.25 + 1e-12 * (bx.extent().max_element() + p.abs().max_element())
}

/// The distance from `p` (in the box) to the nearest of the points [`Search::box_exit`]
/// offers: the depth search's first upper bound, so no cell it looks at lies farther.
pub(super) fn exit_distance(bx: &Aabb, p: Vec3, tol: f64) -> f64 {
    let step = exit_step(bx, p, tol);
    (0..3).map(|a| (p[a] - bx.min[a]).abs().min((bx.max[a] - p[a]).abs()) + step).fold(f64::INFINITY, f64::min)
}

/// The nearest point of the closed box to `p`.
fn box_nearest(bx: &Aabb, p: Vec3) -> Vec3 {
    p.clamp(bx.min, bx.max)
}

/// The state of one depth search.
struct Search<'a> {
    src: &'a ExactSource,
    p: Vec3,
    tol: f64,
    dist: Vec<f64>,
    upper: f64,
    point: Vec3,
    cells: usize,
    /// Smallest key of the MIXED cells left unsearched because it was within the tolerance
    /// of the upper bound at the time.
    dropped: f64,
    /// FULL witnesses (built when the cell search starts).
    witnesses: Option<Witnesses>,
    /// MIXED cells of the smallest size that no test showed FULL.
    smallest: usize,
}

impl Search<'_> {
    /// A point proved outside at distance `d`: the new upper bound if nearer.
    fn offer(&mut self, q: Vec3) {
        let d = (q - self.p).length();
        if d < self.upper {
            self.upper = d;
            self.point = q;
        }
    }

    /// The box of the solid (a closed set inside it): just beyond its nearest face.
    fn box_exit(&mut self) {
        let (bx, p) = (self.src.aabb, self.p);
        let step = exit_step(&bx, p, self.tol);
        for axis in 0..3 {
            let mut lo = p;
            lo[axis] = bx.min[axis] - step;
            let mut hi = p;
            hi[axis] = bx.max[axis] + step;
            self.offer(lo);
            self.offer(hi);
        }
    }

    /// Just beyond the nearest point of the nearest facets (radially from `p`), where the
    /// exact point query says outside.
    fn nearest_facets(&mut self) -> usize {
        let mut order: Vec<usize> = (0..self.dist.len()).collect();
        order.sort_by(|&i, &j| self.dist[i].total_cmp(&self.dist[j]));
        let mut tried = 0;
        for &i in order.iter().take(FIRST_FACETS) {
            if self.dist[i] + self.tol * 0.25 >= self.upper {
                break;
            }
            let x = facet_nearest(&self.src.facets[i], self.p);
            let r = x - self.p;
            let q = if r.length() > 0.0 { x + r.normalize() * (self.tol * 0.25) } else { x };
            tried += 1;
            if !self.src.contains_point(q) {
                self.offer(q);
            }
        }
        tried
    }

    /// Whether a witness point keeps every translation of `bx` in the solid.
    fn witnessed(&mut self, bx: &Aabb, exhaustive: bool) -> bool {
        let src = self.src;
        self.witnesses.get_or_insert_with(|| Witnesses::new(src, self.p)).show(src, bx, exhaustive)
    }

    /// Classify `bx` against the parent's records `cand`; the cell to search further, if any.
    fn visit(&mut self, bx: Aabb, cand: &[u32]) -> Option<Cell> {
        self.cells += 1;
        let src = self.src;
        let mut out = Vec::new();
        let mut label = src.classify_near(&bx, cand, false, None, &mut out);
        if label == Label::Mixed && self.witnessed(&bx, false) {
            label = Label::Full;
        }
        if label == Label::Mixed && bx.extent().max_element() <= src.max_piece {
            let nested = (0..src.obstacles.len()).any(|k| src.vertex_nested(k, &bx));
            if nested || src.piece_contains_box(&bx).is_some() {
                label = Label::Full;
            }
        }
        let near = box_nearest(&bx, self.p);
        match label {
            Label::Full => None,
            Label::Empty => {
                self.offer(near);
                None
            }
            Label::Mixed => {
                if (near - self.p).length() < self.upper && !src.contains_point(near) {
                    self.offer(near);
                }
                let facet = out.iter().map(|&i| self.dist[i as usize]).fold(f64::INFINITY, f64::min);
                let key = bx.distance_to_point(self.p).max(facet);
                if key < self.upper - self.tol {
                    return Some(Cell { key, bx, cand: out });
                }
                // not searched further, but its boundary points still bound the depth
                self.dropped = self.dropped.min(key);
                None
            }
        }
    }

    /// Best first over the cells around `p`: `(lower, converged)`.
    fn cells(&mut self, max_cells: usize) -> (f64, bool) {
        let r = self.upper * (1.0 + 1e-9);
        let root = Aabb::new(self.p - Vec3::splat(r), self.p + Vec3::splat(r));
        let all: Vec<u32> = (0..self.src.facets.len() as u32).collect();
        let min_cell = self.tol * MIN_CELL_PER_TOL;
        let mut heap: BinaryHeap<Cell> = self.visit(root, &all).into_iter().collect();
        let mut floor = f64::INFINITY;
        while let Some(top) = heap.peek() {
            if top.key >= self.upper - self.tol {
                break;
            }
            if self.cells >= max_cells {
                return (top.key.min(floor).min(self.dropped), false);
            }
            let cell = heap.pop().expect("peeked");
            if cell.bx.extent().max_element() <= min_cell {
                if self.witnessed(&cell.bx, true) {
                    continue; // FULL after all: every witness candidate tried
                }
                floor = floor.min(cell.key);
                self.smallest += 1;
                continue;
            }
            for child in octants(&cell.bx) {
                if let Some(c) = self.visit(child, &cell.cand) {
                    heap.push(c);
                }
            }
        }
        let lower = heap.peek().map_or(self.upper, |c| c.key).min(floor).min(self.dropped).min(self.upper);
        (lower, self.upper - lower <= self.tol)
    }
}

/// The refusal of a depth query a source made for another region cannot answer.
fn beyond_region(p: Vec3) -> CoreError {
    CoreError::InvalidParameter {
        name: "depth region".into(),
        value: p.length(),
        detail: "the source kept only the facets near the point it was made for, and this query reaches beyond them; make the sum whole".into(),
    }
}

impl ExactSource {
    /// Whether every facet meeting the cube around `p` of half-width `r` was kept (always,
    /// without a [`ExactSource::region`]): that cube holds the ball of radius `r`.
    fn holds_cube(&self, p: Vec3, r: f64) -> bool {
        self.region.is_none_or(|reg| reg.min.cmple(p - Vec3::splat(r)).all() && (p + Vec3::splat(r)).cmple(reg.max).all())
    }

    /// [`ExactSource::try_depth`] for a source it accepts.
    ///
    /// ```
    /// use minkowski_core::{ExactSource, TriMesh, Vec3};
    ///
    /// // the box [lo, hi] as 12 outward triangles
    /// let cube = |lo: f64, hi: f64| {
    ///     let v = (0..8).map(|k| Vec3::new([lo, hi][k & 1], [lo, hi][k >> 1 & 1], [lo, hi][k >> 2 & 1])).collect();
    ///     let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    ///     let f: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    ///     TriMesh::new(v, &f, "cube").unwrap()
    /// };
    /// // the C-obstacle of [0.25, 1.25]³ for the robot [0, 1]³ (reflected: [-1, 0]³)
    /// let co = ExactSource::new(vec![cube(0.25, 1.25)], cube(-1.0, 0.0), 0.0, None);
    /// let d = co.depth(Vec3::ZERO, 1e-6, 10_000);
    /// assert!(d.inside && d.lower <= 0.75 && 0.75 <= d.upper && d.upper - d.lower <= 1e-6);
    /// ```
    ///
    /// # Panics
    /// When [`ExactSource::try_depth`] refuses the source or the parameters.
    pub fn depth(&self, p: Vec3, tol: f64, max_cells: usize) -> Depth {
        self.try_depth(p, tol, max_cells).expect("a depth query the source accepts")
    }

    /// The distance from `p` to the boundary of the solid as a proved interval (see the
    /// module documentation): inside, the penetration depth, to within `tol` unless the
    /// search runs out of `max_cells` cells; outside, the separation distance, exact up to
    /// rounding.
    ///
    /// # Errors
    /// [`CoreError::InvalidParameter`] for a `tol` that is not positive and finite;
    /// [`CoreError::InvalidGeometry`] for a source with walls, a margin or a surface pair
    /// (the depth is defined for the sum of two solids).
    pub fn try_depth(&self, p: Vec3, tol: f64, max_cells: usize) -> CoreResult<Depth> {
        if !(tol.is_finite() && tol > 0.0) {
            return Err(CoreError::InvalidParameter { name: "tolerance".into(), value: tol, detail: "must be a positive finite number".into() });
        }
        if !p.is_finite() {
            return Err(CoreError::NonFinite { what: "depth query point".into() });
        }
        if self.walls.is_some() || self.margin != 0.0 || !self.piece_pairs.is_empty() {
            return Err(CoreError::InvalidGeometry {
                what: "penetration depth".into(),
                detail: "defined for the sum of two solids (no walls, no margin, no surface); pass closed solids".into(),
            });
        }
        let dist: Vec<f64> = self.facets.par_iter().map(|f| (facet_nearest(f, p) - p).length()).collect();
        let inside = self.contains_point(p);
        if !inside {
            let nearest = (0..dist.len()).min_by(|&i, &j| dist[i].total_cmp(&dist[j]));
            let point = nearest.map_or(p, |i| facet_nearest(&self.facets[i], p));
            let d = (point - p).length();
            if self.region.is_some() && nearest.is_none_or(|_| !self.holds_cube(p, d)) {
                return Err(beyond_region(p)); // a nearer facet may have been left out
            }
            return Ok(Depth { inside, lower: d, upper: d, point, converged: nearest.is_some(), cells: 0, facets_tried: 0, smallest_cells: 0 });
        }
        let mut s = Search { src: self, p, tol, dist, upper: f64::INFINITY, point: p, cells: 0, dropped: f64::INFINITY, witnesses: None, smallest: 0 };
        s.box_exit();
        let facets_tried = s.nearest_facets();
        let nearest_facet = s.dist.iter().copied().fold(f64::INFINITY, f64::min).min(s.upper);
        if !self.holds_cube(p, s.upper * (1.0 + 1e-9)) {
            return Err(beyond_region(p)); // (not for the point the source was made for)
        }
        let (lower, converged) = if s.upper - nearest_facet <= tol { (nearest_facet, true) } else { s.cells(max_cells) };
        // the distances are rounded: the proved bound gives way by their rounding error
        let slack = 1e-12 * (self.aabb.extent().max_element() + p.abs().max_element());
        let lower = (lower.max(nearest_facet.min(s.upper)) - slack).max(0.0);
        Ok(Depth { inside, lower, upper: s.upper, point: s.point, converged, cells: s.cells, facets_tried, smallest_cells: s.smallest })
    }
}
