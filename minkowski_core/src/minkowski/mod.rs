//! Pairwise Minkowski sums of convex pieces and the primitive set they form.
//!
//! Entry points: [`pairwise_sums`] (all `M_ij = conv{p ± q}`), [`PolytopeSet`] (the union
//! of convex primitives with a BVH: point, distance and segment queries).

mod cones;
mod set;
pub use set::{merge_intervals, PolytopeSet};

use crate::error::{CoreError, CoreResult};
use crate::math::Vec3;
use crate::polytope::ConvexPolytope;
use rayon::prelude::*;

/// Whether the second operand is added or subtracted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SumKind {
    /// `A ⊕ B = { a + b }`.
    Add,
    /// `A ⊕ (−B) = { a − b }`: the translational C-obstacle of obstacle A for robot B.
    Subtract,
}

/// Every pairwise sum `M_ij = conv{ p ± q : p ∈ V(A_i), q ∈ V(B_j) }` of the convex pieces
/// `a` and `b` (vertex lists), in row-major order `i * b.len() + j`. Parallel over pairs.
///
/// # Errors
/// [`CoreError::Empty`] when an operand has no pieces, [`CoreError::NonFinite`] and
/// [`CoreError::Degenerate`] for bad pieces (naming the piece).
pub fn pairwise_sums(a: &[Vec<Vec3>], b: &[Vec<Vec3>], kind: SumKind) -> CoreResult<Vec<ConvexPolytope>> {
    if a.is_empty() {
        return Err(CoreError::Empty { what: "operand A".into() });
    }
    if b.is_empty() {
        return Err(CoreError::Empty { what: "operand B".into() });
    }
    for (name, pieces) in [("A", a), ("B", b)] {
        for (i, p) in pieces.iter().enumerate() {
            if p.iter().any(|v| !v.is_finite()) {
                return Err(CoreError::NonFinite { what: format!("operand {name} piece {i}") });
            }
        }
    }
    let s = match kind {
        SumKind::Add => 1.0,
        SumKind::Subtract => -1.0,
    };
    // each piece's normal-cone caps, once (not once per pair it is in)
    let caps_a: Vec<_> = a.par_iter().map(|p| cones::caps(p, 1.0)).collect();
    let caps_b: Vec<_> = b.par_iter().map(|q| cones::caps(q, s)).collect();
    (0..a.len() * b.len())
        .into_par_iter()
        .map(|k| {
            let (i, j) = (k / b.len(), k % b.len());
            let what = format!("sum of A piece {i} and B piece {j}");
            // the sums whose normal cones meet hold every vertex of the sum's hull
            if let Some(pts) = cones::candidate_sums(&a[i], &caps_a[i], &b[j], &caps_b[j], s) {
                if let Ok(hull) = ConvexPolytope::try_from_points(&pts, &what) {
                    return Ok(hull);
                }
            }
            let mut pts = Vec::with_capacity(a[i].len() * b[j].len());
            for p in &a[i] {
                for q in &b[j] {
                    pts.push(*p + *q * s);
                }
            }
            ConvexPolytope::try_from_points(&pts, &what)
        })
        .collect()
}
