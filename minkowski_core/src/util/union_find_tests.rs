//! Unit tests of [`UnionFind`](super::UnionFind).

use super::UnionFind;

#[test]
fn joins_transitively_and_says_when_already_joined() {
    let mut sets = UnionFind::new(6);
    assert!(sets.union(0, 1));
    assert!(sets.union(2, 3));
    assert!(sets.union(1, 3));
    assert!(!sets.union(0, 2), "0 and 2 are joined through 1 and 3");
    assert_eq!(sets.find(0), sets.find(3));
    assert_ne!(sets.find(0), sets.find(4));
    assert_ne!(sets.find(4), sets.find(5));
    let roots = (0..6).filter(|&i| sets.find(i) == i).count();
    assert_eq!(roots, 3);
}
