//! Whether a closed mesh is already *tidy*: a solid on which the cleaning that
//! `planner.meshes.validate_solid` does before its winding check would change nothing, so
//! that the caller may skip it.
//!
//! Tidy means, with the limits the caller's tolerances give ([`TidyLimits`]): every vertex
//! is used; no triangle repeats a corner or another's corners; a triangle with an area at
//! or below the degenerate limit only in a shell that has others above it (the cleaning
//! keeps those: dropping them would open the shell); every directed edge used once and its
//! reverse once (so the winding is consistent and every edge manifold); every shell (the
//! triangles connected over edges) enclosing a positive volume above the flat limit, so
//! none is inside out and none is a cavity; no two vertices within the merge distance; and
//! no two triangles of one shell facing opposite ways in nearly one plane
//! ([`TriMesh::faces_itself`]). Each comparison is made a little looser than the
//! cleaning's, so rounding can only send a mesh to the full cleaning, never past it.
//!
//! Entry point: [`tidy_windings`].

use super::mesh::{TriMesh, Windings};
use crate::math::Vec3;
use crate::util::{FastMap, FastSet, UnionFind};
use rayon::prelude::*;

/// Relative margin by which every limit is widened (see the module documentation).
const SLACK: f64 = 1e-6;

/// The cleaning's tolerances, in the mesh's units.
#[derive(Clone, Copy, Debug)]
pub struct TidyLimits {
    /// Vertices at most this far apart would be merged.
    pub merge: f64,
    /// Triangles whose area is below this are degenerate.
    pub degenerate_area: f64,
    /// Shells whose volume is at most this in magnitude are flat.
    pub zero_volume: f64,
    /// Triangles of one shell whose normals are opposite within this angle (radians)...
    pub fold_angle: f64,
    /// ...and whose centroids lie within this distance of each other's planes are checked
    /// for overlap by the cleaning.
    pub coplanar: f64,
}

/// Each triangle's shell (the components over shared edges, numbered from 0) when the
/// mesh passes every test of tidiness but [`TriMesh::faces_itself`]; else the first reason
/// it is not tidy.
///
/// # Errors
/// A short reason (for logs) when the mesh is not tidy.
pub fn tidy_shells(vertices: &[Vec3], faces: &[[u32; 3]], limits: &TidyLimits) -> Result<Vec<u32>, &'static str> {
    let clear = check_faces(vertices, faces, limits)?;
    let (shells, count) = shells_over_edges(faces)?;
    check_volumes(vertices, faces, &shells, count, limits)?;
    check_degenerate_kept(&clear, &shells, count)?;
    check_vertex_gaps(vertices, limits.merge)?;
    Ok(shells)
}

/// Every vertex used, no corner repeated, no triangle repeated; whether each triangle's
/// area is clearly above the degenerate limit.
fn check_faces(vertices: &[Vec3], faces: &[[u32; 3]], limits: &TidyLimits) -> Result<Vec<bool>, &'static str> {
    let mut used = vec![false; vertices.len()];
    let mut seen: FastSet<[u32; 3]> = FastSet::with_capacity_and_hasher(faces.len(), Default::default());
    let mut clear = Vec::with_capacity(faces.len());
    for f in faces {
        if f[0] == f[1] || f[1] == f[2] || f[2] == f[0] {
            return Err("a triangle repeats a corner");
        }
        let mut sorted = *f;
        sorted.sort_unstable();
        if !seen.insert(sorted) {
            return Err("a triangle repeats another's corners");
        }
        let [a, b, c] = f.map(|i| vertices[i as usize]);
        clear.push(0.5 * (b - a).cross(c - a).length() > limits.degenerate_area * (1.0 + SLACK));
        f.iter().for_each(|&i| used[i as usize] = true);
    }
    if used.contains(&false) {
        return Err("a vertex is not used");
    }
    Ok(clear)
}

/// The components of triangles over shared edges (numbered in order of their first
/// triangle) and how many there are, when every directed edge is used once and its
/// reverse once.
fn shells_over_edges(faces: &[[u32; 3]]) -> Result<(Vec<u32>, usize), &'static str> {
    let mut owner: FastMap<(u32, u32), usize> = FastMap::with_capacity_and_hasher(3 * faces.len(), Default::default());
    for (i, f) in faces.iter().enumerate() {
        for k in 0..3 {
            if owner.insert((f[k], f[(k + 1) % 3]), i).is_some() {
                return Err("a directed edge is used twice");
            }
        }
    }
    let mut sets = UnionFind::new(faces.len());
    for (&(a, b), &i) in &owner {
        let &j = owner.get(&(b, a)).ok_or("an edge is not used once in each direction")?;
        sets.union(i, j);
    }
    let mut number: FastMap<usize, u32> = FastMap::default();
    let shells = (0..faces.len())
        .map(|i| {
            let root = sets.find(i);
            let next = number.len() as u32;
            *number.entry(root).or_insert(next)
        })
        .collect();
    Ok((shells, number.len()))
}

/// Every shell encloses a positive volume above the flat limit.
fn check_volumes(vertices: &[Vec3], faces: &[[u32; 3]], shells: &[u32], count: usize, limits: &TidyLimits) -> Result<(), &'static str> {
    let centre = vertices.iter().fold(Vec3::ZERO, |s, &v| s + v) / vertices.len() as f64;
    let mut six_volumes = vec![0.0; count];
    for (f, &k) in faces.iter().zip(shells) {
        let [a, b, c] = f.map(|i| vertices[i as usize] - centre);
        six_volumes[k as usize] += a.dot(b.cross(c));
    }
    if six_volumes.iter().any(|&v| v / 6.0 <= limits.zero_volume * (1.0 + SLACK)) {
        return Err("a shell is flat or inside out");
    }
    Ok(())
}

/// Every shell has a triangle clearly above the degenerate limit. The cleaning drops
/// degenerate triangles only where the surface stays closed without them; a shell's
/// edges are each shared by two of its triangles ([`shells_over_edges`]) and it is connected,
/// so with a triangle of each kind some edge joins the two and dropping the degenerate
/// ones would open it: the cleaning keeps them.
fn check_degenerate_kept(clear: &[bool], shells: &[u32], count: usize) -> Result<(), &'static str> {
    let mut has_clear = vec![false; count];
    clear.iter().zip(shells).filter(|(&c, _)| c).for_each(|(_, &k)| has_clear[k as usize] = true);
    if has_clear.contains(&false) {
        return Err("a shell is all degenerate triangles");
    }
    Ok(())
}

/// No two vertices within the merge distance (a grid of cells that wide).
fn check_vertex_gaps(vertices: &[Vec3], merge: f64) -> Result<(), &'static str> {
    let reach = merge * (1.0 + SLACK);
    let cell_of = |p: Vec3| (p / reach).floor();
    if reach.is_nan() || reach <= 0.0 || vertices.iter().any(|&p| cell_of(p).abs().max_element() > 1e15) {
        return Err("the merge distance is below the coordinates' rounding");
    }
    let key = |c: Vec3| [c.x as i64, c.y as i64, c.z as i64];
    let mut grid: FastMap<[i64; 3], Vec<u32>> = FastMap::with_capacity_and_hasher(vertices.len(), Default::default());
    for (i, &p) in vertices.iter().enumerate() {
        grid.entry(key(cell_of(p))).or_default().push(i as u32);
    }
    for (i, &p) in vertices.iter().enumerate() {
        let [x, y, z] = key(cell_of(p));
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let near = grid.get(&[x + dx, y + dy, z + dz]).into_iter().flatten();
                    if near.filter(|&&j| j as usize != i).any(|&j| (vertices[j as usize] - p).length() <= reach) {
                        return Err("two vertices lie within the merge distance");
                    }
                }
            }
        }
    }
    Ok(())
}

/// The windings of a tidy mesh ([`TriMesh::checked_windings`]'s) when it is a solid,
/// `None` when it is not tidy or no solid (the caller's full cleaning and checks then say
/// why).
pub fn tidy_windings(vertices: Vec<Vec3>, faces: &[[u32; 3]], limits: &TidyLimits, what: &str) -> Option<Windings> {
    let shells = tidy_shells(&vertices, faces, limits).ok()?;
    let mesh = TriMesh { closed: true, ..TriMesh::surface(vertices, faces, what).ok()? };
    if mesh.faces_itself(&shells, limits) {
        return None;
    }
    let crossings = mesh.crossings();
    let windings = mesh.windings_with(&crossings, what);
    windings.solid.is_ok().then_some(windings)
}

/// A generic direction that sorts normals into those pointing up and down along it
/// ([`TriMesh::faces_itself`]).
const SIGN_DIRECTION: [f64; 3] = [0.577_350_269_189_625_8, 0.618_033_988_749_894_8, 0.532_088_886_237_956_1];

/// Pairs [`TriMesh::faces_itself`] compares per triangle, beyond which it gives up and
/// answers yes (the full cleaning then looks).
const FACING_PAIRS_PER_TRIANGLE: usize = 16;

impl TriMesh {
    /// Whether two triangles of one shell (`shells`, from [`tidy_shells`]) face opposite
    /// ways within the fold angle with one's centroid within the coplanar distance of the
    /// other's plane: the pairs among which the cleaning looks for a surface that overlaps
    /// itself (`planner.meshes.solids._self_overlaps`). Also yes when there are too many
    /// pairs to compare.
    ///
    /// A normal `n` pointing up along [`SIGN_DIRECTION`] `g` (or within the fold angle of
    /// across it) is listed with its plane's offset `n · c` (`c` the centroid, from the
    /// box's centre), one pointing down (or nearly across) with `-n · c`. Of two opposite
    /// normals one is listed up and the other down, and their two offsets differ by at most
    /// the coplanar distance plus the fold angle times `|c|`: each triangle listed down is
    /// compared with those listed up within that of its offset (a binary search).
    pub fn faces_itself(&self, shells: &[u32], limits: &TidyLimits) -> bool {
        let near = limits.coplanar * (1.0 + SLACK) + 1e-12 * self.aabb.diagonal();
        let opposite = -(limits.fold_angle.cos()) + 1e-9;
        let band = limits.fold_angle * (1.0 + SLACK);
        let reach = near + band * self.aabb.diagonal();
        let g = Vec3::from_array(SIGN_DIRECTION).normalize();
        let centre = self.aabb.center();
        let centroid = |i: usize| (self.tris[i].p[0] + self.tris[i].p[1] + self.tris[i].p[2]) / 3.0 - centre;
        let mut up: Vec<(f64, u32)> = Vec::new();
        let mut down: Vec<(f64, u32)> = Vec::new();
        for (i, t) in self.tris.iter().enumerate().filter(|(_, t)| t.n != Vec3::ZERO) {
            let (along, offset) = (t.n.dot(g), t.n.dot(centroid(i)));
            if along >= -band {
                up.push((offset, i as u32));
            }
            if along <= band {
                down.push((-offset, i as u32));
            }
        }
        up.sort_by(|a, b| a.0.total_cmp(&b.0));
        let window = |offset: f64| up.partition_point(|e| e.0 < offset - reach)..up.partition_point(|e| e.0 <= offset + reach);
        let pairs: usize = down.iter().map(|&(offset, _)| window(offset).len()).sum();
        if pairs > FACING_PAIRS_PER_TRIANGLE * self.tris.len() {
            return true;
        }
        let facing = |i: usize, j: usize| {
            let (ni, nj) = (self.tris[i].n, self.tris[j].n);
            let gap = centroid(j) - centroid(i);
            i != j && shells[i] == shells[j] && ni.dot(nj) < opposite && (ni.dot(gap).abs() <= near || nj.dot(gap).abs() <= near)
        };
        down.par_iter().any(|&(offset, j)| up[window(offset)].iter().any(|&(_, i)| facing(i as usize, j as usize)))
    }
}
