//! [`CSpace`]: the translational configuration space of one planning problem.
//!
//! The C-obstacle primitives (optionally grown by a margin), six wall slabs that fill the
//! root cell outside the bounds (so leaving the bounds is a collision like any other),
//! the octree on a lattice fine enough for the floor, and its [`LeafIndex`]. The octree
//! starts at the coarse cell size and is [`refine`]d where the planner asks.

use super::adjacency::{face_adjacency, neighbors, Neighbor};
use super::components::components;
use super::index::LeafIndex;
use super::refine::{refine, rescale, RefineStats};
use super::search::{astar, SearchResult};
use crate::error::{CoreError, CoreResult};
use crate::exact::{BoxWitness, ExactSource, TriMesh, Witness};
use crate::math::{Aabb, Vec3};
use crate::minkowski::PolytopeSet;
use crate::octree::{CellSource, Label, LevelCounts, Octree, MAX_DEPTH};
use crate::polytope::{clip_planes, ConvexPolytope};
use std::collections::BTreeSet;
use std::sync::Arc;

/// How a point joins the roadmap: through `leaf`, entering it at `via` (a free straight
/// segment from the point to `via`, then `via` to the leaf's centre inside the leaf).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attachment {
    /// An EMPTY leaf.
    pub leaf: usize,
    /// Entry point inside that leaf (the point itself when it lies in the leaf).
    pub via: Vec3,
    /// Length point → via → centre.
    pub cost: f64,
}

/// Proof that two leaves lie in different components of the non-FULL leaves: the smaller
/// component and the FULL leaves around it, each inside one primitive.
#[derive(Clone, Debug, PartialEq)]
pub struct Certificate {
    /// Component label of every leaf (`u32::MAX` for FULL leaves).
    pub labels: Vec<u32>,
    /// Leaves of the component containing the first leaf.
    pub start_component: Vec<usize>,
    /// Number of leaves in the component containing the second leaf.
    pub goal_component_size: usize,
    /// Whether the walled component is the start's (`false`: the goal's).
    pub walls_around_start: bool,
    /// FULL leaves face-adjacent to the walled component, each with the primitive (exact
    /// source: obstacle, or `n_obstacle + side` for a wall) that [`CSpace::verify_leaf`]
    /// showed to contain it, `usize::MAX` where that could not be shown.
    pub walls: Vec<(usize, usize)>,
    /// Per wall leaf (as in `walls`), why it is blocked (`None` where that could not be
    /// shown): what a check that trusts nothing of the core needs.
    pub witnesses: Vec<Option<WallWitness>>,
    /// Whether every wall leaf was shown to be blocked (the certificate holds).
    pub verified: bool,
    /// Number of components of the non-FULL leaves.
    pub n_components: usize,
}

/// Why a FULL leaf is blocked.
#[derive(Clone, Debug, PartialEq)]
pub enum WallWitness {
    /// The exact source's witnesses of the parts the leaf's box was split into (their
    /// union is the box), in the coordinates of the obstacles and the reflected robot.
    Exact(Vec<(Aabb, BoxWitness)>),
    /// The convex primitive (or wall, `n_obstacle + side`) of the decomposition that
    /// contains the leaf's box.
    Primitive(usize),
}

/// Box tests [`CSpace::certificate`] spends at most re-verifying the wall leaves of the
/// exact source.
const VERIFY_BUDGET: usize = 2_000_000;

/// The C-obstacles of a [`CSpace`] and the walls outside its bounds.
#[derive(Clone, Debug)]
pub enum Obstacles {
    /// Convex primitives (pairwise sums of convex pieces, grown by the margin), then the
    /// six wall slabs.
    Union(PolytopeSet),
    /// The exact boundary-convolution source over the obstacle meshes and the reflected
    /// robot, grown by the margin, with walls.
    Exact(Box<ExactSource>),
}

impl CellSource for Obstacles {
    fn root_records(&self) -> Vec<u32> {
        match self {
            Obstacles::Union(s) => s.root_records(),
            Obstacles::Exact(e) => e.root_records(),
        }
    }
    fn classify(&self, cell: &Aabb, cand: &[u32], finest: bool, out: &mut Vec<u32>) -> Label {
        match self {
            Obstacles::Union(s) => s.classify(cell, cand, finest, out),
            Obstacles::Exact(e) => e.classify(cell, cand, finest, out),
        }
    }
    fn classify_near(&self, cell: &Aabb, cand: &[u32], finest: bool, known: Option<(Vec3, bool)>, out: &mut Vec<u32>) -> Label {
        match self {
            Obstacles::Union(s) => s.classify(cell, cand, finest, out),
            Obstacles::Exact(e) => e.classify_near(cell, cand, finest, known, out),
        }
    }
    fn center_sign(&self, centre: Vec3, cand: &[u32], own: &[u32], known: Option<(Vec3, bool)>) -> Option<bool> {
        match self {
            Obstacles::Union(_) => None,
            Obstacles::Exact(e) => e.center_sign(centre, cand, own, known),
        }
    }
    fn cell_contains(&self, cand: &[u32], p: Vec3) -> bool {
        match self {
            Obstacles::Union(s) => s.cell_contains(cand, p),
            Obstacles::Exact(e) => e.cell_contains(cand, p),
        }
    }
    fn boundary_intervals(&self, cand: &[u32], a: Vec3, b: Vec3, out: &mut Vec<(f64, f64)>) {
        match self {
            Obstacles::Union(s) => s.boundary_intervals(cand, a, b, out),
            Obstacles::Exact(e) => e.boundary_intervals(cand, a, b, out),
        }
    }
    fn solid_intervals(&self, a: Vec3, b: Vec3, sa: bool, sb: bool, bnd: &[(f64, f64)], out: &mut Vec<(f64, f64)>) {
        match self {
            Obstacles::Union(s) => s.solid_intervals(a, b, sa, sb, bnd, out),
            Obstacles::Exact(e) => e.solid_intervals(a, b, sa, sb, bnd, out),
        }
    }
}

impl Obstacles {
    /// Whether `p` lies in a C-obstacle or a wall.
    pub fn contains_point(&self, p: Vec3) -> bool {
        match self {
            Obstacles::Union(s) => s.contains_point(p),
            Obstacles::Exact(e) => e.contains_point(p),
        }
    }

    /// Signed distance (see [`PolytopeSet::signed_distance`] and
    /// [`ExactSource::signed_distance`]).
    pub fn signed_distance(&self, p: Vec3) -> f64 {
        match self {
            Obstacles::Union(s) => s.signed_distance(p),
            Obstacles::Exact(e) => e.signed_distance(p),
        }
    }

    /// Number of primitives (union: convex primitives and walls; exact: obstacles and
    /// walls).
    pub fn len(&self) -> usize {
        match self {
            Obstacles::Union(s) => s.len(),
            Obstacles::Exact(e) => e.obstacles.len() + 6,
        }
    }

    /// Whether there is nothing (never: the walls are always there).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether this is the exact source.
    pub fn is_exact(&self) -> bool {
        matches!(self, Obstacles::Exact(_))
    }
}

/// The C-space of a translational planning problem (see the module documentation).
#[derive(Clone, Debug)]
pub struct CSpace {
    /// The C-obstacles (grown by `margin`) and the walls.
    pub obstacles: Obstacles,
    /// Number of obstacle primitives (union) or obstacles (exact); the six walls follow.
    pub n_obstacle: usize,
    /// The box of allowed translations.
    pub bounds: Aabb,
    /// Growth of the obstacle primitives (Minkowski sum with the cube `[-m, m]^3`).
    pub margin: f64,
    /// The octree, on the floor's lattice.
    pub oct: Octree,
    /// Its index.
    pub index: LeafIndex,
    /// Level of the coarse cells the octree was built with.
    pub coarse_level: u8,
}

fn wall_slabs(b: &Aabb, t: f64) -> Vec<ConvexPolytope> {
    let (lo, hi) = (b.min - Vec3::splat(t), b.max + Vec3::splat(t));
    let mut out = Vec::new();
    for axis in 0..3 {
        for upper in [false, true] {
            let (mut a, mut c) = (lo, hi);
            if upper {
                a[axis] = b.max[axis];
            } else {
                c[axis] = b.min[axis];
            }
            let pts: Vec<Vec3> = (0..8).map(|k| Vec3::new([a.x, c.x][k & 1], [a.y, c.y][(k >> 1) & 1], [a.z, c.z][(k >> 2) & 1])).collect();
            out.push(ConvexPolytope::from_points(&pts));
        }
    }
    out
}

/// `p`'s convex hull grown by the cube `[-m, m]^3` (contains `p ⊕ ball(m)`).
fn grow(p: &ConvexPolytope, m: f64, i: usize) -> CoreResult<ConvexPolytope> {
    let mut pts = Vec::with_capacity(p.vertices.len() * 8);
    for v in &p.vertices {
        for k in 0..8 {
            pts.push(*v + Vec3::new([-m, m][k & 1], [-m, m][(k >> 1) & 1], [-m, m][(k >> 2) & 1]));
        }
    }
    ConvexPolytope::try_from_points(&pts, &format!("primitive {i} grown by the margin"))
}

fn invalid(name: &str, value: f64, detail: &str) -> CoreError {
    CoreError::InvalidParameter { name: name.into(), value, detail: detail.into() }
}

fn check(bounds: &Aabb, h_floor: f64, h_coarse: f64, margin: f64) -> CoreResult<()> {
    if !(bounds.min.is_finite() && bounds.max.is_finite() && bounds.min.cmplt(bounds.max).all()) {
        return Err(invalid("bounds", f64::NAN, "need finite min < max on every axis"));
    }
    if !(h_floor > 0.0 && h_floor.is_finite()) {
        return Err(invalid("floor cell size", h_floor, "must be positive and finite"));
    }
    if !(h_coarse.is_finite() && h_coarse >= h_floor) {
        return Err(invalid("coarse cell size", h_coarse, "must be finite and at least the floor"));
    }
    if !(margin >= 0.0 && margin.is_finite()) {
        return Err(invalid("margin", margin, "must be finite and >= 0"));
    }
    Ok(())
}

impl CSpace {
    /// Build the C-space over `obstacles` (C-obstacle primitives) within `bounds`: octree
    /// cells of size about `h_coarse` (a power-of-two multiple of the floor), refinable
    /// down to `h_floor`; primitives grown by `margin`; at most `max_leaves` leaves.
    ///
    /// The floor is raised when the lattice would exceed `2^MAX_DEPTH` cells per side;
    /// [`CSpace::floor`] says what it is.
    ///
    /// # Errors
    /// [`CoreError::InvalidParameter`] for bad bounds, sizes or margin,
    /// [`CoreError::ResourceLimit`] when the coarse octree exceeds `max_leaves`.
    pub fn build(obstacles: &[ConvexPolytope], bounds: Aabb, h_floor: f64, h_coarse: f64, margin: f64, max_leaves: usize) -> CoreResult<CSpace> {
        check(&bounds, h_floor, h_coarse, margin)?;
        let k = (h_coarse / h_floor).log2().floor().clamp(0.0, MAX_DEPTH as f64) as u32;
        let h0 = h_floor * (1u64 << k) as f64;
        let mut polys: Vec<ConvexPolytope> =
            if margin > 0.0 { obstacles.iter().enumerate().map(|(i, p)| grow(p, margin, i)).collect::<CoreResult<_>>()? } else { obstacles.to_vec() };
        let n_obstacle = polys.len();
        let t = 2.0 * (bounds.extent().max_element() + 8.0 * h0) + 8.0 * h0;
        polys.extend(wall_slabs(&bounds, t));
        Self::finish(Obstacles::Union(PolytopeSet::new(polys)), n_obstacle, bounds, margin, h0, k, max_leaves)
    }

    /// [`CSpace::build`] with the exact source: the C-obstacles `O_k ⊕ (−R)` of the closed
    /// `meshes` for the closed `robot` mesh (in its own frame), grown by `margin`, no
    /// decomposition.
    ///
    /// # Errors
    /// As [`CSpace::build`], and [`CoreError::FacetLimit`] beyond `max_facets` boundary
    /// candidates (taking such a pair piece by piece instead fills the octree with the
    /// pieces' shell: measured on IndustReal's gears, 210 s and then over the record budget).
    #[allow(clippy::too_many_arguments)] // the problem's parts, the octree's sizes and its two budgets
    pub fn build_exact(meshes: Vec<TriMesh>, robot: &TriMesh, bounds: Aabb, h_floor: f64, h_coarse: f64, margin: f64, max_leaves: usize, max_facets: usize) -> CoreResult<CSpace> {
        Self::build_exact_reusing(meshes, robot, bounds, h_floor, h_coarse, margin, max_leaves, max_facets, &[]).map(|(cs, _)| cs)
    }

    /// [`CSpace::build_exact`], taking obstacle `k`'s reduced convolution from the pair sum
    /// `given[k]` of the same meshes (`O_k ⊕ −R`, built before) where there is one
    /// ([`ExactSource::try_new_reusing`]); whether each was taken.
    ///
    /// # Errors
    /// As [`CSpace::build_exact`].
    #[allow(clippy::too_many_arguments)] // as build_exact, and the sums to reuse
    pub fn build_exact_reusing(
        meshes: Vec<TriMesh>,
        robot: &TriMesh,
        bounds: Aabb,
        h_floor: f64,
        h_coarse: f64,
        margin: f64,
        max_leaves: usize,
        max_facets: usize,
        given: &[Option<Arc<ExactSource>>],
    ) -> CoreResult<(CSpace, Vec<bool>)> {
        check(&bounds, h_floor, h_coarse, margin)?;
        let k = (h_coarse / h_floor).log2().floor().clamp(0.0, MAX_DEPTH as f64) as u32;
        let h0 = h_floor * (1u64 << k) as f64;
        let n_obstacle = meshes.len();
        let (src, taken) = ExactSource::try_new_reusing(meshes, robot.negated(), margin, Some(bounds), max_facets, given)?;
        Ok((Self::finish(Obstacles::Exact(Box::new(src)), n_obstacle, bounds, margin, h0, k, max_leaves)?, taken))
    }

    fn finish(obstacles: Obstacles, n_obstacle: usize, bounds: Aabb, margin: f64, h0: f64, k: u32, max_leaves: usize) -> CoreResult<CSpace> {
        let oct0 = Octree::build(&obstacles, &bounds, h0, max_leaves)?;
        let k = k.min(MAX_DEPTH - oct0.depth as u32);
        let oct = rescale(oct0, k as u8)?;
        let index = LeafIndex::new(&oct);
        Ok(CSpace { obstacles, n_obstacle, bounds, margin, oct, index, coarse_level: k as u8 })
    }

    /// Finest cell size refinement can reach.
    pub fn floor(&self) -> f64 {
        self.oct.h
    }

    /// Size of leaf `i`.
    pub fn leaf_size(&self, i: usize) -> f64 {
        (1u64 << self.oct.leaves[i].level) as f64 * self.oct.h
    }

    /// Centre of leaf `i`.
    pub fn center(&self, i: usize) -> Vec3 {
        self.oct.cell_box(&self.oct.leaves[i]).center()
    }

    /// The leaf containing `p`.
    pub fn locate(&self, p: Vec3) -> Option<usize> {
        self.index.locate(&self.oct, p)
    }

    /// Leaves sharing a face with leaf `i`.
    pub fn neighbors(&self, i: usize) -> Vec<Neighbor> {
        let mut out = Vec::new();
        neighbors(&self.oct, &self.index, i, &mut out);
        out
    }

    /// `(primitive, depth)` for every primitive containing `p`; depth = distance to its
    /// nearest facet plane. With the exact source, `(obstacle, depth)` with depth a lower
    /// bound (0 when only nesting shows the collision); walls are `n_obstacle + side`.
    pub fn containing(&self, p: Vec3) -> Vec<(usize, f64)> {
        match &self.obstacles {
            Obstacles::Union(set) => set.containing(p).into_iter().map(|i| (i, -set.polys[i].plane_distance(p))).collect(),
            Obstacles::Exact(e) => {
                let mut out: Vec<(usize, f64)> = e.containing(p).into_iter().map(|k| (k, (-e.signed_distance(p)).max(0.0))).collect();
                if e.walls.is_some() {
                    for side in 0..6 {
                        let d = -e.wall_gap(side, p);
                        if d >= 0.0 {
                            out.push((self.n_obstacle + side, d));
                        }
                    }
                }
                out
            }
        }
    }

    /// Whether the closed segment `a → b` stays farther than `margin` from every primitive
    /// (exact for `margin = 0`; for `margin > 0` each primitive's facet planes are pushed
    /// out by `margin`, which contains the primitive grown by a ball of that radius).
    pub fn segment_is_free(&self, a: Vec3, b: Vec3, margin: f64) -> bool {
        let set = match &self.obstacles {
            Obstacles::Union(set) => set,
            Obstacles::Exact(e) => return e.segment_is_free(a, b, margin.max(0.0)),
        };
        if margin <= 0.0 {
            return set.segment_is_free(a, b);
        }
        let q = Aabb::new(a.min(b), a.max(b)).inflated(margin);
        let mut free = true;
        set.bvh.for_each_overlapping(&q, |i| {
            if free {
                let p = &set.polys[i];
                if clip_planes(p.normals.iter().zip(&p.offsets).map(|(n, d)| (*n, *d + margin)), a, b).is_some() {
                    free = false;
                }
            }
        });
        free
    }

    /// How `p` joins the roadmap: its own leaf when EMPTY; from a MIXED leaf, the EMPTY
    /// leaves within `rings` face-steps (through non-FULL leaves) reachable by an exactly
    /// free straight segment to a point a quarter of their size inside them. Sorted by
    /// cost. Empty when `p` is outside the root, in a FULL leaf or nothing is reachable.
    pub fn attach(&self, p: Vec3, rings: usize) -> Vec<Attachment> {
        let Some(leaf) = self.locate(p) else { return Vec::new() };
        match self.oct.leaves[leaf].label {
            Label::Empty => return vec![Attachment { leaf, via: p, cost: (p - self.center(leaf)).length() }],
            Label::Full => return Vec::new(),
            Label::Mixed => {}
        }
        let mut seen = BTreeSet::from([leaf]);
        let mut frontier = vec![leaf];
        let mut out = Vec::new();
        for _ in 0..rings {
            let mut next = Vec::new();
            for &u in &frontier {
                for m in self.neighbors(u) {
                    if !seen.insert(m.leaf) {
                        continue;
                    }
                    let l = self.oct.leaves[m.leaf];
                    match l.label {
                        Label::Full => {}
                        Label::Mixed => next.push(m.leaf),
                        Label::Empty => {
                            let b = self.oct.cell_box(&l);
                            let inset = 0.25 * b.extent().x;
                            let q = p.clamp(b.min + Vec3::splat(inset), b.max - Vec3::splat(inset));
                            if self.segment_is_free(p, q, 0.0) {
                                out.push(Attachment { leaf: m.leaf, via: q, cost: (p - q).length() + (q - b.center()).length() });
                            }
                        }
                    }
                }
            }
            frontier = next;
        }
        out.sort_by(|a, b| a.cost.total_cmp(&b.cost).then(a.leaf.cmp(&b.leaf)));
        out
    }

    /// Shortest roadmap path through EMPTY leaves from the attachments of `start` to those
    /// of `goal`, as waypoints `start, [via], centre, portal, centre, ..., [via], goal`:
    /// every segment lies in one closed EMPTY leaf or is an attachment segment, so the
    /// path is exactly free. `None` when they are not connected through EMPTY leaves.
    pub fn free_path(&self, start: Vec3, goal: Vec3, s_att: &[Attachment], g_att: &[Attachment]) -> Option<(Vec<Vec3>, SearchResult)> {
        let src: Vec<(usize, f64)> = s_att.iter().map(|a| (a.leaf, a.cost)).collect();
        let dst: Vec<(usize, f64)> = g_att.iter().map(|a| (a.leaf, a.cost)).collect();
        let labels = &self.oct.leaves;
        let r = astar(&self.oct, &self.index, &src, &dst, goal, |i| (labels[i].label == Label::Empty).then_some(1.0))?;
        let first = *r.leaves.first()?;
        let last = *r.leaves.last()?;
        let best = |att: &[Attachment], leaf: usize| att.iter().filter(|a| a.leaf == leaf).min_by(|a, b| a.cost.total_cmp(&b.cost)).map(|a| a.via);
        let mut pts = vec![start];
        if let Some(v) = best(s_att, first) {
            if v != start {
                pts.push(v);
            }
        }
        for (k, &leaf) in r.leaves.iter().enumerate() {
            pts.push(self.center(leaf));
            if k < r.portals.len() {
                pts.push(r.portals[k]);
            }
        }
        if let Some(v) = best(g_att, last) {
            if v != goal {
                pts.push(v);
            }
        }
        pts.push(goal);
        pts.dedup();
        Some((pts, r))
    }

    /// The cheapest channel of non-FULL leaves from the leaf of `start` to that of `goal`:
    /// MIXED leaves cost `1 + penalty` per length, EMPTY ones 1. With `refinable_only`,
    /// MIXED leaves at the floor (level 0) are avoided, except the two end leaves.
    pub fn channel(&self, start: Vec3, goal: Vec3, penalty: f64, refinable_only: bool) -> Option<SearchResult> {
        let s = self.locate(start)?;
        let g = self.locate(goal)?;
        let leaves = &self.oct.leaves;
        let weight = |i: usize| match leaves[i].label {
            Label::Empty => Some(1.0),
            Label::Full => None,
            Label::Mixed if refinable_only && leaves[i].level == 0 && i != s && i != g => None,
            Label::Mixed => Some(1.0 + penalty.max(0.0)),
        };
        let cs = (start - self.center(s)).length() * weight(s).unwrap_or(1.0);
        let cg = (goal - self.center(g)).length() * weight(g).unwrap_or(1.0);
        astar(&self.oct, &self.index, &[(s, cs)], &[(g, cg)], goal, weight)
    }

    /// Split the MIXED leaves above the floor among `leaves` (and, with `ring`, their MIXED
    /// face neighbours above the floor) `levels` times.
    ///
    /// # Errors
    /// [`CoreError::ResourceLimit`] beyond `max_leaves` leaves,
    /// [`CoreError::RecordLimit`] beyond the records' budget, [`CoreError::TimeLimit`]
    /// when the time limit ([`crate::deadline`]) passed (nothing is changed then).
    pub fn refine(&mut self, leaves: &[usize], ring: bool, levels: u8, max_leaves: usize) -> CoreResult<RefineStats> {
        let refinable = |i: usize| self.oct.leaves[i].label == Label::Mixed && self.oct.leaves[i].level > 0;
        let mut targets: BTreeSet<usize> = leaves.iter().copied().filter(|&i| i < self.oct.leaves.len() && refinable(i)).collect();
        if ring {
            let base: Vec<usize> = leaves.iter().copied().filter(|&i| i < self.oct.leaves.len() && self.oct.leaves[i].label == Label::Mixed).collect();
            for i in base {
                for m in self.neighbors(i) {
                    if refinable(m.leaf) {
                        targets.insert(m.leaf);
                    }
                }
            }
        }
        let targets: Vec<usize> = targets.into_iter().collect();
        refine(&self.obstacles, &mut self.oct, &mut self.index, &targets, levels, max_leaves)
    }

    /// Leaves per level and label.
    pub fn level_counts(&self) -> LevelCounts {
        self.oct.level_counts()
    }

    /// `(EMPTY leaves, pairs of face-adjacent EMPTY leaves)`: the roadmap's size.
    pub fn roadmap_size(&self) -> (usize, usize) {
        let leaves = &self.oct.leaves;
        let pairs = face_adjacency(&self.oct, &self.index, |i| leaves[i].label == Label::Empty);
        (leaves.iter().filter(|l| l.label == Label::Empty).count(), pairs.len())
    }

    /// A primitive whose closed polytope contains the closed box of leaf `i`; with the
    /// exact source the obstacle (or `n_obstacle + side` for a wall) whose C-obstacle
    /// contains it, shown by one triangle pair's piece or by nesting.
    pub fn primitive_containing_leaf(&self, i: usize) -> Option<usize> {
        let b = self.oct.cell_box(&self.oct.leaves[i]);
        let set = match &self.obstacles {
            Obstacles::Union(set) => set,
            Obstacles::Exact(e) => return e.box_witness(&b).map(|w| self.primitive_of(w)),
        };
        let mut found: Option<usize> = None;
        set.bvh.for_each_overlapping(&b, |k| {
            if set.polys[k].contains_box(&b) {
                found = Some(found.map_or(k, |f| f.min(k)));
            }
        });
        found
    }

    /// The primitive (exact source: obstacle, or `n_obstacle + side` for a wall) shown to
    /// contain the closed box of leaf `i` by an exact test that does not trust the octree's
    /// label: a convex primitive containing it, or [`ExactSource::verify_box`] (triangle
    /// pairs and nesting, never the reduced convolution). `budget`: box tests left for the
    /// exact source.
    pub fn verify_leaf(&self, i: usize, budget: &mut usize) -> Option<usize> {
        self.verify_leaf_witness(i, budget).map(|(prim, _)| prim)
    }

    /// The primitive an exact witness names: its obstacle, or `n_obstacle + side` for a
    /// wall.
    fn primitive_of(&self, w: Witness) -> usize {
        match w {
            Witness::Piece { k, .. } | Witness::Nested { k } => k,
            Witness::Wall { side } => self.n_obstacle + side,
        }
    }

    /// [`CSpace::verify_leaf`] with the witness: `(primitive, why)`.
    pub fn verify_leaf_witness(&self, i: usize, budget: &mut usize) -> Option<(usize, WallWitness)> {
        match &self.obstacles {
            Obstacles::Union(_) => self.primitive_containing_leaf(i).map(|k| (k, WallWitness::Primitive(k))),
            Obstacles::Exact(e) => {
                let parts = e.verify_box_witnesses(&self.oct.cell_box(&self.oct.leaves[i]), budget)?;
                Some((self.primitive_of(parts[0].1.kind()), WallWitness::Exact(parts)))
            }
        }
    }

    /// When the leaves of `start` and `goal` lie in different components of the non-FULL
    /// (EMPTY ∪ MIXED) leaves, the certificate: the smaller of the two components and the
    /// FULL leaves around it, each re-verified ([`CSpace::verify_leaf`]). `None` when they
    /// are connected (or a point is outside).
    pub fn certificate(&self, start: Vec3, goal: Vec3) -> Option<Certificate> {
        let s = self.locate(start)?;
        let g = self.locate(goal)?;
        let leaves = &self.oct.leaves;
        let free = |i: usize| leaves[i].label != Label::Full;
        let pairs = face_adjacency(&self.oct, &self.index, free);
        let labels = components(leaves.len(), &pairs, free);
        let (cs, cg) = (labels[s], labels[g]);
        if cs == cg && cs != u32::MAX {
            return None;
        }
        let n_components = labels.iter().filter(|&&c| c != u32::MAX).max().map_or(0, |&m| m as usize + 1);
        let members = |c: u32| -> Vec<usize> {
            if c == u32::MAX {
                Vec::new()
            } else {
                (0..leaves.len()).filter(|&i| labels[i] == c).collect()
            }
        };
        let (ms, mg) = (members(cs), members(cg));
        let around_start = ms.len() <= mg.len();
        let walled = if around_start { &ms } else { &mg };
        let mut walls = self.full_neighbours(walled);
        // A FULL end leaf walls itself off: the point is in collision.
        for (c, leaf) in [(cs, s), (cg, g)] {
            if c == u32::MAX && walled.is_empty() {
                walls.insert(leaf);
            }
        }
        let (walls, witnesses, verified) = self.verified_walls(walls);
        Some(Certificate { labels: labels.clone(), goal_component_size: mg.len(), start_component: ms, walls_around_start: around_start, walls, witnesses, verified, n_components })
    }

    /// The component of the non-FULL leaves that holds `start` and the FULL leaves around
    /// it, each re-verified ([`CSpace::verify_leaf`]), as a [`Certificate`] walling off the
    /// start (no goal: `goal_component_size` is 0). When it is `verified` and no wall leaf is
    /// a wall outside the bounds (every primitive `< n_obstacle`), no path leaves the
    /// component, whatever lies beyond the bounds. `None` when `start` is outside the root
    /// or in a FULL leaf.
    pub fn enclosure(&self, start: Vec3) -> Option<Certificate> {
        let s = self.locate(start)?;
        let leaves = &self.oct.leaves;
        if leaves[s].label == Label::Full {
            return None;
        }
        let free = |i: usize| leaves[i].label != Label::Full;
        let pairs = face_adjacency(&self.oct, &self.index, free);
        let labels = components(leaves.len(), &pairs, free);
        let n_components = labels.iter().filter(|&&c| c != u32::MAX).max().map_or(0, |&m| m as usize + 1);
        let members: Vec<usize> = (0..leaves.len()).filter(|&i| labels[i] == labels[s]).collect();
        let (walls, witnesses, verified) = self.verified_walls(self.full_neighbours(&members));
        Some(Certificate { labels, goal_component_size: 0, start_component: members, walls_around_start: true, walls, witnesses, verified, n_components })
    }

    /// FULL leaves face-adjacent to a leaf of `component`.
    fn full_neighbours(&self, component: &[usize]) -> BTreeSet<usize> {
        let mut walls = BTreeSet::new();
        for &i in component {
            for m in self.neighbors(i) {
                if self.oct.leaves[m.leaf].label == Label::Full {
                    walls.insert(m.leaf);
                }
            }
        }
        walls
    }

    /// Each wall leaf with the primitive shown to contain it (`usize::MAX` where none
    /// was), and whether all were shown.
    fn verified_walls(&self, walls: BTreeSet<usize>) -> (Vec<(usize, usize)>, Vec<Option<WallWitness>>, bool) {
        let mut budget = VERIFY_BUDGET;
        let (walls, witnesses): (Vec<(usize, usize)>, Vec<Option<WallWitness>>) = walls
            .into_iter()
            .map(|w| match self.verify_leaf_witness(w, &mut budget) {
                Some((prim, why)) => ((w, prim), Some(why)),
                None => ((w, usize::MAX), None),
            })
            .unzip();
        let verified = witnesses.iter().all(Option::is_some);
        (walls, witnesses, verified)
    }
}

impl CSpace {
    /// Shorten a path greedily: from each kept waypoint jump to the farthest later one
    /// reachable by a straight segment that stays `margin` away from every primitive
    /// (galloping, then bisection), keeping the original segment when no jump passes.
    /// Repeated while it shortens the path, at most `passes` times.
    pub fn shortcut(&self, pts: &[Vec3], margin: f64, passes: usize) -> Vec<Vec3> {
        let mut cur = pts.to_vec();
        for _ in 0..passes.max(1) {
            let n = cur.len();
            if n <= 2 {
                break;
            }
            let free = |a: usize, b: usize| self.segment_is_free(cur[a], cur[b], margin);
            let mut out = vec![cur[0]];
            let mut i = 0;
            while i < n - 1 {
                let mut best = i + 1;
                if n - 1 > i + 1 && free(i, n - 1) {
                    best = n - 1;
                } else {
                    let mut k = 2;
                    let mut hi = n - 1;
                    while i + k < n - 1 {
                        if free(i, i + k) {
                            best = i + k;
                            k *= 2;
                        } else {
                            hi = i + k;
                            break;
                        }
                    }
                    let mut lo = best;
                    while hi > lo + 1 {
                        let mid = (lo + hi) / 2;
                        if free(i, mid) {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    best = lo;
                }
                out.push(cur[best]);
                i = best;
            }
            let done = out.len() == cur.len();
            cur = out;
            if done {
                break;
            }
        }
        cur
    }
}
