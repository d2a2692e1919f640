//! Integration tests: closedness, orientation, the error bound and topology of extracted
//! surfaces on shapes with closed-form answers.

use minkowski_core::*;
use std::collections::HashMap;

fn boxp(min: [f64; 3], max: [f64; 3]) -> Vec<Vec3> {
    (0..8).map(|k| Vec3::new(if k & 1 == 1 { max[0] } else { min[0] }, if k & 2 == 2 { max[1] } else { min[1] }, if k & 4 == 4 { max[2] } else { min[2] })).collect()
}

fn set_of(boxes: &[([f64; 3], [f64; 3])]) -> PolytopeSet {
    PolytopeSet::new(boxes.iter().map(|(a, b)| ConvexPolytope::from_points(&boxp(*a, *b))).collect())
}

/// Each directed edge once, its reverse once: closed, manifold, consistently oriented.
fn check_closed_oriented(s: &Surface) {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for f in &s.faces {
        assert!(f[0] != f[1] && f[1] != f[2] && f[0] != f[2], "degenerate face {f:?}");
        for k in 0..3 {
            *directed.entry((f[k], f[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "directed edge {a}->{b} used {n} times");
        assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}->{b} has no opposite");
    }
}

fn volume(s: &Surface) -> f64 {
    s.faces
        .iter()
        .map(|f| {
            let (a, b, c) = (s.vertices[f[0] as usize], s.vertices[f[1] as usize], s.vertices[f[2] as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

fn euler(s: &Surface) -> i64 {
    let mut edges = std::collections::HashSet::new();
    for f in &s.faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    s.vertices.len() as i64 - edges.len() as i64 + s.faces.len() as i64
}

fn run(set: &PolytopeSet, eps: f64) -> UnionResult {
    approximate_union(set, &UnionParams { eps, max_cells: 20_000_000, max_refinements: 2, simplify: false, planes: true }).unwrap()
}

#[test]
fn cube_surface_is_closed_and_within_the_bound() {
    let set = set_of(&[([0.0; 3], [1.0; 3])]);
    let r = run(&set, 0.05);
    let s = &r.surface;
    assert!(!s.faces.is_empty());
    assert_eq!(s.complex_cells, 0);
    assert_eq!(s.inconsistent_edges, 0);
    check_closed_oriented(s);
    assert_eq!(euler(s), 2);
    // vertices are exact boundary points (up to the clamp)
    let cube = &set.polys[0];
    for v in &s.vertices {
        assert!(cube.signed_distance(*v).abs() <= r.error_bound);
    }
    // volume within area × bound
    let v = volume(s);
    assert!((v - 1.0).abs() <= 6.0 * r.error_bound, "volume {v}");
    assert!(v > 0.0, "outward orientation gives positive volume");
}

#[test]
fn square_ring_keeps_its_hole() {
    // four bars around a 1×1 hole: genus 1
    let set = set_of(&[([0.0, 0.0, 0.0], [3.0, 1.0, 1.0]), ([0.0, 2.0, 0.0], [3.0, 3.0, 1.0]), ([0.0, 0.0, 0.0], [1.0, 3.0, 1.0]), ([2.0, 0.0, 0.0], [3.0, 3.0, 1.0])]);
    let r = run(&set, 0.1);
    check_closed_oriented(&r.surface);
    assert_eq!(euler(&r.surface), 0, "genus 1");
    let v = volume(&r.surface);
    assert!((v - 8.0).abs() <= 32.0 * r.error_bound, "volume {v}");
}

#[test]
fn thin_slot_is_detected_as_complex_then_refined_open() {
    // two blocks 0.06 apart: at eps 0.25 (h ≈ 0.144) no lattice point falls in the slot,
    // the samples join the blocks, and the cells across the slot must be flagged
    // (sampled everywhere: resolved by planes, the slot's two faces are exact at once)
    let set = set_of(&[([0.0, 0.0, 0.0], [1.0, 2.0, 2.0]), ([1.06, 0.0, 0.0], [2.06, 2.0, 2.0])]);
    let coarse = approximate_union(&set, &UnionParams { eps: 0.25, max_cells: 20_000_000, max_refinements: 0, simplify: false, planes: false }).unwrap();
    assert!(coarse.surface.complex_cells > 0, "the slot must be flagged");
    assert_eq!(euler(&coarse.surface), 2, "unrefined, the slot is closed (one sphere)");
    let fine = approximate_union(&set, &UnionParams { eps: 0.25, max_cells: 20_000_000, max_refinements: 4, simplify: false, planes: false }).unwrap();
    assert_eq!(fine.surface.complex_cells, 0);
    assert!(fine.refinements > 0);
    check_closed_oriented(&fine.surface);
    assert_eq!(euler(&fine.surface), 4, "two separate boxes: two spheres");
    // resolved by planes: the cells across the slot hold its two parallel faces, exact at
    // the coarse grid with no refinement
    let planar = approximate_union(&set, &UnionParams { eps: 0.25, max_cells: 20_000_000, max_refinements: 4, simplify: true, planes: true }).unwrap();
    assert_eq!((planar.surface.complex_cells, planar.refinements, planar.surface.band_cells), (0, 0, 0));
    check_closed_oriented(&planar.surface);
    assert_eq!(euler(&planar.surface), 4);
    assert_eq!(planar.surface.faces.len(), 24, "two boxes' faces");
}

#[test]
fn minkowski_of_boxes_is_the_box_of_summed_extents() {
    let a = vec![boxp([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0])];
    let b = vec![boxp([9.5, -0.5, -0.5], [10.5, 0.5, 0.5])];
    let sums = pairwise_sums(&a, &b, SumKind::Add).unwrap();
    assert_eq!(sums.len(), 1);
    let s = &sums[0];
    assert!((s.volume() - 27.0).abs() < 1e-9);
    assert!((s.aabb.min - Vec3::new(8.5, -1.5, -1.5)).length() < 1e-12);
    let diff = pairwise_sums(&a, &b, SumKind::Subtract).unwrap();
    assert!((diff[0].aabb.max - Vec3::new(-8.5, 1.5, 1.5)).length() < 1e-12);
    assert!(matches!(pairwise_sums(&[], &b, SumKind::Add), Err(CoreError::Empty { .. })));
}

#[test]
fn bad_eps_is_an_error() {
    let set = set_of(&[([0.0; 3], [1.0; 3])]);
    for eps in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let r = approximate_union(&set, &UnionParams { eps, max_cells: 1000, max_refinements: 0, simplify: false, planes: true });
        assert!(matches!(r, Err(CoreError::InvalidParameter { .. })), "eps {eps}");
    }
    // sampled everywhere, a fine grid exceeds the budget; resolved by planes, the cube's
    // faces, edges and corners need a few hundred cells at any eps
    let r = approximate_union(&set, &UnionParams { eps: 1e-4, max_cells: 1000, max_refinements: 0, simplify: false, planes: false });
    assert!(matches!(r, Err(CoreError::ResourceLimit { .. })));
    let r = approximate_union(&set, &UnionParams { eps: 1e-4, max_cells: 1000, max_refinements: 0, simplify: true, planes: true }).unwrap();
    assert_eq!(r.surface.band_cells, 0);
    assert_eq!(r.surface.faces.len(), 12, "a cube's six faces");
}

#[test]
fn set_queries() {
    let set = set_of(&[([0.0; 3], [1.0; 3]), ([2.0, 0.0, 0.0], [3.0, 1.0, 1.0])]);
    assert!(set.contains_point(Vec3::splat(0.5)));
    assert!(!set.contains_point(Vec3::new(1.5, 0.5, 0.5)));
    assert!((set.signed_distance(Vec3::new(1.5, 0.5, 0.5)) - 0.5).abs() < 1e-12);
    assert!((set.signed_distance(Vec3::new(2.5, 0.5, 0.5)) + 0.5).abs() < 1e-12);
    assert!((set.signed_distance(Vec3::new(10.0, 0.5, 0.5)) - 7.0).abs() < 1e-12);
    assert!(!set.segment_is_free(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(4.0, 0.5, 0.5)));
    assert!(set.segment_is_free(Vec3::new(1.5, -1.0, 0.5), Vec3::new(1.5, 2.0, 0.5)));
    let iv = set.segment_intervals(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(4.0, 0.5, 0.5));
    assert_eq!(iv.len(), 2);
}

#[test]
fn simplification_keeps_the_surface_and_drops_flat_interiors() {
    let set = set_of(&[([0.0, 0.0, 0.0], [3.0, 1.0, 1.0]), ([0.0, 0.0, 0.0], [1.0, 3.0, 1.0])]);
    // (sampled: resolved by planes, the L's surface is its exact faces before simplification)
    let p = |simplify| UnionParams { eps: 0.05, max_cells: 20_000_000, max_refinements: 1, simplify, planes: false };
    let raw = approximate_union(&set, &p(false)).unwrap();
    let simple = approximate_union(&set, &p(true)).unwrap();
    check_closed_oriented(&simple.surface);
    assert_eq!(euler(&simple.surface), euler(&raw.surface));
    assert!((volume(&simple.surface) - volume(&raw.surface)).abs() < 1e-9, "same solid");
    assert!(simple.surface.faces.len() * 5 < raw.surface.faces.len(), "{} vs {}", simple.surface.faces.len(), raw.surface.faces.len());
    assert_eq!(simple.triangles_extracted, raw.surface.faces.len());
    // every kept vertex is one of the exact crossings
    let l = &set;
    for v in &simple.surface.vertices {
        assert!(l.signed_distance(*v).abs() <= simple.error_bound);
    }
}

#[test]
fn apart_primitives_are_their_hulls_and_overlapping_ones_need_a_grid() {
    let params = UnionParams { eps: 0.05, max_cells: 1_000_000, max_refinements: 0, simplify: true, planes: true };
    let apart = approximate_union(&set_of(&[([0.0; 3], [1.0; 3]), ([2.0, 0.0, 0.0], [3.0, 1.0, 1.0])]), &params).unwrap();
    assert_eq!((apart.h, apart.surface.band_cells, apart.surface.faces.len()), (0.0, 0, 24), "two boxes, twelve triangles each");
    assert!(apart.error_bound > 0.0 && apart.error_bound < 1e-8);
    let meeting = approximate_union(&set_of(&[([0.0; 3], [1.0; 3]), ([0.5, 0.0, 0.0], [1.5, 1.0, 1.0])]), &params).unwrap();
    assert!(meeting.h > 0.0, "overlapping boxes: the grid's union");
    assert_eq!(meeting.surface.faces.len(), 12, "one box 1.5 x 1 x 1");
}
