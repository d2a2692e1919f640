//! # minkowski_core
//!
//! The native Minkowski-sum approximator of minkplan (after Varadhan & Manocha, "Accurate
//! Minkowski sum approximation of polyhedral models", 2006).
//!
//! Pipeline: convex pieces of both operands → pairwise sums `M_ij` ([`pairwise_sums`]) →
//! their union as a [`PolytopeSet`] with a [`Bvh`] → the adaptive [`Octree`] with cell and
//! primitive culling → a closed, manifold surface over the band of finest MIXED cells
//! ([`extract`]) with a two-sided Hausdorff bound of `sqrt(3) h (1 + 2·EDGE_CLAMP)` unless
//! complex cells remain ([`approximate_union`] refines until they do not, within limits).
//!
//! All numbers are f64. File I/O and Python live outside the core (`py` module behind the
//! `python` feature).
#![warn(missing_docs)]

pub mod bvh;
pub mod deadline;
pub mod error;
pub mod exact;
pub mod flat_faces;
pub mod math;
pub mod minkowski;
pub mod octree;
pub mod offset;
pub mod polytope;
pub mod roadmap;
pub mod surface;
mod union;
pub mod util;

pub use bvh::Bvh;
pub use error::{CoreError, CoreResult};
pub use exact::{ExactSource, TriMesh};
pub use math::{Aabb, Vec3};
pub use minkowski::{pairwise_sums, PolytopeSet, SumKind};
pub use octree::{CellSource, Label, Leaf, Octree};
pub use polytope::ConvexPolytope;
pub use surface::{extract, Surface};
pub use union::{approximate_solid, approximate_union, cell_size_for_eps, grid_error_bound, surface_error_bound, UnionParams, UnionResult};

#[cfg(feature = "python")]
mod py;
