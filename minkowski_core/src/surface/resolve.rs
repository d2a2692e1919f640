//! The exact surface of one MIXED cell from the planes of its candidates ([`super::planar`]), or
//! of its sub-cells where the cell itself has too many planes or too thin a piece.
//!
//! A cell resolved by planes gives the plane pieces whose two sides differ in membership
//! (one answer per region of the cut, shared by the pieces: carried along a segment that
//! meets no candidate from a region answered before, else one point query). A finest cell
//! that is not resolvable is split below the lattice a few times ([`SUB_LEVELS`]): its
//! sub-cells take their own records from the source (as any child cell does) and are
//! resolved the same way, so a vertex where many facets meet, or two facets crossing at a
//! grazing angle, is still exact. Their polygons meet each other exactly inside the cell, and the cell's
//! neighbours on its faces as any resolved cell's do.
//!
//! Entry point: [`resolve_cell`].

use super::planar::{Cut, Piece};
use super::regions::{plane_key, PlaneKey};
use crate::math::{Aabb, Vec3};
use crate::octree::{CellSource, Label};

/// How many times a finest cell is split below the lattice when it is not resolvable.
pub const SUB_LEVELS: u32 = 3;

/// How many regions answered before (latest first) a region of a cut tries to take its
/// answer from, before a point query: a point query of the exact source is a traversal of
/// every triangle pair whose box holds the point, a carry a clip against the cell's few
/// candidates (on part2k ⊕ icosphere, two thirds of the queries are carried).
const CARRY_TRIES: usize = 8;

/// Record words a region's carries may clip against in all: a carry costs a clip per
/// record, so a cell with many records (coplanar facets of a finely tessellated face)
/// tries fewer, or none (two grates: a few hundred facets on a few planes per cell).
const CARRY_WORDS: usize = 256;

/// The exact surface in one cell.
#[derive(Clone, Default)]
pub struct CellSurface {
    /// Polygons, outward (counter-clockwise seen from outside).
    pub polys: Vec<Vec<Vec3>>,
    /// Per polygon, its outward plane ([`super::regions`] merges the polygons of one).
    pub planes: Vec<PlaneKey>,
    /// How far the boundary may lie from them ([`Piece::deviation`]).
    pub deviation: f64,
}

/// The surface in `cell` (records `recs`), splitting it up to `sub_levels` times where it
/// is not resolvable by planes; `None` when some part of it is not. `known`: a point of
/// the closed cell and the source's answer there (a corner the octree's build answered),
/// which regions take when no candidate lies between.
pub fn resolve_cell<S: CellSource + ?Sized>(src: &S, cell: &Aabb, recs: &[u32], sub_levels: u32, known: Option<(Vec3, bool)>) -> Option<CellSurface> {
    // (the point serves only a cell it lies in: the records cover no more)
    let known = known.filter(|(q, _)| cell.contains_point(*q));
    if let Some(surface) = src.plane_cut(recs).and_then(|cut| Some((cut, cut.pieces(cell)?))).and_then(|(cut, pieces)| cut_surface(src, recs, &cut, pieces, known)) {
        return Some(surface);
    }
    if sub_levels == 0 {
        return None;
    }
    // the octants' shared corner, for each MIXED one, answered when the first needs it:
    // carried from the known point, else one query for the eight
    let mut centre = None;
    let mut out = CellSurface::default();
    let mut own = Vec::new();
    for child in octants(cell) {
        own.clear();
        if src.classify(&child, recs, true, &mut own) != Label::Mixed {
            continue;
        }
        let known = *centre.get_or_insert_with(|| centre_answer(src, cell, recs, known));
        let part = resolve_cell(src, &child, &own, sub_levels - 1, Some(known))?;
        out.deviation = out.deviation.max(part.deviation);
        out.polys.extend(part.polys);
        out.planes.extend(part.planes);
    }
    Some(out)
}

/// The pieces of `cut` whose sides differ, oriented outward; `None` when a sheet thinner
/// than the planes taken as one lies between them ([`Piece::slab`]).
fn cut_surface<S: CellSource + ?Sized>(src: &S, recs: &[u32], cut: &Cut, pieces: Vec<Piece>, known: Option<(Vec3, bool)>) -> Option<CellSurface> {
    // one answer per region of the cut (pieces share them): carried from a region answered
    // before (or the known point, of no region) when the segment between their points
    // meets no candidate (the boundary in the cell lies on candidates, so none lies
    // between them), else one point query
    let mut answered: Vec<(usize, bool, Vec3)> = known.map(|(q, inside)| (usize::MAX, inside, q)).into_iter().collect();
    let mut scratch = Vec::new();
    let tries = CARRY_TRIES.min(CARRY_WORDS / recs.len().max(1));
    let mut inside = |p: Vec3| {
        let region = cut.region(p);
        if let Some(&(_, known, _)) = answered.iter().find(|r| r.0 == region) {
            return known;
        }
        let carried = answered.iter().rev().take(tries).find_map(|&(_, known, q)| (!src.meets_boundary(recs, q, p, &mut scratch)).then_some(known));
        let known = carried.unwrap_or_else(|| src.cell_contains(recs, p));
        answered.push((region, known, p));
        known
    };
    let mut out = CellSurface::default();
    for p in pieces {
        let (front, behind) = (inside(p.sides[0]), inside(p.sides[1]));
        // the polygon facing out of the solid, and its plane as it faces
        let (polygon, out_normal) = match (front, behind) {
            (false, true) => (p.polygon, p.normal),
            (true, false) => (p.polygon.into_iter().rev().collect(), -p.normal),
            _ => {
                // the same on both sides: no boundary there, unless a sheet thinner than
                // the planes taken as this one lies between them
                if p.slab.is_some_and(|q| inside(q) != front) {
                    return None;
                }
                continue;
            }
        };
        let (n, w) = cut.planes[p.plane];
        out.planes.push(if n.dot(out_normal) > 0.0 { plane_key(n, w) } else { plane_key(-n, -w) });
        out.deviation = out.deviation.max(p.deviation);
        out.polys.push(polygon);
    }
    Some(out)
}

/// The cell's centre and the source's answer there: carried from the `known` point when
/// no candidate lies between (and the records are few enough to clip), else one query.
fn centre_answer<S: CellSource + ?Sized>(src: &S, cell: &Aabb, recs: &[u32], known: Option<(Vec3, bool)>) -> (Vec3, bool) {
    let c = cell.center();
    let mut scratch = Vec::new();
    let carried = known.filter(|&(q, _)| recs.len() <= CARRY_WORDS && !src.meets_boundary(recs, q, c, &mut scratch));
    (c, carried.map_or_else(|| src.cell_contains(recs, c), |(_, inside)| inside))
}

/// The eight octants of a box.
fn octants(cell: &Aabb) -> [Aabb; 8] {
    let c = cell.center();
    std::array::from_fn(|k| {
        let pick = |bit: usize, lo: f64, mid: f64, hi: f64| if k & bit == 0 { (lo, mid) } else { (mid, hi) };
        let (x0, x1) = pick(1, cell.min.x, c.x, cell.max.x);
        let (y0, y1) = pick(2, cell.min.y, c.y, cell.max.y);
        let (z0, z1) = pick(4, cell.min.z, c.z, cell.max.z);
        Aabb::new(Vec3::new(x0, y0, z0), Vec3::new(x1, y1, z1))
    })
}
