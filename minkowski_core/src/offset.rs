//! The offset of a closed solid `P` by a radius, as a [`CellSource`] for the octree and
//! the surface extraction (Varadhan and Manocha's section 5.2: the boundary of the offset
//! lies on the spheres, cylinders and prisms of `P`'s vertices, edges and faces).
//!
//! Growing (`r > 0`): `O = {x : dist(x, P) <= r} = P ∪ {x : dist(x, ∂P) <= r}`.
//! Eroding (`r < 0`): `E = {x ∈ P : dist(x, ∂P) >= |r|}`.
//!
//! Cells are classified by exact distances to the triangles of `∂P`: a triangle is a
//! record of a cell when its `|r|`-neighbourhood may meet the cell (the distance from the
//! cell's centre minus its half-diagonal is at most `|r|`). A cell with no record meets
//! neither `∂P` nor any neighbourhood, so it lies wholly inside or outside `P` (one exact
//! winding-number test at its centre decides); a cell within `|r|` of one triangle at
//! all eight corners (the distance to a convex set is convex, so the corners bound it)
//! is wholly in the neighbourhoods. Along a segment, the part within `|r|` of a triangle
//! is one interval (a convex function's sublevel set), found by golden-section search for
//! the nearest point and bisection for the two ends; the offset's boundary lies at the
//! ends of those intervals, and between them a stretch is wholly inside or outside `P`.

use crate::exact::TriMesh;
use crate::math::{Aabb, Vec3};
use crate::octree::{merge_sorted, CellSource, Label};

/// Bisection and golden-section steps along a segment: bisection to 2^-76 of its length,
/// golden-section search to 0.618^76, about 1e-16.
const STEPS: usize = 76;

/// The offset of a closed solid by a radius (see the module documentation).
pub struct OffsetSource<'a> {
    mesh: &'a TriMesh,
    radius: f64,
    grow: bool,
    /// The box the offset lies in.
    pub aabb: Aabb,
}

impl<'a> OffsetSource<'a> {
    /// The offset of the solid `mesh` by `r` (grown for `r > 0`, eroded for `r < 0`).
    ///
    /// # Panics
    /// When `r` is zero or not finite (the caller checks it), or in debug builds when
    /// `mesh` is no solid.
    pub fn new(mesh: &'a TriMesh, r: f64) -> Self {
        assert!(r.is_finite() && r != 0.0, "offset radius {r}");
        debug_assert!(mesh.solid, "the offset of a surface");
        let grow = r > 0.0;
        let aabb = if grow { mesh.aabb.inflated(r * (1.0 + 1e-9)) } else { mesh.aabb };
        OffsetSource { mesh, radius: r.abs(), grow, aabb }
    }

    fn distance(&self, t: u32, p: Vec3) -> f64 {
        let [a, b, c] = self.mesh.tris[t as usize].p;
        (closest_on_triangle(p, a, b, c) - p).length()
    }

    /// The part `[s0, s1]` of `a → b` within the radius of triangle `t`, if any. The
    /// distance is convex along the segment, so an end within the radius bounds the
    /// search to one bisection, both ends within it give the whole segment, and only a
    /// segment whose ends are both farther needs the nearest point searched for (after a
    /// cheap test: the midpoint's distance less half the length).
    fn near_interval(&self, t: u32, a: Vec3, b: Vec3) -> Option<(f64, f64)> {
        let f = |s: f64| self.distance(t, a + (b - a) * s) - self.radius;
        let (fa, fb) = (f(0.0), f(1.0));
        match (fa <= 0.0, fb <= 0.0) {
            (true, true) => return Some((0.0, 1.0)),
            (true, false) => return Some((0.0, crossing(&f, 0.0, 1.0))),
            (false, true) => return Some((crossing(&f, 1.0, 0.0), 1.0)),
            (false, false) => {}
        }
        if f(0.5) - 0.5 * (b - a).length() > 0.0 {
            return None;
        }
        let (mut lo, mut hi) = (0.0, 1.0);
        let golden = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..STEPS {
            let m1 = hi - golden * (hi - lo);
            let m2 = lo + golden * (hi - lo);
            if f(m1) <= f(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        let best = 0.5 * (lo + hi);
        if f(best) > 0.0 {
            return None;
        }
        Some((crossing(&f, best, 0.0), crossing(&f, best, 1.0)))
    }

    /// Whether `p`, not within the radius of the boundary, is in the offset: inside `P`.
    fn inside_far(&self, p: Vec3) -> bool {
        self.mesh.contains(p)
    }
}

impl CellSource for OffsetSource<'_> {
    fn root_records(&self) -> Vec<u32> {
        (0..self.mesh.tris.len() as u32).collect()
    }

    fn classify(&self, cell: &Aabb, cand: &[u32], _finest: bool, out: &mut Vec<u32>) -> Label {
        let centre = cell.center();
        let half = cell.half().length();
        for &t in cand {
            if self.distance(t, centre) - half > self.radius {
                continue;
            }
            let corners_near = (0..8).all(|k| self.distance(t, corner(cell, k)) <= self.radius);
            if corners_near {
                out.clear();
                return if self.grow { Label::Full } else { Label::Empty };
            }
            out.push(t);
        }
        if !out.is_empty() {
            return Label::Mixed;
        }
        if self.inside_far(centre) {
            Label::Full
        } else {
            Label::Empty
        }
    }

    fn cell_contains(&self, cand: &[u32], p: Vec3) -> bool {
        let near = cand.iter().map(|&t| self.distance(t, p)).fold(f64::INFINITY, f64::min);
        if self.grow {
            near <= self.radius || self.inside_far(p)
        } else {
            near >= self.radius && self.inside_far(p)
        }
    }

    fn boundary_intervals(&self, cand: &[u32], a: Vec3, b: Vec3, out: &mut Vec<(f64, f64)>) {
        out.clear();
        out.extend(cand.iter().filter_map(|&t| self.near_interval(t, a, b)));
        merge_sorted(out);
    }

    fn solid_intervals(&self, a: Vec3, b: Vec3, sa: bool, sb: bool, bnd: &[(f64, f64)], out: &mut Vec<(f64, f64)>) {
        out.clear();
        let mut start = 0.0; // the current stretch between neighbourhood intervals
        for (k, &(s0, s1)) in bnd.iter().enumerate() {
            if s0 > start {
                let inside = if k == 0 { sa } else { self.inside_far(a + (b - a) * (0.5 * (start + s0))) };
                if inside {
                    out.push((start, s0));
                }
            }
            if self.grow {
                out.push((s0, s1));
            }
            start = s1;
        }
        if start < 1.0 {
            let last = if bnd.is_empty() { sa && sb } else { sb };
            if last {
                out.push((start, 1.0));
            }
        }
        merge_sorted(out);
    }
}

/// Where `f` (at most zero at `inside`, positive at `outside`, convex) crosses zero
/// between them: the last point found with `f <= 0` (bisection).
fn crossing(f: &impl Fn(f64) -> f64, inside: f64, outside: f64) -> f64 {
    let (mut i, mut o) = (inside, outside);
    for _ in 0..STEPS {
        let m = 0.5 * (i + o);
        if f(m) <= 0.0 {
            i = m;
        } else {
            o = m;
        }
    }
    i
}

/// The point of segment `ab` nearest `p`.
fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 == 0.0 {
        return a;
    }
    a + ab * ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
}

fn corner(cell: &Aabb, k: usize) -> Vec3 {
    Vec3::new(if k & 1 == 0 { cell.min.x } else { cell.max.x }, if k & 2 == 0 { cell.min.y } else { cell.max.y }, if k & 4 == 0 { cell.min.z } else { cell.max.z })
}

/// The point of triangle `abc` nearest `p` (by the regions of its vertices, edges and
/// face; exact up to rounding).
pub fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    if ab.cross(ac).length_squared() == 0.0 {
        // degenerate: the triangle is its edges (the regions below divide by zero)
        let on = [closest_on_segment(p, a, b), closest_on_segment(p, b, c), closest_on_segment(p, c, a)];
        return on.into_iter().min_by(|x, y| (*x - p).length_squared().total_cmp(&(*y - p).length_squared())).unwrap_or(a);
    }
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return if d1 - d3 > 0.0 { a + ab * (d1 / (d1 - d3)) } else { a };
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return if d2 - d6 > 0.0 { a + ac * (d2 / (d2 - d6)) } else { a };
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let span = (d4 - d3) + (d5 - d6);
        return if span > 0.0 { b + (c - b) * ((d4 - d3) / span) } else { b };
    }
    let denom = va + vb + vc;
    if denom == 0.0 {
        return a; // a degenerate triangle: its vertices and edges are what is left
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::union::{approximate_solid, UnionParams};

    fn unit_cube() -> TriMesh {
        let v: Vec<Vec3> = (0..8).map(|k| Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64)).collect();
        let f: Vec<[u32; 3]> = vec![[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]];
        TriMesh::new(v, &f, "cube").expect("a solid cube")
    }

    #[test]
    fn closest_points_of_a_triangle() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let near = |p: Vec3, q: Vec3| (closest_on_triangle(p, a, b, c) - q).length() < 1e-15;
        assert!(near(Vec3::new(0.2, 0.2, 5.0), Vec3::new(0.2, 0.2, 0.0))); // the face
        assert!(near(Vec3::new(-1.0, -1.0, 0.0), a)); // a vertex
        assert!(near(Vec3::new(0.5, -2.0, 0.0), Vec3::new(0.5, 0.0, 0.0))); // an edge
        assert!(near(Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.5, 0.5, 0.0))); // the hypotenuse
                                                                           // a triangle with two equal corners is its edge: no NaN from 0 / 0
        let q = closest_on_triangle(Vec3::new(-0.5, 2.0, 0.0), a, a, c);
        assert!(q.is_finite() && (q - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-15, "{q}");
    }

    #[test]
    fn membership_follows_the_distance() {
        let cube = unit_cube();
        let grown = OffsetSource::new(&cube, 0.5);
        let all = grown.root_records();
        assert!(grown.cell_contains(&all, Vec3::new(1.4, 0.5, 0.5)));
        assert!(!grown.cell_contains(&all, Vec3::new(1.6, 0.5, 0.5)));
        assert!(grown.cell_contains(&all, Vec3::new(1.3, 1.3, 0.5))); // 0.42 from the edge
        assert!(!grown.cell_contains(&all, Vec3::new(1.3, 1.3, 1.3))); // 0.52 from the corner
        let shrunk = OffsetSource::new(&cube, -0.2);
        assert!(shrunk.cell_contains(&all, Vec3::new(0.5, 0.5, 0.5)));
        assert!(!shrunk.cell_contains(&all, Vec3::new(0.1, 0.5, 0.5)));
    }

    #[test]
    fn the_grown_cube_has_the_closed_form_volume() {
        let cube = unit_cube();
        let r = 0.25;
        let src = OffsetSource::new(&cube, r);
        let params = UnionParams { eps: 0.02, max_cells: 4_000_000, max_refinements: 0, simplify: false, planes: true };
        let result = approximate_solid(&src, &src.aabb, &params).expect("a surface");
        let volume = signed_volume(&result.surface.vertices, &result.surface.faces);
        let exact = 1.0 + 6.0 * r + 3.0 * std::f64::consts::PI * r * r + 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        assert!((volume - exact).abs() < 0.03 * exact, "{volume} vs {exact}");
    }

    fn signed_volume(v: &[Vec3], f: &[[u32; 3]]) -> f64 {
        f.iter().map(|t| v[t[0] as usize].dot(v[t[1] as usize].cross(v[t[2] as usize])) / 6.0).sum()
    }
}
