//! Connected components of a set of leaves by union–find over face adjacency.

use super::adjacency::Adjacency;
use crate::util::UnionFind;

/// Component label of each of `n` leaves over the adjacency `pairs`, for the leaves with
/// `member(i)`; non-members get `u32::MAX`. Components are numbered 0, 1, ... in the order
/// of their first leaf, so the labels are deterministic.
pub fn components(n: usize, pairs: &[Adjacency], member: impl Fn(usize) -> bool) -> Vec<u32> {
    let mut uf = UnionFind::new(n);
    for p in pairs {
        let (a, b) = (p.a as usize, p.b as usize);
        if member(a) && member(b) {
            uf.union(a, b);
        }
    }
    let mut label = vec![u32::MAX; n];
    let mut of_root = vec![u32::MAX; n];
    let mut next = 0u32;
    for (i, l) in label.iter_mut().enumerate() {
        if !member(i) {
            continue;
        }
        let r = uf.find(i);
        if of_root[r] == u32::MAX {
            of_root[r] = next;
            next += 1;
        }
        *l = of_root[r];
    }
    label
}
