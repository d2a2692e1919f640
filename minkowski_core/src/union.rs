//! The union-approximation driver: octree, surface, and refinement while complex cells
//! lie farther from the surface than the grid's bound allows.

use crate::error::{CoreError, CoreResult};
use crate::math::Aabb;
use crate::minkowski::PolytopeSet;
use crate::octree::{CellSource, Label, LevelCounts, Octree};
use crate::polytope::PLANE_TOL_REL;
use crate::surface::sag::{refine_sag, SagStats};
use crate::surface::{extract, loose_reach, merge_coplanar, ResolvedCells, Surface, EDGE_CLAMP, MAX_OPEN_REPORTED};
use std::time::Instant;

/// Parameters of [`approximate_union`].
#[derive(Clone, Debug)]
pub struct UnionParams {
    /// Target two-sided Hausdorff bound of the grid (absolute).
    pub eps: f64,
    /// Leaf budget of one octree.
    pub max_cells: usize,
    /// How many times the grid may be halved while complex cells lie too far from the
    /// surface ([`surface_error_bound`]).
    pub max_refinements: u32,
    /// Collapse interior vertices of planar patches ([`merge_coplanar`]): same surface,
    /// far fewer triangles on flat facets.
    pub simplify: bool,
    /// Keep cells the source resolves by a few planes (at most
    /// [`crate::surface::planar::MAX_PLANES`]) as exact polygons at their
    /// size ([`Octree::build_resolving_planes`]); the sampled band is left only where the
    /// boundary is not that simple (an exact edge running into the band is chamfered
    /// there, within its bound). Where the polygons and the band do not join into a
    /// closed manifold surface, or the band has complex cells, the grid is rebuilt
    /// sampling around those places while that leaves fewer of them (up to
    /// `MAX_JOIN_RETRIES` times per grid); then complex cells left in a closed join are
    /// bounded and refined as a sampled grid's, and an open join samples everywhere (at
    /// once when the boxes around the places would hold half the band that gives).
    pub planes: bool,
}

/// What [`approximate_union`] produced.
#[derive(Clone, Debug)]
pub struct UnionResult {
    /// The surface.
    pub surface: Surface,
    /// Finest cell size used.
    pub h: f64,
    /// Two-sided Hausdorff bound of the surface to the union's boundary that is proved for
    /// this surface: `grid_error_bound(h)`, and where the lattice may have missed boundary
    /// (loose cells) at least its reach ([`loose_reach`]).
    pub error_bound: f64,
    /// The part of the bound from cells where the lattice may have missed boundary (their
    /// [`loose_reach`], taken on the surface before simplification: it measures to vertices).
    pub missed_reach: f64,
    /// Grid halvings done.
    pub refinements: u32,
    /// Leaves per level and label of the final octree.
    pub level_counts: LevelCounts,
    /// Seconds building octrees (all rounds).
    pub seconds_octree: f64,
    /// Seconds extracting surfaces (all rounds).
    pub seconds_surface: f64,
    /// Seconds simplifying the final surface.
    pub seconds_simplify: f64,
    /// Triangles before simplification.
    pub triangles_extracted: usize,
    /// Open edges seen where plane-resolved cells met the band, over the rebuilds that then
    /// sampled around them (0: none).
    pub planes_fallback_edges: usize,
    /// What the refinement where the surface sags from the boundary did (for a source with
    /// boundary points, [`CellSource::boundary_point`]).
    pub sag: SagStats,
    /// Seconds of that refinement.
    pub seconds_sag: f64,
}

/// Rebuilds sampling around the edges where plane-resolved cells failed to join the band,
/// before sampling everywhere.
const MAX_JOIN_RETRIES: u32 = 3;

/// Finest band cells a box sampled around one bad place adds, about: the box reaches 4
/// cells past the place each way, and the band crosses its 9 × 9 × 9 cells in some 9 × 9.
const BAND_CELLS_PER_PLACE: usize = 81;

/// The finest cells the band would have if every MIXED leaf of `oct` were sampled, about:
/// a leaf `2^l` cells wide holds `4^l` of them (the boundary is a surface).
fn band_if_sampled(oct: &Octree) -> usize {
    oct.leaves.iter().filter(|l| l.label == Label::Mixed).map(|l| 1usize << (2 * l.level as u32)).sum()
}

/// Finest cell size whose grid bound is `eps`.
pub fn cell_size_for_eps(eps: f64) -> f64 {
    eps / (3f64.sqrt() * (1.0 + 2.0 * EDGE_CLAMP))
}

/// Two-sided bound of a surface extracted at cell size `h` with no unresolved cell: every
/// output point lies in a tetrahedron whose edge crossings are exact boundary points (≤ the
/// longest tetrahedron edge, `sqrt(3) h`, away), and every boundary point lies in a band
/// cell that the surface crosses (≤ the cell diagonal away); the clamp of vertices off
/// lattice points adds `2 · EDGE_CLAMP` of that. With unresolved cells (all next to a cell
/// the surface crosses) the bound is twice this.
pub fn grid_error_bound(h: f64) -> f64 {
    3f64.sqrt() * h * (1.0 + 2.0 * EDGE_CLAMP)
}

/// The bound that holds for `surface` extracted at cell size `h`: the grid's, the loose
/// cells' reach ([`loose_reach`]: how far boundary the lattice did not see may lie from the
/// surface, at most twice the grid's next to a sign change) or the plane-resolved cells'
/// deviation, whichever is largest, plus how far vertices moved apart where sheets touched
/// ([`Surface::sheets_apart`]); and, of those, the loose cells' reach.
pub fn surface_error_bound(surface: &Surface, h: f64) -> (f64, f64) {
    let grid = grid_error_bound(h);
    let missed = loose_reach(surface, 2.0 * grid);
    (grid.max(missed).max(surface.planar_deviation) + surface.sheets_apart, missed)
}

/// Approximate the boundary of the union of `set` at resolution `params.eps`: the grid has
/// `grid_error_bound(h) = eps`, which is the proved bound when every band cell resolves the
/// boundary; cells where the lattice may have missed boundary widen it by their reach
/// ([`surface_error_bound`]). While that is above twice the grid's, the grid is halved, at
/// most `max_refinements` times and only while the next grid (about four times the band
/// cells) is expected to fit the budget. With `params.planes`, primitives whose boxes do
/// not meet (one primitive: two convex operands) need no grid: the surface is their hulls,
/// bound by the hulls' plane tolerance ([`PLANE_TOL_REL`] of the diagonal), `h` 0.
///
/// # Errors
/// [`CoreError::InvalidParameter`] for a bad eps, [`CoreError::ResourceLimit`] when even
/// the first grid does not fit, [`CoreError::Empty`] for an empty set.
pub fn approximate_union(set: &PolytopeSet, params: &UnionParams) -> CoreResult<UnionResult> {
    if set.is_empty() {
        return Err(CoreError::Empty { what: "primitive set".into() });
    }
    if params.eps <= 0.0 || !params.eps.is_finite() || !params.planes {
        // a bad eps: its error names it; no planes: sampled everywhere, as asked
        return approximate_solid(set, &set.aabb, params);
    }
    match apart_hulls(set) {
        Some(surface) => Ok(exact_hulls(surface, set, params)),
        None => approximate_solid(set, &set.aabb, params),
    }
}

/// The boundary of the union when no two primitives' boxes meet: their hulls' triangles
/// (outward, closed, one shell each), with the vertices they use; `None` otherwise.
fn apart_hulls(set: &PolytopeSet) -> Option<Surface> {
    for (i, p) in set.polys.iter().enumerate() {
        let mut other = false;
        // the BVH's leaves may hold several primitives: each box is asked itself
        set.bvh.for_each_overlapping(&p.aabb, |j| other |= j != i && set.polys[j].aabb.overlaps(&p.aabb));
        if other {
            return None;
        }
    }
    let mut surface = Surface::default();
    for p in &set.polys {
        let mut index = vec![u32::MAX; p.vertices.len()];
        for t in &p.triangles {
            let face = t.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = surface.vertices.len() as u32;
                    surface.vertices.push(p.vertices[v as usize]);
                }
                index[v as usize]
            });
            surface.faces.push(face);
        }
    }
    Some(surface)
}

/// The union of apart hulls as a result: exact up to the hulls' plane tolerance
/// ([`PLANE_TOL_REL`] of the union's diagonal: no grid, no cells, `h` 0); simplified as
/// any surface (coplanar hull triangles share their facet's plane).
fn exact_hulls(surface: Surface, set: &PolytopeSet, params: &UnionParams) -> UnionResult {
    let scale = set.aabb.diagonal();
    let mut r = UnionResult {
        triangles_extracted: surface.faces.len(),
        surface,
        h: 0.0,
        error_bound: PLANE_TOL_REL * scale,
        missed_reach: 0.0,
        refinements: 0,
        level_counts: Vec::new(),
        seconds_octree: 0.0,
        seconds_surface: 0.0,
        seconds_simplify: 0.0,
        planes_fallback_edges: 0,
        sag: SagStats::default(),
        seconds_sag: 0.0,
    };
    if params.simplify {
        simplify(&mut r, scale, 1e-18 * scale * scale);
    }
    r
}

/// [`merge_coplanar`] on the result's surface (planes within `1e-10` of `scale`, no
/// triangle below `min_area` made), timed.
fn simplify(r: &mut UnionResult, scale: f64, min_area: f64) {
    let t = Instant::now();
    merge_coplanar(&mut r.surface, 1e-10 * scale, min_area);
    r.seconds_simplify = t.elapsed().as_secs_f64();
}

/// The share of the grid's bound a triangle may sag from the boundary before it is split
/// ([`crate::surface::sag`]): well below the bound, about what the sampled band's smooth
/// parts sag by, so the creases no longer set the error.
const SAG_SHARE: f64 = 1.0 / 16.0;

/// Refine `r`'s surface where it sags from `set`'s boundary ([`refine_sag`]); the bound
/// takes the new triangles' covering radius, off by what vertices moved apart.
fn refine_sag_of<S: CellSource>(r: &mut UnionResult, set: &S) {
    if !r.error_bound.is_finite() {
        return;
    }
    let t = Instant::now();
    let off = r.surface.sheets_apart;
    let tol = SAG_SHARE * grid_error_bound(r.h);
    r.sag = refine_sag(&mut r.surface, &|x, reach| set.boundary_point(x, reach), (tol, r.error_bound - off), off);
    r.error_bound = r.error_bound.max(r.sag.covering + r.surface.sheets_apart);
    r.seconds_sag = t.elapsed().as_secs_f64();
}

/// Part the vertices a reader welding by position would merge, a last time: what the
/// extraction parted, the join and the clean-ups after it may bring back within a weld.
/// The moves add to the bound as the extraction's own do.
fn kept_apart(r: &mut UnionResult) {
    let before = r.surface.sheets_apart;
    let parted = crate::surface::stitch::part_coincident_vertices(&mut r.surface, r.h);
    r.surface.sheets_unzipped += parted;
    r.error_bound += r.surface.sheets_apart - before;
}

/// [`approximate_union`] for any [`CellSource`] whose solid lies in `region`.
///
/// # Errors
/// As [`approximate_union`].
pub fn approximate_solid<S: CellSource>(set: &S, region: &Aabb, params: &UnionParams) -> CoreResult<UnionResult> {
    if params.eps <= 0.0 || !params.eps.is_finite() {
        return Err(CoreError::InvalidParameter { name: "eps".into(), value: params.eps, detail: "must be positive and finite".into() });
    }
    let mut h = cell_size_for_eps(params.eps);
    let mut best: Option<UnionResult> = None;
    let (mut t_oct, mut t_surf) = (0.0, 0.0);
    let mut planes = params.planes;
    let mut sampled: Vec<Aabb> = Vec::new();
    let (mut open_seen, mut retries, mut last_bad) = (0, 0, usize::MAX);
    let mut round = 0;
    let resolved = ResolvedCells::default();
    while round <= params.max_refinements {
        let t0 = Instant::now();
        let built = if planes { Octree::build_resolving_planes(set, region, h, params.max_cells, &sampled, &resolved) } else { Octree::build(set, region, h, params.max_cells) };
        let oct = match built {
            Ok(o) => o,
            Err(e) => match best {
                // the finer grid does not fit: keep what we have (a time limit is no fit)
                Some(b) if !matches!(e, CoreError::TimeLimit { .. }) => return Ok(b),
                _ => return Err(e),
            },
        };
        t_oct += t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let surface = extract(&oct, set, &resolved);
        t_surf += t1.elapsed().as_secs_f64();
        if crate::deadline::cancelled() {
            return Err(CoreError::TimeLimit { during: "surface extraction".into() });
        }
        // where the exact polygons did not join the band, or the band has complex cells
        // next to them, sample around those places while that leaves fewer of them; then,
        // if the join is closed, its complex cells are thin features the bound covers as
        // the sampled grid's (they are there too); else sample everywhere
        let joined_badly = surface.open_edges > 0 || (surface.complex_cells > 0 && surface.planar_cells > 0);
        if planes && joined_badly {
            let bad = surface.open_edges + surface.complex_cells;
            open_seen += bad;
            retries += 1;
            // sampling around that many places would sample most of the band anyway
            let most = bad.saturating_mul(BAND_CELLS_PER_PLACE) >= band_if_sampled(&oct) / 2;
            let anew = surface.open_at.iter().any(|b| !sampled.iter().any(|s| s.contains_point(b.min) && s.contains_point(b.max)));
            let stuck = retries > MAX_JOIN_RETRIES || surface.open_edges > MAX_OPEN_REPORTED || bad >= last_bad || most || !anew;
            if !stuck || surface.open_edges > 0 {
                planes = !stuck;
                last_bad = bad;
                sampled.extend(surface.open_at.iter().map(|b| b.inflated(4.0 * h)));
                continue;
            }
        }
        let (bound, missed_reach) = surface_error_bound(&surface, h);
        // complex cells within the unresolved cells' allowance need no finer grid
        let done = bound <= (2.0 * grid_error_bound(h)).max(surface.planar_deviation);
        let next_fits = 4 * (oct.leaves.len() + surface.band_cells) <= params.max_cells;
        best = Some(UnionResult {
            surface,
            h,
            error_bound: bound,
            missed_reach,
            refinements: round,
            level_counts: oct.level_counts(),
            seconds_octree: t_oct,
            seconds_surface: t_surf,
            seconds_simplify: 0.0,
            triangles_extracted: 0,
            planes_fallback_edges: open_seen,
            sag: SagStats::default(),
            seconds_sag: 0.0,
        });
        if done || !next_fits {
            break;
        }
        h *= 0.5;
        round += 1;
        (retries, last_bad) = (0, usize::MAX);
    }
    let mut r = best.expect("at least one round");
    r.triangles_extracted = r.surface.faces.len();
    // the sag refinement first: merging coplanar triangles would make the chords across a
    // straight crease (a strip of them in one plane) a few long triangles, too long to split
    if set.has_boundary_points() {
        refine_sag_of(&mut r, set);
    }
    if params.simplify {
        let min_area = 1e-12 * r.h * r.h;
        simplify(&mut r, region.diagonal(), min_area);
    }
    kept_apart(&mut r);
    Ok(r)
}
