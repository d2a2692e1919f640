//! How far boundary the lattice did not see may lie from the extracted surface.
//!
//! A loose cell (unresolved, or silent and not cleared by its source) may hold boundary its
//! samples do not show: a sliver or passage thinner than the cell. Every point `x` of a
//! cell with centre `c` is within `|x - c| + |c - v|` of the surface for any surface point
//! `v`, so half the cell's diagonal plus the distance from its centre to a near surface
//! point bounds how far the boundary there is from the surface; next to a cell with a sign
//! change the two cells' joint diagonal bounds it too. The point is the nearest vertex,
//! found on a hash grid of the surface's vertices ring by ring around the cell, or the
//! nearest point of a triangle longer than the grid's bins (the exact polygons of large
//! plane-resolved cells, whose corners lie far from the cells over their middle) when that
//! is nearer.
//!
//! Entry point: [`loose_reach`].

use super::Surface;
use crate::bvh::Bvh;
use crate::math::{Aabb, Vec3};
use crate::polytope::closest_on_triangle;
use crate::util::FastMap;
use rayon::prelude::*;

/// Rings of hash-grid bins searched around a loose cell before every vertex is tried.
const MAX_RING: i64 = 8;

type Bins = FastMap<[i64; 3], Vec<Vec3>>;

/// The largest distance from a point of a loose cell to the surface (an upper bound), a
/// cell next to a sign change taking at most `near_cap`: `0` with no loose cells,
/// infinite when some cell has no near sign change and there is no surface.
pub fn loose_reach(surface: &Surface, near_cap: f64) -> f64 {
    let Some(first) = surface.loose_at.first() else {
        return 0.0;
    };
    let points = used_vertices(surface);
    let bin = 2.0 * first.0.extent().max_element();
    let bins = bin_points(&points, bin);
    let large = LargeFaces::new(surface, bin);
    surface
        .loose_at
        .par_iter()
        .map(|(cell, near)| {
            let c = cell.center();
            let reach = 0.5 * cell.diagonal() + large.nearer(surface, c, nearest(&bins, &points, c, bin));
            if *near {
                reach.min(near_cap)
            } else {
                reach
            }
        })
        .reduce(|| 0.0, f64::max)
}

/// The faces with an edge longer than a bin, and a BVH over their boxes.
struct LargeFaces {
    faces: Vec<[u32; 3]>,
    bvh: Bvh,
}

impl LargeFaces {
    fn new(surface: &Surface, bin: f64) -> LargeFaces {
        let corners = |f: &[u32; 3]| f.map(|v| surface.vertices[v as usize]);
        let long = |f: &&[u32; 3]| {
            let [a, b, c] = corners(f);
            (b - a).length().max((c - b).length()).max((a - c).length()) > bin
        };
        let faces: Vec<[u32; 3]> = surface.faces.iter().filter(long).copied().collect();
        let boxes: Vec<Aabb> = faces.iter().map(|f| Aabb::from_points(&corners(f))).collect();
        LargeFaces { bvh: Bvh::build(&boxes), faces }
    }

    /// The distance from `c` to the surface: `within`, a distance to a surface point,
    /// unless one of the large faces comes nearer.
    fn nearer(&self, surface: &Surface, c: Vec3, within: f64) -> f64 {
        let mut best = within;
        self.bvh.for_each_within(c, within, |i| {
            let [a, b, d] = self.faces[i].map(|v| surface.vertices[v as usize]);
            best = best.min((closest_on_triangle(c, a, b, d) - c).length());
        });
        best
    }
}

/// The boxes that lie apart from the surface: no vertex of it within `within` of the box
/// (none within that plus half its diagonal of its centre; a box near only the middle of
/// a large face counts as apart, and [`loose_reach`] then finds it near).
pub fn apart_from(surface: &Surface, boxes: &[Aabb], within: f64) -> Vec<Aabb> {
    if boxes.is_empty() {
        return Vec::new();
    }
    let bins = bin_points(&used_vertices(surface), within);
    boxes.iter().filter(|b| !any_within(&bins, b.center(), within + 0.5 * b.diagonal(), within)).copied().collect()
}

/// Whether a point binned in `bins` (of size `bin`) lies within `radius` of `c`.
fn any_within(bins: &Bins, c: Vec3, radius: f64, bin: f64) -> bool {
    let home = bin_of(c, bin);
    let rings = (radius / bin).ceil() as i64 + 1;
    (0..=rings).flat_map(ring_offsets).any(|d| {
        let key = [home[0] + d[0], home[1] + d[1], home[2] + d[2]];
        bins.get(&key).into_iter().flatten().any(|&p| (p - c).length() <= radius)
    })
}

/// The vertices the faces use (a dropped sliver may leave others behind).
fn used_vertices(surface: &Surface) -> Vec<Vec3> {
    let mut used = vec![false; surface.vertices.len()];
    for face in &surface.faces {
        for &v in face {
            used[v as usize] = true;
        }
    }
    surface.vertices.iter().zip(&used).filter(|(_, &u)| u).map(|(&p, _)| p).collect()
}

fn bin_of(p: Vec3, bin: f64) -> [i64; 3] {
    [(p.x / bin).floor() as i64, (p.y / bin).floor() as i64, (p.z / bin).floor() as i64]
}

fn bin_points(points: &[Vec3], bin: f64) -> Bins {
    let mut bins = Bins::default();
    for &p in points {
        bins.entry(bin_of(p, bin)).or_default().push(p);
    }
    bins
}

/// The distance from `c` to a near vertex: the nearest in the first ring of bins that
/// holds any, and the next ring (or the nearest of all, past [`MAX_RING`]).
fn nearest(bins: &Bins, points: &[Vec3], c: Vec3, bin: f64) -> f64 {
    let home = bin_of(c, bin);
    let mut best = f64::INFINITY;
    let mut found_at: Option<i64> = None;
    for ring in 0..=MAX_RING {
        if found_at.is_some_and(|r| ring > r + 1) {
            break;
        }
        for d in ring_offsets(ring) {
            let key = [home[0] + d[0], home[1] + d[1], home[2] + d[2]];
            for &p in bins.get(&key).into_iter().flatten() {
                best = best.min((p - c).length());
            }
        }
        if best.is_finite() && found_at.is_none() {
            found_at = Some(ring);
        }
    }
    if best.is_finite() {
        return best;
    }
    points.iter().map(|&p| (p - c).length()).fold(f64::INFINITY, f64::min)
}

/// The bin offsets at Chebyshev distance exactly `ring`.
fn ring_offsets(ring: i64) -> impl Iterator<Item = [i64; 3]> {
    (-ring..=ring).flat_map(move |z| (-ring..=ring).flat_map(move |y| (-ring..=ring).map(move |x| [x, y, z]))).filter(move |d| d.iter().map(|c| c.abs()).max() == Some(ring))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Aabb;

    fn surface_with(vertices: Vec<Vec3>, loose_at: Vec<(Aabb, bool)>) -> Surface {
        let faces = vec![[0, 1, 2]];
        Surface { vertices, faces, complex_cells: loose_at.len(), loose_at, ..Default::default() }
    }

    #[test]
    fn the_reach_is_half_the_diagonal_plus_the_distance_to_the_nearest_vertex() {
        let tri = vec![Vec3::new(3.0, 0.5, 0.5), Vec3::new(5.0, 0.5, 0.5), Vec3::new(3.0, 2.5, 0.5)];
        let cell = Aabb::new(Vec3::ZERO, Vec3::splat(1.0));
        let reach = loose_reach(&surface_with(tri.clone(), vec![(cell, false)]), 1.0);
        assert!((reach - (0.5 * 3f64.sqrt() + 2.5)).abs() < 1e-12, "{reach}");
        // next to a sign change the joint diagonal caps it
        assert_eq!(loose_reach(&surface_with(tri, vec![(cell, true)]), 1.0), 1.0);
    }

    #[test]
    fn a_large_triangle_is_near_a_cell_over_its_middle_though_its_corners_are_far() {
        // a plane-resolved polygon's triangle, 40 cells long, and a loose cell just above
        // its middle: the surface is half a cell from its face, its corners some 20 cells
        let tri = vec![Vec3::new(-20.0, -20.0, 0.0), Vec3::new(20.0, -20.0, 0.0), Vec3::new(0.0, 20.0, 0.0)];
        let cell = Aabb::new(Vec3::new(-0.5, -0.5, 0.5), Vec3::new(0.5, 0.5, 1.5));
        let reach = loose_reach(&surface_with(tri, vec![(cell, false)]), 1e9);
        assert!((reach - (0.5 * 3f64.sqrt() + 1.0)).abs() < 1e-12, "{reach}");
    }

    #[test]
    fn a_far_surface_is_found_past_the_rings_and_none_is_infinite() {
        let tri = vec![Vec3::new(100.0, 0.5, 0.5), Vec3::new(101.0, 0.5, 0.5), Vec3::new(100.0, 1.5, 0.5)];
        let cell = Aabb::new(Vec3::ZERO, Vec3::splat(1.0));
        let reach = loose_reach(&surface_with(tri, vec![(cell, false)]), 1.0);
        assert!((reach - (0.5 * 3f64.sqrt() + 99.5)).abs() < 1e-9, "{reach}");
        let none = Surface { complex_cells: 1, loose_at: vec![(cell, false)], ..Default::default() };
        assert!(loose_reach(&none, 1.0).is_infinite());
        assert_eq!(loose_reach(&Surface::default(), 1.0), 0.0);
    }

    #[test]
    fn boxes_with_no_vertex_within_the_distance_are_apart() {
        let tri = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let surface = surface_with(tri, Vec::new());
        let near = Aabb::new(Vec3::new(1.1, 0.0, 0.0), Vec3::new(1.2, 0.1, 0.0)); // 0.1 off a corner
        let far = Aabb::new(Vec3::new(5.0, 0.0, 0.0), Vec3::new(5.1, 0.1, 0.0));
        let apart = apart_from(&surface, &[near, far], 0.5);
        assert_eq!(apart.len(), 1);
        assert_eq!(apart[0].min, far.min);
        // with every vertex farther than the distance, each is apart
        assert_eq!(apart_from(&surface, &[near, far], 0.05).len(), 2);
        assert!(apart_from(&surface, &[], 0.5).is_empty());
    }
}
