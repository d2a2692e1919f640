//! A closed, manifold, outward-oriented surface of the union over the octree's band.
//!
//! Marching tetrahedra over the finest MIXED cells, each split into the six Kuhn tetrahedra
//! around its main diagonal (consistent across neighbouring cells, so no cracks). Signs at
//! lattice points are exact point-in-union tests with the cell's culled planes, one per set
//! of points joined by edges the boundary cannot cross (the rest take its sign); the vertex
//! on a sign-changing edge is the exact crossing, found by clipping the edge against the
//! cell's primitives (not interpolated). The same clipping finds *complex edges* — ones the
//! boundary crosses more than once, or crosses twice with no sign change (thin slots,
//! needles) — where the sampling is too coarse for the two-sided bound, so the caller can
//! refine. A *silent* cell (no sign change, no complex edge) may still hold boundary that
//! slips between its edges (a needle-thin void); the source clears it or it counts, with the
//! unresolved cells, in what the bound must cover ([`loose_reach`]). Triangle orientation comes from integer determinants on the lattice, never from
//! rounded geometry, so the mesh is consistently oriented.
//!
//! Cells the source resolved by a few planes (at most [`planar::MAX_PLANES`])
//! ([`planar`]) give their exact polygons instead, joined to the sampled band ([`stitch`]).
//!
//! Entry point: [`extract`].

mod folds;
pub mod planar;
mod reach;
pub mod regions;
mod resolve;
#[cfg(test)]
mod resolve_tests;
pub mod sag;
mod simplify;
pub mod stitch;
#[cfg(test)]
mod surface_tests;

pub use reach::loose_reach;
pub use resolve::{resolve_cell, CellSurface};
pub use simplify::merge_coplanar;

use crate::math::{Aabb, Vec3};
use crate::octree::{CellSource, Label, Octree};
use crate::util::{FastMap, UnionFind};
use rayon::prelude::*;
use std::sync::{Mutex, OnceLock};

/// Vertices are kept this fraction of an edge away from lattice points, so that no two
/// vertices coincide (a boundary exactly through a lattice point would otherwise give
/// zero-area triangles).
pub const EDGE_CLAMP: f64 = 1e-4;

struct EdgeInfo {
    t: Option<f64>,
    gap: bool,
    sliver: bool,
    inconsistent: bool,
}

/// The extracted surface and what was seen on the way.
#[derive(Clone, Debug, Default)]
pub struct Surface {
    /// Vertex positions.
    pub vertices: Vec<Vec3>,
    /// Triangles, outward winding.
    pub faces: Vec<[u32; 3]>,
    /// Finest MIXED cells visited.
    pub band_cells: usize,
    /// Distinct lattice points evaluated.
    pub lattice_points: usize,
    /// Point queries made: one per set of lattice points joined by edges the boundary
    /// cannot cross (the others take that point's sign).
    pub point_queries: usize,
    /// Distinct tetrahedron edges clipped.
    pub edges: usize,
    /// Edges the boundary crosses more than once or without a sign change.
    pub complex_edges: usize,
    /// Cells whose corners all have one sign although solid (a sliver) or free space (a
    /// gap) crosses one of their edges: the samples do not see that piece of boundary. This
    /// costs accuracy (the bound takes the cell's reach, [`loose_reach`]; next to a cell
    /// with a sign change at most `2 sqrt(3) h`), not closedness.
    pub unresolved_cells: usize,
    /// Silent cells the source could not clear ([`CellSource::misses_boundary`]): no sign
    /// change and no edge the boundary crosses, yet boundary candidates meet them, so a
    /// sliver or void thinner than the cell may lie between their edges unseen.
    pub silent_cells: usize,
    /// Unresolved cells with no 26-neighbour that has a sign change: a thin feature or
    /// passage there may be lost, and the boundary in them is only as near the surface as
    /// the cells are, so the caller bounds that ([`loose_reach`]) or refines.
    pub complex_cells: usize,
    /// Every unresolved or uncleared silent cell, and whether a 26-neighbour has a sign
    /// change (the surface then passes within the two cells' joint diagonal): what the
    /// bound must cover beyond the grid's ([`loose_reach`]).
    pub loose_at: Vec<(Aabb, bool)>,
    /// Edges whose clipped crossings disagreed with the lattice signs (rounding); should be 0.
    pub inconsistent_edges: usize,
    /// MIXED cells above the finest level, resolved by planes: their surface is exact.
    pub planar_cells: usize,
    /// Exact polygons those cells gave.
    pub planar_pieces: usize,
    /// How the pieces' planes were triangulated: merged into regions, or fanned piece by
    /// piece ([`regions`]).
    pub regions: regions::RegionStats,
    /// How far the true boundary may lie from those polygons: 0 where they are exact, the
    /// gap of nearly coincident facet planes taken as one where there were such, or how far
    /// the fill of a small hole closed where they met may lie from it (its diameter and
    /// its vertices' own distance, [`Surface::loops_closed`]).
    pub planar_deviation: f64,
    /// Edges left open (or used twice), or vertices pinched, where those polygons met the
    /// band: 0 for a closed manifold surface (the caller samples there instead when not).
    pub open_edges: usize,
    /// The boxes of those edges and vertices, then of the complex cells (at most
    /// [`MAX_OPEN_REPORTED`]).
    pub open_at: Vec<Aabb>,
    /// Holes narrower than the grid's bound where polygons met at a crevice or needle
    /// thinner than the weld tolerance, closed by a fan ([`stitch::close_small_loops`]; their
    /// diameter counts in `planar_deviation`).
    pub loops_closed: usize,
    /// Copies of vertices made where sheets of the joined surface touch (along a hair-thin
    /// edge or at a point), one per sheet ([`stitch::unzip_touching_sheets`]), and vertices
    /// a reader welding by position would merge that were collapsed or moved apart
    /// ([`stitch::part_coincident_vertices`]).
    pub sheets_unzipped: usize,
    /// How far those vertices moved (so that a reader welding vertices by position keeps
    /// them apart); the bound adds it.
    pub sheets_apart: f64,
    /// Closed slivers (two layers folded onto each other, under two cells across) removed
    /// after the join ([`stitch::drop_slivers`]).
    pub slivers_dropped: usize,
    /// Of those, how many lay apart from the rest (farther than two cells from its
    /// vertices): parts of a sheet thinner than the weld, whose reach the bound takes
    /// (they are in [`Surface::loose_at`]).
    pub slivers_apart: usize,
}

#[inline]
fn key(i: u32, j: u32, k: u32) -> u64 {
    (i as u64) | ((j as u64) << 21) | ((k as u64) << 42)
}

#[inline]
fn unkey(q: u64) -> (u32, u32, u32) {
    ((q & 0x1F_FFFF) as u32, ((q >> 21) & 0x1F_FFFF) as u32, ((q >> 42) & 0x1F_FFFF) as u32)
}

#[inline]
fn corner(c: usize) -> [i64; 3] {
    [(c & 1) as i64, ((c >> 1) & 1) as i64, ((c >> 2) & 1) as i64]
}

/// The six Kuhn tetrahedra of the unit cube, as corner indices (bit 0 = x, 1 = y, 2 = z).
fn tets() -> [[usize; 4]; 6] {
    let perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let mut t = [[0usize; 4]; 6];
    for (n, p) in perms.iter().enumerate() {
        let v1 = 1 << p[0];
        let v2 = v1 | (1 << p[1]);
        t[n] = [0, v1, v2, 7];
    }
    t
}

/// The 19 distinct edges of the Kuhn split (12 cube edges, 6 face diagonals, 1 main
/// diagonal), as sorted corner pairs.
fn cell_edges() -> &'static [(usize, usize)] {
    static E: OnceLock<Vec<(usize, usize)>> = OnceLock::new();
    E.get_or_init(|| {
        let mut e = Vec::new();
        for t in tets() {
            for a in 0..4 {
                for b in a + 1..4 {
                    let (x, y) = (t[a].min(t[b]), t[a].max(t[b]));
                    if !e.contains(&(x, y)) {
                        e.push((x, y));
                    }
                }
            }
        }
        e.sort_unstable();
        e
    })
}

fn det3(a: [i64; 3], b: [i64; 3], c: [i64; 3]) -> i64 {
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
}

fn sub(a: [i64; 3], b: [i64; 3]) -> [i64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Triangles (as triples of corner-pair edges) for tetrahedron `t` with inside mask
/// `mask` (bit `n` = vertex `t[n]` inside), oriented to face from inside to outside.
type TriEdges = [(usize, usize); 3];

fn tet_case(t: [usize; 4], mask: u8) -> Vec<TriEdges> {
    let inside: Vec<usize> = (0..4).filter(|&n| mask >> n & 1 == 1).map(|n| t[n]).collect();
    let outside: Vec<usize> = (0..4).filter(|&n| mask >> n & 1 == 0).map(|n| t[n]).collect();
    let e = |a: usize, b: usize| (a.min(b), a.max(b));
    match (inside.len(), outside.len()) {
        (1, 3) | (3, 1) => {
            let (apex, others, away) = if inside.len() == 1 { (inside[0], outside, true) } else { (outside[0], inside, false) };
            let (j, k, l) = (others[0], others[1], others[2]);
            let v = corner(apex);
            let d = det3(sub(corner(j), v), sub(corner(k), v), sub(corner(l), v));
            // d > 0: (j, k, l) winds with its normal away from the apex.
            let keep = (d > 0) == away;
            if keep {
                vec![[e(apex, j), e(apex, k), e(apex, l)]]
            } else {
                vec![[e(apex, j), e(apex, l), e(apex, k)]]
            }
        }
        (2, 2) => {
            let (a, b, c, d) = (inside[0], inside[1], outside[0], outside[1]);
            let mut q = [e(a, c), e(a, d), e(b, d), e(b, c)];
            // normal of the midpoint parallelogram ∝ (d − c) × (b − a); it must point from
            // {a, b} towards {c, d}
            let (ca, cb, cc, cd) = (corner(a), corner(b), corner(c), corner(d));
            let u = sub(cd, cc);
            let w = sub(cb, ca);
            let n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
            let g = [cc[0] + cd[0] - ca[0] - cb[0], cc[1] + cd[1] - ca[1] - cb[1], cc[2] + cd[2] - ca[2] - cb[2]];
            if n[0] * g[0] + n[1] * g[1] + n[2] * g[2] < 0 {
                q.reverse();
            }
            vec![[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
        }
        _ => Vec::new(),
    }
}

fn case_table() -> &'static Vec<Vec<Vec<TriEdges>>> {
    static T: OnceLock<Vec<Vec<Vec<TriEdges>>>> = OnceLock::new();
    T.get_or_init(|| tets().iter().map(|&t| (0..16u8).map(|m| tet_case(t, m)).collect()).collect())
}

/// Edges taken together in one parallel task when their intervals are gathered.
const EDGE_CHUNK: usize = 4096;

/// One parallel task's intervals and the count per edge.
type IntervalChunk = (Vec<(f64, f64)>, Vec<u32>);

/// Every edge's boundary intervals in one flat array (no allocation per edge): edge `n`'s
/// are `data[ends[n - 1]..ends[n]]`.
struct EdgeIntervals {
    data: Vec<(f64, f64)>,
    ends: Vec<usize>,
}

impl EdgeIntervals {
    /// Gather `fill(edge, out)` (which clears and fills `out`) over `edges`, in parallel chunks.
    fn collect<E: Sync>(edges: &[E], fill: impl Fn(&E, &mut Vec<(f64, f64)>) + Sync) -> EdgeIntervals {
        let chunks: Vec<IntervalChunk> = edges
            .par_chunks(EDGE_CHUNK)
            .map(|chunk| {
                let (mut data, mut lens, mut iv) = (Vec::new(), Vec::with_capacity(chunk.len()), Vec::new());
                for e in chunk {
                    fill(e, &mut iv);
                    data.extend_from_slice(&iv);
                    lens.push(iv.len() as u32);
                }
                (data, lens)
            })
            .collect();
        let mut out = EdgeIntervals { data: Vec::with_capacity(chunks.iter().map(|c| c.0.len()).sum()), ends: Vec::with_capacity(edges.len()) };
        for (data, lens) in chunks {
            out.data.extend_from_slice(&data);
            for l in lens {
                let end = out.ends.last().copied().unwrap_or(0) + l as usize;
                out.ends.push(end);
            }
        }
        out
    }

    /// The intervals of edge `n`.
    #[inline]
    fn of(&self, n: usize) -> &[(f64, f64)] {
        let start = if n == 0 { 0 } else { self.ends[n - 1] };
        &self.data[start..self.ends[n]]
    }
}

/// Extract the surface of the solid of `src` over the finest MIXED cells of `oct` (built
/// over `src`).
///
/// MIXED cells above the finest level (an octree from [`Octree::build_resolving_planes`])
/// give their exact polygons ([`planar`]), joined to the band's triangles ([`stitch`]).
///
/// `resolved` keeps each cell's plane resolution for the next extraction over the same
/// source (a rebuild sampling around other places, or a finer grid, meets most cells again).
pub fn extract<S: CellSource>(oct: &Octree, src: &S, resolved: &ResolvedCells) -> Surface {
    let planar = planar_polygons(oct, src, resolved);
    let mut s = sample_band(oct, src, &planar);
    if crate::deadline::cancelled() {
        return s; // dropped by the caller
    }
    s.planar_cells = planar.cells;
    s.planar_pieces = planar.polys.len();
    s.planar_deviation = planar.deviation;
    if !planar.polys.is_empty() {
        s.regions = stitch::join(&mut s, &planar.polys, &planar.planes, STITCH_TOL * oct.h, (oct.origin, oct.h));
        if crate::deadline::cancelled() {
            return s;
        }
        // a fill point is within its loop's diameter of a loop vertex, and that within the
        // weld and the polygons' deviation of the boundary (a band vertex is on it, unless
        // its edge's crossings were inconsistent: then within half the edge); holes up to
        // what the grid's bound leaves room for are closed, so it stays the grid's
        let off = STITCH_TOL * oct.h + s.planar_deviation + if s.inconsistent_edges > 0 { 0.5 * 3f64.sqrt() * oct.h } else { 0.0 };
        let closed = stitch::close_small_loops(&mut s, 3f64.sqrt() * oct.h - off);
        s.loops_closed = closed.loops;
        if closed.loops > 0 {
            s.planar_deviation = s.planar_deviation.max(closed.diameter + off);
        }
        // (regions of a plane facing opposite ways, and fans of loops of a sliver's
        // width, fold the surface back onto itself in their planes)
        s.regions.unfolded = stitch::unfold(&mut s, STITCH_TOL * oct.h, oct.h);
        let (mut open, mut pinched) = open_or_pinched(&s.faces);
        if !open.is_empty() || !pinched.is_empty() {
            let at = open.iter().flat_map(|&(a, b)| [a, b]).chain(pinched.iter().copied()).collect();
            s.sheets_unzipped = stitch::unzip_touching_sheets(&mut s, at, oct.h);
        }
        // (a sheet unzipped from the rest may be a sliver: a triangle and its reverse; a
        // sheet thinner than the weld, its sides welded, comes apart into slivers far from
        // the rest, which are loose cells: their reach is in the bound)
        let slivers = stitch::drop_slivers(&mut s, 2.0 * oct.h, 1e-4 * oct.h.powi(3));
        s.slivers_dropped = slivers.len();
        let apart = reach::apart_from(&s, &slivers, 2.0 * oct.h);
        s.slivers_apart = apart.len();
        // (each at least a cell across: the reach's search bins follow the first's size)
        s.loose_at.extend(apart.into_iter().map(|b| (b.inflated(0.5 * oct.h), false)));
        s.sheets_unzipped += stitch::part_coincident_vertices(&mut s, oct.h);
        if s.sheets_unzipped > 0 || s.slivers_dropped > 0 {
            (open, pinched) = open_or_pinched(&s.faces);
        }
        s.open_edges = open.len() + pinched.len();
        let at: Vec<Aabb> = open
            .iter()
            .map(|&(a, b)| Aabb::from_points(&[s.vertices[a as usize], s.vertices[b as usize]]))
            .chain(pinched.iter().map(|&v| Aabb::new(s.vertices[v as usize], s.vertices[v as usize])))
            .take(MAX_OPEN_REPORTED)
            .collect();
        s.open_at.extend(at);
    } else {
        // (a collapse or a move keeps the band closed and manifold)
        s.sheets_unzipped = stitch::part_coincident_vertices(&mut s, oct.h);
    }
    s
}

/// The open edges of `faces` ([`stitch::open_edges`]) and, when there are none, the pinched
/// vertices ([`stitch::pinched_vertices`]).
fn open_or_pinched(faces: &[[u32; 3]]) -> (Vec<(u32, u32)>, Vec<u32>) {
    let open = stitch::open_edges(faces);
    let pinched = if open.is_empty() { stitch::pinched_vertices(faces) } else { Vec::new() };
    (open, pinched)
}

/// Most open edges whose boxes [`Surface::open_at`] keeps.
pub const MAX_OPEN_REPORTED: usize = 10_000;

/// Welding and T-junction tolerance where plane-resolved cells meet the band, in finest
/// cells: above the band's vertex clamp off lattice points ([`EDGE_CLAMP`] of an edge of
/// at most `sqrt(3) h`), far below any feature the band resolves.
const STITCH_TOL: f64 = 4.0 * EDGE_CLAMP;

/// Plane-resolved cells with a surface, by `(level, lattice key of their lower corner)`.
type PlanarSet = crate::util::FastSet<(u8, u64)>;

/// The exact polygons of the MIXED cells above the finest level (outward, counter-clockwise),
/// the cells that have some, and how many such cells there are.
fn planar_polygons<S: CellSource>(oct: &Octree, src: &S, resolved: &ResolvedCells) -> PlanarPolygons {
    // above the finest level the octree kept only resolvable MIXED cells; at the finest
    // level, those outside the sampled boxes are tried here
    let sampled: &[Aabb] = match &oct.planar {
        Some(boxes) => boxes,
        None => return PlanarPolygons::default(),
    };
    let tried = |i: usize| {
        let l = &oct.leaves[i];
        l.label == Label::Mixed && (l.level > 0 || !sampled.iter().any(|b| b.overlaps(&oct.cell_box(l))))
    };
    let cells: Vec<usize> = (0..oct.leaves.len()).filter(|&i| tried(i)).collect();
    let per_cell: Vec<(usize, CellKey, Option<CellSurface>, bool)> = cells
        .par_iter()
        .map(|&li| {
            let leaf = &oct.leaves[li];
            // a finest cell is split below the lattice if need be; above, a cell the octree
            // kept as resolvable that is not after all leaves a hole the stitch check sees
            let sub_levels = if leaf.level == 0 { resolve::SUB_LEVELS } else { 0 };
            let (cell, recs) = (oct.cell_box(leaf), oct.records(leaf));
            let k = cell_key(&cell, recs, sub_levels);
            match resolved.get(&k) {
                Some(known) => (li, k, known, false),
                None => (li, k, resolve::resolve_cell(src, &cell, recs, sub_levels, oct.known_corner(leaf)), true),
            }
        })
        .collect();
    let mut out = PlanarPolygons { resolved: vec![false; oct.leaves.len()], ..Default::default() };
    for (li, k, cell, fresh) in per_cell {
        if fresh {
            resolved.insert(k, cell.clone());
        }
        let l = &oct.leaves[li];
        if cell.is_none() && l.level == 0 {
            continue; // sampled
        }
        out.resolved[li] = true;
        out.cells += 1;
        let cell = cell.unwrap_or_default();
        out.deviation = out.deviation.max(cell.deviation);
        if !cell.polys.is_empty() {
            let k = (l.level, key(l.ijk[0], l.ijk[1], l.ijk[2]));
            out.with_surface.insert(k);
            out.polys.extend(cell.polys);
            out.planes.extend(cell.planes);
        }
    }
    out
}

/// A cell's box (its corners' bits), a hash of its records and the levels it may be split.
pub type CellKey = ([u64; 6], u64, u32);

/// The key of `cell` with records `recs`, resolved splitting it up to `sub_levels` times.
pub fn cell_key(cell: &Aabb, recs: &[u32], sub_levels: u32) -> CellKey {
    use std::hash::{Hash, Hasher};
    let mut hasher = crate::util::KeyHasher::default();
    recs.hash(&mut hasher);
    let c = [cell.min.x, cell.min.y, cell.min.z, cell.max.x, cell.max.y, cell.max.z];
    (c.map(f64::to_bits), hasher.finish(), sub_levels)
}

/// Cells already resolved by planes over one source, and what they gave (`None`: not
/// resolvable), kept across the octree builds and extractions of one sum (the octree
/// resolves the cells it keeps as leaves; the extraction takes their surfaces from here).
#[derive(Default)]
pub struct ResolvedCells(Mutex<FastMap<CellKey, Option<CellSurface>>>);

impl ResolvedCells {
    /// What `key`'s cell gave, if it was resolved before.
    pub fn get(&self, key: &CellKey) -> Option<Option<CellSurface>> {
        self.lock().get(key).cloned()
    }

    /// Whether `key`'s cell was resolved, if it was tried before.
    pub fn resolves(&self, key: &CellKey) -> Option<bool> {
        self.lock().get(key).map(Option::is_some)
    }

    /// Keep what `key`'s cell gave.
    pub fn insert(&self, key: CellKey, surface: Option<CellSurface>) {
        self.lock().insert(key, surface);
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, FastMap<CellKey, Option<CellSurface>>> {
        // a panic elsewhere while holding the lock leaves the map as it was: still usable
        self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }
}

/// What the plane-resolved cells gave.
#[derive(Default)]
struct PlanarPolygons {
    /// Their exact polygons, outward.
    polys: Vec<Vec<Vec3>>,
    /// Per polygon, its outward plane.
    planes: Vec<regions::PlaneKey>,
    /// The cells with some.
    with_surface: PlanarSet,
    /// How many cells were resolved by planes.
    cells: usize,
    /// Per leaf, whether it was resolved by planes (empty: none was).
    resolved: Vec<bool>,
    /// How far the boundary may lie from their polygons (0: exact).
    deviation: f64,
}

/// Whether the finest cell at `(x, y, z)` lies in a plane-resolved cell with a surface.
fn in_planar(planar: &PlanarSet, x: u32, y: u32, z: u32, max_level: u8) -> bool {
    (0..=max_level).any(|lv| {
        let m = !((1u32 << lv) - 1);
        planar.contains(&(lv, key(x & m, y & m, z & m)))
    })
}

/// Marching tetrahedra over the finest MIXED cells (see the module docs); `planar`: the
/// plane-resolved cells with a surface, which count as neighbours with a sign change.
fn sample_band<S: CellSource>(oct: &Octree, src: &S, planar: &PlanarPolygons) -> Surface {
    let sampled = |i: usize| oct.leaves[i].label == Label::Mixed && oct.leaves[i].level == 0 && !planar.resolved.get(i).copied().unwrap_or(false);
    let band: Vec<usize> = (0..oct.leaves.len()).filter(|&i| sampled(i)).collect();
    let mut s = Surface { band_cells: band.len(), ..Default::default() };
    if band.is_empty() || crate::deadline::cancelled() {
        return s;
    }
    let leaf_corner_key = |li: usize, c: usize| -> u64 {
        let l = &oct.leaves[li];
        let o = corner(c);
        key(l.ijk[0] + o[0] as u32, l.ijk[1] + o[1] as u32, l.ijk[2] + o[2] as u32)
    };

    // 1. distinct lattice points with an owning leaf, and their signs
    let mut pts: Vec<(u64, u32)> = band.par_iter().flat_map_iter(|&li| (0..8).map(move |c| (leaf_corner_key(li, c), li as u32))).collect();
    pts.par_sort_unstable();
    pts.dedup_by_key(|p| p.0);
    let point_of = |q: u64| {
        let (i, j, k) = unkey(q);
        oct.lattice_point(i, j, k)
    };
    s.lattice_points = pts.len();

    // 2. edges: every Kuhn edge runs from a lower corner `lo` to `lo | m` for an axis mask
    // m in 1..=7, so edge (point index of lo) * 7 + (m - 1) names it without a search
    // corner point indices without searching: for a fixed corner offset, the corner keys of
    // the cells taken in order of their first corner increase, so one merge walk over the
    // sorted points finds them all
    let mut by_key: Vec<(u64, u32)> = band.iter().enumerate().map(|(n, &li)| (leaf_corner_key(li, 0), n as u32)).collect();
    by_key.par_sort_unstable();
    let columns: Vec<Vec<u32>> = (0..8usize)
        .into_par_iter()
        .map(|c| {
            let o = corner(c);
            let off = key(o[0] as u32, o[1] as u32, o[2] as u32);
            let mut col = vec![0u32; band.len()];
            let mut j = 0usize;
            for &(k0, n) in &by_key {
                let target = k0 + off; // no carries: coordinates stay below 2^21
                while pts[j].0 < target {
                    j += 1;
                }
                debug_assert_eq!(pts[j].0, target);
                col[n as usize] = j as u32;
            }
            col
        })
        .collect();
    let cell_points: Vec<[u32; 8]> = (0..band.len()).map(|n| std::array::from_fn(|c| columns[c][n])).collect();
    drop(columns);
    let edges_local = cell_edges();
    let edge_slot = |idx: &[u32; 8], a: usize, b: usize| -> usize { idx[a] as usize * 7 + (b ^ a) - 1 };
    // owner[slot] = (owning leaf, point index of the upper end)
    let mut owner = vec![(u32::MAX, 0u32); pts.len() * 7];
    for (n, idx) in cell_points.iter().enumerate() {
        for &(a, b) in edges_local {
            owner[edge_slot(idx, a, b)] = (band[n] as u32, idx[b]);
        }
    }
    let edges: Vec<(u64, u64, u32, usize, u32)> =
        owner.iter().enumerate().filter(|(_, o)| o.0 != u32::MAX).map(|(slot, &(o, pb))| (pts[slot / 7].0, pts[pb as usize].0, o, slot, pb)).collect();
    s.edges = edges.len();
    if crate::deadline::cancelled() {
        return s;
    }

    // where the boundary may cross each edge; an edge it cannot cross joins its ends' signs
    // (cancelled work skips the queries: its surface is dropped)
    let bnd = EdgeIntervals::collect(&edges, |&(ka, kb, li, _, _), iv| {
        if crate::deadline::cancelled() {
            iv.clear();
            return;
        }
        src.boundary_intervals(oct.records(&oct.leaves[li as usize]), point_of(ka), point_of(kb), iv);
    });

    // signs: one point query per set of lattice points joined by such edges
    if crate::deadline::cancelled() {
        return s;
    }
    let mut joined = UnionFind::new(pts.len());
    for (n, e) in edges.iter().enumerate() {
        if bnd.of(n).is_empty() {
            joined.union(e.3 / 7, e.4 as usize);
        }
    }
    let roots: Vec<u32> = (0..pts.len()).map(|i| joined.find(i) as u32).collect();
    let queried: Vec<(u32, bool)> = roots
        .par_iter()
        .enumerate()
        .filter(|(i, &r)| *i as u32 == r)
        .map(|(i, _)| {
            let (q, li) = pts[i];
            (i as u32, !crate::deadline::cancelled() && src.cell_contains(oct.records(&oct.leaves[li as usize]), point_of(q)))
        })
        .collect();
    s.point_queries = queried.len();
    let mut root_sign = vec![false; pts.len()];
    for (i, v) in queried {
        root_sign[i as usize] = v;
    }
    let inside: Vec<bool> = roots.iter().map(|&r| root_sign[r as usize]).collect();
    drop(root_sign);
    // per edge: the crossing (parameter from the lower key's end) when the signs differ, and
    // what else the clipped intervals show: a gap (free space strictly between two solid
    // intervals: a passage the samples may miss) or a sliver (solid strictly between the
    // ends: a thin feature or a clipped convex edge)
    let results: Vec<EdgeInfo> = edges
        .par_iter()
        .enumerate()
        .map_init(Vec::new, |merged: &mut Vec<(f64, f64)>, (n, &(ka, kb, _, slot, ib))| {
            let iv = bnd.of(n);
            let (pa, pb) = (point_of(ka), point_of(kb));
            let (sa, sb) = (inside[slot / 7], inside[ib as usize]);
            src.solid_intervals(pa, pb, sa, sb, iv, merged);
            let tiny = 1e-12;
            let gap = merged.len() >= 2;
            let sliver = merged.iter().any(|&(a, b)| a > tiny && b < 1.0 - tiny);
            if sa == sb {
                return EdgeInfo { t: None, gap, sliver, inconsistent: false };
            }
            let t = if sa {
                // inside at a: the interval starting at 0 ends at the crossing
                merged.first().filter(|iv| iv.0 <= tiny).map(|iv| iv.1)
            } else {
                merged.last().filter(|iv| iv.1 >= 1.0 - tiny).map(|iv| iv.0)
            };
            let inconsistent = t.is_none();
            let t = t.unwrap_or(0.5).clamp(EDGE_CLAMP, 1.0 - EDGE_CLAMP);
            EdgeInfo { t: Some(t), gap, sliver, inconsistent }
        })
        .collect();
    drop(bnd);

    // vertex ids for sign-changing edges, and edge info by slot
    let mut vid = vec![u32::MAX; owner.len()];
    let mut info_of = vec![u32::MAX; owner.len()];
    for (n, (e, r)) in edges.iter().zip(&results).enumerate() {
        info_of[e.3] = n as u32;
        if let Some(t) = r.t {
            vid[e.3] = s.vertices.len() as u32;
            let (pa, pb) = (point_of(e.0), point_of(e.1));
            s.vertices.push(pa + (pb - pa) * t);
        }
        s.complex_edges += (r.gap || r.sliver) as usize;
        s.inconsistent_edges += r.inconsistent as usize;
    }

    // 3. triangles per cell, and whether the cell resolves the boundary
    let table = case_table();
    let tet_list = tets();
    // per cell: (has a sign change, unresolved: silent but solid or free space on an edge)
    let flags: Vec<(bool, bool)> = cell_points
        .par_iter()
        .map(|idx| {
            let signs: [bool; 8] = std::array::from_fn(|c| inside[idx[c] as usize]);
            let sign_change = signs.iter().any(|&x| x != signs[0]);
            let unresolved = !sign_change
                && edges_local.iter().any(|&(a, b)| {
                    let r = &results[info_of[edge_slot(idx, a, b)] as usize];
                    r.gap || r.sliver
                });
            (sign_change, unresolved)
        })
        .collect();
    let faces: Vec<[u32; 3]> = cell_points
        .par_iter()
        .zip(&flags)
        .filter(|(_, f)| f.0)
        .flat_map_iter(|(idx, _)| {
            let signs: [bool; 8] = std::array::from_fn(|c| inside[idx[c] as usize]);
            let vid = &vid;
            tet_list.iter().enumerate().flat_map(move |(tn, t)| {
                let mask = (0..4).fold(0u8, |m, n| m | ((signs[t[n]] as u8) << n));
                table[tn][mask as usize].iter().map(move |tri| {
                    let mut f = [0u32; 3];
                    for (m, &(a, b)) in tri.iter().enumerate() {
                        f[m] = vid[edge_slot(idx, a, b)];
                    }
                    f
                })
            })
        })
        .collect();
    s.faces = faces;
    // an unresolved cell is complex unless a 26-neighbour has a sign change: then the
    // surface passes within the two cells' joint diagonal (2 sqrt(3) h) of its points
    let mut resolved: Vec<u64> = band.iter().zip(&flags).filter(|(_, c)| c.0).map(|(&li, _)| leaf_corner_key(li, 0)).collect();
    resolved.sort_unstable();
    // silent cells (no sign change, no edge the boundary crosses) the source cannot clear
    let unproved: Vec<bool> = band
        .par_iter()
        .zip(&flags)
        .zip(&cell_points)
        .map(|((&li, &(sign_change, unresolved)), idx)| {
            let l = &oct.leaves[li];
            !sign_change && !unresolved && !crate::deadline::cancelled() && !src.misses_boundary(&oct.cell_box(l), oct.records(l), inside[idx[0] as usize])
        })
        .collect();
    for ((&li, &(_, unresolved)), &silent) in band.iter().zip(&flags).zip(&unproved) {
        if !unresolved && !silent {
            continue;
        }
        s.unresolved_cells += unresolved as usize;
        s.silent_cells += silent as usize;
        let l = &oct.leaves[li];
        let mut near = false;
        'n: for dz in -1i64..=1 {
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let (x, y, z) = (l.ijk[0] as i64 + dx, l.ijk[1] as i64 + dy, l.ijk[2] as i64 + dz);
                    if x < 0 || y < 0 || z < 0 {
                        continue;
                    }
                    if resolved.binary_search(&key(x as u32, y as u32, z as u32)).is_ok() || in_planar(&planar.with_surface, x as u32, y as u32, z as u32, oct.depth) {
                        near = true;
                        break 'n;
                    }
                }
            }
        }
        s.loose_at.push((oct.cell_box(l), near));
        if unresolved && !near {
            s.complex_cells += 1;
            if s.open_at.len() < MAX_OPEN_REPORTED {
                s.open_at.push(oct.cell_box(l));
            }
        }
    }
    s
}
