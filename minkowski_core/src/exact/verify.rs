//! Certificates re-verified: whether a closed box lies in the solid, shown without the
//! boundary candidates.
//!
//! A no-path certificate stands on its FULL wall cells. The octree labels a cell FULL when
//! one piece contains it, or when no boundary candidate (facet) meets it and its centre is
//! inside — and the facets are complete only for solids that are what they claim to be.
//! [`ExactSource::verify_box`] shows a box blocked from the triangles alone: every part of
//! it lies in a wall slab, in one triangle-pair piece `T_i ⊕ S_j` (a contact: always in the
//! sum), in the region where a vertex of one mesh lies inside the other, solid, mesh
//! (a solid mesh containing a box: no triangle meets the box, the winding number at its
//! centre is not zero), or where a connected part of one mesh crosses a closed shell of
//! the other ([`super::shells`]: surfaces too). Boxes none of these shows are split into
//! octants, a few times.

use super::inside_grid::{InsideGrid, Span, MAX_VOXELS};
use super::mesh::TriMesh;
use super::shells::Shells;
use super::{ExactSource, Witness};
use crate::math::{Aabb, Vec3};
use std::sync::{Arc, OnceLock};

/// Octant splits of one box at most.
const MAX_SPLITS: u32 = 6;

/// Vertices per box and mesh asked exactly at most: a sample of them, or those whose
/// shifted box the inside grid cannot tell.
const NESTED_VERTICES: usize = 12;

/// Nodes of the other mesh's BVH visited per box at most (where most of its shifted boxes
/// lie near the solid's boundary, a walk to every vertex would cost more than it finds).
const NESTED_NODES: usize = 512;

/// BVH queries of the solid per box and mesh at most, for vertices whose shifted box
/// touches an inside voxel of its grid ([`InsideGrid::box_inside`]).
const NESTED_QUERIES: usize = 64;

/// Why one box lies in the C-obstacle `A_k ⊕ B`, in the parts' own coordinates: what a
/// check that trusts nothing of the core needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoxWitness {
    /// Inside the piece `a ⊕ b` of two triangles: at every `p` of the box, `a` and
    /// `p − b` meet.
    Piece {
        /// Obstacle.
        k: usize,
        /// Its triangle.
        i: usize,
        /// The triangle of `B`.
        j: usize,
        /// Corners of the obstacle's triangle.
        a: [Vec3; 3],
        /// Corners of `B`'s triangle.
        b: [Vec3; 3],
    },
    /// At every `p` of the box, the vertex `p − v` of `p − B` lies in the solid `A_k`
    /// (the box shifted by `−v` does).
    VertexOfB {
        /// Obstacle.
        k: usize,
        /// The vertex of `B`.
        v: Vec3,
    },
    /// At every `p` of the box, the vertex `v` of `A_k` lies in the solid `p − B` (the
    /// box shifted by `−v` lies in `B`).
    VertexOfA {
        /// Obstacle.
        k: usize,
        /// The obstacle's vertex.
        v: Vec3,
    },
    /// Beyond the wall `side` (= 2 · axis + upper).
    Wall {
        /// Side.
        side: usize,
    },
    /// At every `p` of the box, a connected part of one mesh crosses a closed shell of the
    /// other ([`super::shells`]): the point `x` of that part (on its triangle `tri`) lies
    /// in the shell's odd region and its vertex `y` outside the shell's box (`bx − x` in
    /// the region, `bx − y` off the box).
    Pierced {
        /// Obstacle.
        k: usize,
        /// Whether the shell is `B`'s (then `x`, `y` are the obstacle's), else the
        /// obstacle's (then `x`, `y` are `B`'s).
        shell_of_b: bool,
        /// The shell: index into the mesh's shells.
        shell: usize,
        /// The point inside.
        x: Vec3,
        /// Corners of the triangle holding `x`.
        tri: [Vec3; 3],
        /// The vertex outside.
        y: Vec3,
    },
}

impl BoxWitness {
    /// The witness without its coordinates.
    pub fn kind(&self) -> Witness {
        match *self {
            BoxWitness::Piece { k, i, j, .. } => Witness::Piece { k, i, j },
            BoxWitness::VertexOfB { k, .. } | BoxWitness::VertexOfA { k, .. } | BoxWitness::Pierced { k, .. } => Witness::Nested { k },
            BoxWitness::Wall { side } => Witness::Wall { side },
        }
    }
}

impl ExactSource {
    /// Why every point of the closed box `cell` lies in the (grown) solid, shown from the
    /// triangles alone (see the module documentation), or `None` when that cannot be shown
    /// within `budget` box tests (decremented) and a few octant splits. The witness is that
    /// of the first part shown.
    pub fn verify_box(&self, cell: &Aabb, budget: &mut usize) -> Option<Witness> {
        self.verify_box_witnesses(cell, budget).map(|parts| parts[0].1.kind())
    }

    /// [`ExactSource::verify_box`] with the witness of every part the box was split into:
    /// `(part, witness)`, the parts covering the box.
    pub fn verify_box_witnesses(&self, cell: &Aabb, budget: &mut usize) -> Option<Vec<(Aabb, BoxWitness)>> {
        let mut stack = vec![(*cell, 0u32)];
        let mut shown = Vec::new();
        while let Some((bx, depth)) = stack.pop() {
            if *budget == 0 {
                return None;
            }
            *budget -= 1;
            if let Some(w) = self.box_witness_of(&bx) {
                shown.push((bx, w));
                continue;
            }
            if depth == MAX_SPLITS {
                return None;
            }
            stack.extend(octants(&bx).map(|c| (c, depth + 1)));
        }
        Some(shown)
    }

    /// A wall slab, one piece, or one vertex nested for the whole box.
    pub(super) fn box_shown(&self, bx: &Aabb) -> Option<Witness> {
        self.box_witness_of(bx).map(|w| w.kind())
    }

    /// [`ExactSource::box_shown`] with the witness's coordinates.
    fn box_witness_of(&self, bx: &Aabb) -> Option<BoxWitness> {
        if self.walls.is_some() {
            if let Some(side) = (0..6).find(|&side| self.wall_box(side, bx).0) {
                return Some(BoxWitness::Wall { side });
            }
        }
        if let Some(Witness::Piece { k, i, j }) = self.piece_contains_box(bx) {
            return Some(BoxWitness::Piece { k, i, j, a: self.obstacles[k].tris[i].p, b: self.b.tris[j].p });
        }
        (0..self.obstacles.len()).find_map(|k| self.nested_exactly(k, bx).or_else(|| self.pierced(k, bx)))
    }

    /// A connected part of `B` or of the obstacle `k` crossing a closed shell of the other
    /// at every translation of the box ([`super::shells`]), for pairs with a surface (two
    /// solids have the nested-vertex test).
    pub(super) fn pierced(&self, k: usize, bx: &Aabb) -> Option<BoxWitness> {
        let a = &self.obstacles[k];
        if a.solid && self.b.solid {
            return None;
        }
        let (of_a, of_b) = (self.shells_of(Some(k)), self.shells_of(None));
        let found = |shells: &Shells, other: &TriMesh, others: &Shells, shell_of_b: bool| {
            shells.pierce(bx, other, others).map(|p| BoxWitness::Pierced { k, shell_of_b, shell: p.shell, x: p.x, tri: other.tris[p.tri].p, y: p.y })
        };
        found(of_b, a, of_a, true).or_else(|| found(of_a, &self.b, of_b, false))
    }

    /// The closed shells of obstacle `k` (or, `None`, of `B`), made when first asked.
    pub fn shells_of(&self, k: Option<usize>) -> &Shells {
        match k {
            Some(k) => self.shells[k].get_or_init(|| Arc::new(Shells::of(&self.obstacles[k]))),
            None => self.b_shells.get_or_init(|| Arc::new(Shells::of(&self.b))),
        }
    }

    /// [`ExactSource::vertex_nested`], its vertex's box then tested exactly (the grid's
    /// answer re-verified: a certificate does not rest on the grid).
    fn nested_exactly(&self, k: usize, bx: &Aabb) -> Option<BoxWitness> {
        let (solid, v) = self.nested_vertex(k, bx)?;
        if !solid.contains_box(&shifted(bx, v)) {
            return None;
        }
        Some(if std::ptr::eq(solid, &self.obstacles[k]) { BoxWitness::VertexOfB { k, v } } else { BoxWitness::VertexOfA { k, v } })
    }

    /// Whether at every `p` of the box a vertex of `p − B` lies in the solid `A_k` (the box
    /// `bx − b` inside `A_k` for a vertex `b` of `B`), or a vertex `a` of `A_k` lies in the
    /// solid `p − B` (`bx − a` inside `B`): then `A_k` and `p − B` meet.
    pub(super) fn vertex_nested(&self, k: usize, bx: &Aabb) -> bool {
        self.nested_vertex(k, bx).is_some()
    }

    /// The solid and the vertex `v` of the other mesh that show [`ExactSource::vertex_nested`]
    /// (`bx − v` in the solid). The vertices are asked through the solid's inside grid
    /// ([`nested_in`]) when the nested test comes first ([`ExactSource::nested_first`]: the
    /// planner's cells with a surface taken piece by piece, where it spares FULL cells
    /// their costly records); else a sample of [`NESTED_VERTICES`] vertices is asked
    /// exactly (the grid's voxels would cost more than they spare).
    fn nested_vertex(&self, k: usize, bx: &Aabb) -> Option<(&TriMesh, Vec3)> {
        let a = &self.obstacles[k];
        let nested = |solid: &TriMesh, g: &OnceLock<Arc<InsideGrid>>, other: &TriMesh| {
            if self.nested_first() {
                nested_in(solid, self.grid(g, solid), other, bx)
            } else {
                sample(other).find(|&v| solid.contains_box(&shifted(bx, v)))
            }
        };
        let in_a = if a.solid { nested(a, &self.grids[k], &self.b) } else { None };
        let in_b = || if self.b.solid { nested(&self.b, &self.b_grid, a) } else { None };
        in_a.map(|v| (a, v)).or_else(|| in_b().map(|v| (&self.b, v)))
    }

    /// The inside grid `g` of the solid `mesh`, made on first use with its share of
    /// [`MAX_VOXELS`] by the volume of its box among the solids' boxes.
    fn grid<'a>(&self, g: &'a OnceLock<Arc<InsideGrid>>, mesh: &TriMesh) -> &'a InsideGrid {
        g.get_or_init(|| {
            let volume = |m: &TriMesh| m.aabb.extent().x * m.aabb.extent().y * m.aabb.extent().z;
            let all: f64 = self.obstacles.iter().chain([&self.b]).filter(|m| m.solid).map(volume).sum();
            let share = if all > 0.0 { volume(mesh) / all } else { 1.0 };
            Arc::new(InsideGrid::new(mesh, (share * MAX_VOXELS as f64) as usize))
        })
    }
}

/// The box `bx − v`.
fn shifted(bx: &Aabb, v: Vec3) -> Aabb {
    Aabb::new(bx.min - v, bx.max - v)
}

/// The mesh's shell anchors, then corners of evenly spaced triangles (a vertex no
/// triangle uses is no part of it), [`NESTED_VERTICES`] in all at most.
fn sample(mesh: &TriMesh) -> impl Iterator<Item = Vec3> + '_ {
    let step = (mesh.tris.len() / NESTED_VERTICES).max(1);
    mesh.anchors.iter().copied().chain(mesh.tris.iter().step_by(step).map(|t| t.p[0])).take(NESTED_VERTICES)
}

/// A vertex `v` of `other` whose box `bx − v` lies in `solid`, if one is found: `other`'s BVH
/// walked with the boxes `bx − node` asked of the solid's inside grid (a node all of whose
/// shifted boxes lie inside answers yes, one all outside is skipped), each vertex of a
/// leaf asked alone ([`InsideGrid::box_inside`], with at most [`NESTED_QUERIES`] BVH
/// queries), and the first [`NESTED_VERTICES`] the grid cannot tell asked exactly; at most
/// [`NESTED_NODES`] nodes visited (then: none).
fn nested_in(solid: &TriMesh, grid: &InsideGrid, other: &TriMesh, bx: &Aabb) -> Option<Vec3> {
    let (mut queries, mut exact_left) = (NESTED_QUERIES, NESTED_VERTICES);
    let mut stack = vec![0u32];
    let mut visits = 0usize;
    while let Some(ni) = stack.pop() {
        visits += 1;
        if visits > NESTED_NODES {
            return None;
        }
        let n = &other.nodes[ni as usize];
        match grid.span(solid, &Aabb::new(bx.min - n.aabb.max, bx.max - n.aabb.min)) {
            Span::Inside => return Some(first_vertex(other, ni)),
            Span::Outside => continue,
            _ => {}
        }
        if !n.is_leaf() {
            stack.extend([n.left + 1, n.left]);
            continue;
        }
        for v in other.tris[n.tri as usize].p {
            let q = shifted(bx, v);
            let inside = match grid.box_inside(solid, &q, &mut queries) {
                Some(inside) => inside,
                None if exact_left > 0 => {
                    exact_left -= 1;
                    solid.contains_box(&q)
                }
                None => false,
            };
            if inside {
                return Some(v);
            }
        }
    }
    None
}

/// A vertex under node `ni` of the mesh's BVH (its first leaf's triangle's first corner).
fn first_vertex(mesh: &TriMesh, mut ni: u32) -> Vec3 {
    while !mesh.nodes[ni as usize].is_leaf() {
        ni = mesh.nodes[ni as usize].left;
    }
    mesh.tris[mesh.nodes[ni as usize].tri as usize].p[0]
}

/// The eight octants of a box.
pub(super) fn octants(b: &Aabb) -> impl Iterator<Item = Aabb> + '_ {
    let c = b.center();
    (0..8).map(move |i| {
        let pick = |bit: usize, axis: usize| if i >> bit & 1 == 0 { (b.min[axis], c[axis]) } else { (c[axis], b.max[axis]) };
        let (x, y, z) = (pick(0, 0), pick(1, 1), pick(2, 2));
        Aabb::new(Vec3::new(x.0, y.0, z.0), Vec3::new(x.1, y.1, z.1))
    })
}
