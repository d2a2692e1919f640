//! [`InsideGrid`]: which voxels of a uniform grid over a solid mesh lie inside it, each
//! found exactly the first time it is asked and kept, so that "does this box lie in the
//! solid?" is mostly answered by a few lookups instead of a BVH query and a ray cast.
//!
//! The nested-vertex test of the exact source ([`super::ExactSource::vertex_nested`]) asks
//! that for a cell translated by the vertices of the other part: a cell is FULL when one
//! vertex of the robot lies inside a solid obstacle at every translation of the cell. With
//! a few exact tests per cell only a sample of the vertices could be asked; with the grid
//! far more can be (walking the part's BVH, whole nodes at once), and the C-obstacle's
//! interior where the parts cross each other (a union of many triangle-pair pieces, none
//! of which alone covers a cell) becomes FULL at the cell size of that crossing instead
//! of at the size of the pieces.
//!
//! A voxel is *inside* when no triangle meets the closed voxel and its centre is inside
//! (then all of it is: the boundary is never crossed), *outside* when no triangle meets it
//! and its centre is outside, else *boundary*. A box is inside the solid when every voxel
//! it overlaps is inside, or when one is and no triangle meets the box (a BVH query: the
//! two are connected and the boundary is not crossed); outside when every one is outside;
//! not inside when one is outside; when all are on the boundary the grid does not tell.
//! These answers are exact.
//! The grid has levels of voxels twice as large, each classified the same way, so that a
//! box is asked on the level where it overlaps a few voxels.

use super::mesh::TriMesh;
use crate::math::{Aabb, Vec3};
use std::sync::atomic::{AtomicU8, Ordering};

/// Voxels of the finest levels of all the grids of one source (one byte each; the coarser
/// levels add a seventh), shared among them: 2.3 MB in all, and [`MIN_VOXELS`] more per
/// grid at most.
pub const MAX_VOXELS: usize = 1 << 21;

/// Voxels of the finest level of one grid at least (a small solid among large ones).
const MIN_VOXELS: usize = 1 << 15;

/// Voxels along the mesh's longest side at most, on the finest level.
const SIDE_VOXELS: f64 = 256.0;

/// A box is asked on the finest level where it overlaps at most this many voxels along
/// each axis.
const MAX_SPAN: usize = 3;

const UNKNOWN: u8 = 0;
const INSIDE: u8 = 1;
const OUTSIDE: u8 = 2;
const BOUNDARY: u8 = 3;

/// How a box lies against the solid, as far as the grid tells from the voxels it
/// overlaps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Span {
    /// In the solid (every voxel inside).
    Inside,
    /// Outside the solid, not even touching it (every voxel outside).
    Outside,
    /// Across the boundary (some voxel inside, some outside).
    Crossing,
    /// Some voxel inside, the others on the boundary: in the solid exactly when no
    /// triangle meets the box (the box and that voxel are connected and would not cross
    /// the boundary).
    TouchesInside,
    /// Some voxel outside, the others on the boundary: not in the solid.
    TouchesOutside,
    /// Every voxel on the boundary, or the box too large to ask.
    Unknown,
}

/// The voxels of a solid, classified on demand, on levels of doubling size (see the
/// module documentation).
#[derive(Debug)]
pub struct InsideGrid {
    origin: Vec3,
    levels: Vec<Level>,
}

/// One level of an [`InsideGrid`]: cubic voxels of side `size`.
#[derive(Debug)]
struct Level {
    size: f64,
    dims: [usize; 3],
    state: Vec<AtomicU8>,
}

impl Level {
    fn new(ext: Vec3, size: f64) -> Level {
        let dims = Level::dims(ext, size);
        Level { size, dims, state: (0..dims.iter().product()).map(|_| AtomicU8::new(UNKNOWN)).collect() }
    }

    /// Voxels along each axis of a box of extent `ext`.
    fn dims(ext: Vec3, size: f64) -> [usize; 3] {
        ext.to_array().map(|e| ((e / size).ceil() as usize).max(1))
    }
}

impl InsideGrid {
    /// The grid over the box of the solid `mesh`: cubic voxels, at most [`SIDE_VOXELS`]
    /// along its longest side and `voxels` (no less than [`MIN_VOXELS`]) on the finest
    /// level, doubling up to one voxel; nothing classified yet.
    pub fn new(mesh: &TriMesh, voxels: usize) -> InsideGrid {
        debug_assert!(mesh.solid, "an inside grid of a surface");
        let most = voxels.max(MIN_VOXELS);
        let ext = mesh.aabb.extent().max(Vec3::splat(f64::MIN_POSITIVE));
        let by_side = ext.max_element() / SIDE_VOXELS;
        let by_count = (ext.x * ext.y * ext.z / most as f64).cbrt();
        let mut size = by_side.max(by_count).max(f64::MIN_POSITIVE);
        while Level::dims(ext, size).iter().product::<usize>() > most {
            size *= 1.01; // rounding of the ceilings
        }
        let mut levels = vec![Level::new(ext, size)];
        while levels.last().is_some_and(|l| l.state.len() > 1) {
            levels.push(Level::new(ext, 2.0 * levels.last().map_or(size, |l| l.size)));
        }
        InsideGrid { origin: mesh.aabb.min, levels }
    }

    /// How the closed box `b` lies against the solid `mesh` (the grid's own), from the
    /// voxels it overlaps on the finest level where they are at most [`MAX_SPAN`] along
    /// each axis (none: [`Span::Unknown`]); what lies beyond the mesh's box counts as an
    /// outside voxel.
    pub fn span(&self, mesh: &TriMesh, b: &Aabb) -> Span {
        let bounds = &mesh.aabb;
        if !b.overlaps(bounds) {
            return Span::Outside;
        }
        let within = bounds.contains_point(b.min) && bounds.contains_point(b.max);
        let (lo, hi) = (b.min.max(bounds.min), b.max.min(bounds.max));
        // no level of voxels smaller than a third of the box's longest side: it spans more
        // than three of them
        let first = ((hi - lo).max_element() / (MAX_SPAN as f64 * self.levels[0].size)).log2().ceil().max(0.0) as usize;
        for (l, level) in self.levels.iter().enumerate().skip(first) {
            let Some((vlo, vhi)) = self.covering(l, lo).zip(self.covering(l, hi)) else {
                return Span::Unknown;
            };
            if (0..3).any(|a| vhi[a] + 1 - vlo[a] > MAX_SPAN) {
                continue;
            }
            let (mut inside, mut outside, mut boundary) = (false, !within, false);
            for i in vlo[0]..=vhi[0] {
                for j in vlo[1]..=vhi[1] {
                    for k in vlo[2]..=vhi[2] {
                        match self.voxel(mesh, level, [i, j, k]) {
                            INSIDE => inside = true,
                            OUTSIDE => outside = true,
                            _ => boundary = true,
                        }
                        if inside && outside {
                            return Span::Crossing;
                        }
                    }
                }
            }
            return match (inside, outside, boundary) {
                (true, false, false) => Span::Inside,
                (false, true, false) => Span::Outside,
                (true, false, true) => Span::TouchesInside,
                (false, true, _) => Span::TouchesOutside,
                _ => Span::Unknown,
            };
        }
        Span::Unknown
    }

    /// Whether the closed box `b` lies in the solid `mesh`, as [`TriMesh::contains_box`]
    /// says, from the grid ([`InsideGrid::span`]) and, where it does not tell, a BVH query
    /// for a box touching an inside voxel (while `queries` last, decremented); `None` when
    /// neither told.
    pub fn box_inside(&self, mesh: &TriMesh, b: &Aabb, queries: &mut usize) -> Option<bool> {
        match self.span(mesh, b) {
            Span::Inside => Some(true),
            Span::Outside | Span::Crossing | Span::TouchesOutside => Some(false),
            Span::TouchesInside if *queries > 0 => {
                *queries -= 1;
                Some(!mesh.meets_box(b))
            }
            Span::TouchesInside | Span::Unknown => None,
        }
    }

    /// A voxel of level `l` whose closed box (as [`InsideGrid::voxel_box`] computes it)
    /// holds `p`, a point of the mesh's box (`None` if rounding left `p` past the last).
    fn covering(&self, l: usize, p: Vec3) -> Option<[usize; 3]> {
        let level = &self.levels[l];
        let v: [usize; 3] = std::array::from_fn(|a| {
            let last = level.dims[a] - 1;
            // (truncation is the floor here: the quotient is not negative, or is clamped)
            let mut i = (((p[a] - self.origin[a]) / level.size).max(0.0) as usize).min(last);
            // the division may round across a voxel face
            while i > 0 && self.lattice(level, a, i) > p[a] {
                i -= 1;
            }
            while i < last && self.lattice(level, a, i + 1) < p[a] {
                i += 1;
            }
            i
        });
        (0..3).all(|a| self.lattice(level, a, v[a]) <= p[a] && p[a] <= self.lattice(level, a, v[a] + 1)).then_some(v)
    }

    /// Coordinate `a` of the level's lattice plane `i`.
    #[inline]
    fn lattice(&self, level: &Level, a: usize, i: usize) -> f64 {
        self.origin[a] + i as f64 * level.size
    }

    fn voxel_box(&self, level: &Level, v: [usize; 3]) -> Aabb {
        let corner = |d: usize| Vec3::new(self.lattice(level, 0, v[0] + d), self.lattice(level, 1, v[1] + d), self.lattice(level, 2, v[2] + d));
        Aabb::new(corner(0), corner(1))
    }

    /// The class of voxel `v` of `level`, found exactly the first time
    /// (racing threads find the same).
    fn voxel(&self, mesh: &TriMesh, level: &Level, v: [usize; 3]) -> u8 {
        let cell = &level.state[(v[2] * level.dims[1] + v[1]) * level.dims[0] + v[0]];
        let known = cell.load(Ordering::Relaxed);
        if known != UNKNOWN {
            return known;
        }
        let b = self.voxel_box(level, v);
        let class = if mesh.meets_box(&b) {
            BOUNDARY
        } else if mesh.contains(b.center()) {
            INSIDE
        } else {
            OUTSIDE
        };
        cell.store(class, Ordering::Relaxed);
        class
    }
}
