//! [`LeafIndex`]: a hash map from `(level, ijk)` to leaf id, and point location.

use crate::math::Vec3;
use crate::octree::Octree;
use crate::util::FastMap;

type Map = FastMap<u128, u32>;

/// The key of the cell of size `2^level` finest cells with lower corner `ijk`.
#[inline]
pub fn cell_key(level: u8, ijk: [u32; 3]) -> u128 {
    (level as u128) << 96 | (ijk[0] as u128) << 64 | (ijk[1] as u128) << 32 | ijk[2] as u128
}

/// `(level, ijk) → leaf id` over the leaves of an octree (leaves tile the root cell).
#[derive(Clone, Debug, Default)]
pub struct LeafIndex {
    map: Map,
    depth: u8,
}

impl LeafIndex {
    /// Index the leaves of `oct`.
    pub fn new(oct: &Octree) -> Self {
        let mut map = Map::with_capacity_and_hasher(oct.leaves.len(), Default::default());
        for (i, l) in oct.leaves.iter().enumerate() {
            map.insert(cell_key(l.level, l.ijk), i as u32);
        }
        LeafIndex { map, depth: oct.depth }
    }

    /// Root level of the indexed octree.
    pub fn depth(&self) -> u8 {
        self.depth
    }

    /// Number of indexed leaves.
    pub fn len(&self) -> usize {
        self.map.len()
    }

    /// Whether nothing is indexed.
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    /// The leaf that is exactly the cell `(level, ijk)`, if any.
    #[inline]
    pub fn get(&self, level: u8, ijk: [u32; 3]) -> Option<usize> {
        self.map.get(&cell_key(level, ijk)).map(|&i| i as usize)
    }

    pub(crate) fn insert(&mut self, level: u8, ijk: [u32; 3], id: usize) {
        self.map.insert(cell_key(level, ijk), id as u32);
    }

    pub(crate) fn remove(&mut self, level: u8, ijk: [u32; 3]) {
        self.map.remove(&cell_key(level, ijk));
    }

    /// The leaf of level `>= min_level` that contains the finest cell `c`, if the leaf
    /// containing `c` is that large (`None` when it is smaller or `c` is outside the root).
    #[inline]
    pub fn containing_cell(&self, c: [u32; 3], min_level: u8) -> Option<usize> {
        let n = 1u64 << self.depth;
        if c.iter().any(|&x| x as u64 >= n) {
            return None;
        }
        for level in min_level..=self.depth {
            let mask = !((1u32 << level) - 1);
            if let Some(i) = self.get(level, [c[0] & mask, c[1] & mask, c[2] & mask]) {
                return Some(i);
            }
        }
        None
    }

    /// The finest lattice cell containing `p`, or `None` outside the root cell.
    pub fn lattice_cell(&self, oct: &Octree, p: Vec3) -> Option<[u32; 3]> {
        let n = (1u64 << self.depth) as f64;
        let q = (p - oct.origin) / oct.h;
        if !q.is_finite() {
            return None;
        }
        let mut c = [0u32; 3];
        for k in 0..3 {
            let f = q[k].floor();
            if f < 0.0 || f >= n {
                // a point on the root's upper face belongs to the last cell
                if f == n && q[k] == n {
                    c[k] = (n - 1.0) as u32;
                    continue;
                }
                return None;
            }
            c[k] = f as u32;
        }
        Some(c)
    }

    /// The leaf whose closed box contains `p` (one of them when `p` lies on a face), or
    /// `None` outside the root cell.
    pub fn locate(&self, oct: &Octree, p: Vec3) -> Option<usize> {
        self.lattice_cell(oct, p).and_then(|c| self.containing_cell(c, 0))
    }
}
