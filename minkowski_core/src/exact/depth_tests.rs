use super::exact_tests::{box_mesh, frame, u_block, voxel_mesh};
use super::witness::Witnesses;
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
fn nearly_coincident_frames_converge() {
    // two frames 0.1 apart in x: every face nearly meets its twin, so interior facets crowd
    // the origin's neighbourhood; the depth is the frame's thickness (lift it off)
    let shifted = |m: &TriMesh, d: Vec3| TriMesh::new(m.vertices.iter().map(|v| *v + d).collect(), &m.faces, "shifted").unwrap();
    let robot = shifted(&frame(), Vec3::new(0.1, 0.0, 0.0));
    let src = ExactSource::new(vec![frame()], robot.negated(), 0.0, None);
    let d = src.try_depth(Vec3::ZERO, 1e-3, 200_000).unwrap();
    check(&d, &src, 1.0, 1e-3);
    assert!(d.point.normalize().z.abs() > 0.999, "{d:?}");
}

#[test]
fn deep_overlaps_of_a_non_convex_part_converge() {
    // a U block against itself moved a little: interior facets of the convolution lie
    // nearer than the depth and no single piece covers the cells they cross; witness
    // points (inside one part, the whole cell of translations keeping them in the other)
    // show those cells inside
    let (u, _) = u_block();
    let shifted = |d: Vec3| TriMesh::new(u.vertices.iter().map(|v| *v + d).collect(), &u.faces, "shifted").unwrap();
    for d in [Vec3::new(0.3, 0.2, 0.1), Vec3::new(0.05, 0.03, 0.02), Vec3::new(-0.4, 0.1, 0.3)] {
        let src = ExactSource::new(vec![u.clone()], shifted(d).negated(), 0.0, None);
        let r = src.try_depth(Vec3::ZERO, 1e-3, 200_000).unwrap();
        assert!(r.converged && r.upper - r.lower <= 1e-3, "{d}: {r:?}");
        assert!(!src.contains_point(r.point), "{r:?}");
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

#[test]
fn witnesses_show_cells_inside_only() {
    // C-obstacle of [0, 2]³ for the unit cube: the box [-1, 2]³ of translations
    let src = c_obstacle(box_mesh([0.0; 3], [2.0; 3]), [0.0; 3], [1.0; 3]);
    let mut w = Witnesses::new(&src, Vec3::splat(0.5));
    let cube = |c: f64, r: f64| Aabb::new(Vec3::splat(c - r), Vec3::splat(c + r));
    assert!(w.show(&src, &cube(0.5, 0.4), false));
    assert!(w.show(&src, &cube(1.0, 0.9), true));
    for exhaustive in [false, true] {
        assert!(!w.show(&src, &cube(2.2, 0.1), exhaustive), "outside the sum");
        assert!(!w.show(&src, &cube(1.9, 0.2), exhaustive), "across its boundary");
    }
}

#[test]
fn a_sum_made_for_one_depth_query_answers_it_as_the_whole_sum_does() {
    // the facets beyond the cube the search can reach are left out: the same interval,
    // from fewer facets
    let (u, _) = u_block();
    let shifted = |m: &TriMesh, d: Vec3| TriMesh::new(m.vertices.iter().map(|v| *v + d).collect(), &m.faces, "shifted").unwrap();
    let block = voxel_mesh(|x, y, z| (0..3).contains(&x) && (0..3).contains(&y) && (0..2).contains(&z) && !(x == 1 && y == 1 && z == 1), "block");
    let pairs = [
        (u.clone(), shifted(&u, Vec3::new(0.3, 0.2, 0.1)).negated()),
        (u.clone(), shifted(&u, Vec3::new(-0.4, 0.1, 0.3)).negated()),
        (frame(), shifted(&frame(), Vec3::new(0.1, 0.0, 0.0)).negated()),
        (block, box_mesh([-2.15, -1.9, -3.0], [-1.35, -1.1, -1.5])),
    ];
    let mut fewer = 0;
    for (a, b) in pairs {
        for tol in [1e-2, 1e-3] {
            let whole = ExactSource::new(vec![a.clone()], b.clone(), 0.0, None);
            let near = ExactSource::try_new_for_depth(a.clone(), b.clone(), usize::MAX, Vec3::ZERO, tol).unwrap();
            let region = near.region.expect("made for a depth query");
            // every facet of the whole sum that meets the region is kept, and only those
            let meeting = whole.facets.iter().filter(|f| f.aabb(0.0).overlaps(&region)).count();
            assert_eq!(near.facets.len(), meeting);
            fewer += usize::from(near.facets.len() < whole.facets.len());
            let (dw, dn) = (whole.try_depth(Vec3::ZERO, tol, 200_000).unwrap(), near.try_depth(Vec3::ZERO, tol, 200_000).unwrap());
            assert!(dw.inside && dn.inside && dn.converged, "{dn:?}");
            assert_eq!((dw.lower, dw.upper, dw.point), (dn.lower, dn.upper, dn.point), "tol {tol}: {} of {} facets", near.facets.len(), whole.facets.len());
        }
    }
    assert!(fewer >= 4, "the region left out facets in {fewer} of 8 sums only");
}

#[test]
fn a_sum_made_for_one_depth_query_refuses_what_reaches_beyond_its_facets() {
    // two boxes far apart: the box of the sum lies away from the origin, so no facet is
    // kept near it, and the separation is refused rather than answered wrong
    let src = ExactSource::try_new_for_depth(box_mesh([1.5, 1.3, 0.0], [2.0, 2.0, 1.0]), box_mesh([-1.0; 3], [0.0; 3]), usize::MAX, Vec3::ZERO, 1e-3).unwrap();
    assert!(matches!(src.try_depth(Vec3::ZERO, 1e-3, 1000), Err(CoreError::InvalidParameter { .. })));
    // overlapping cubes, asked at another point than the one the sum was made for
    let src = ExactSource::try_new_for_depth(box_mesh([0.7, 0.0, 0.0], [1.7, 1.0, 1.0]), box_mesh([-1.0; 3], [0.0; 3]), usize::MAX, Vec3::ZERO, 1e-3).unwrap();
    assert!(src.try_depth(Vec3::ZERO, 1e-3, 1000).is_ok_and(|d| d.inside && (d.lower - 0.3).abs() <= 1e-3));
    assert!(matches!(src.try_depth(Vec3::new(0.9, 0.5, 0.5), 1e-3, 1000), Err(CoreError::InvalidParameter { .. })));
}
