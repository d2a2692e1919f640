//! The exact source: Minkowski sums of triangle meshes by boundary convolution, no convex
//! decomposition.
//!
//! For closed meshes `A` (triangles `T_i`) and `B` (triangles `S_j`), every boundary point
//! `p` of `A ⊕ B` is a contact: `A` and `p − B` touch, so some `T_i` meets some `p − S_j`,
//! that is `p ∈ T_i ⊕ S_j`. Hence:
//!
//! * a cell that no *piece* `T_i ⊕ S_j` meets holds no boundary point, so it lies wholly
//!   inside or wholly outside the sum, and one exact point query labels it;
//! * every piece lies in the sum (its points are contacts), so a cell inside one piece is
//!   FULL;
//! * the exact point query for `p` that no piece contains: `A` and `p − B` do not touch,
//!   so they meet only if one contains the other — one vertex of each, tested for
//!   containment in the other by ray parity ([`TriMesh::contains`]).
//!
//! The pieces fill a shell around the boundary (every translation where the surfaces
//! cross), so they are not what the octree splits on: its boundary candidates are the
//! facets of the *reduced convolution* ([`convolution`]), a surface. Pieces serve the point
//! query and the FULL witness, found lazily by a traversal of pairs of BVH nodes of the two
//! meshes (never all `n·m` pairs). The solid can be the union over several `A_k` with one
//! `B` (C-obstacles of many obstacles for one robot, `B = −R`), optionally with the outside
//! of a box of allowed translations (walls), each grown by a cube of half-width `margin`.
//!
//! Solids and surfaces: a mesh is a *solid* ([`TriMesh::new`]: closed, and its winding
//! number never negative, see [`winding`]) or a *surface* ([`TriMesh::surface`]: any
//! triangles, no inside, as FCL sees a mesh). Containment counts only for solids: the
//! nesting test above asks a solid. A surface's closed shells (mod 2) still show cells
//! FULL: a connected part of the other mesh inside one and reaching out of it crosses it
//! ([`shells`]). A pair with a surface has no reduced convolution; every
//! one of its pieces is a boundary candidate, kept per cell as pairs of BVH nodes that are
//! split as the cells shrink (see `root_records`), so no `n·m` list is built.
//!
//! Entry points: [`ExactSource`], [`TriMesh`], [`ExactSource::verify_box`],
//! [`ExactSource::try_depth`] (penetration depth and separation distance).

mod convolution;
pub mod crossing;
mod depth;
#[cfg(test)]
mod depth_tests;
#[cfg(test)]
pub(crate) mod exact_tests;
mod gauss;
mod inside_grid;
#[cfg(test)]
mod inside_grid_tests;
mod mesh;
mod nearest;
mod piece;
pub mod shells;
#[cfg(test)]
mod shells_tests;
#[cfg(test)]
mod surface_pair_tests;
pub mod tidy;
#[cfg(test)]
mod tidy_tests;
mod verify;
pub mod winding;
#[cfg(test)]
mod winding_tests;
mod witness;

pub use convolution::{convolution, convolution_within, Facet, FlatPlanes};
#[cfg(test)]
use convolution::{convolution_scan, planar_regions};
pub use depth::{facet_nearest, Depth};
pub use mesh::{MeshNode, Tri, TriMesh, Windings};
pub use piece::{pair_box_relation, pair_contains_box, pair_contains_point, BoxRelation, Piece};
pub use verify::BoxWitness;

use crate::bvh::Bvh;
use crate::error::{CoreError, CoreResult};
use crate::math::{Aabb, Vec3};
use crate::octree::{merge_sorted, CellSource, Label};
use crate::surface::planar::Cut;
use inside_grid::InsideGrid;
use shells::Shells;
use std::sync::{Arc, OnceLock};

/// Records at or above this are walls (`WALL + side`, side = 2 · axis + upper); below
/// [`PAIR`], facet indices.
const WALL: u32 = u32::MAX - 7;

/// A record `[PAIR, k, a, b]`: the pieces of obstacle `k` (a surface pair) under BVH nodes
/// `a` of the obstacle and `b` of `B`.
const PAIR: u32 = WALL - 1;

/// One record of a cell's list.
#[derive(Clone, Copy, Debug)]
enum Rec {
    /// A reduced-convolution facet.
    Facet(usize),
    /// The pieces of obstacle `k` under a pair of BVH nodes.
    Pair(usize, u32, u32),
    /// The slab beyond wall `side`.
    Wall(usize),
}

/// The records of a cell's list, decoded.
fn records(cand: &[u32]) -> impl Iterator<Item = Rec> + '_ {
    let mut i = 0;
    std::iter::from_fn(move || {
        let r = *cand.get(i)?;
        if r == PAIR {
            i += 4;
            Some(Rec::Pair(cand[i - 3] as usize, cand[i - 2], cand[i - 1]))
        } else {
            i += 1;
            Some(if r >= WALL { Rec::Wall((r - WALL) as usize) } else { Rec::Facet(r as usize) })
        }
    })
}

/// Memory of one facet with its box, its share of the BVH and of the convolution's search
/// (bytes), for budgets: peak resident memory measured 560 bytes per facet for 36.6k
/// facets (a torus and a bumpy sphere, the meshes' BVHs included), before the precomputed
/// half-spaces of a sum without a margin (about 200 more) were added.
pub const FACET_BYTES: usize = 768;

/// Longest record list [`ExactSource::carry`] scans; beyond it a point query is cheaper.
const CARRY_MAX: usize = 256;

/// The union of `A_k ⊕ B` over the obstacles `A_k`, grown by `margin`, plus optional walls.
#[derive(Clone, Debug)]
pub struct ExactSource {
    /// The meshes `A_k`.
    pub obstacles: Vec<TriMesh>,
    /// The mesh `B` (for C-obstacles `O ⊕ (−R)`: the robot reflected through its origin).
    pub b: TriMesh,
    /// The obstacles taken piece by piece (every triangle-pair piece a boundary candidate, no
    /// reduced convolution): pairs with a surface, and solid pairs over the facet budget
    /// ([`ExactSource::with_piece_fallback`]).
    pub piece_pairs: Vec<usize>,
    /// Growth of every sum by the cube `[-margin, margin]^3`.
    pub margin: f64,
    /// When set, everything outside this box is solid too (closed slabs beyond each face).
    pub walls: Option<Aabb>,
    /// Box around the sums (without walls).
    pub aabb: Aabb,
    /// Largest possible piece extent: no cell wider than this lies inside one piece.
    max_piece: f64,
    /// The reduced convolution facets of every solid `A_k` with a solid `B`: only those
    /// meeting [`ExactSource::region`] when that is set.
    pub facets: Vec<Facet>,
    /// Set for a source made for one depth query ([`ExactSource::try_new_for_depth`]):
    /// the box holding every point its search can look at; facets beyond it were left out.
    pub region: Option<Aabb>,
    /// BVH over the facets' boxes (grown by `margin`).
    fbvh: Bvh,
    /// Each facet's half-spaces, computed once (only without a margin, where the tests
    /// use them; empty otherwise).
    flat: Vec<Option<FlatPlanes>>,
    /// Whether finest MIXED cells inside the solid (one triangle-pair piece, or a vertex of
    /// one part nested in the other) are relabelled FULL: the planner wants FULL walls for
    /// its certificates, the surface does not need them. Coarser cells always are
    /// (interior culling: they are never split).
    pub full_witness: bool,
    /// The inside grid of each solid obstacle (for the nested-vertex test), made when
    /// first asked.
    grids: Vec<OnceLock<Arc<InsideGrid>>>,
    /// The inside grid of `B` when it is a solid, made when first asked.
    b_grid: OnceLock<Arc<InsideGrid>>,
    /// The closed shells and connected parts of each obstacle, made when first asked.
    shells: Vec<OnceLock<Arc<Shells>>>,
    /// Those of `B`.
    b_shells: OnceLock<Arc<Shells>>,
}

/// Why a cell or point is solid: which obstacle (or wall) and how.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Witness {
    /// Inside the piece of triangles `(i, j)` of obstacle `k` and `B`.
    Piece {
        /// Obstacle.
        k: usize,
        /// Triangle of the obstacle.
        i: usize,
        /// Triangle of `B`.
        j: usize,
    },
    /// Deep in the C-obstacle of obstacle `k`, shown by one point: a vertex of one part
    /// inside the other, solid, part, or a connected part of one crossing a closed shell of
    /// the other ([`shells`]).
    Nested {
        /// Obstacle.
        k: usize,
    },
    /// Beyond the wall `side` (= 2 · axis + upper).
    Wall {
        /// Side.
        side: usize,
    },
}

impl ExactSource {
    /// The sums `A_k ⊕ B`, grown by `margin`, with optional `walls`.
    ///
    /// # Panics
    /// Never for a lack of memory budget (there is none); see [`ExactSource::try_new`].
    pub fn new(obstacles: Vec<TriMesh>, b: TriMesh, margin: f64, walls: Option<Aabb>) -> ExactSource {
        ExactSource::try_new(obstacles, b, margin, walls, usize::MAX).expect("no facet budget")
    }

    /// [`ExactSource::new`] with at most `max_facets` reduced-convolution facets over all
    /// pairs (each about [`FACET_BYTES`] of memory with its box and BVH node).
    ///
    /// # Errors
    /// [`CoreError::FacetLimit`] when the facets would exceed the budget; the search
    /// stops soon after, so little of that memory is taken.
    pub fn try_new(obstacles: Vec<TriMesh>, b: TriMesh, margin: f64, walls: Option<Aabb>, max_facets: usize) -> CoreResult<ExactSource> {
        Self::build(obstacles, b, margin, walls, max_facets, false, &[], None).map(|(src, _)| src)
    }

    /// The sum `a ⊕ b` of two solids for the depth query at `p` to within `tol`
    /// ([`ExactSource::try_depth`]) and nothing else: only the facets meeting the cube
    /// around `p` that the search can reach are made (its half-width is the way out of
    /// the sum's box, which bounds the depth). Two parts that overlap a little have few
    /// facets there, where their whole reduced convolution (IndustReal's gears: tens of
    /// millions) would not fit in memory. A point outside the sum whose nearest facet
    /// lies beyond the cube is refused by the query.
    ///
    /// # Errors
    /// As [`ExactSource::try_new`], counting only the facets kept.
    pub fn try_new_for_depth(a: TriMesh, b: TriMesh, max_facets: usize, p: Vec3, tol: f64) -> CoreResult<ExactSource> {
        if !(tol.is_finite() && tol > 0.0) {
            return Err(CoreError::InvalidParameter { name: "tolerance".into(), value: tol, detail: "must be a positive finite number".into() });
        }
        if !p.is_finite() {
            return Err(CoreError::NonFinite { what: "depth query point".into() });
        }
        let aabb = Aabb::new(a.aabb.min + b.aabb.min, a.aabb.max + b.aabb.max);
        let half = depth::exit_distance(&aabb, p, tol).max(0.0) * (1.0 + 1e-6) + 1e-9 * (aabb.extent().max_element() + p.abs().max_element());
        let region = Aabb::new(p - Vec3::splat(half), p + Vec3::splat(half));
        Self::build(vec![a], b, 0.0, None, max_facets, false, &[], Some(region)).map(|(src, _)| src)
    }

    /// [`ExactSource::try_new`], taking obstacle `k`'s reduced convolution from `given[k]`
    /// when that is a pair sum of the same two meshes (one obstacle, no margin, built
    /// before: an assembly's pair cache), instead of computing it again; a `None`, or a
    /// sum of other meshes, is computed. Whether each was taken.
    ///
    /// # Errors
    /// As [`ExactSource::try_new`] (the facets taken count against the budget too).
    pub fn try_new_reusing(
        obstacles: Vec<TriMesh>,
        b: TriMesh,
        margin: f64,
        walls: Option<Aabb>,
        max_facets: usize,
        given: &[Option<Arc<ExactSource>>],
    ) -> CoreResult<(ExactSource, Vec<bool>)> {
        Self::build(obstacles, b, margin, walls, max_facets, false, given, None)
    }

    /// Whether this is the sum of exactly `a` and `b` with its reduced convolution (one
    /// obstacle, no margin, no walls): the same triangles in the same order.
    fn is_pair_of(&self, a: &TriMesh, b: &TriMesh) -> bool {
        let same = |x: &TriMesh, y: &TriMesh| x.solid == y.solid && x.tris.len() == y.tris.len() && x.tris.iter().zip(&y.tris).all(|(t, u)| t.p == u.p);
        self.obstacles.len() == 1
            && self.region.is_none()
            && self.piece_pairs.is_empty()
            && self.margin == 0.0
            && self.walls.is_none()
            && same(&self.obstacles[0], a)
            && same(&self.b, b)
    }

    /// [`ExactSource::try_new`], but a solid pair whose reduced convolution would exceed
    /// what is left of `max_facets` is taken piece by piece, as a surface pair is (every
    /// triangle-pair piece a boundary candidate, found per cell by the BVH pair traversal;
    /// containment still counts, both meshes being solids): the same solid, exactly, in
    /// memory bounded by the octree's records instead of `n·m` facets. Its pieces fill a
    /// shell around the boundary, so cells inside the C-obstacle near it are MIXED until
    /// one piece or a nested vertex shows them FULL: right for a planner, which refines
    /// only where its search asks, not for a surface, which would refine the whole shell.
    pub fn with_piece_fallback(obstacles: Vec<TriMesh>, b: TriMesh, margin: f64, walls: Option<Aabb>, max_facets: usize) -> ExactSource {
        Self::build(obstacles, b, margin, walls, max_facets, true, &[], None).expect("pairs over the budget are taken piece by piece").0
    }

    #[allow(clippy::too_many_arguments)] // (private: the constructors above name them)
    fn build(
        obstacles: Vec<TriMesh>,
        b: TriMesh,
        margin: f64,
        walls: Option<Aabb>,
        max_facets: usize,
        fallback: bool,
        given: &[Option<Arc<ExactSource>>],
        region: Option<Aabb>,
    ) -> CoreResult<(ExactSource, Vec<bool>)> {
        let aabb = obstacles.iter().fold(Aabb::empty(), |acc, a| acc.union(&Aabb::new(a.aabb.min + b.aabb.min, a.aabb.max + b.aabb.max).inflated(margin)));
        let tri_ext = |m: &TriMesh| m.tris.iter().map(|t| Aabb::from_points(&t.p).extent().max_element()).fold(0.0f64, f64::max);
        let max_a = obstacles.iter().map(tri_ext).fold(0.0f64, f64::max);
        let max_piece = (max_a + tri_ext(&b) + 2.0 * margin) * 1.000_001;
        let mut piece_pairs: Vec<usize> = (0..obstacles.len()).filter(|&k| !(obstacles[k].solid && b.solid)).collect();
        let budget = max_facets.min(PAIR as usize - 1);
        let mut facets: Vec<Facet> = Vec::new();
        let mut taken = vec![false; obstacles.len()];
        for (k, a) in obstacles.iter().enumerate() {
            if piece_pairs.contains(&k) {
                continue;
            }
            let left = budget - facets.len();
            let reused = given.get(k).and_then(Option::as_ref).filter(|g| g.is_pair_of(a, &b));
            taken[k] = reused.is_some();
            let found = match reused {
                Some(g) if g.facets.len() <= left => Ok(g.facets.iter().map(|f| Facet { k: k as u32, ..*f }).collect()),
                Some(g) => Err(g.facets.len()),
                None => convolution_within(a, &b, k as u32, left, region.as_ref()),
            };
            match found {
                Ok(found) => facets.extend(found),
                Err(_) if fallback => piece_pairs.push(k),
                Err(n) => {
                    return Err(CoreError::FacetLimit { what: format!("obstacle {k}"), found: facets.len() + n, budget, bytes_per_facet: FACET_BYTES });
                }
            }
        }
        piece_pairs.sort_unstable();
        let boxes: Vec<Aabb> = facets.iter().map(|f| f.aabb(margin)).collect();
        let fbvh = Bvh::build(&boxes);
        let flat = if margin == 0.0 { facets.iter().map(Facet::flat_planes).collect() } else { Vec::new() };
        let grids = obstacles.iter().map(|_| OnceLock::new()).collect();
        let shells = obstacles.iter().map(|_| OnceLock::new()).collect();
        let b_grid = OnceLock::new();
        Ok((
            ExactSource {
                full_witness: walls.is_some(),
                obstacles,
                b,
                piece_pairs,
                margin,
                walls,
                aabb,
                max_piece,
                facets,
                region,
                fbvh,
                flat,
                grids,
                b_grid,
                shells,
                b_shells: OnceLock::new(),
            },
            taken,
        ))
    }

    /// Whether `p` lies in facet `i` grown by `m` (its precomputed half-spaces when `m` is 0).
    #[inline]
    fn facet_contains(&self, i: usize, p: Vec3, m: f64) -> bool {
        match self.flat.get(i) {
            Some(Some((pl, n))) if m == 0.0 => pl[..*n].iter().all(|&(d, w)| d.dot(p) <= w),
            _ => self.facets[i].contains_point(p, m),
        }
    }

    /// The parameter interval of `a → b` in facet `i` grown by `m` (as [`Facet::clip`]).
    #[inline]
    fn facet_clip(&self, i: usize, a: Vec3, b: Vec3, m: f64) -> Option<(f64, f64)> {
        match self.flat.get(i) {
            Some(Some((pl, n))) if m == 0.0 => crate::polytope::clip_planes(pl[..*n].iter().copied(), a, b),
            _ => self.facets[i].clip(a, b, m),
        }
    }

    /// Whether `p` lies in the exact (ungrown) solid, walls excluded.
    fn exact_point(&self, p: Vec3) -> bool {
        (0..self.obstacles.len()).any(|k| self.touches(k, 0.0, p)) || self.nested(p).is_some()
    }

    /// Whether some triangle pair of obstacle `k` (grown by `m`) contains `p`.
    fn touches(&self, k: usize, m: f64, p: Vec3) -> bool {
        let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
        self.any_pair(k, m, |bx| bx.contains_point(p), |i, j| pair_contains_point(&ta[i], &tb[j], m, p))
    }

    /// Whether a single triangle-pair piece (grown by the margin) contains `cell`.
    fn piece_contains_box(&self, cell: &Aabb) -> Option<Witness> {
        for k in 0..self.obstacles.len() {
            let mut hit = None;
            let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
            self.any_pair(
                k,
                self.margin,
                |bx| bx.min.cmple(cell.min).all() && cell.max.cmple(bx.max).all(),
                |i, j| {
                    if pair_contains_box(&ta[i], &tb[j], self.margin, cell) {
                        hit = Some(Witness::Piece { k, i, j });
                    }
                    hit.is_some()
                },
            );
            if hit.is_some() {
                return hit;
            }
        }
        None
    }

    #[inline]
    fn sum_box(&self, k: usize, a: u32, b: u32, m: f64) -> Aabb {
        let (na, nb) = (&self.obstacles[k].nodes[a as usize], &self.b.nodes[b as usize]);
        Aabb::new(na.aabb.min + nb.aabb.min, na.aabb.max + nb.aabb.max).inflated(m)
    }

    /// Children of a node pair: split the larger inner node.
    #[inline]
    fn split(&self, k: usize, a: u32, b: u32) -> [[u32; 3]; 2] {
        let (na, nb) = (&self.obstacles[k].nodes[a as usize], &self.b.nodes[b as usize]);
        let k = k as u32;
        if !na.is_leaf() && (nb.is_leaf() || na.size() >= nb.size()) {
            [[k, na.left, b], [k, na.left + 1, b]]
        } else {
            [[k, a, nb.left], [k, a, nb.left + 1]]
        }
    }

    /// How far `p` lies outside the slab beyond wall `side` (= 2 · axis + upper): `<= 0`
    /// in the slab, minus its depth there.
    #[inline]
    pub fn wall_gap(&self, side: usize, p: Vec3) -> f64 {
        let w = self.walls.expect("wall record without walls");
        let axis = side / 2;
        if side.is_multiple_of(2) {
            p[axis] - w.min[axis]
        } else {
            w.max[axis] - p[axis]
        }
    }

    /// Whether `p` lies beyond the wall `side` grown by `extra`.
    #[inline]
    fn in_wall(&self, side: usize, p: Vec3, extra: f64) -> bool {
        self.wall_gap(side, p) <= extra
    }

    /// `(inside, meets)`: whether the closed box lies in / meets the slab beyond `side`.
    #[inline]
    fn wall_box(&self, side: usize, cell: &Aabb) -> (bool, bool) {
        let (near, far) = if side.is_multiple_of(2) { (cell.min, cell.max) } else { (cell.max, cell.min) };
        (self.wall_gap(side, far) <= 0.0, self.wall_gap(side, near) <= 0.0)
    }

    /// The obstacle whose sum contains `p` because a shell of one mesh lies inside the
    /// other (no surface contact: then one vertex of the shell decides).
    pub fn nested(&self, p: Vec3) -> Option<usize> {
        (0..self.obstacles.len()).find(|&k| self.nested_k(k, p))
    }

    fn nested_k(&self, k: usize, p: Vec3) -> bool {
        let a = &self.obstacles[k];
        // a shell of p − B inside the solid A: its vertex p − b in A; a shell of A inside
        // the solid p − B: p − a in B (a surface contains nothing)
        (a.solid && self.b.anchors.iter().any(|&b0| a.contains(p - b0))) || (self.b.solid && a.anchors.iter().any(|&a0| self.b.contains(p - a0)))
    }

    /// Visit the leaf pieces of obstacle `k` whose summed boxes pass `test`, until `f`
    /// returns true; whether it did.
    fn any_piece(&self, k: usize, m: f64, with_axes: bool, test: impl Fn(&Aabb) -> bool, mut f: impl FnMut(&Piece<'_>, usize, usize) -> bool) -> bool {
        let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
        self.any_pair(k, m, test, |i, j| f(&Piece::new(&ta[i], &tb[j], m, with_axes), i, j))
    }

    /// Visit the triangle pairs `(i, j)` of obstacle `k` whose summed boxes (grown by `m`)
    /// pass `test`, by a traversal of pairs of BVH nodes, until `f` returns true; whether it
    /// did.
    fn any_pair(&self, k: usize, m: f64, test: impl Fn(&Aabb) -> bool, f: impl FnMut(usize, usize) -> bool) -> bool {
        self.any_pair_under(k, [0, 0], m, test, f)
    }

    /// [`ExactSource::any_pair`] below the node pair `start`.
    fn any_pair_under(&self, k: usize, start: [u32; 2], m: f64, test: impl Fn(&Aabb) -> bool, mut f: impl FnMut(usize, usize) -> bool) -> bool {
        // median-split BVHs are at most ~log2(n) deep, so the pair stack stays short; a
        // deeper one spills to the heap
        let mut fixed = [[0u32; 2]; 64];
        fixed[0] = start;
        let mut len = 1usize;
        let mut spill: Vec<[u32; 2]> = Vec::new();
        let (ma, mb) = (&self.obstacles[k].nodes, &self.b.nodes);
        loop {
            let [a, b] = if let Some(x) = spill.pop() {
                x
            } else if len > 0 {
                len -= 1;
                fixed[len]
            } else {
                return false;
            };
            if !test(&self.sum_box(k, a, b, m)) {
                continue;
            }
            let (na, nb) = (&ma[a as usize], &mb[b as usize]);
            if na.is_leaf() && nb.is_leaf() {
                if f(na.tri as usize, nb.tri as usize) {
                    return true;
                }
                continue;
            }
            for [_, ca, cb] in self.split(k, a, b) {
                if len < fixed.len() {
                    fixed[len] = [ca, cb];
                    len += 1;
                } else {
                    spill.push([ca, cb]);
                }
            }
        }
    }

    /// Why `p` is in the (grown) solid, or `None` when it is not.
    pub fn point_witness(&self, p: Vec3) -> Option<Witness> {
        if self.walls.is_some() {
            if let Some(side) = (0..6).find(|&s| self.in_wall(s, p, 0.0)) {
                return Some(Witness::Wall { side });
            }
        }
        for k in 0..self.obstacles.len() {
            let mut hit = None;
            let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
            self.any_pair(
                k,
                self.margin,
                |bx| bx.contains_point(p),
                |i, j| {
                    let inside = pair_contains_point(&ta[i], &tb[j], self.margin, p);
                    if inside {
                        hit = Some(Witness::Piece { k, i, j });
                    }
                    inside
                },
            );
            if hit.is_some() {
                return hit;
            }
        }
        if let Some(k) = self.nested(p) {
            return Some(Witness::Nested { k });
        }
        if self.margin > 0.0 {
            // within the margin of the boundary: in a grown facet
            let mut hit = None;
            self.fbvh.for_each_at_point(p, |i| {
                if hit.is_none() && self.facet_contains(i, p, self.margin) {
                    hit = Some(Witness::Nested { k: self.facets[i].k as usize });
                }
            });
            return hit;
        }
        None
    }

    /// Whether `p` lies in the closed (grown) solid.
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.point_witness(p).is_some()
    }

    /// The obstacles whose (grown) sum contains `p`.
    pub fn containing(&self, p: Vec3) -> Vec<usize> {
        let mut out: Vec<usize> = (0..self.obstacles.len()).filter(|&k| self.touches(k, self.margin, p) || self.nested_k(k, p)).collect();
        if self.margin > 0.0 {
            self.fbvh.for_each_at_point(p, |i| {
                let k = self.facets[i].k as usize;
                if !out.contains(&k) && self.facet_contains(i, p, self.margin) {
                    out.push(k);
                }
            });
            out.sort_unstable();
        }
        out
    }

    /// Signed distance bound: outside, a lower bound on the distance to the solid (the
    /// nearest solid point is a boundary point, on a facet: each facet's separating-axis
    /// distance; walls exact); inside, minus a lower bound on the depth (the largest depth
    /// in one triangle-pair piece over its axes; 0 when only nesting shows it inside).
    pub fn signed_distance(&self, p: Vec3) -> f64 {
        let mut best = f64::INFINITY;
        if let Some(w) = self.walls {
            let d = (p - w.min).min(w.max - p).min_element();
            if d <= 0.0 {
                return d;
            }
            best = d;
        }
        if self.contains_point(p) {
            let mut depth = 0.0f64;
            for k in 0..self.obstacles.len() {
                self.any_piece(
                    k,
                    self.margin,
                    false,
                    |bx| bx.contains_point(p),
                    |piece, _, _| {
                        depth = depth.max(-piece.separation(p));
                        false
                    },
                );
            }
            return -depth;
        }
        for f in &self.facets {
            let bx = f.aabb(self.margin);
            let gap = bx.distance_to_point(p);
            if gap >= best {
                continue;
            }
            best = best.min(f.separation(p, self.margin).max(0.0));
        }
        for &k in &self.piece_pairs {
            // every piece of a surface pair is a boundary candidate
            let bound = std::cell::Cell::new(best);
            let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
            self.any_pair(
                k,
                self.margin,
                |bx| bx.distance_to_point(p) < bound.get(),
                |i, j| {
                    bound.set(bound.get().min(Piece::new(&ta[i], &tb[j], self.margin, false).separation(p).max(0.0)));
                    false
                },
            );
            best = bound.get();
        }
        best
    }

    /// Why the closed box `cell` lies in the (grown) solid: a wall, one triangle-pair
    /// piece containing it, or — when no facet meets it — the solid at its centre.
    pub fn box_witness(&self, cell: &Aabb) -> Option<Witness> {
        if self.walls.is_some() {
            if let Some(side) = (0..6).find(|&side| self.wall_box(side, cell).0) {
                return Some(Witness::Wall { side });
            }
        }
        if let Some(w) = self.piece_contains_box(cell) {
            return Some(w);
        }
        let mut touched = false;
        self.fbvh.for_each_overlapping(cell, |i| {
            touched = touched || self.facets[i].overlaps_box(cell, self.margin);
        });
        touched = touched
            || self.piece_pairs.iter().any(|&k| {
                let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
                self.any_pair(k, self.margin, |bx| bx.overlaps(cell), |i, j| pair_box_relation(&ta[i], &tb[j], self.margin, cell) != BoxRelation::Apart)
            });
        if touched || self.walls.is_some_and(|w| !(w.min.cmplt(cell.min).all() && cell.max.cmplt(w.max).all())) {
            return None;
        }
        self.point_witness(cell.center())
    }

    /// The membership of `p`, carried from `q` (membership `sq`) when no boundary candidate
    /// of `cand` (the records of a cell holding both) meets the segment between them;
    /// `None` when one does, or when `cand` is too long to be worth scanning.
    fn carry(&self, cand: &[u32], q: Vec3, sq: bool, p: Vec3) -> Option<bool> {
        if cand.len() > CARRY_MAX {
            return None;
        }
        let seg = Aabb::new(q.min(p), q.max(p));
        for rec in records(cand) {
            let crossed = match rec {
                Rec::Wall(side) => self.wall_gap(side, q) <= 0.0 || self.wall_gap(side, p) <= 0.0,
                Rec::Facet(i) => self.facets[i].aabb(self.margin).overlaps(&seg) && self.facet_clip(i, q, p, self.margin).is_some(),
                Rec::Pair(k, a, b) => self.pieces_meet_segment(k, [a, b], self.margin, q, p),
            };
            if crossed {
                return None;
            }
        }
        Some(sq)
    }

    /// Whether a piece of obstacle `k` below the node pair `start`, grown by `m`, meets the
    /// closed segment `a → b`.
    fn pieces_meet_segment(&self, k: usize, start: [u32; 2], m: f64, a: Vec3, b: Vec3) -> bool {
        let seg = Aabb::new(a.min(b), a.max(b));
        let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
        self.any_pair_under(k, start, m, |bx| bx.overlaps(&seg) && bx.overlaps_segment(a, b), |i, j| Piece::new(&ta[i], &tb[j], m, false).clip(a, b).is_some())
    }

    /// Split the node pair `start` of obstacle `k` (a surface pair) against `cell`: push
    /// `[PAIR, k, a, b]` records of the pairs whose pieces meet it — split while their box
    /// is much larger than the cell, then kept as one record (a leaf pair, or a small
    /// inner pair) when one piece below them meets the cell, tested exactly and stopping
    /// at the first; so a cell's list stays about as long as the pairs of its size, not
    /// all pieces. Whether one piece contains the whole cell (then it is FULL); `unchecked`
    /// is set when some piece that meets the cell may not have been asked (a record kept
    /// above the leaves).
    fn refine_pair(&self, k: usize, start: [u32; 2], cell: &Aabb, out: &mut Vec<u32>, unchecked: &mut bool) -> bool {
        let m = self.margin;
        let big = 2.0 * cell.extent().max_element();
        let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
        let mut stack = vec![start];
        while let Some([a, b]) = stack.pop() {
            let bx = self.sum_box(k, a, b, m);
            if !bx.overlaps(cell) {
                continue;
            }
            let (na, nb) = (&self.obstacles[k].nodes[a as usize], &self.b.nodes[b as usize]);
            let leaf = na.is_leaf() && nb.is_leaf();
            // split while that can shrink the pair to the cell's size: a pair with one long
            // leaf (a 35-unit strip of a pipe) is kept once the other node is that small,
            // not split down to every triangle of it
            let splittable = [na, nb].iter().filter(|n| !n.is_leaf()).map(|n| n.size()).fold(0.0f64, f64::max);
            if !leaf && bx.extent().max_element() > big && splittable > 0.5 * big {
                stack.extend(self.split(k, a, b).map(|[_, ca, cb]| [ca, cb]));
                continue;
            }
            let mut full = false;
            let meets = self.any_pair_under(
                k,
                [a, b],
                m,
                |q| q.overlaps(cell),
                |i, j| match pair_box_relation(&ta[i], &tb[j], m, cell) {
                    BoxRelation::Apart => false,
                    BoxRelation::Meets => true,
                    BoxRelation::Inside => {
                        full = true;
                        true
                    }
                },
            );
            if full {
                return true;
            }
            if meets {
                out.extend([PAIR, k as u32, a, b]);
                *unchecked |= !leaf;
            }
        }
        false
    }

    /// Whether a vertex of one part lies inside the other, solid, part at every
    /// translation of `cell` ([`ExactSource::vertex_nested`]), or a connected part of one
    /// crosses a closed shell of the other ([`ExactSource::pierced`]): deep in a C-obstacle, where
    /// no single piece covers the cell (exact, and the walls of certificates of surfaces
    /// need it: their interiors are unions of pieces). For the planner's cells, and for
    /// the surface's above the finest level (it needs no FULL witness there).
    fn nested_full(&self, cell: &Aabb, finest: bool) -> bool {
        (self.full_witness || !finest) && (0..self.obstacles.len()).any(|k| self.vertex_nested(k, cell) || self.pierced(k, cell).is_some())
    }

    /// Whether [`ExactSource::nested_full`] is asked before a cell's records are filtered,
    /// of the vertices through the inside grids (else after, of MIXED cells only, of a
    /// sample of vertices): for the planner's cells when a surface is taken piece by piece
    /// against a solid (an open robot, a slab of a part). Its filtering costs triangle-pair
    /// tests per record, which a FULL cell is spared; and the interior of its C-obstacle, a
    /// union of pieces, is shown FULL in cells as large as the parts' crossing, not as a
    /// piece (OMPL.app's spirelli: a local proof 5× faster, 8k wall cells instead of 63k;
    /// Factory's nut proved interlocked on its bolt as fast as before). Facets filter
    /// cheaply, and the surface's cells are mostly not FULL: there the grids would cost
    /// more than they spare (measured: sums 2–3× slower).
    pub(super) fn nested_first(&self) -> bool {
        self.full_witness && self.piece_pairs.iter().any(|&k| !(self.obstacles[k].solid && self.b.solid))
    }

    /// The parameter intervals of the segment `a → b` inside the (grown) solid, sorted and
    /// merged: the boundary candidates the segment meets are solid, and each stretch
    /// between them is decided by its ends or one exact point.
    pub fn segment_intervals(&self, a: Vec3, b: Vec3) -> Vec<(f64, f64)> {
        let seg = Aabb::new(a.min(b), a.max(b)).inflated(self.margin);
        let mut cand: Vec<u32> = Vec::new();
        self.fbvh.for_each_overlapping(&seg, |i| cand.push(i as u32));
        cand.sort_unstable();
        for &k in &self.piece_pairs {
            cand.extend([PAIR, k as u32, 0, 0]);
        }
        if self.walls.is_some() {
            cand.extend((0..6).map(|s| WALL + s));
        }
        let (mut bnd, mut out) = (Vec::new(), Vec::new());
        self.boundary_intervals(&cand, a, b, &mut bnd);
        self.solid_intervals(a, b, self.contains_point(a), self.contains_point(b), &bnd, &mut out);
        out
    }

    /// Whether the closed segment `a → b` stays out of the solid grown by a further cube of
    /// half-width `extra` (walls pulled in by `extra`).
    pub fn segment_is_free(&self, a: Vec3, b: Vec3, extra: f64) -> bool {
        let extra = extra.max(0.0);
        if self.walls.is_some() && (0..6).any(|s| self.in_wall(s, a, extra) || self.in_wall(s, b, extra)) {
            return false; // slabs are convex and the segment is too: its ends decide
        }
        let m = self.margin + extra;
        let q = Aabb::new(a.min(b), a.max(b)).inflated(extra);
        let mut hit = false;
        self.fbvh.for_each_overlapping(&q, |i| {
            hit = hit || self.facet_clip(i, a, b, m).is_some();
        });
        hit = hit || self.piece_pairs.iter().any(|&k| self.pieces_meet_segment(k, [0, 0], m, a, b));
        // no grown boundary candidate meets the segment: all of it is inside or all outside
        !hit && !self.exact_point(a)
    }
}

impl CellSource for ExactSource {
    /// Every facet, one `[PAIR, k, 0, 0]` (the root nodes) per surface pair, the walls.
    fn root_records(&self) -> Vec<u32> {
        let mut r: Vec<u32> = (0..self.facets.len() as u32).collect();
        for &k in &self.piece_pairs {
            r.extend([PAIR, k as u32, 0, 0]);
        }
        if self.walls.is_some() {
            r.extend((0..6).map(|s| WALL + s));
        }
        r
    }

    fn classify(&self, cell: &Aabb, cand: &[u32], finest: bool, out: &mut Vec<u32>) -> Label {
        self.classify_near(cell, cand, finest, None, out)
    }

    fn center_sign(&self, c: Vec3, cand: &[u32], own: &[u32], known: Option<(Vec3, bool)>) -> Option<bool> {
        Some(known.and_then(|(q, s)| self.carry(cand, q, s, c)).unwrap_or_else(|| self.cell_contains(own, c)))
    }

    fn classify_near(&self, cell: &Aabb, cand: &[u32], finest: bool, known: Option<(Vec3, bool)>, out: &mut Vec<u32>) -> Label {
        if self.nested_first() && self.nested_full(cell, finest) {
            return Label::Full;
        }
        // whether a piece that contains the cell may not have been asked yet: the pieces of
        // solid pairs are no records, and a pair record kept above the leaves was asked
        // only up to its first piece that meets the cell
        let mut unchecked = self.piece_pairs.len() < self.obstacles.len();
        for rec in records(cand) {
            match rec {
                Rec::Wall(side) => {
                    let (inside, meets) = self.wall_box(side, cell);
                    if inside {
                        out.clear();
                        return Label::Full;
                    }
                    if meets {
                        out.push(WALL + side as u32);
                    }
                }
                Rec::Facet(i) => {
                    if self.facets[i].overlaps_box(cell, self.margin) {
                        out.push(i as u32);
                    }
                }
                Rec::Pair(k, a, b) => {
                    if self.refine_pair(k, [a, b], cell, out, &mut unchecked) {
                        out.clear();
                        return Label::Full;
                    }
                }
            }
        }
        if out.is_empty() {
            // no boundary in the cell: its centre decides (not in any grown candidate),
            // carried from the parent's known point when no boundary lies between them
            let c = cell.center();
            let inside = known.and_then(|(q, s)| self.carry(cand, q, s, c)).unwrap_or_else(|| self.exact_point(c));
            return if inside { Label::Full } else { Label::Empty };
        }
        // interior culling: a cell inside the solid is FULL and never split; the surface
        // needs that only above the finest level, the planner's certificates everywhere
        let witness = self.full_witness || !finest;
        if witness && unchecked && cell.extent().max_element() <= self.max_piece && self.piece_contains_box(cell).is_some() {
            out.clear();
            return Label::Full;
        }
        if !self.nested_first() && self.nested_full(cell, finest) {
            out.clear();
            return Label::Full;
        }
        Label::Mixed
    }

    /// Inside: a single piece, or a nested vertex, holds the whole cell (a FULL witness;
    /// walls aside), or its candidates lie on a few planes and every region they cut the
    /// cell into is inside (the boundary lies on those planes, between regions that
    /// differ). Outside: never — every record of a finest cell (a facet, a pair's pieces)
    /// meets it and lies in the solid, so such a cell holds solid the lattice missed.
    fn misses_boundary(&self, cell: &Aabb, own: &[u32], inside: bool) -> bool {
        if !inside || records(own).any(|r| matches!(r, Rec::Wall(_))) {
            return false;
        }
        self.box_shown(cell).is_some() || crate::octree::planes_clear(self, cell, own)
    }

    fn cell_contains(&self, cand: &[u32], p: Vec3) -> bool {
        for rec in records(cand) {
            let inside = match rec {
                Rec::Wall(side) => self.in_wall(side, p, 0.0),
                Rec::Facet(i) => self.facet_contains(i, p, self.margin),
                Rec::Pair(k, a, b) => {
                    let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
                    self.any_pair_under(k, [a, b], self.margin, |bx| bx.contains_point(p), |i, j| pair_contains_point(&ta[i], &tb[j], self.margin, p))
                }
            };
            if inside {
                return true;
            }
        }
        self.exact_point(p)
    }

    fn meets_boundary(&self, cand: &[u32], a: Vec3, b: Vec3, _scratch: &mut Vec<(f64, f64)>) -> bool {
        // as `boundary_intervals`, stopping at the first record that meets the segment
        records(cand).any(|rec| match rec {
            Rec::Wall(side) => self.wall_gap(side, a) <= 0.0 || self.wall_gap(side, b) <= 0.0,
            Rec::Facet(i) => self.facet_clip(i, a, b, self.margin).is_some(),
            Rec::Pair(k, na, nb) => {
                let seg = Aabb::new(a.min(b), a.max(b));
                let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
                self.any_pair_under(k, [na, nb], self.margin, |bx| bx.overlaps(&seg), |i, j| Piece::new(&ta[i], &tb[j], self.margin, false).clip(a, b).is_some())
            }
        })
    }

    fn boundary_intervals(&self, cand: &[u32], a: Vec3, b: Vec3, out: &mut Vec<(f64, f64)>) {
        out.clear();
        for rec in records(cand) {
            match rec {
                Rec::Wall(side) => {
                    // inside the slab: gap <= 0, linear along the segment
                    let (fa, fb) = (self.wall_gap(side, a), self.wall_gap(side, b));
                    if fa <= 0.0 && fb <= 0.0 {
                        out.push((0.0, 1.0));
                    } else if fa <= 0.0 {
                        out.push((0.0, fa / (fa - fb)));
                    } else if fb <= 0.0 {
                        out.push((fa / (fa - fb), 1.0));
                    }
                }
                Rec::Facet(i) => {
                    if let Some(t) = self.facet_clip(i, a, b, self.margin) {
                        out.push(t);
                    }
                }
                Rec::Pair(k, na, nb) => {
                    let seg = Aabb::new(a.min(b), a.max(b));
                    let (ta, tb) = (&self.obstacles[k].tris, &self.b.tris);
                    self.any_pair_under(
                        k,
                        [na, nb],
                        self.margin,
                        |bx| bx.overlaps(&seg),
                        |i, j| {
                            if let Some(t) = Piece::new(&ta[i], &tb[j], self.margin, false).clip(a, b) {
                                out.push(t);
                            }
                            false
                        },
                    );
                }
            }
        }
        merge_sorted(out);
    }

    /// Only facets, each flat with its half-spaces known (no margin), on at most
    /// [`crate::surface::planar::MAX_PLANES`] planes; each plane's extent holds the boxes
    /// of its facets.
    fn plane_cut(&self, own: &[u32]) -> Option<Cut> {
        let mut cut = Cut::new();
        for rec in records(own) {
            let Rec::Facet(i) = rec else { return None };
            let Some(Some((pl, _))) = self.flat.get(i) else { return None };
            // the plane from both sides, each thickened by the facet's slack
            let (n, w, slack) = (pl[0].0, 0.5 * (pl[0].1 - pl[1].1), 0.5 * (pl[0].1 + pl[1].1));
            if !cut.add_within(n, w, 100.0 * slack, self.facets[i].aabb(self.margin).inflated(100.0 * slack)) {
                return None;
            }
        }
        Some(cut)
    }

    fn solid_intervals(&self, a: Vec3, b: Vec3, sa: bool, sb: bool, bnd: &[(f64, f64)], out: &mut Vec<(f64, f64)>) {
        // the facets, pieces and slabs are solid; between them the segment meets no boundary, so
        // each gap is all in or all out: the ends decide the outer ones, a point the others
        out.clear();
        out.extend_from_slice(bnd);
        let tiny = 1e-12;
        if out.is_empty() {
            if sa {
                out.push((0.0, 1.0));
            }
            return;
        }
        let mut gaps = Vec::new();
        let mut prev = 0.0f64;
        let n = out.len();
        for idx in 0..=n {
            let cur = out.get(idx).copied();
            let next = cur.map_or(1.0, |iv| iv.0);
            if next > prev + tiny {
                let inside = if prev <= tiny && idx == 0 {
                    sa
                } else if idx == n {
                    sb
                } else {
                    self.exact_point(a + (b - a) * (0.5 * (prev + next)))
                };
                if inside {
                    gaps.push((prev, next));
                }
            }
            if let Some(iv) = cur {
                prev = prev.max(iv.1);
            }
        }
        if !gaps.is_empty() {
            out.extend(gaps);
            merge_sorted(out);
        }
    }
}
