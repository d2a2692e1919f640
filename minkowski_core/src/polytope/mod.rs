//! Convex polytopes: construction by a robust 3D hull and exact queries.
//!
//! Entry points: [`ConvexPolytope::try_from_points`] (hull of a point cloud),
//! [`ConvexPolytope::contains_point`], [`ConvexPolytope::signed_distance`],
//! [`ConvexPolytope::overlaps_box`] (separating axes, exact),
//! [`ConvexPolytope::contains_box`], [`ConvexPolytope::clip_segment`].

mod hull;
#[cfg(test)]
mod polytope_tests;
mod queries;
mod rounded;
mod weld;

pub use hull::{ConvexPolytope, PLANE_TOL_REL};
pub use queries::{clip_planes, closest_on_triangle, point_triangle_distance2};
pub use rounded::{rounded, Rounded};
