//! Welding a closed triangle mesh's points that lie closer than a distance (a float32
//! file would weld them anyway, into edges of four triangles), with the distance it moved
//! the surface.
//!
//! Each cluster of points (chained by pairs closer than `within`) becomes its first point;
//! `moved` is the farthest any point went. Triangles left with fewer than three distinct
//! corners collapse. Every point of a kept triangle moves by at most `moved`
//! (barycentric interpolation), and a collapsed triangle's image is a segment or a point
//! that is checked to lie on an edge (or a corner) of the kept ones, so the welded
//! surface lies within `moved` of the old one both ways. The kept triangles must still
//! form a closed, consistently wound surface; anything else is refused.

use crate::error::{CoreError, CoreResult};
use crate::math::Vec3;
use crate::util::{FastMap, FastSet, UnionFind};

/// A welded mesh: its points, its triangles, each one's index in the input, and how far
/// the surface moved.
#[derive(Clone, Debug)]
pub struct Welded {
    /// Points (the clusters' first points, in input order).
    pub vertices: Vec<Vec3>,
    /// Kept triangles on `vertices`.
    pub triangles: Vec<[u32; 3]>,
    /// Per kept triangle, its index in the input.
    pub kept: Vec<usize>,
    /// The farthest any point moved.
    pub moved: f64,
}

/// Weld the closed mesh's points closer than `within` (see the module documentation).
///
/// # Errors
/// [`CoreError::Degenerate`] when the welded surface is not closed and consistently wound,
/// or a collapsed triangle's image is not on it.
pub fn weld(vertices: &[Vec3], triangles: &[[u32; 3]], within: f64) -> CoreResult<Welded> {
    let refuse = |detail: &str| CoreError::Degenerate { what: "welded mesh".into(), detail: detail.into() };
    let cluster = clusters(vertices, within);
    let mut index = vec![u32::MAX; vertices.len()];
    let mut welded = Vec::new();
    let mut moved: f64 = 0.0;
    for (i, &root) in cluster.iter().enumerate() {
        if index[root] == u32::MAX {
            index[root] = welded.len() as u32;
            welded.push(vertices[root]);
        }
        index[i] = index[root];
        moved = moved.max((vertices[i] - vertices[root]).length());
    }
    let mut kept_triangles = Vec::with_capacity(triangles.len());
    let mut kept = Vec::with_capacity(triangles.len());
    let mut collapsed = Vec::new();
    for (t, tri) in triangles.iter().enumerate() {
        let w = tri.map(|i| index[i as usize]);
        if w[0] != w[1] && w[1] != w[2] && w[2] != w[0] {
            kept_triangles.push(w);
            kept.push(t);
        } else {
            collapsed.push(w);
        }
    }
    let mut directed = FastSet::with_capacity_and_hasher(kept_triangles.len() * 3, Default::default());
    for w in &kept_triangles {
        for k in 0..3 {
            if !directed.insert((w[k], w[(k + 1) % 3])) {
                return Err(refuse("an edge is used twice the same way"));
            }
        }
    }
    if directed.iter().any(|&(a, b)| !directed.contains(&(b, a))) {
        return Err(refuse("the welded surface is open"));
    }
    let used: FastSet<u32> = kept_triangles.iter().flatten().copied().collect();
    for w in collapsed {
        let on_surface = |a: u32, b: u32| if a == b { used.contains(&a) } else { directed.contains(&(a, b)) };
        if !(on_surface(w[0], w[1]) && on_surface(w[1], w[2]) && on_surface(w[2], w[0])) {
            return Err(refuse("a collapsed triangle is not on the welded surface"));
        }
    }
    Ok(Welded { vertices: welded, triangles: kept_triangles, kept, moved })
}

/// Per point, its cluster's first point: pairs closer than `within` chained, found on a
/// grid of that spacing.
fn clusters(vertices: &[Vec3], within: f64) -> Vec<usize> {
    let mut sets = UnionFind::new(vertices.len());
    if within > 0.0 {
        let cell = |p: Vec3| ((p.x / within).floor() as i64, (p.y / within).floor() as i64, (p.z / within).floor() as i64);
        let mut grid: FastMap<(i64, i64, i64), Vec<usize>> = FastMap::default();
        for (i, &p) in vertices.iter().enumerate() {
            grid.entry(cell(p)).or_default().push(i);
        }
        for (i, &p) in vertices.iter().enumerate() {
            let (x, y, z) = cell(p);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        for &j in grid.get(&(x + dx, y + dy, z + dz)).map_or(&[][..], |v| &v[..]) {
                            if j > i && (vertices[j] - p).length() < within {
                                sets.union(i, j);
                            }
                        }
                    }
                }
            }
        }
    }
    let mut first = vec![usize::MAX; vertices.len()];
    let mut root_of = vec![0; vertices.len()];
    for (i, root) in root_of.iter_mut().enumerate() {
        let r = sets.find(i);
        if first[r] == usize::MAX {
            first[r] = i;
        }
        *root = first[r];
    }
    root_of
}

#[cfg(test)]
mod tests {
    use super::*;

    fn octahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let t = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        (v, t)
    }

    #[test]
    fn points_farther_apart_than_the_distance_are_left_alone() {
        let (v, t) = octahedron();
        let w = weld(&v, &t, 1e-6).expect("weld");
        assert_eq!((w.vertices.len(), w.triangles.len(), w.moved), (6, 8, 0.0));
    }

    #[test]
    fn a_sliver_strip_collapses_onto_its_edge_and_the_move_is_measured() {
        // the octahedron with its top corner doubled 1e-9 apart and a sliver pair of
        // triangles joining the two halves of its upper fan
        let (mut v, _) = octahedron();
        v.push(Vec3::new(1e-9, 0.0, 1.0)); // 6: a twin of 4
        let t = vec![[0, 2, 6], [2, 1, 4], [1, 3, 4], [3, 0, 6], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5], [2, 4, 6], [4, 3, 6]];
        let w = weld(&v, &t, 1e-6).expect("weld");
        assert_eq!((w.vertices.len(), w.triangles.len()), (6, 8));
        assert!((w.moved - 1e-9).abs() < 1e-15, "moved {}", w.moved);
    }

    #[test]
    fn a_weld_that_opens_the_surface_is_refused() {
        // the octahedron's top and bottom corners (no edge between them) welded: the
        // upper and lower fans then use their edges to the corner twice the same way
        let (mut v, t) = octahedron();
        v[5] = v[4] + Vec3::new(0.0, 1e-9, 0.0);
        assert!(weld(&v, &t, 1e-6).is_err());
    }
}
