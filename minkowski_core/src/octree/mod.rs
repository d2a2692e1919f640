//! The adaptive octree over a set of convex primitives (seed paper §4.2).
//!
//! A cell keeps only the primitives that meet it, and of each only the facet planes that
//! cut it (primitive and facet culling: every other plane is satisfied by the whole cell,
//! so by Theorem 1 of the paper nothing else can change a query inside it). A cell inside a
//! single primitive is FULL (cell culling), a cell no primitive meets is EMPTY (exactly
//! free), otherwise MIXED and split down to the finest size `h`. Children filter their
//! parent's lists, so work follows the boundary, not the volume. Parallel over subtrees.
//!
//! Entry points: [`Octree::build`], [`Leaf`], [`Label`], [`Octree::cell_box`],
//! [`Octree::candidates`].

#[cfg(test)]
mod octree_tests;

use crate::error::{CoreError, CoreResult};
use crate::math::{Aabb, Vec3};
use crate::polytope::ConvexPolytope;
use crate::surface::planar::Cut;
use crate::surface::sag::BoundaryPoint;
use crate::surface::{cell_key, resolve_cell, ResolvedCells};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Deepest octree the lattice keys can address (coordinates below 2^21).
pub const MAX_DEPTH: u32 = 20;

/// Most candidate-record words (`u32`) an octree may hold: 4 GiB, and every offset into
/// the arena stays a `u32`. Beyond it the build or refinement stops with
/// [`CoreError::RecordLimit`] instead of running out of memory.
pub const MAX_RECORD_WORDS: usize = 1 << 30;

/// The record budget [`Octree::build`] and [`crate::roadmap::refine`] use, in words:
/// [`MAX_RECORD_WORDS`] unless the binding set a smaller one from the caller's memory
/// limit ([`set_record_budget`]). One process-wide value, like the memory it stands for.
static RECORD_BUDGET: AtomicUsize = AtomicUsize::new(MAX_RECORD_WORDS);

/// The candidate-record budget in words (see [`set_record_budget`]).
pub fn record_budget() -> usize {
    RECORD_BUDGET.load(Ordering::Relaxed)
}

/// Set the candidate-record budget to `words` (clamped to `1..=MAX_RECORD_WORDS`); the
/// previous value is returned.
pub fn set_record_budget(words: usize) -> usize {
    RECORD_BUDGET.swap(words.clamp(1, MAX_RECORD_WORDS), Ordering::Relaxed)
}

/// The fraction of a finest cell by which the lattice is shifted off the region's corner,
/// so that axis-aligned facets rarely fall exactly on lattice planes.
const LATTICE_SHIFT: f64 = 0.381_966_011_250_105_1;

/// What the octree is built over: a source of candidate records per cell.
///
/// A cell's *records* (`u32` runs in [`Octree::cands`]) name what may meet it; children
/// filter their parent's records. The decomposition source ([`PolytopeSet`], a union of
/// solid convex pieces) keeps `[prim, k, plane_1 .. plane_k]`; the exact source
/// ([`crate::exact::ExactSource`]) keeps pairs of BVH nodes of the two meshes.
///
/// [`PolytopeSet`]: crate::minkowski::PolytopeSet
pub trait CellSource: Sync {
    /// The records of the root cell.
    fn root_records(&self) -> Vec<u32>;
    /// Filter the records `cand` of a parent against `cell` into `out` (cleared by the
    /// caller) and label the cell. `finest`: the cell will not be split, so its records
    /// must be resolved to what the surface and point queries use.
    fn classify(&self, cell: &Aabb, cand: &[u32], finest: bool, out: &mut Vec<u32>) -> Label;
    /// [`CellSource::classify`] with a point `known = (q, inside)` of the parent cell
    /// (whose records are `cand`) of known membership, which a source with costly point
    /// queries may carry to this cell. Default: ignore it.
    fn classify_near(&self, cell: &Aabb, cand: &[u32], finest: bool, known: Option<(Vec3, bool)>, out: &mut Vec<u32>) -> Label {
        let _ = known;
        self.classify(cell, cand, finest, out)
    }
    /// For a MIXED cell that will be split: the membership of its `centre` (the lattice
    /// point its children share), for its children's [`CellSource::classify_near`]
    /// (`cand`: the parent's records, `own`: the cell's, `known`: the parent's known
    /// point). Default: `None` (not worth computing).
    fn center_sign(&self, centre: Vec3, cand: &[u32], own: &[u32], known: Option<(Vec3, bool)>) -> Option<bool> {
        let _ = (centre, cand, own, known);
        None
    }
    /// Whether `p`, a point of a cell with records `cand`, lies in the (closed) solid.
    fn cell_contains(&self, cand: &[u32], p: Vec3) -> bool;
    /// Where on the segment `a → b` (inside a cell with records `cand`) the boundary
    /// may lie: sorted, merged parameter intervals of `[0, 1]`. Each stretch between them
    /// lies wholly inside or wholly outside the solid, so with none the ends agree.
    fn boundary_intervals(&self, cand: &[u32], a: Vec3, b: Vec3, out: &mut Vec<(f64, f64)>);
    /// Whether the boundary may lie on the segment `a → b` inside a cell with records
    /// `cand`: its [`CellSource::boundary_intervals`] are not empty (`scratch` holds them
    /// meanwhile). Sources answer at the first candidate that meets it.
    fn meets_boundary(&self, cand: &[u32], a: Vec3, b: Vec3, scratch: &mut Vec<(f64, f64)>) -> bool {
        self.boundary_intervals(cand, a, b, scratch);
        !scratch.is_empty()
    }
    /// The parts of the segment `a → b` that lie in the solid, as sorted, merged parameter
    /// intervals of `[0, 1]`, given its [`CellSource::boundary_intervals`] `bnd` and the
    /// known memberships `sa`, `sb` of its ends.
    fn solid_intervals(&self, a: Vec3, b: Vec3, sa: bool, sb: bool, bnd: &[(f64, f64)], out: &mut Vec<(f64, f64)>);
    /// Whether the boundary provably misses `cell`, a finest MIXED cell with records `own`
    /// whose corners all have membership `inside` and whose edges the boundary does not
    /// cross: a sliver or void thinner than the cell can slip between the lattice edges,
    /// and the surface's bound covers such a cell only by its distance to the surface
    /// ([`crate::surface::Surface::loose_at`]). Default: an inside cell whose regions
    /// between its candidates' planes are all inside ([`planes_clear`]).
    fn misses_boundary(&self, cell: &Aabb, own: &[u32], inside: bool) -> bool
    where
        Self: Sized,
    {
        inside && planes_clear(self, cell, own)
    }
    /// The boundary point that `x`, a point within `reach` of some boundary point (a
    /// vertex of an extracted surface), moves to along the gradient of the distance the
    /// source is a level set of, and the boundary's outward unit normal there, when the
    /// source can find it exactly: the surface is then refined where it sags from the
    /// boundary ([`crate::surface::sag`]). Default: `None` (see
    /// [`CellSource::has_boundary_points`]).
    fn boundary_point(&self, x: Vec3, reach: f64) -> Option<BoundaryPoint> {
        let _ = (x, reach);
        None
    }
    /// Whether [`CellSource::boundary_point`] may give points. Default: `false`.
    fn has_boundary_points(&self) -> bool {
        false
    }
    /// The planes of the boundary candidates of a MIXED cell with records `own`, when
    /// every candidate is flat and they lie on at most [`planar::MAX_PLANES`] planes (the
    /// cell is then resolved exactly at its size, see [`planar`]). Default: `None`.
    ///
    /// [`planar`]: crate::surface::planar
    /// [`planar::MAX_PLANES`]: crate::surface::planar::MAX_PLANES
    fn plane_cut(&self, own: &[u32]) -> Option<Cut> {
        let _ = own;
        None
    }
}

/// Whether no boundary lies in `cell` (records `own`) by its candidates' planes
/// ([`CellSource::plane_cut`]): the boundary lies on them, between regions of the cell
/// that differ, so when every region on either side of every exact plane piece is
/// inside, the cell holds none (a point on a piece is then a limit of inside points on
/// both sides).
pub fn planes_clear<S: CellSource>(src: &S, cell: &Aabb, own: &[u32]) -> bool {
    let Some(pieces) = src.plane_cut(own).and_then(|cut| cut.pieces(cell)) else {
        return false;
    };
    pieces.iter().all(|p| p.deviation == 0.0 && p.sides.iter().all(|&q| src.cell_contains(own, q)))
}

impl CellSource for crate::minkowski::PolytopeSet {
    fn root_records(&self) -> Vec<u32> {
        let mut root = Vec::new();
        for (i, p) in self.polys.iter().enumerate() {
            root.push(i as u32);
            root.push(p.normals.len() as u32);
            root.extend(0..p.normals.len() as u32);
        }
        root
    }

    fn classify(&self, cell: &Aabb, cand: &[u32], _finest: bool, out: &mut Vec<u32>) -> Label {
        classify_cell(&self.polys, cell, cand, out)
    }

    fn cell_contains(&self, cand: &[u32], p: Vec3) -> bool {
        cell_contains(&self.polys, CandIter { data: cand }, p)
    }

    fn boundary_intervals(&self, cand: &[u32], a: Vec3, b: Vec3, out: &mut Vec<(f64, f64)>) {
        // the union's boundary lies in its pieces, which are solid: the clips are both
        out.clear();
        for (prim, planes) in (CandIter { data: cand }) {
            let poly = &self.polys[prim];
            let it = planes.iter().map(|&k| (poly.normals[k as usize], poly.offsets[k as usize]));
            if let Some(t) = crate::polytope::clip_planes(it, a, b) {
                out.push(t);
            }
        }
        merge_sorted(out);
    }

    fn solid_intervals(&self, _a: Vec3, _b: Vec3, _sa: bool, _sb: bool, bnd: &[(f64, f64)], out: &mut Vec<(f64, f64)>) {
        out.clear();
        out.extend_from_slice(bnd);
    }

    /// The union's boundary in a cell lies on the planes its primitives kept (the others
    /// do not cut it): resolved when those are at most three distinct planes.
    fn plane_cut(&self, own: &[u32]) -> Option<Cut> {
        let mut cut = Cut::new();
        let tol = 1e-12 * self.aabb.min.abs().max(self.aabb.max.abs()).max_element().max(1e-300);
        for (prim, planes) in (CandIter { data: own }) {
            let poly = &self.polys[prim];
            for &k in planes {
                if !cut.add(poly.normals[k as usize], poly.offsets[k as usize], tol) {
                    return None;
                }
            }
        }
        Some(cut)
    }
}

/// Sort `iv` and merge overlapping (or touching within 1e-12) intervals in place.
pub fn merge_sorted(iv: &mut Vec<(f64, f64)>) {
    iv.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    let mut m = 0usize;
    for i in 0..iv.len() {
        let (a, b) = iv[i];
        if m > 0 && a <= iv[m - 1].1 + 1e-12 {
            iv[m - 1].1 = iv[m - 1].1.max(b);
        } else {
            iv[m] = (a, b);
            m += 1;
        }
    }
    iv.truncate(m);
}

/// Cell labels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Label {
    /// Meets no primitive: exactly free.
    Empty = 0,
    /// Inside one primitive: exactly blocked.
    Full = 1,
    /// Meets a primitive boundary (conservatively); at the finest level, or above it when
    /// resolved by planes ([`Octree::build_resolving_planes`]).
    Mixed = 2,
}

/// A leaf of the octree.
#[derive(Clone, Copy, Debug)]
pub struct Leaf {
    /// Lower corner in finest-lattice units.
    pub ijk: [u32; 3],
    /// Size is `2^level` finest cells (0 = finest).
    pub level: u8,
    /// Label.
    pub label: Label,
    /// Start of this leaf's candidate list in [`Octree::cands`] (MIXED leaves only).
    pub cand_start: u32,
    /// Length of that list (0 unless MIXED).
    pub cand_len: u32,
    /// The source's answer at the corner of the leaf that its parent's centre is, when the
    /// build knew it ([`Octree::known_corner`]): regions of the cell take it from there
    /// when no candidate lies between.
    pub corner_sign: Option<bool>,
}

/// The built octree: leaves in depth-first order and the candidate arena.
#[derive(Clone, Debug)]
pub struct Octree {
    /// Position of lattice point (0, 0, 0).
    pub origin: Vec3,
    /// Finest cell size.
    pub h: f64,
    /// Root level (root cell is `2^depth` finest cells wide).
    pub depth: u8,
    /// All leaves.
    pub leaves: Vec<Leaf>,
    /// Candidate arena: for each MIXED leaf, records `[prim, k, plane_1 .. plane_k]`.
    pub cands: Vec<u32>,
    /// Built by [`Octree::build_resolving_planes`]: the boxes where cells are sampled all the
    /// same (elsewhere MIXED leaves the source resolves by planes are exact, at any level,
    /// and their surfaces are in the [`ResolvedCells`] it was given);
    /// `None` for [`Octree::build`].
    pub planar: Option<Vec<Aabb>>,
}

/// Counts of leaves by level (index = level) and label (index = `Label as usize`).
pub type LevelCounts = Vec<[usize; 3]>;

struct Ctx<'a> {
    src: &'a dyn CellSource,
    origin: Vec3,
    h: f64,
    budget: usize,
    max_words: usize,
    /// Stop at MIXED cells the source resolves by planes ([`CellSource::plane_cut`]),
    /// except those meeting one of these boxes; their surfaces are kept in the cache for
    /// the extraction.
    planar: Option<(&'a [Aabb], &'a ResolvedCells)>,
    count: AtomicUsize,
    words: AtomicUsize,
    abort: AtomicBool,
    /// Whether the time limit ([`crate::deadline`]) stopped the build.
    timed_out: AtomicBool,
}

type Out = (Vec<Leaf>, Vec<u32>);

/// Whether the MIXED cell `cell` with records `own` is resolved by planes: outside the
/// `sampled` boxes, and its surface exact by the planes of its candidates
/// ([`resolve_cell`], kept in `resolved` for the extraction, which then need not cut the
/// cell again).
pub fn resolvable<S: CellSource + ?Sized>(src: &S, (sampled, resolved): (&[Aabb], &ResolvedCells), cell: &Aabb, own: &[u32], known: Option<(Vec3, bool)>) -> bool {
    if sampled.iter().any(|b| b.overlaps(cell)) || src.plane_cut(own).is_none() {
        return false;
    }
    let key = cell_key(cell, own, 0);
    if let Some(known) = resolved.resolves(&key) {
        return known;
    }
    let surface = resolve_cell(src, cell, own, 0, known);
    let found = surface.is_some();
    resolved.insert(key, surface);
    found
}

impl Octree {
    /// Build the octree over `source` covering `region` (grown by two cells and shifted off
    /// the lattice), with finest cell size `h` and at most `max_cells` leaves.
    ///
    /// # Errors
    /// [`CoreError::InvalidParameter`] for a non-positive or non-finite `h`,
    /// [`CoreError::ResourceLimit`] when the lattice or the leaf count would exceed the limits,
    /// [`CoreError::RecordLimit`] when the candidate records would pass [`record_budget`],
    /// [`CoreError::TimeLimit`] when the time limit ([`crate::deadline`]) passed.
    pub fn build<S: CellSource>(source: &S, region: &Aabb, h: f64, max_cells: usize) -> CoreResult<Octree> {
        Self::build_within(source, region, h, max_cells, record_budget())
    }

    /// [`Octree::build`] with at most `max_words` candidate-record words.
    pub(crate) fn build_within<S: CellSource>(source: &S, region: &Aabb, h: f64, max_cells: usize, max_words: usize) -> CoreResult<Octree> {
        Self::build_with(source, region, h, max_cells, max_words, None)
    }

    /// [`Octree::build`] that keeps MIXED cells the source resolves by planes
    /// ([`CellSource::plane_cut`]) as leaves at their size: such leaves are MIXED above
    /// the finest level. Cells meeting a box of `sampled` are split as usual (where joining their polygons
    /// to the band failed before). The surfaces of the cells it resolves go into `resolved`
    /// (cells met there before take what they gave), so the extraction does not cut them again.
    ///
    /// # Errors
    /// As [`Octree::build`] (the candidate records within [`record_budget`] too).
    pub fn build_resolving_planes<S: CellSource>(source: &S, region: &Aabb, h: f64, max_cells: usize, sampled: &[Aabb], resolved: &ResolvedCells) -> CoreResult<Octree> {
        Self::build_with(source, region, h, max_cells, record_budget(), Some((sampled, resolved)))
    }

    fn build_with<S: CellSource>(source: &S, region: &Aabb, h: f64, max_cells: usize, max_words: usize, planar: Option<(&[Aabb], &ResolvedCells)>) -> CoreResult<Octree> {
        if h <= 0.0 || !h.is_finite() {
            return Err(CoreError::InvalidParameter { name: "cell size".into(), value: h, detail: "must be positive and finite".into() });
        }
        let origin = region.min - Vec3::splat((2.0 + LATTICE_SHIFT) * h);
        let span = region.extent().max_element() + (4.0 + 2.0 * LATTICE_SHIFT) * h;
        let n = (span / h).ceil().max(1.0);
        let depth = n.log2().ceil().max(0.0) as u32;
        if depth > MAX_DEPTH {
            return Err(CoreError::ResourceLimit {
                budget: max_cells,
                cell_size: h,
                detail: format!("the region is {n:.3e} cells wide; the lattice addresses at most 2^{MAX_DEPTH}"),
            });
        }
        let ctx = Ctx {
            src: source,
            origin,
            h,
            budget: max_cells,
            max_words,
            planar,
            count: AtomicUsize::new(0),
            words: AtomicUsize::new(0),
            abort: AtomicBool::new(false),
            timed_out: AtomicBool::new(false),
        };
        let root = source.root_records();
        let (leaves, cands) = ctx.node([0, 0, 0], depth as u8, &root, None);
        if ctx.words.load(Ordering::Relaxed) > max_words {
            return Err(record_limit(max_words, h, "octree build"));
        }
        if ctx.timed_out.load(Ordering::Relaxed) {
            return Err(CoreError::TimeLimit { during: "octree build".into() });
        }
        if ctx.abort.load(Ordering::Relaxed) {
            return Err(CoreError::ResourceLimit { budget: max_cells, cell_size: h, detail: "octree leaves".into() });
        }
        Ok(Octree { origin, h, depth: depth as u8, leaves, cands, planar: planar.map(|(sampled, _)| sampled.to_vec()) })
    }

    /// The closed box of a leaf.
    pub fn cell_box(&self, leaf: &Leaf) -> Aabb {
        lattice_cell(self.origin, self.h, leaf.ijk, leaf.level)
    }

    /// The root cell's box.
    pub fn root_box(&self) -> Aabb {
        let s = (1u64 << self.depth) as f64 * self.h;
        Aabb::new(self.origin, self.origin + Vec3::splat(s))
    }

    /// Position of lattice point `(i, j, k)`.
    #[inline]
    pub fn lattice_point(&self, i: u32, j: u32, k: u32) -> Vec3 {
        lattice_at(self.origin, self.h, [i, j, k].map(u64::from))
    }

    /// The candidate records of a leaf of an octree over a [`PolytopeSet`]:
    /// `(primitive, planes that cut the cell)`.
    ///
    /// [`PolytopeSet`]: crate::minkowski::PolytopeSet
    pub fn candidates<'a>(&'a self, leaf: &Leaf) -> CandIter<'a> {
        CandIter { data: self.records(leaf) }
    }

    /// The raw candidate records of a leaf (see [`CellSource`]).
    pub fn records<'a>(&'a self, leaf: &Leaf) -> &'a [u32] {
        let s = leaf.cand_start as usize;
        &self.cands[s..s + leaf.cand_len as usize]
    }

    /// The corner of `leaf` that its parent's centre is, and the source's answer there,
    /// when the build knew it ([`Leaf::corner_sign`]).
    pub fn known_corner(&self, leaf: &Leaf) -> Option<(Vec3, bool)> {
        let inside = leaf.corner_sign?;
        let parent = leaf.ijk.map(|i| i & !((2u32 << leaf.level) - 1));
        Some((lattice_centre(self.origin, self.h, parent, leaf.level + 1), inside))
    }

    /// Leaves per level and label.
    pub fn level_counts(&self) -> LevelCounts {
        let mut c = vec![[0usize; 3]; self.depth as usize + 1];
        for l in &self.leaves {
            c[l.level as usize][l.label as usize] += 1;
        }
        c
    }
}

/// Iterator over `(primitive, planes)` records of a candidate list.
pub struct CandIter<'a> {
    pub(crate) data: &'a [u32],
}

impl<'a> Iterator for CandIter<'a> {
    type Item = (usize, &'a [u32]);
    fn next(&mut self) -> Option<Self::Item> {
        if self.data.len() < 2 {
            return None;
        }
        let (p, k) = (self.data[0] as usize, self.data[1] as usize);
        let planes = &self.data[2..2 + k];
        self.data = &self.data[2 + k..];
        Some((p, planes))
    }
}

/// Whether `p` (inside a cell) lies in the union, given that cell's candidate records.
#[inline]
pub fn cell_contains(polys: &[ConvexPolytope], cands: CandIter<'_>, p: Vec3) -> bool {
    for (prim, planes) in cands {
        let poly = &polys[prim];
        if planes.iter().all(|&k| poly.normals[k as usize].dot(p) <= poly.offsets[k as usize]) {
            return true;
        }
    }
    false
}

/// Filter the candidate records `cand` (`[prim, k, plane_1 .. plane_k]`, see
/// [`Octree::cands`]) against `cell` into `out` and return the cell's label: a primitive
/// goes when one of its planes separates the cell; a plane that no longer cuts the cell is
/// dropped; a primitive with no plane left contains the cell, which is then FULL; a cell no
/// primitive meets is EMPTY.
pub(crate) fn classify_cell(polys: &[ConvexPolytope], cell: &Aabb, cand: &[u32], out: &mut Vec<u32>) -> Label {
    let (c, hh) = (cell.center(), cell.half());
    let mut i = 0;
    while i < cand.len() {
        let prim = cand[i] as usize;
        let k = cand[i + 1] as usize;
        let planes = &cand[i + 2..i + 2 + k];
        i += 2 + k;
        let poly = &polys[prim];
        if !poly.aabb.overlaps(cell) {
            continue;
        }
        let mark = out.len();
        out.push(prim as u32);
        out.push(0);
        let mut separated = false;
        for &pl in planes {
            let n = poly.normals[pl as usize];
            let s = n.dot(c) - poly.offsets[pl as usize];
            let r = n.abs().dot(hh);
            if s - r > 0.0 {
                separated = true;
                break;
            }
            if s + r > 0.0 {
                out.push(pl);
            }
        }
        if separated {
            out.truncate(mark);
            continue;
        }
        let kept = out.len() - mark - 2;
        if kept == 0 {
            out.clear();
            return Label::Full;
        }
        out[mark + 1] = kept as u32;
    }
    if out.is_empty() {
        Label::Empty
    } else {
        Label::Mixed
    }
}

/// The closed box of the cell with lower lattice corner `ijk` and size `2^level` finest
/// cells, on the lattice with point `(0, 0, 0)` at `origin` and spacing `h`.
/// Its corners are lattice points computed as [`lattice_at`] does, so a corner shared by
/// cells of different sizes is one point.
#[inline]
pub(crate) fn lattice_cell(origin: Vec3, h: f64, ijk: [u32; 3], level: u8) -> Aabb {
    let size = 1u64 << level;
    Aabb::new(lattice_at(origin, h, ijk.map(u64::from)), lattice_at(origin, h, ijk.map(|i| u64::from(i) + size)))
}

/// The centre of the cell at `ijk` of `level` above the finest: the lattice point its
/// children share.
#[inline]
pub(crate) fn lattice_centre(origin: Vec3, h: f64, ijk: [u32; 3], level: u8) -> Vec3 {
    let half = 1u64 << (level - 1);
    lattice_at(origin, h, ijk.map(|i| u64::from(i) + half))
}

/// The position of lattice point `ijk` (every corner of every cell is computed this way).
#[inline]
pub(crate) fn lattice_at(origin: Vec3, h: f64, ijk: [u64; 3]) -> Vec3 {
    origin + Vec3::new(ijk[0] as f64, ijk[1] as f64, ijk[2] as f64) * h
}

impl Ctx<'_> {
    fn cell(&self, ijk: [u32; 3], level: u8) -> Aabb {
        lattice_cell(self.origin, self.h, ijk, level)
    }

    /// Filter `cand` against `cell` into `out`; the cell's label.
    fn classify(&self, cell: &Aabb, cand: &[u32], finest: bool, known: Option<(Vec3, bool)>, out: &mut Vec<u32>) -> Label {
        out.clear();
        self.src.classify_near(cell, cand, finest, known, out)
    }

    /// Whether a MIXED cell above the finest level stays a leaf: resolved by planes.
    fn resolved(&self, cell: &Aabb, own: &[u32], known: Option<(Vec3, bool)>) -> bool {
        self.planar.is_some_and(|planar| resolvable(self.src, planar, cell, own, known))
    }

    fn leaf(&self, ijk: [u32; 3], level: u8, label: Label, cand_len: usize) -> Leaf {
        if self.count.fetch_add(1, Ordering::Relaxed) >= self.budget {
            self.abort.store(true, Ordering::Relaxed);
        }
        if crate::deadline::passed() {
            self.timed_out.store(true, Ordering::Relaxed);
            self.abort.store(true, Ordering::Relaxed);
        }
        Leaf { ijk, level, label, cand_start: 0, cand_len: cand_len as u32, corner_sign: None }
    }

    fn node(&self, ijk: [u32; 3], level: u8, cand: &[u32], known: Option<(Vec3, bool)>) -> Out {
        let mut out = (Vec::new(), Vec::new());
        if level >= 4 {
            let mut own = Vec::with_capacity(cand.len());
            let cell = self.cell(ijk, level);
            let label = self.classify(&cell, cand, level == 0, known, &mut own);
            if label != Label::Mixed || level == 0 || self.resolved(&cell, &own, known) {
                self.push_leaf(&mut out, ijk, level, label, &own, known);
                return out;
            }
            let centre = lattice_centre(self.origin, self.h, ijk, level);
            let mine = self.src.center_sign(centre, cand, &own, known).map(|s| (centre, s));
            let parts: Vec<Out> = (0..8u32)
                .into_par_iter()
                .map(|c| {
                    if self.abort.load(Ordering::Relaxed) {
                        return (Vec::new(), Vec::new());
                    }
                    self.node(child(ijk, level, c), level - 1, &own, mine)
                })
                .collect();
            for (leaves, cands) in parts {
                let off = out.1.len() as u32;
                out.0.extend(leaves.into_iter().map(|mut l| {
                    l.cand_start += off;
                    l
                }));
                out.1.extend(cands);
            }
        } else {
            self.node_seq(ijk, level, cand, known, &mut out);
        }
        out
    }

    fn node_seq(&self, ijk: [u32; 3], level: u8, cand: &[u32], known: Option<(Vec3, bool)>, out: &mut Out) {
        if self.abort.load(Ordering::Relaxed) {
            return;
        }
        let mut own = Vec::with_capacity(cand.len());
        let cell = self.cell(ijk, level);
        let label = self.classify(&cell, cand, level == 0, known, &mut own);
        if label != Label::Mixed || level == 0 || self.resolved(&cell, &own, known) {
            self.push_leaf(out, ijk, level, label, &own, known);
            return;
        }
        let centre = lattice_centre(self.origin, self.h, ijk, level);
        let mine = self.src.center_sign(centre, cand, &own, known).map(|s| (centre, s));
        for c in 0..8u32 {
            self.node_seq(child(ijk, level, c), level - 1, &own, mine, out);
        }
    }

    /// `known`: the parent's centre and its answer (a corner of this leaf), if any.
    fn push_leaf(&self, out: &mut Out, ijk: [u32; 3], level: u8, label: Label, own: &[u32], known: Option<(Vec3, bool)>) {
        let keep = if label == Label::Mixed { own.len() } else { 0 };
        let mut leaf = self.leaf(ijk, level, label, keep);
        leaf.cand_start = out.1.len() as u32;
        leaf.corner_sign = known.map(|(_, inside)| inside);
        if keep > 0 {
            if self.words.fetch_add(keep, Ordering::Relaxed) + keep > self.max_words {
                self.abort.store(true, Ordering::Relaxed);
                return;
            }
            out.1.extend_from_slice(own);
        }
        out.0.push(leaf);
    }
}

/// The error for an octree whose candidate records would pass its budget of `max_words`.
pub(crate) fn record_limit(max_words: usize, h: f64, during: &str) -> CoreError {
    CoreError::RecordLimit { gib: (max_words * std::mem::size_of::<u32>()) as f64 / (1u64 << 30) as f64, cell_size: h, detail: during.into() }
}

#[inline]
fn child(ijk: [u32; 3], level: u8, c: u32) -> [u32; 3] {
    let half = 1u32 << (level - 1);
    [ijk[0] + (c & 1) * half, ijk[1] + ((c >> 1) & 1) * half, ijk[2] + ((c >> 2) & 1) * half]
}
