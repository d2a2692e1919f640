//! Cells whose boundary lies on a few planes: the exact surface pieces there.
//!
//! When every boundary candidate that meets a closed cell lies on one of `k <=`
//! [`MAX_PLANES`] planes,
//! the boundary inside the cell lies on those planes, so each open region of the cell cut
//! by them holds no boundary point: it is wholly inside or wholly outside the solid, and one
//! point decides it. The surface in the cell is then the set of plane pieces (the plane
//! clipped to the cell and to one side of each other plane) whose two sides differ: a flat
//! cell gives one polygon, an edge two, a corner three, a vertex where more facets meet
//! more — exact, at any cell size, so such cells are never split. Each plane's section of
//! the cell is split by every other plane in turn (the arrangement of their lines in it). A cell whose pieces are too thin or whose planes nearly coincide
//! to decide a side safely is not resolved this way (it is split, and at the finest level
//! sampled like any other).
//!
//! Entry points: [`Cut`], [`Cut::pieces`].

use crate::math::{Aabb, Vec3};

/// Most planes a resolved cell may have (a cell where more meet is split).
pub const MAX_PLANES: usize = 16;

/// Pieces thinner than this fraction of the cell (from their centre to any other plane or
/// a cell face) are not resolved.
const THIN: f64 = 1e-6;

/// Planes closer to parallel than this (`1 − |n_i · n_j|`) and nearer each other than
/// [`MERGE`] of the cell everywhere in it are taken as one (the first): the boundary on
/// them then lies within that distance of the pieces ([`Piece::deviation`]). Tessellated
/// curved operands make such pairs (facets at angles of 1e-5 crossing in a cell), whose
/// pieces between them are far too thin to tell their sides apart.
const NEAR_PARALLEL: f64 = 1e-8;

/// See [`NEAR_PARALLEL`].
const MERGE: f64 = 1e-4;

/// The distinct planes `(n, w)` (`n · x = w`, `n` unit) of the boundary candidates in one cell.
#[derive(Clone, Copy, Debug)]
pub struct Cut {
    /// The planes; the first `n` are used.
    pub planes: [(Vec3, f64); MAX_PLANES],
    /// Per plane, a box holding every candidate on it (everywhere when the source gave
    /// none): a part of the plane wholly outside it holds no boundary, so it is no piece
    /// ([`Cut::pieces`]).
    pub extents: [Aabb; MAX_PLANES],
    /// How many.
    pub n: usize,
}

/// One piece of a plane in a cell: a convex polygon (counter-clockwise about the plane's
/// normal) and a point on either side of it, in the regions it separates.
#[derive(Clone, Debug)]
pub struct Piece {
    /// Corners, counter-clockwise about `normal`.
    pub polygon: Vec<Vec3>,
    /// The plane's unit normal.
    pub normal: Vec3,
    /// The index of its plane in the cut.
    pub plane: usize,
    /// A point just in front of the piece (along `normal`) and one just behind it.
    pub sides: [Vec3; 2],
    /// How far the planes taken as this piece's plane ([`MERGE`]) lie from it in the
    /// cell: 0 when none (the piece is exact).
    pub deviation: f64,
    /// With planes taken as its own: a point between them, off both, which must be on the
    /// side the piece's sides are when they agree (else a sheet thinner than the
    /// deviation lies there and the cell is not resolved).
    pub slab: Option<Vec3>,
}

impl Cut {
    /// An empty cut.
    pub fn new() -> Cut {
        Cut { planes: [(Vec3::ZERO, 0.0); MAX_PLANES], extents: [EVERYWHERE; MAX_PLANES], n: 0 }
    }

    /// Add the plane `(n, w)` unless one of the cut's planes is the same (within `tol` in
    /// offset, either orientation); `false` when that would make more than [`MAX_PLANES`].
    pub fn add(&mut self, n: Vec3, w: f64, tol: f64) -> bool {
        self.add_within(n, w, tol, EVERYWHERE)
    }

    /// [`Cut::add`] for a candidate lying in the box `extent`: its plane's extent grows to
    /// hold it.
    pub fn add_within(&mut self, n: Vec3, w: f64, tol: f64, extent: Aabb) -> bool {
        for (k, &(m, v)) in self.planes[..self.n].iter().enumerate() {
            let c = n.dot(m);
            if c.abs() >= 1.0 - 1e-12 && (w - c.signum() * v).abs() <= tol {
                self.extents[k] = self.extents[k].union(&extent);
                return true;
            }
        }
        if self.n == MAX_PLANES {
            return false;
        }
        self.planes[self.n] = (n, w);
        self.extents[self.n] = extent;
        self.n += 1;
        true
    }

    /// The extent of plane `i` and of those taken as it.
    fn extent_of(&self, i: usize, merged: &Merged) -> Aabb {
        (0..self.n).filter(|&j| merged.rep[j] == i).fold(Aabb::empty(), |e, j| e.union(&self.extents[j]))
    }

    /// The region of the cut holding `p` (off every plane): bit `i` set in front of plane `i`.
    pub fn region(&self, p: Vec3) -> usize {
        self.planes[..self.n].iter().enumerate().fold(0, |r, (i, &(n, w))| r | (((n.dot(p) > w) as usize) << i))
    }

    /// The pieces of every plane in `cell` (parts of a plane outside its candidates'
    /// extent left out: they hold no boundary), or `None` when the cell cannot be
    /// resolved safely (a piece too thin to tell its sides: nearly coincident planes, a
    /// grazing line, a sliver at a cell face).
    pub fn pieces(&self, cell: &Aabb) -> Option<Vec<Piece>> {
        let size = cell.extent().max_element();
        let planes = &self.planes[..self.n];
        let merged = Merged::of(planes, cell, MERGE * size);
        let mut out = Vec::new();
        for (i, &(n, w)) in planes.iter().enumerate().filter(|&(i, _)| merged.rep[i] == i) {
            let section = plane_section(cell, n, w);
            // (grown past the planes taken as this one, which lie that close in the cell)
            let extent = self.extent_of(i, &merged).inflated(MERGE * size);
            if section.len() < 3 || !meets(&section, &extent) {
                continue;
            }
            // the section split by the line of every other (kept) plane in it, the parts
            // wholly outside the candidates' extent dropped as they are made
            let (mut parts, mut next) = (vec![section], Vec::new());
            for (_, &(m, v)) in planes.iter().enumerate().filter(|&(j, _)| j != i && merged.rep[j] == j) {
                for poly in parts.drain(..) {
                    split(poly, (m, v), THIN * THIN * size * size, &mut next);
                }
                next.retain(|poly| meets(poly, &extent));
                std::mem::swap(&mut parts, &mut next);
            }
            for poly in parts {
                out.push(piece(cell, &poly, (i, n), planes, &merged, size)?);
            }
        }
        Some(out)
    }
}

/// Which planes of a cut are taken as one ([`MERGE`]): per plane, the plane it is taken as
/// (itself for a kept one), and per kept plane how far those lie from it in the cell.
struct Merged {
    rep: [usize; MAX_PLANES],
    deviation: [f64; MAX_PLANES],
}

impl Merged {
    fn of(planes: &[(Vec3, f64)], cell: &Aabb, tol: f64) -> Merged {
        let mut m = Merged { rep: std::array::from_fn(|i| i), deviation: [0.0; MAX_PLANES] };
        for j in 0..planes.len() {
            for i in (0..j).filter(|&i| m.rep[i] == i) {
                if let Some(gap) = gap_in_cell(planes[i], planes[j], cell).filter(|&g| g <= tol) {
                    m.rep[j] = i;
                    m.deviation[i] = m.deviation[i].max(gap);
                    break;
                }
            }
        }
        m
    }
}

/// The largest distance between two nearly parallel planes over the cell (at its corners:
/// the difference of two affine functions), `None` when they are not nearly parallel.
fn gap_in_cell((n, w): (Vec3, f64), (m, v): (Vec3, f64), cell: &Aabb) -> Option<f64> {
    let c = n.dot(m);
    if 1.0 - c.abs() >= NEAR_PARALLEL {
        return None;
    }
    let s = c.signum();
    let corners = (0..8).map(|k| Vec3::new([cell.min.x, cell.max.x][k & 1], [cell.min.y, cell.max.y][(k >> 1) & 1], [cell.min.z, cell.max.z][(k >> 2) & 1]));
    Some(corners.map(|x| ((n.dot(x) - w) - s * (m.dot(x) - v)).abs()).fold(0.0, f64::max))
}

/// The box of every point: the extent of a plane whose candidates' are not known.
pub const EVERYWHERE: Aabb = Aabb { min: Vec3::splat(f64::NEG_INFINITY), max: Vec3::splat(f64::INFINITY) };

/// Whether the polygon's box meets `extent`.
fn meets(poly: &[Vec3], extent: &Aabb) -> bool {
    Aabb::from_points(poly).overlaps(extent)
}

impl Default for Cut {
    fn default() -> Self {
        Cut::new()
    }
}

/// A piece for the polygon `poly` on the plane with normal `n`, with its side points;
/// `None` when it is too thin for them.
fn piece(cell: &Aabb, poly: &[Vec3], (plane, n): (usize, Vec3), planes: &[(Vec3, f64)], merged: &Merged, size: f64) -> Option<Piece> {
    let c = poly.iter().fold(Vec3::ZERO, |acc, &p| acc + p) / poly.len() as f64;
    // room around the centre: to every plane not taken as this one, and every cell face
    // (a side point moved by d along n changes its distance to a plane by at most d, so
    // both stay in the regions next to the piece; parallel planes count with their gap)
    let mut room = f64::INFINITY;
    for (j, &(m, v)) in planes.iter().enumerate() {
        if merged.rep[j] != plane {
            room = room.min((m.dot(c) - v).abs());
        }
    }
    for a in 0..3 {
        room = room.min(c[a] - cell.min[a]).min(cell.max[a] - c[a]);
    }
    // a polygon whose corners all hug its centre is a sliver
    let reach = poly.iter().map(|&p| (p - c).length()).fold(0.0f64, f64::max);
    let deviation = merged.deviation[plane];
    let d = 0.5 * room;
    // the side points must clear the planes taken as this one, with room to spare
    if room < THIN * size || reach < THIN * size || d <= 4.0 * deviation {
        return None;
    }
    let slab = (deviation > 0.0).then(|| slab_point(poly, c, (plane, n), planes, merged));
    Some(Piece { polygon: poly.to_vec(), normal: n, plane, sides: [c + n * d, c - n * d], deviation, slab })
}

/// A point off the piece's plane between it and a plane taken as it, where they part most
/// over the polygon (near the corner of widest gap, a little inside it towards `c`).
fn slab_point(poly: &[Vec3], c: Vec3, (plane, n): (usize, Vec3), planes: &[(Vec3, f64)], merged: &Merged) -> Vec3 {
    let along = |x: Vec3, (m, v): (Vec3, f64)| (v - m.dot(x)) / m.dot(n); // to plane (m, v) from x along n
    let others: Vec<(Vec3, f64)> = planes.iter().enumerate().filter(|&(j, _)| j != plane && merged.rep[j] == plane).map(|(_, &p)| p).collect();
    let mut best = (c, others[0], 0.0f64);
    for &x in poly {
        for &o in &others {
            let t = along(x, o);
            if t.abs() > best.2.abs() {
                best = (x, o, t);
            }
        }
    }
    let q = best.0 + (c - best.0) * 0.01;
    q + n * (0.5 * along(q, best.1))
}

/// The area of a planar polygon (a fan from its first corner).
fn area(poly: &[Vec3]) -> f64 {
    if poly.len() < 3 {
        return 0.0;
    }
    let sum = (1..poly.len() - 1).fold(Vec3::ZERO, |acc, i| acc + (poly[i] - poly[0]).cross(poly[i + 1] - poly[0]));
    0.5 * sum.length()
}

/// The convex polygon where the plane `n · x = w` crosses the closed box, counter-clockwise
/// about `n` (fewer than three corners when it misses or only touches it).
fn plane_section(cell: &Aabb, n: Vec3, w: f64) -> Vec<Vec3> {
    let corner = |k: usize| Vec3::new([cell.min.x, cell.max.x][k & 1], [cell.min.y, cell.max.y][(k >> 1) & 1], [cell.min.z, cell.max.z][(k >> 2) & 1]);
    let mut pts: Vec<Vec3> = Vec::with_capacity(6);
    for a in 0..8usize {
        for bit in [1usize, 2, 4] {
            if a & bit != 0 {
                continue;
            }
            let (p, q) = (corner(a), corner(a | bit));
            let (fp, fq) = (n.dot(p) - w, n.dot(q) - w);
            if (fp < 0.0) != (fq < 0.0) {
                let t = fp / (fp - fq);
                pts.push(p + (q - p) * t);
            }
        }
    }
    if pts.len() < 3 {
        return pts;
    }
    let c = pts.iter().fold(Vec3::ZERO, |acc, &p| acc + p) / pts.len() as f64;
    let u = (pts[0] - c).normalize_or_zero();
    let v = n.cross(u);
    pts.sort_by(|&p, &q| {
        let (a, b) = ((p - c).dot(v).atan2((p - c).dot(u)), (q - c).dot(v).atan2((q - c).dot(u)));
        a.total_cmp(&b)
    });
    pts
}

/// The parts of the convex polygon `poly` where `m · x <= v` and where `m · x >= v`, in
/// that order, as [`clip`] gives them, each appended to `out` when its area is above
/// `min_area`. A polygon wholly on one side (most of them: a plane's line misses most
/// parts of a section) is moved there, not clipped (its other part would be at most the
/// corners on the line: no area).
fn split(poly: Vec<Vec3>, (m, v): (Vec3, f64), min_area: f64, out: &mut Vec<Vec<Vec3>>) {
    let (mut below, mut above, mut on) = (false, false, 0);
    for &p in &poly {
        let f = m.dot(p) - v;
        below |= f < 0.0;
        above |= f > 0.0;
        on += usize::from(f == 0.0);
    }
    let mut keep = |part: Vec<Vec3>| {
        if area(&part) > min_area {
            out.push(part);
        }
    };
    if below != above && on < 3 {
        keep(poly);
    } else {
        keep(clip(&poly, m, v));
        keep(clip(&poly, -m, -v));
    }
}

/// The part of the convex polygon `poly` where `m · x <= v` (Sutherland–Hodgman).
fn clip(poly: &[Vec3], m: Vec3, v: f64) -> Vec<Vec3> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (fp, fq) = (m.dot(p) - v, m.dot(q) - v);
        if fp <= 0.0 {
            out.push(p);
        }
        if (fp < 0.0 && fq > 0.0) || (fp > 0.0 && fq < 0.0) {
            out.push(p + (q - p) * (fp / (fp - fq)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_plane_through_a_cube_is_one_square_with_a_point_on_each_side() {
        let cell = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let mut cut = Cut::new();
        assert!(cut.add(Vec3::Z, 0.3, 1e-12));
        assert!(cut.add(-Vec3::Z, -0.3, 1e-12), "the same plane facing the other way");
        assert_eq!(cut.n, 1);
        let pieces = cut.pieces(&cell).unwrap();
        assert_eq!(pieces.len(), 1);
        let p = &pieces[0];
        assert_eq!(p.polygon.len(), 4);
        assert!(p.polygon.iter().all(|q| (q.z - 0.3).abs() < 1e-15));
        let e = (p.polygon[1] - p.polygon[0]).cross(p.polygon[2] - p.polygon[1]);
        assert!(e.dot(Vec3::Z) > 0.0, "counter-clockwise about the normal");
        assert!(p.sides[0].z > 0.3 && p.sides[1].z < 0.3);
    }

    #[test]
    fn an_edge_gives_four_pieces_and_a_corner_twelve() {
        let cell = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let mut cut = Cut::new();
        cut.add(Vec3::X, 0.4, 1e-12);
        cut.add(Vec3::Y, 0.6, 1e-12);
        assert_eq!(cut.pieces(&cell).unwrap().len(), 4);
        cut.add(Vec3::Z, 0.5, 1e-12);
        let pieces = cut.pieces(&cell).unwrap();
        assert_eq!(pieces.len(), 12);
        let area: f64 =
            pieces.iter().map(|p| (1..p.polygon.len() - 1).map(|i| 0.5 * (p.polygon[i] - p.polygon[0]).cross(p.polygon[i + 1] - p.polygon[0]).length()).sum::<f64>()).sum();
        assert!((area - 3.0).abs() < 1e-12, "three unit squares, {area}");
    }

    /// Four planes through one point (the apex of a square pyramid, a vertex where four
    /// facets meet): each plane's section is split by the three others' lines, which all
    /// pass through the apex; no piece is lost and none is degenerate.
    #[test]
    fn four_planes_through_one_point_give_the_full_arrangement() {
        let cell = Aabb::new(-Vec3::ONE, Vec3::ONE);
        let apex = Vec3::new(0.1, -0.05, 0.2);
        let mut cut = Cut::new();
        for n in [Vec3::new(1.0, 0.0, 1.0), Vec3::new(-1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0), Vec3::new(0.0, -1.0, 1.0)] {
            let n = n.normalize();
            assert!(cut.add(n, n.dot(apex), 1e-12));
        }
        let pieces = cut.pieces(&cell).unwrap();
        // the pieces of each plane tile its section
        for i in 0..4 {
            let (n, w) = cut.planes[i];
            let total: f64 = pieces.iter().filter(|p| p.plane == i).map(|p| area(&p.polygon)).sum();
            assert!((total - area(&plane_section(&cell, n, w))).abs() < 1e-12, "plane {i}");
            assert!(pieces.iter().filter(|p| p.plane == i).count() >= 4, "plane {i} split by three lines through one point");
        }
        // the sides of every piece are in the regions that differ in its plane's bit only
        for p in &pieces {
            let (front, behind) = (cut.region(p.sides[0]), cut.region(p.sides[1]));
            assert_eq!(front ^ behind, 1 << p.plane);
        }
        // more than MAX_PLANES planes are refused
        let mut many = Cut::new();
        let added = (0..=MAX_PLANES).filter(|&k| many.add(Vec3::new(1.0, k as f64, 0.0).normalize(), 0.1, 1e-12)).count();
        assert_eq!(added, MAX_PLANES);
    }

    #[test]
    fn a_split_is_the_two_clips_to_the_bit() {
        // random convex polygons (sections of the unit cube) and lines, some through corners
        let cell = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let mut state = 11u64;
        let mut unit = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut checked = 0;
        for _ in 0..2000 {
            let n = Vec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize();
            let poly = plane_section(&cell, n, n.dot(Vec3::splat(0.5)) + 0.3 * (unit() - 0.5));
            if poly.len() < 3 {
                continue;
            }
            let m = Vec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize();
            // through a corner of the polygon half the time, so corners lie on the line
            let v = if unit() < 0.5 { m.dot(poly[0]) } else { m.dot(Vec3::splat(unit())) };
            let min_area = 1e-12;
            let expected: Vec<Vec<Vec3>> = [clip(&poly, m, v), clip(&poly, -m, -v)].into_iter().filter(|p| area(p) > min_area).collect();
            let mut got = Vec::new();
            split(poly, (m, v), min_area, &mut got);
            assert_eq!(got, expected);
            checked += 1;
        }
        assert!(checked > 1000);
    }

    #[test]
    fn thin_cuts_are_not_resolved_and_parallel_ones_are() {
        let cell = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let mut cut = Cut::new();
        cut.add(Vec3::Z, 1e-9, 1e-15);
        assert!(cut.pieces(&cell).is_none(), "a plane hugging a face");
        // parallel planes well apart (two faces of a slab) are two exact pieces
        let mut cut = Cut::new();
        cut.add(Vec3::Z, 0.2, 1e-15);
        cut.add(Vec3::new(0.0, 1e-4, 1.0).normalize(), 0.5, 1e-15);
        let pieces = cut.pieces(&cell).expect("a slab");
        assert_eq!(pieces.len(), 2);
        for p in &pieces {
            assert_eq!(cut.region(p.sides[0]) ^ cut.region(p.sides[1]), 1 << p.plane);
            assert!(p.deviation == 0.0 && p.slab.is_none());
        }
    }

    /// Planes nearly coincident in the cell (a gap of 1e-9, or crossing at an angle of
    /// 1e-7) are taken as one: one piece, its deviation the largest gap in the cell, its
    /// side points clear of both planes and its slab point between them.
    #[test]
    fn nearly_coincident_planes_are_taken_as_one_within_their_gap() {
        let cell = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let grazing = Vec3::new(0.0, -1e-7, 1.0).normalize();
        for (second, gap) in [((Vec3::Z, 0.5 + 1e-9), 1e-9), ((grazing, grazing.dot(Vec3::new(0.0, 0.5, 0.5))), 0.5e-7)] {
            let mut cut = Cut::new();
            cut.add(Vec3::Z, 0.5, 1e-15);
            cut.add(second.0, second.1, 1e-15);
            assert_eq!(cut.n, 2);
            let pieces = cut.pieces(&cell).expect("resolved as one plane");
            assert_eq!(pieces.len(), 1);
            let p = &pieces[0];
            assert!((p.deviation - gap).abs() < 1e-3 * gap, "{} vs {gap}", p.deviation);
            let side = |q: Vec3| [Vec3::Z.dot(q) > 0.5, second.0.dot(q) > second.1];
            assert_eq!(side(p.sides[0]), [true, true]);
            assert_eq!(side(p.sides[1]), [false, false]);
            let slab = side(p.slab.expect("a point between the planes"));
            assert!(slab[0] != slab[1], "the slab point lies between them");
        }
        // not taken as one when they part by more than the tolerance in the cell
        let mut cut = Cut::new();
        cut.add(Vec3::Z, 0.5, 1e-15);
        cut.add(Vec3::Z, 0.5 + 1e-3, 1e-15);
        assert_eq!(cut.pieces(&cell).expect("a thin slab").len(), 2);
    }
}
