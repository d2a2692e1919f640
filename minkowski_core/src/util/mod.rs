//! Small data structures the modules above share (kept below all of them, so no module
//! reaches up for one).
//!
//! Entry points: [`UnionFind`], [`FastMap`].

mod fast_hash;
mod union_find;
#[cfg(test)]
mod union_find_tests;

pub use fast_hash::{FastMap, FastSet, KeyHasher};
pub use union_find::UnionFind;
