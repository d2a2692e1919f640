//! The free-space roadmap over the leaves of an [`Octree`](crate::octree::Octree).
//!
//! Leaves are addressed by `(level, ijk)` on the finest lattice; a hash index turns that
//! key into a leaf id, and every query below walks the lattice through it, so leaves of
//! any sizes mix freely (an octree built by [`Octree::build`](crate::octree::Octree::build),
//! [`rescale`]d to a finer lattice and locally [`refine`]d).
//!
//! Entry points:
//!
//! - [`LeafIndex`]: `(level, ijk) → leaf`, [`LeafIndex::locate`] (which leaf contains a
//!   point), [`LeafIndex::containing_cell`].
//! - [`neighbors`]: every leaf sharing a face region of positive area with a leaf, with the
//!   centre of the shared face (the portal); [`face_adjacency`]: all such pairs once,
//!   in parallel; [`shared_face`]: the shared rectangle of two leaves.
//! - [`components`]: connected components of a label set (EMPTY, or EMPTY ∪ MIXED) by
//!   union–find.
//! - [`rescale`], [`refine`]: move an octree to a finer lattice; split chosen MIXED leaves
//!   (children filter their parent's candidate lists, as in the octree build).
//! - [`astar`]: A* over face-adjacent leaves through portals, with per-leaf cost weights.
//! - [`CSpace`]: the translational C-space of a planning problem: C-obstacle primitives,
//!   walls outside the bounds, the refinable octree and its index, point attachment, the
//!   no-path certificate.

mod adjacency;
mod components;
mod cspace;
mod index;
mod refine;
mod search;

#[cfg(test)]
mod roadmap_tests;

pub use adjacency::{face_adjacency, neighbors, shared_face, Adjacency, Neighbor};
pub use components::components;
pub use cspace::{Attachment, CSpace, Certificate, Obstacles, WallWitness};
pub use index::{cell_key, LeafIndex};
#[cfg(test)]
pub(crate) use refine::refine_within;
pub use refine::{refine, rescale, RefineStats};
pub use search::{astar, SearchResult};
