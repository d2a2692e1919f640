//! Connected components of a set of leaves by union–find over face adjacency.

use super::adjacency::Adjacency;

/// Union–find with path halving and union by size.
#[derive(Clone, Debug)]
pub struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    /// `n` singletons.
    pub fn new(n: usize) -> Self {
        UnionFind { parent: (0..n as u32).collect(), size: vec![1; n] }
    }

    /// Representative of `x`'s set.
    pub fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            let p = self.parent[x] as usize;
            self.parent[x] = self.parent[p];
            x = p;
        }
        x
    }

    /// Merge the sets of `a` and `b`; whether they were apart.
    pub fn union(&mut self, a: usize, b: usize) -> bool {
        let (mut ra, mut rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        if self.size[ra] < self.size[rb] {
            std::mem::swap(&mut ra, &mut rb);
        }
        self.parent[rb] = ra as u32;
        self.size[ra] += self.size[rb];
        true
    }
}

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
