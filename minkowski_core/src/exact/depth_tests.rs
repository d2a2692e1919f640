use super::exact_tests::{box_mesh, frame, voxel_mesh};
use super::*;

/// The C-obstacle `B ⊕ (−A)` of `B` for `A = [lo, hi]` (a box, reflected as `[−hi, −lo]`).
fn c_obstacle(b: TriMesh, lo: [f64; 3], hi: [f64; 3]) -> ExactSource {
    let neg = |v: [f64; 3]| [-v[0], -v[1], -v[2]];
    ExactSource::new(vec![b], box_mesh(neg(hi), neg(lo)), 0.0, None)
}

fn check(d: &Depth, src: &ExactSource, expect: f64, tol: f64) {
    assert!(d.inside && d.converged, "{d:?}");
    assert!(d.lower <= expect + 1e-12 && expect <= d.upper + 1e-12, "{d:?} vs {expect}");
    assert!(d.upper - d.lower <= tol, "{d:?}");
    assert!(!src.contains_point(d.point), "{d:?}: the upper point is inside");
    assert!((d.point.length() - d.upper).abs() < 1e-12);
}

#[test]
fn cubes_overlapping_along_x() {
    let src = c_obstacle(box_mesh([0.7, 0.0, 0.0], [1.7, 1.0, 1.0]), [0.0; 3], [1.0; 3]);
    let d = src.try_depth(Vec3::ZERO, 1e-3, 100_000).unwrap();
    check(&d, &src, 0.3, 1e-3);
    assert!((d.point.normalize() - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-3, "{d:?}");
}

#[test]
fn boxes_take_the_smallest_axis() {
    // overlaps 0.5 in x, 0.25 in y, 0.4 in z
    let src = c_obstacle(box_mesh([0.5, 0.75, 0.6], [2.0, 2.0, 2.0]), [0.0; 3], [1.0; 3]);
    let d = src.try_depth(Vec3::ZERO, 1e-4, 100_000).unwrap();
    check(&d, &src, 0.25, 1e-4);
    assert!(d.point.normalize().y < -0.999, "{d:?}");
}

#[test]
fn peg_in_a_hole_pushed_into_the_wall() {
    // the frame's hole is [1, 2]²; the peg reaches 0.2 into the wall at x = 2
    for tol in [1e-2, 1e-3, 1e-5] {
        let src = c_obstacle(frame(), [1.6, 1.2, 0.0], [2.2, 1.8, 1.0]);
        let d = src.try_depth(Vec3::ZERO, tol, 200_000).unwrap();
        check(&d, &src, 0.2, tol);
        assert!(d.point.normalize().x < -0.999, "{d:?}");
    }
}

#[test]
fn peg_in_a_blind_hole_lower_bound_stays_below_the_depth() {
    // a 3×3×2 block with a blind hole [1, 2]² × [1, 2]; the peg stands 0.5 above the
    // hole's floor and reaches 0.15 into the wall at x = 2 (lifting it out takes 0.5)
    let block = voxel_mesh(|x, y, z| (0..3).contains(&x) && (0..3).contains(&y) && (0..2).contains(&z) && !(x == 1 && y == 1 && z == 1), "block");
    for tol in [1e-2, 1e-3, 1e-4] {
        let src = c_obstacle(block.clone(), [1.35, 1.1, 1.5], [2.15, 1.9, 3.0]);
        let d = src.try_depth(Vec3::ZERO, tol, 200_000).unwrap();
        check(&d, &src, 0.15, tol);
    }
}

#[test]
fn separated_parts_give_the_exact_distance() {
    // A = [0, 1]³ and B 0.5 beyond it in x and 0.3 in y: distance sqrt(0.34)
    let src = c_obstacle(box_mesh([1.5, 1.3, 0.0], [2.0, 2.0, 1.0]), [0.0; 3], [1.0; 3]);
    let d = src.try_depth(Vec3::ZERO, 1e-3, 1000).unwrap();
    assert!(!d.inside);
    assert!((d.lower - 0.34f64.sqrt()).abs() < 1e-12 && d.lower == d.upper, "{d:?}");
    assert!(src.contains_point(d.point));
}

#[test]
fn facet_nearest_is_exact() {
    let f = Facet { p: [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y], n: 4, k: 0 };
    assert_eq!(facet_nearest(&f, Vec3::new(0.5, 0.5, 2.0)), Vec3::new(0.5, 0.5, 0.0));
    assert_eq!(facet_nearest(&f, Vec3::new(2.0, 0.5, 1.0)), Vec3::new(1.0, 0.5, 0.0));
    let t = Facet { p: [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ZERO], n: 3, k: 0 };
    assert_eq!(facet_nearest(&t, Vec3::new(1.0, 1.0, -1.0)), Vec3::new(0.5, 0.5, 0.0));
}

#[test]
fn bad_tolerance_is_refused() {
    let src = c_obstacle(box_mesh([0.5; 3], [2.0; 3]), [0.0; 3], [1.0; 3]);
    assert!(matches!(src.try_depth(Vec3::ZERO, 0.0, 10), Err(CoreError::InvalidParameter { .. })));
}
