//! minkowski_core's hand-written union-find, A* and BVH against the crates that offer
//! them (issue 19, item 6): `petgraph` (`unionfind::UnionFind`, `algo::astar`),
//! `pathfinding` (`directed::astar::astar`) and `parry3d-f64` (`partitioning::Bvh`, already
//! a dependency of the core). Opt-in, not part of the wheel or of `cargo test`:
//!
//! ```text
//! cargo run --release --manifest-path tests/benchmarks/rust_libraries/Cargo.toml
//! ```
//!
//! Inputs are made here, deterministically (a fixed-seed generator): an octree over 400
//! random boxes in the unit cube at h = 1/256 (the roadmap's leaves, adjacency and A*
//! from one corner to the other, as the planner runs them), and 200,000 random boxes
//! queried by 200,000 boxes and 200,000 points (what the octree build and the segment and
//! point queries ask a BVH). Each time is the best of five; each library's answer is
//! checked against ours. Prints a Markdown table: seconds, the library's time as a ratio
//! to ours (the anchor), and what agreed. "Ours" for the union-find is the hand-written
//! one the core had before it took petgraph's, kept here for the comparison.

use minkowski_core::roadmap::{astar, face_adjacency, neighbors, LeafIndex, Neighbor};
use minkowski_core::{Aabb, Bvh, ConvexPolytope, Label, Octree, PolytopeSet, Vec3};
use ordered_float::OrderedFloat;
use parry3d_f64::bounding_volume::Aabb as ParryAabb;
use parry3d_f64::partitioning::{Bvh as ParryBvh, BvhBuildStrategy};
use std::time::Instant;

/// A small deterministic generator (SplitMix64), so the inputs need no crate.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn point(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }

    fn index(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

/// The union-find minkowski_core had before petgraph's (path halving, union by size).
struct HandUnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl HandUnionFind {
    fn new(n: usize) -> Self {
        HandUnionFind { parent: (0..n as u32).collect(), size: vec![1; n] }
    }

    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            let p = self.parent[x] as usize;
            self.parent[x] = self.parent[p];
            x = p;
        }
        x
    }

    fn union(&mut self, a: usize, b: usize) -> bool {
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

/// Best wall-clock seconds of five runs (the machine is shared), and the last result.
fn best<T>(mut run: impl FnMut() -> T) -> (f64, T) {
    let mut fastest = f64::INFINITY;
    let mut out = None;
    for _ in 0..5 {
        let start = Instant::now();
        out = Some(run());
        fastest = fastest.min(start.elapsed().as_secs_f64());
    }
    (fastest, out.expect("five runs"))
}

fn row(item: &str, ours: f64, library: &str, theirs: f64, agree: &str) {
    println!("| {item} | {ours:.4} | {library} | {theirs:.4} | {:.2} | {agree} |", theirs / ours);
}

fn random_box(rng: &mut Rng, size: f64) -> Aabb {
    let lo = rng.point() * (1.0 - size);
    Aabb::new(lo, lo + rng.point() * size + Vec3::splat(1e-3))
}

fn scene(rng: &mut Rng) -> Octree {
    let polys = (0..400)
        .map(|_| {
            let b = random_box(rng, 0.08);
            let corners: Vec<Vec3> = (0..8).map(|k| Vec3::new([b.min.x, b.max.x][k & 1], [b.min.y, b.max.y][(k >> 1) & 1], [b.min.z, b.max.z][(k >> 2) & 1])).collect();
            ConvexPolytope::from_points(&corners)
        })
        .collect();
    let set = PolytopeSet::new(polys);
    let region = Aabb::new(Vec3::ZERO, Vec3::ONE);
    Octree::build(&set, &region, 1.0 / 256.0, 20_000_000).expect("octree")
}

fn empty_leaf_near(oct: &Octree, index: &LeafIndex, p: Vec3) -> usize {
    let mut q = p;
    loop {
        if let Some(id) = index.locate(oct, q) {
            if oct.leaves[id].label == Label::Empty {
                return id;
            }
        }
        q += Vec3::splat(0.01 * (0.5 - p.x).signum());
    }
}

fn bench_search(oct: &Octree, index: &LeafIndex) {
    let n = oct.leaves.len();
    let start = empty_leaf_near(oct, index, Vec3::splat(0.01));
    let target = empty_leaf_near(oct, index, Vec3::splat(0.99));
    let center = |i: usize| oct.cell_box(&oct.leaves[i]).center();
    let goal = center(target);
    let free = |i: usize| (oct.leaves[i].label == Label::Empty).then_some(1.0);
    let (ours, found) = best(|| astar(oct, index, &[(start, 0.0)], &[(target, 0.0)], goal, free).expect("a path"));

    let (closures, (_, cost)) = best(|| {
        let mut nb: Vec<Neighbor> = Vec::new();
        pathfinding::directed::astar::astar(
            &start,
            |&u| {
                nb.clear();
                neighbors(oct, index, u, &mut nb);
                let cu = center(u);
                nb.iter().filter(|m| free(m.leaf).is_some()).map(|m| (m.leaf, OrderedFloat((cu - m.portal).length() + (m.portal - center(m.leaf)).length()))).collect::<Vec<_>>()
            },
            |&v| OrderedFloat((center(v) - goal).length()),
            |&v| v == target,
        )
        .expect("a path")
    });
    row(
        &format!("A* corner to corner, {n} leaves, {} expanded", found.expanded),
        ours,
        "pathfinding::directed::astar (successors from the same octree walk)",
        closures,
        &format!("costs {:.6} and {:.6}", found.cost, cost.0),
    );

    let (graph_and_search, petgraph_cost) = best(|| {
        let pairs = face_adjacency(oct, index, |i| free(i).is_some());
        let mut graph = petgraph::graph::UnGraph::<(), f64, u32>::with_capacity(n, pairs.len());
        for _ in 0..n {
            graph.add_node(());
        }
        for p in &pairs {
            let (a, b) = (p.a as usize, p.b as usize);
            graph.add_edge((a as u32).into(), (b as u32).into(), (center(a) - p.portal).length() + (p.portal - center(b)).length());
        }
        let goal_node = petgraph::graph::NodeIndex::new(target);
        petgraph::algo::astar(&graph, petgraph::graph::NodeIndex::new(start), |v| v == goal_node, |e| *e.weight(), |v| (center(v.index()) - goal).length()).expect("a path").0
    });
    row(
        "A* as above, graph built first",
        ours,
        "petgraph::algo::astar on a Graph of the EMPTY leaves' face adjacency",
        graph_and_search,
        &format!("costs {:.6} and {petgraph_cost:.6}", found.cost),
    );
}

fn bench_union_find(oct: &Octree, index: &LeafIndex, rng: &mut Rng) {
    let n = oct.leaves.len();
    let pairs = face_adjacency(oct, index, |i| oct.leaves[i].label != Label::Full);
    let ours_sets = |uf: &mut HandUnionFind| (0..n).filter(|&i| uf.find(i) == i).count();
    let (ours, ours_count) = best(|| {
        let mut uf = HandUnionFind::new(n);
        for p in &pairs {
            uf.union(p.a as usize, p.b as usize);
        }
        ours_sets(&mut uf)
    });
    let (theirs, their_count) = best(|| {
        let mut uf = petgraph::unionfind::UnionFind::<u32>::new(n);
        for p in &pairs {
            uf.union(p.a, p.b);
        }
        (0..n as u32).filter(|&i| uf.find_mut(i) == i).count()
    });
    row(
        &format!("union-find: components of EMPTY ∪ MIXED, {n} leaves, {} pairs", pairs.len()),
        ours,
        "petgraph::unionfind::UnionFind<u32> (the core's now)",
        theirs,
        &format!("sets {ours_count} and {their_count}"),
    );

    let size = 4_000_000;
    let joins: Vec<(usize, usize)> = (0..size).map(|_| (rng.index(size), rng.index(size))).collect();
    let (ours, ours_count) = best(|| {
        let mut uf = HandUnionFind::new(size);
        joins.iter().filter(|&&(a, b)| uf.union(a, b)).count()
    });
    let (theirs, their_count) = best(|| {
        let mut uf = petgraph::unionfind::UnionFind::<u32>::new(size);
        joins.iter().filter(|&&(a, b)| uf.union(a as u32, b as u32)).count()
    });
    row(&format!("union-find: {size} random unions of {size} elements"), ours, "petgraph::unionfind::UnionFind<u32>", theirs, &format!("merges {ours_count} and {their_count}"));
}

fn bench_bvh(rng: &mut Rng) {
    let boxes: Vec<Aabb> = (0..200_000).map(|_| random_box(rng, 0.01)).collect();
    let queries: Vec<Aabb> = (0..200_000).map(|_| random_box(rng, 0.01)).collect();
    let points: Vec<Vec3> = (0..200_000).map(|_| rng.point()).collect();
    let parry = |b: &Aabb| ParryAabb::new(b.min, b.max);
    let (ours_build, ours) = best(|| Bvh::build(&boxes));
    let leaves: Vec<ParryAabb> = boxes.iter().map(parry).collect();
    let (their_build, theirs) = best(|| ParryBvh::from_leaves(BvhBuildStrategy::default(), &leaves));
    row("BVH build, 200000 boxes", ours_build, "parry3d_f64::partitioning::Bvh::from_leaves (binned)", their_build, "");

    let (ours_boxes, ours_hits) = best(|| {
        let mut hits = 0usize;
        for q in &queries {
            ours.for_each_overlapping(q, |_| hits += 1);
        }
        hits
    });
    let (ours_exact, exact_hits) = best(|| {
        let mut hits = 0usize;
        for q in &queries {
            ours.for_each_overlapping(q, |i| hits += boxes[i].overlaps(q) as usize);
        }
        hits
    });
    let (their_boxes, their_hits) = best(|| queries.iter().map(|q| theirs.intersect_aabb(&parry(q)).count()).sum::<usize>());
    row(
        "BVH: 200000 box queries",
        ours_boxes,
        "Bvh::intersect_aabb",
        their_boxes,
        &format!("hits: ours {ours_hits} (leaf candidates, up to 4 a leaf), {exact_hits} once filtered by each box ({ours_exact:.4} s), parry {their_hits}"),
    );

    let (ours_points, ours_hits) = best(|| {
        let mut hits = 0usize;
        for &p in &points {
            ours.for_each_at_point(p, |_| hits += 1);
        }
        hits
    });
    let (ours_exact, exact_hits) = best(|| {
        let mut hits = 0usize;
        for &p in &points {
            ours.for_each_at_point(p, |i| hits += boxes[i].contains_point(p) as usize);
        }
        hits
    });
    let (their_points, their_hits) = best(|| points.iter().map(|&p| theirs.intersect_aabb(&ParryAabb::new(p, p)).count()).sum::<usize>());
    row(
        "BVH: 200000 point queries",
        ours_points,
        "Bvh::intersect_aabb (a point box)",
        their_points,
        &format!("hits: ours {ours_hits} (leaf candidates), {exact_hits} once filtered by each box ({ours_exact:.4} s), parry {their_hits}"),
    );
}

fn main() {
    let mut rng = Rng(19);
    let start = Instant::now();
    let oct = scene(&mut rng);
    let index = LeafIndex::new(&oct);
    eprintln!("octree: {} leaves in {:.2} s", oct.leaves.len(), start.elapsed().as_secs_f64());
    println!("| item | ours (s) | library | library (s) | library / ours | answers |");
    println!("| --- | ---: | --- | ---: | ---: | --- |");
    bench_search(&oct, &index);
    bench_union_find(&oct, &index, &mut rng);
    bench_bvh(&mut rng);
}
