//! Closed shells of a mesh, and the witness that a connected part of one mesh crosses a
//! closed shell of the other at every translation of a box.
//!
//! A set of triangles in which every edge (vertices welded by their exact coordinates) is
//! used an even number of times is closed mod 2: the parity of the number of its
//! triangles a ray from a point crosses does not depend on the ray, is constant off the
//! surface and changes across it ([`TriMesh::parity`]). Orientation does not matter, so
//! shells glued inside out, or sharing caps (OMPL.app's ring in `escape`: eight tube
//! segments, each closed by caps it shares with its neighbours), still bound an odd
//! region.
//!
//! If a connected set `K` of one mesh's triangles holds a point `x` in the odd region of a
//! shell `S` of the other mesh and a point `y` outside `S`'s box, every path in `K` from
//! `x` to `y` crosses `S`: the meshes' triangles meet, a collision as FCL sees surfaces
//! (and as solids do). For a box `bx` of translations `p` (the source's terms: `A_k` meets
//! `p − B`) that holds at every `p` when the box `bx − x` lies in the odd region and
//! `bx − y` misses the shell's box — with `x`, `y` on `A_k` and `S` in `B`, or `x`, `y` on
//! `B` and `S` in `A_k`. Unlike a nested vertex, `x` may be any point of the surface (the
//! middle of a long triangle) and neither mesh need be a solid; unlike one triangle-pair
//! piece, the box may be as wide as the shell is thick.
//!
//! Shells: patches (triangles joined across edges used exactly twice), the closed ones as
//! they are and the open ones summed mod 2 where their boundaries cancel (elimination over
//! GF(2), smallest patches first), plus the sum of all those sums (OMPL.app's ring whole,
//! its shared caps cancelled). Each gets a lattice of
//! points in its odd region with their distance to it (balls inside it), from which a
//! box's `x` is found by walking the other mesh's BVH; the witness is then tested exactly
//! (no triangle of the shell meets `bx − x`, the parity at its centre is odd).
//!
//! Entry points: [`Shells::of`], [`Shells::pierce`].

use super::mesh::TriMesh;
use crate::math::{Aabb, Vec3};
use crate::polytope::closest_on_triangle;
use crate::util::UnionFind;
use rayon::prelude::*;
use std::collections::HashMap;

/// Open patches summed at most (the elimination is quadratic in them); with more, only
/// closed patches are shells.
const MAX_OPEN_PATCHES: usize = 512;

/// Shells kept per mesh at most (those of the most triangles).
const MAX_SHELLS: usize = 32;

/// Fewest triangles of a shell (a tetrahedron).
const MIN_SHELL_TRIANGLES: usize = 4;

/// Lattice points per shell triangle, and their bounds per shell.
const POINTS_PER_TRIANGLE: usize = 8;
const MIN_POINTS: usize = 512;
const MAX_POINTS: usize = 16_384;

/// Lattice points per side of a block whose deepest point prunes the search.
const BLOCK: usize = 4;

/// BVH nodes of the other mesh visited per shell and box at most.
const MAX_VISITS: usize = 4096;

/// Lattice points tried against the other mesh's triangles per shell and box at most.
const MAX_POINT_TESTS: usize = 4096;

/// A closed shell (mod 2) of a mesh, with balls inside its odd region.
#[derive(Debug)]
pub struct Shell {
    /// Its triangles: indices into the mesh's triangles.
    pub tris: Vec<u32>,
    /// Those triangles as a surface (its BVH for the box, ray and distance tests).
    pub mesh: TriMesh,
    lattice: Lattice,
}

/// Points of a regular lattice over a shell's box, each with the radius of a ball about
/// it inside the odd region (0 for points outside it or on the surface).
#[derive(Debug)]
struct Lattice {
    origin: Vec3,
    step: f64,
    dims: [usize; 3],
    radius: Vec<f32>,
    /// Per block of [`BLOCK`]³ points, its largest radius.
    block_dims: [usize; 3],
    block_radius: Vec<f32>,
    largest: f64,
}

/// A mesh's closed shells and connected parts.
#[derive(Debug)]
pub struct Shells {
    /// The shells, most triangles first.
    pub shells: Vec<Shell>,
    /// The connected part (triangles sharing a vertex, welded) of each triangle.
    part: Vec<u32>,
    /// Per part, its vertices of least and greatest x, y and z.
    far: Vec<[Vec3; 6]>,
}

/// A box shown blocked by a shell of one mesh and a connected part of the other: `x` on the
/// other mesh's triangle `tri` with `bx − x` in the shell's odd region, `y` a vertex of
/// the same part with `bx − y` outside the shell's box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pierce {
    /// The shell (index into [`Shells::shells`]).
    pub shell: usize,
    /// The point inside.
    pub x: Vec3,
    /// The other mesh's triangle holding `x`.
    pub tri: usize,
    /// The vertex outside.
    pub y: Vec3,
}

impl Shells {
    /// The closed shells and connected parts of `mesh` (see the module documentation).
    pub fn of(mesh: &TriMesh) -> Shells {
        let welded = weld(&mesh.vertices);
        let (part, far) = parts(mesh, &welded);
        let shells = closed_shells(&mesh.vertices, &mesh.faces).into_par_iter().filter_map(|tris| Shell::new(mesh, tris)).collect();
        Shells { shells, part, far }
    }

    /// A shell of these and a point of `other` (whose parts are `others`) that show every
    /// translation `p` of `bx` blocked: `bx − x` in the shell's odd region, `bx − y`
    /// outside its box (see the module documentation).
    pub fn pierce(&self, bx: &Aabb, other: &TriMesh, others: &Shells) -> Option<Pierce> {
        let (c, r) = (bx.center(), bx.half().length());
        let slack = 1e-9 * (other.aabb.diagonal() + c.abs().max_element() + bx.extent().max_element());
        self.shells.iter().enumerate().filter(|(_, s)| s.lattice.largest > r).find_map(|(si, s)| {
            let outside = |y: Vec3| !Aabb::new(bx.min - y, bx.max - y).inflated(slack).overlaps(&s.mesh.aabb);
            // each part's vertex outside first (cheap): a part with none is not searched
            let far: Vec<Option<Vec3>> = others.far.iter().map(|f| f.iter().copied().find(|&y| outside(y))).collect();
            if far.iter().all(Option::is_none) {
                return None;
            }
            let far_of = |tri: usize| far[others.part[tri] as usize];
            let found = s.lattice.search(
                other,
                c,
                r,
                |tri| far_of(tri).is_some(),
                |x, tri| {
                    let probe = Aabb::new(bx.min - x, bx.max - x).inflated(slack);
                    if s.mesh.meets_box(&probe) || s.mesh.parity(probe.center()) != Some(true) {
                        return None;
                    }
                    far_of(tri)
                },
            )?;
            Some(Pierce { shell: si, x: found.0, tri: found.1, y: found.2 })
        })
    }
}

impl Shell {
    /// The shell of `mesh`'s triangles `tris`, with its lattice; `None` when its odd
    /// region holds no lattice point.
    fn new(mesh: &TriMesh, tris: Vec<u32>) -> Option<Shell> {
        let mut index: HashMap<u32, u32> = HashMap::new();
        let mut vertices = Vec::new();
        let faces: Vec<[u32; 3]> = tris
            .iter()
            .map(|&t| {
                mesh.faces[t as usize].map(|v| {
                    *index.entry(v).or_insert_with(|| {
                        vertices.push(mesh.vertices[v as usize]);
                        vertices.len() as u32 - 1
                    })
                })
            })
            .collect();
        let surface = TriMesh::surface(vertices, &faces, "shell").ok()?;
        let lattice = Lattice::new(&surface, tris.len());
        (lattice.largest > 0.0).then_some(Shell { tris, mesh: surface, lattice })
    }
}

impl Lattice {
    /// The lattice over the shell's box, about `POINTS_PER_TRIANGLE` points per triangle.
    fn new(shell: &TriMesh, triangles: usize) -> Lattice {
        let b = shell.aabb;
        let ext = b.extent().max(Vec3::splat(1e-12 * b.diagonal().max(1e-300)));
        let want = (triangles * POINTS_PER_TRIANGLE).clamp(MIN_POINTS, MAX_POINTS) as f64;
        let step = (ext.x * ext.y * ext.z / want).cbrt().max(ext.max_element() / 128.0);
        let count = |e: f64| ((e / step).floor() as usize).max(1);
        let dims = [count(ext.x), count(ext.y), count(ext.z)];
        // points at the centres of `dims` cells of side `step`, centred in the box
        let used = Vec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) * step;
        let origin = b.center() - used * 0.5 + Vec3::splat(0.5 * step);
        let n = dims[0] * dims[1] * dims[2];
        let radius: Vec<f32> = (0..n)
            .into_par_iter()
            .map(|i| {
                let q = origin + Vec3::new((i % dims[0]) as f64, (i / dims[0] % dims[1]) as f64, (i / (dims[0] * dims[1])) as f64) * step;
                match shell.parity(q) {
                    Some(true) => (distance(shell, q) * (1.0 - 1e-6)) as f32,
                    _ => 0.0,
                }
            })
            .collect();
        let block_dims = dims.map(|d| d.div_ceil(BLOCK));
        let mut block_radius = vec![0.0f32; block_dims[0] * block_dims[1] * block_dims[2]];
        for (i, &rad) in radius.iter().enumerate() {
            let [x, y, z] = [i % dims[0], i / dims[0] % dims[1], i / (dims[0] * dims[1])].map(|v| v / BLOCK);
            let slot = &mut block_radius[x + block_dims[0] * (y + block_dims[1] * z)];
            *slot = slot.max(rad);
        }
        let largest = radius.iter().copied().fold(0.0f32, f32::max) as f64;
        Lattice { origin, step, dims, radius, block_dims, block_radius, largest }
    }

    /// The lattice points' index ranges (inclusive) within the box `q`, or `None`.
    fn range(&self, q: &Aabb) -> Option<[[usize; 2]; 3]> {
        let mut out = [[0usize; 2]; 3];
        for (axis, o) in out.iter_mut().enumerate() {
            let lo = ((q.min[axis] - self.origin[axis]) / self.step).ceil().max(0.0);
            let hi = ((q.max[axis] - self.origin[axis]) / self.step).floor().min(self.dims[axis] as f64 - 1.0);
            if hi < lo {
                return None;
            }
            *o = [lo as usize, hi as usize];
        }
        Some(out)
    }

    /// Calls `f` on each block of lattice points within the index ranges `range` whose
    /// points can hold a box of half-diagonal `r` moved by a point of `moved` (the box
    /// `c − x` over the other mesh's points `x` at hand): its largest radius above `r`, and
    /// within that radius less `r` of `moved`. Stops when `f` says so; whether it did.
    fn blocks(&self, range: &[[usize; 2]; 3], moved: &Aabb, r: f64, mut f: impl FnMut([usize; 3]) -> bool) -> bool {
        for z in range[2][0] / BLOCK..=range[2][1] / BLOCK {
            for y in range[1][0] / BLOCK..=range[1][1] / BLOCK {
                for x in range[0][0] / BLOCK..=range[0][1] / BLOCK {
                    let rad = self.block_radius[x + self.block_dims[0] * (y + self.block_dims[1] * z)] as f64;
                    if rad > r && box_gap(&self.block_box([x, y, z]), moved) + r <= rad && f([x, y, z]) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// The box of the lattice points of block `b`.
    fn block_box(&self, b: [usize; 3]) -> Aabb {
        let lo = b.map(|v| (v * BLOCK) as f64);
        let hi = [0, 1, 2].map(|a| ((b[a] * BLOCK + BLOCK).min(self.dims[a]) - 1) as f64);
        Aabb::new(self.origin + Vec3::from_array(lo) * self.step, self.origin + Vec3::from_array(hi) * self.step)
    }

    /// A point `x` of `other` (on its triangle `tri`, one that is `usable`) and a lattice
    /// point `m` with `|c − x − m| + r ≤ radius(m)` (the box of half-diagonal `r` about
    /// `c`, moved by `−x`, inside the ball about `m`) that `accept` takes, returning its
    /// vertex `y`. At
    /// most [`MAX_VISITS`] nodes and [`MAX_POINT_TESTS`] lattice points are tried.
    fn search(&self, other: &TriMesh, c: Vec3, r: f64, usable: impl Fn(usize) -> bool, accept: impl Fn(Vec3, usize) -> Option<Vec3>) -> Option<(Vec3, usize, Vec3)> {
        let mut stack = vec![0u32];
        let (mut visits, mut tests) = (0usize, 0usize);
        while let Some(ni) = stack.pop() {
            visits += 1;
            if visits > MAX_VISITS || tests > MAX_POINT_TESTS {
                return None;
            }
            let node = &other.nodes[ni as usize];
            // where c − x lies for the node's points x, and the lattice points in reach
            let moved = Aabb::new(c - node.aabb.max, c - node.aabb.min);
            let Some(range) = self.range(&moved.inflated(self.largest - r)) else { continue };
            if !node.is_leaf() {
                if self.blocks(&range, &moved, r, |_| true) {
                    stack.extend([node.left + 1, node.left]);
                }
                continue;
            }
            let (tri, p) = (node.tri as usize, other.tris[node.tri as usize].p);
            if !usable(tri) {
                continue;
            }
            let mut found = None;
            self.blocks(&range, &moved, r, |b| {
                found = self.in_block(b, &range, p, c, r, &mut tests).and_then(|x| accept(x, tri).map(|y| (x, tri, y)));
                found.is_some() || tests > MAX_POINT_TESTS
            });
            if found.is_some() {
                return found;
            }
        }
        None
    }

    /// The point of the triangle `p` nearest `c − m` for the first lattice point `m` of
    /// block `b` (within `range`) whose ball holds the box moved there; `tests` counts the
    /// points tried.
    fn in_block(&self, b: [usize; 3], range: &[[usize; 2]; 3], p: [Vec3; 3], c: Vec3, r: f64, tests: &mut usize) -> Option<Vec3> {
        let span = |a: usize| (b[a] * BLOCK).max(range[a][0])..=(b[a] * BLOCK + BLOCK - 1).min(range[a][1]);
        for z in span(2) {
            for y in span(1) {
                for x in span(0) {
                    let rad = self.radius[x + self.dims[0] * (y + self.dims[1] * z)] as f64;
                    if rad <= r {
                        continue;
                    }
                    *tests += 1;
                    let m = self.origin + Vec3::new(x as f64, y as f64, z as f64) * self.step;
                    let target = c - m;
                    let near = closest_on_triangle(target, p[0], p[1], p[2]);
                    if (target - near).length() + r <= rad {
                        return Some(near);
                    }
                }
            }
        }
        None
    }
}

/// The distance between two boxes (0 when they overlap).
fn box_gap(a: &Aabb, b: &Aabb) -> f64 {
    (a.min - b.max).max(b.min - a.max).max(Vec3::ZERO).length()
}

/// The distance from `q` to the nearest triangle of `mesh` (its BVH, nearer nodes first).
fn distance(mesh: &TriMesh, q: Vec3) -> f64 {
    let mut best = f64::INFINITY;
    let mut stack = vec![0u32];
    while let Some(ni) = stack.pop() {
        let n = &mesh.nodes[ni as usize];
        if n.aabb.distance_to_point(q) >= best {
            continue;
        }
        if n.is_leaf() {
            let t = &mesh.tris[n.tri as usize];
            best = best.min((q - closest_on_triangle(q, t.p[0], t.p[1], t.p[2])).length());
            continue;
        }
        let (l, r) = (n.left, n.left + 1);
        let (dl, dr) = (mesh.nodes[l as usize].aabb.distance_to_point(q), mesh.nodes[r as usize].aabb.distance_to_point(q));
        // the nearer child popped first
        if dl <= dr {
            stack.extend([r, l]);
        } else {
            stack.extend([l, r]);
        }
    }
    best
}

/// The triangle sets (sorted indices into `faces`) of the closed shells (mod 2) of a mesh,
/// at most [`MAX_SHELLS`], those of the most triangles first (see the module
/// documentation).
pub fn closed_shells(vertices: &[Vec3], faces: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut sets = shell_sets(faces, &weld(vertices));
    sets.sort_by_key(|s| std::cmp::Reverse(s.len()));
    sets.truncate(MAX_SHELLS);
    sets
}

/// Each vertex's welded id: vertices of equal coordinates share one.
pub(crate) fn weld(vertices: &[Vec3]) -> Vec<u32> {
    let mut ids: HashMap<[u64; 3], u32> = HashMap::with_capacity(vertices.len());
    vertices
        .iter()
        .map(|v| {
            let key = v.to_array().map(|x| (x + 0.0).to_bits()); // -0.0 welds with 0.0
            let next = ids.len() as u32;
            *ids.entry(key).or_insert(next)
        })
        .collect()
}

/// The connected part of each triangle (sharing a welded vertex) and each part's extreme
/// vertices.
fn parts(mesh: &TriMesh, welded: &[u32]) -> (Vec<u32>, Vec<[Vec3; 6]>) {
    let mut sets = UnionFind::new(welded.len());
    for f in &mesh.faces {
        let [a, b, c] = f.map(|v| welded[v as usize] as usize);
        sets.union(a, b);
        sets.union(a, c);
    }
    let mut id: HashMap<usize, u32> = HashMap::new();
    let mut far: Vec<[Vec3; 6]> = Vec::new();
    let part = mesh
        .faces
        .iter()
        .map(|f| {
            let root = sets.find(welded[f[0] as usize] as usize);
            let next = id.len() as u32;
            let p = *id.entry(root).or_insert(next);
            if p as usize == far.len() {
                far.push([mesh.vertices[f[0] as usize]; 6]);
            }
            for &v in f {
                let v = mesh.vertices[v as usize];
                let e = &mut far[p as usize];
                for axis in 0..3 {
                    if v[axis] < e[2 * axis][axis] {
                        e[2 * axis] = v;
                    }
                    if v[axis] > e[2 * axis + 1][axis] {
                        e[2 * axis + 1] = v;
                    }
                }
            }
            p
        })
        .collect();
    (part, far)
}

/// The triangle sets of the mesh's closed shells (mod 2): closed patches, and sums of
/// open patches whose boundaries cancel, plus the sum of all those sums (not of the
/// closed patches).
fn shell_sets(faces: &[[u32; 3]], welded: &[u32]) -> Vec<Vec<u32>> {
    let nf = faces.len();
    // every (edge, triangle), edges as welded vertex pairs, sorted by edge
    let mut uses: Vec<(u64, u32)> = Vec::with_capacity(3 * nf);
    for (t, f) in faces.iter().enumerate() {
        let w = f.map(|v| welded[v as usize]);
        for k in 0..3 {
            let (a, b) = (w[k], w[(k + 1) % 3]);
            if a != b {
                uses.push(((a.min(b) as u64) << 32 | a.max(b) as u64, t as u32));
            }
        }
    }
    uses.sort_unstable();
    let runs: Vec<&[(u64, u32)]> = uses.chunk_by(|x, y| x.0 == y.0).collect();
    // patches: triangles joined across edges used exactly twice
    let mut sets = UnionFind::new(nf);
    for run in runs.iter().filter(|r| r.len() == 2) {
        sets.union(run[0].1 as usize, run[1].1 as usize);
    }
    let mut id: HashMap<usize, usize> = HashMap::new();
    let patch: Vec<usize> = (0..nf)
        .map(|t| {
            let next = id.len();
            *id.entry(sets.find(t)).or_insert(next)
        })
        .collect();
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); id.len()];
    for (t, &p) in patch.iter().enumerate() {
        members[p].push(t as u32);
    }
    // each patch's boundary: the edges it uses an odd number of times
    let mut boundary: Vec<Vec<u64>> = vec![Vec::new(); members.len()];
    for run in &runs {
        let mut seen: Vec<(usize, usize)> = Vec::new();
        for &(_, t) in run.iter() {
            let p = patch[t as usize];
            match seen.iter_mut().find(|(q, _)| *q == p) {
                Some(entry) => entry.1 += 1,
                None => seen.push((p, 1)),
            }
        }
        for (p, n) in seen {
            if n % 2 == 1 {
                boundary[p].push(run[0].0);
            }
        }
    }
    let mut out: Vec<Vec<usize>> = (0..members.len()).filter(|&p| boundary[p].is_empty()).map(|p| vec![p]).collect();
    let mut open: Vec<usize> = (0..members.len()).filter(|&p| !boundary[p].is_empty()).collect();
    if open.len() <= MAX_OPEN_PATCHES {
        open.sort_by_key(|&p| members[p].len());
        let cycles = cancelling_sums(open.iter().map(|&p| (boundary[p].clone(), vec![p])).collect());
        if cycles.len() >= 2 {
            let total = cycles.iter().fold(Vec::new(), |acc, c| xor_sorted(&acc, c));
            if !total.is_empty() && !cycles.contains(&total) {
                out.push(total);
            }
        }
        out.extend(cycles);
    }
    out.into_iter()
        .map(|ps| {
            let mut tris: Vec<u32> = ps.iter().flat_map(|&p| members[p].iter().copied()).collect();
            tris.sort_unstable();
            tris
        })
        .filter(|tris| tris.len() >= MIN_SHELL_TRIANGLES)
        .collect()
}

/// The sums (sorted patch lists) of rows `(boundary, patches)` whose boundaries cancel:
/// Gaussian elimination over GF(2), each row reduced by the earlier pivots (on its
/// largest edge); a row reduced to nothing is a closed sum.
fn cancelling_sums(rows: Vec<(Vec<u64>, Vec<usize>)>) -> Vec<Vec<usize>> {
    let mut pivots: HashMap<u64, (Vec<u64>, Vec<usize>)> = HashMap::new();
    let mut sums = Vec::new();
    for (mut edges, mut patches) in rows {
        edges.sort_unstable();
        while let Some(&top) = edges.last() {
            match pivots.get(&top) {
                Some((e, p)) => {
                    edges = xor_sorted(&edges, e);
                    patches = xor_sorted(&patches, p);
                }
                None => break,
            }
        }
        match edges.last() {
            Some(&top) => {
                pivots.insert(top, (edges, patches));
            }
            None => sums.push(patches),
        }
    }
    sums
}

/// The symmetric difference of two sorted lists.
fn xor_sorted<T: Ord + Copy>(a: &[T], b: &[T]) -> Vec<T> {
    let (mut i, mut j) = (0, 0);
    let mut out = Vec::with_capacity(a.len() + b.len());
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => {
                out.push(a[i]);
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                out.push(b[j]);
                j += 1;
            }
            std::cmp::Ordering::Equal => {
                i += 1;
                j += 1;
            }
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}
