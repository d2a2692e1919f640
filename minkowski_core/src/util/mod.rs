//! Small data structures the modules above share (kept below all of them, so no module
//! reaches up for one).
//!
//! Entry points: [`UnionFind`], [`FastMap`], [`faces_by_edge`].

mod fast_hash;
mod union_find;
#[cfg(test)]
mod union_find_tests;

pub use fast_hash::{FastMap, FastSet, KeyHasher};
pub use union_find::UnionFind;

/// The triangles of a mesh by each of their directed edges (`(a, b)` for the corners
/// `a`, `b` in that order): in a closed, consistently wound mesh, the face across an edge
/// of face `f` is the one holding it reversed.
pub fn faces_by_edge(faces: &[[u32; 3]]) -> FastMap<(u32, u32), u32> {
    faces.iter().enumerate().flat_map(|(i, f)| (0..3).map(move |k| ((f[k], f[(k + 1) % 3]), i as u32))).collect()
}
