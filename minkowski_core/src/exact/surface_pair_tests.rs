//! Tests of surface pairs: every piece a boundary candidate, containment only in solids.

use super::exact_tests::{box_mesh, push_box, torus_mesh, Lcg};
use super::*;
use crate::octree::{Label, Octree};

/// The box `[lo, hi]` without its top (z = hi) face: an open surface.
fn open_box(lo: [f64; 3], hi: [f64; 3]) -> TriMesh {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::from_array(lo), Vec3::from_array(hi), &mut v, &mut f);
    f.retain(|t| !t.iter().all(|&i| i >= 4)); // push_box's top quad uses vertices 4..8
    TriMesh::surface(v, &f, "open box").unwrap()
}

/// Brute force over all triangle pairs, plus containment in a solid partner.
fn truth(a: &TriMesh, b: &TriMesh, p: Vec3) -> bool {
    let pair = a.tris.iter().any(|t| b.tris.iter().any(|s| pair_contains_point(t, s, 0.0, p)));
    let a_in_b = b.solid && a.anchors.iter().any(|&a0| b.contains(p - a0));
    let b_in_a = a.solid && b.anchors.iter().any(|&b0| a.contains(p - b0));
    pair || a_in_b || b_in_a
}

fn cases() -> Vec<(TriMesh, TriMesh)> {
    vec![
        // an open box (a cup) and a solid robot that fits inside it
        (open_box([0.0; 3], [3.0, 3.0, 2.0]), box_mesh([-0.4; 3], [0.4; 3]).negated()),
        // a surface robot (an open box) and a solid obstacle it could swallow
        (box_mesh([0.0; 3], [0.5, 0.5, 0.5]), open_box([-1.0; 3], [1.0; 3]).negated()),
        // a closed torus used as a surface and a solid box
        (TriMesh { solid: false, ..torus_mesh(1.5, 0.5, 12, 8) }, box_mesh([-0.3; 3], [0.3; 3]).negated()),
    ]
}

#[test]
fn surface_pairs_have_no_facets_and_membership_matches_brute_force() {
    for (a, b) in cases() {
        let src = ExactSource::new(vec![a.clone()], b.clone(), 0.0, None);
        assert!(src.facets.is_empty());
        assert_eq!(src.piece_pairs, vec![0]);
        let mut rng = Lcg(5);
        let region = src.aabb.inflated(0.3);
        for _ in 0..3000 {
            let p = rng.point(&region);
            assert_eq!(src.contains_point(p), truth(&a, &b, p), "{p:?}");
        }
    }
}

#[test]
fn a_solid_inside_a_cup_is_free_and_a_swallowed_one_collides() {
    let cup = open_box([0.0; 3], [3.0, 3.0, 2.0]);
    let robot = box_mesh([-0.4; 3], [0.4; 3]).negated();
    let src = ExactSource::new(vec![cup], robot, 0.0, None);
    assert!(!src.contains_point(Vec3::new(1.5, 1.5, 1.0)), "inside the cup, touching nothing");
    assert!(src.contains_point(Vec3::new(1.5, 1.5, 0.3)), "touching the bottom");
    // a solid robot around a small obstacle surface contains it
    let src = ExactSource::new(vec![open_box([0.0; 3], [0.2; 3])], box_mesh([-1.0; 3], [1.0; 3]).negated(), 0.0, None);
    assert!(src.contains_point(Vec3::splat(0.1)));
}

#[test]
fn octree_labels_over_surface_pairs_are_exact() {
    for (a, b) in cases() {
        let src = ExactSource::new(vec![a.clone()], b.clone(), 0.0, None);
        let region = src.aabb.inflated(0.2);
        let oct = Octree::build(&src, &region, 0.1, 1 << 22).unwrap();
        let mut rng = Lcg(9);
        let (mut empty, mut full) = (0, 0);
        for leaf in &oct.leaves {
            let cell = oct.cell_box(leaf);
            match leaf.label {
                Label::Empty => {
                    empty += 1;
                    for _ in 0..4 {
                        let p = rng.point(&cell);
                        assert!(!truth(&a, &b, p), "EMPTY cell {cell:?} holds {p:?}");
                    }
                }
                Label::Full => {
                    full += 1;
                    for _ in 0..4 {
                        let p = rng.point(&cell);
                        assert!(truth(&a, &b, p), "FULL cell {cell:?} misses {p:?}");
                    }
                }
                Label::Mixed => {}
            }
        }
        assert!(empty > 0 && full > 0, "{empty} empty, {full} full");
    }
}

#[test]
fn segments_over_surface_pairs() {
    let cup = open_box([0.0; 3], [3.0, 3.0, 2.0]);
    let src = ExactSource::new(vec![cup], box_mesh([-0.4; 3], [0.4; 3]).negated(), 0.0, None);
    // down into the cup through its open top, and across its floor through a wall
    assert!(src.segment_is_free(Vec3::new(1.5, 1.5, 4.0), Vec3::new(1.5, 1.5, 1.0), 0.0));
    assert!(!src.segment_is_free(Vec3::new(1.5, 1.5, 1.0), Vec3::new(5.0, 1.5, 1.0), 0.0));
    assert!(!src.segment_is_free(Vec3::new(1.5, 1.5, 4.0), Vec3::new(1.5, 1.5, 1.0), 0.7), "the margin meets the floor");
    assert!(src.signed_distance(Vec3::new(1.5, 1.5, 1.0)) > 0.0);
    assert!(src.signed_distance(Vec3::new(1.5, 1.5, 1.0)) <= 0.6 + 1e-9, "a lower bound of 0.6");
}

#[test]
fn solid_pairs_over_the_facet_budget_are_taken_piece_by_piece_exactly() {
    // a torus and a box, both solids: the same membership and segments with all of the
    // reduced convolution as with none of it (budget 0), nesting included
    let a = torus_mesh(1.5, 0.5, 12, 8);
    let b = box_mesh([-0.3; 3], [0.3; 3]).negated();
    let full = ExactSource::new(vec![a.clone()], b.clone(), 0.0, None);
    assert!(matches!(ExactSource::try_new(vec![a.clone()], b.clone(), 0.0, None, 0), Err(CoreError::FacetLimit { .. })));
    let pieces = ExactSource::with_piece_fallback(vec![a.clone()], b.clone(), 0.0, None, 0);
    assert!(!full.facets.is_empty() && full.piece_pairs.is_empty());
    assert!(pieces.facets.is_empty() && pieces.piece_pairs == vec![0]);
    let (mut rng, region) = (Lcg(11), full.aabb.inflated(0.3));
    let mut inside = 0;
    for _ in 0..3000 {
        let p = rng.point(&region);
        assert_eq!(pieces.contains_point(p), truth(&a, &b, p), "{p:?}");
        inside += usize::from(full.contains_point(p));
        let q = rng.point(&region);
        assert_eq!(pieces.segment_is_free(p, q, 0.0), full.segment_is_free(p, q, 0.0), "{p:?} → {q:?}");
    }
    assert!(inside > 100, "{inside} points inside");
    // in the tube, and in its hole
    assert!(pieces.contains_point(Vec3::new(1.5, 0.0, 0.0)));
    assert!(!pieces.contains_point(Vec3::ZERO), "the hole");
}

/// The lazy pair tests (one unnormalised direction at a time, stopping at the first that
/// decides) say what a built [`Piece`] says, on random triangles (some flat, some with an
/// edge collapsed), margins and boxes around, across and inside the pieces.
#[test]
fn lazy_pair_tests_agree_with_the_built_piece() {
    let mut rng = Lcg(11);
    let unit = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
    let (mut inside, mut meets, mut apart) = (0, 0, 0);
    for case in 0..4000 {
        let mut corners = || [rng.point(&unit), rng.point(&unit), rng.point(&unit)];
        let (mut p, mut q) = (corners(), corners());
        match case % 5 {
            0 => p[2] = p[0] + (p[1] - p[0]) * 0.5,     // collinear: a flat, degenerate triangle
            1 => q[1] = q[0],                           // an edge collapsed
            2 => p.iter_mut().for_each(|v| v.z = 0.25), // parallel to an axis plane
            3 if case % 10 == 3 => {
                // both segments, on parallel lines: no normal, no edge × edge product
                let d = p[1] - p[0];
                p[2] = p[0] + d * 0.5;
                q = [q[0], q[0] + d * 0.7, q[0] + d * 0.2];
            }
            _ => {}
        }
        let (t, s) = (Tri::new(p), Tri::new(q));
        let m = if case % 3 == 0 { 0.05 } else { 0.0 };
        let piece = Piece::new(&t, &s, m, true);
        // a point of the piece, moved a little or a lot
        let mut bary = |x: [Vec3; 3]| {
            let (u, v) = (rng.next(), rng.next());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            x[0] + (x[1] - x[0]) * u + (x[2] - x[0]) * v
        };
        let on = bary(p) + bary(q);
        let c = on + rng.point(&unit) * if case % 4 < 2 { 0.1 } else { 1.0 };
        let h = Vec3::new(rng.next(), rng.next(), rng.next()) * if case % 2 == 0 { 0.02 } else { 0.4 };
        let bx = Aabb::new(c - h, c + h);
        let want = match (piece.overlaps_box(&bx), piece.contains_box(&bx)) {
            (false, _) => BoxRelation::Apart,
            (true, false) => BoxRelation::Meets,
            (true, true) => BoxRelation::Inside,
        };
        assert_eq!(pair_box_relation(&t, &s, m, &bx), want, "case {case}");
        assert_eq!(pair_contains_box(&t, &s, m, &bx), want == BoxRelation::Inside, "case {case}");
        assert_eq!(pair_contains_point(&t, &s, m, c), piece.contains_point(c), "case {case}");
        match want {
            BoxRelation::Inside => inside += 1,
            BoxRelation::Meets => meets += 1,
            BoxRelation::Apart => apart += 1,
        }
    }
    assert!(inside > 100 && meets > 500 && apart > 500, "{inside} inside, {meets} meet, {apart} apart");
}
