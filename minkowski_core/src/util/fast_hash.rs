//! A small, fast hasher for the crate's integer keys (lattice keys, vertex ids, bins):
//! std's SipHash resists hash flooding, which these maps, keyed by our own geometry, do
//! not need, and costs several times more per lookup.

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// The splitmix64 finaliser over the words written.
#[derive(Default, Clone, Copy)]
pub struct KeyHasher(u64);

#[inline]
fn mix(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut b = [0u8; 8];
            b[..chunk.len()].copy_from_slice(chunk);
            self.0 = mix(self.0 ^ u64::from_le_bytes(b));
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.0 = mix(self.0 ^ u64::from(v));
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = mix(self.0 ^ v);
    }
    fn write_i64(&mut self, v: i64) {
        self.0 = mix(self.0 ^ v as u64);
    }
    fn write_u128(&mut self, v: u128) {
        self.0 = mix(mix(self.0 ^ (v >> 64) as u64) ^ v as u64);
    }
    fn write_usize(&mut self, v: usize) {
        self.0 = mix(self.0 ^ v as u64);
    }
}

/// A `HashMap` with [`KeyHasher`].
pub type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<KeyHasher>>;

/// A `HashSet` with [`KeyHasher`].
pub type FastSet<K> = HashSet<K, BuildHasherDefault<KeyHasher>>;
