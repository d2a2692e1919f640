//! Tests of the winding number, the solid test and certificate re-verification.

use super::exact_tests::{box_mesh, boxes_mesh, hollow_box, push_box, Lcg};
use super::*;
use crate::octree::{Label, Octree};

/// A floor slab wound inside out and a wall wound outward, overlapping, in one mesh (the
/// winding number is −1 in the floor, +1 in the wall, 0 where they overlap), as OMPL.app's
/// Easy frame is imported.
fn inverted_frame() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::new(0.0, 0.0, 0.0), Vec3::new(10.0, 1.0, 10.0), &mut v, &mut f);
    for t in &mut f {
        t.swap(1, 2);
    }
    push_box(Vec3::new(0.0, 0.0, 0.0), Vec3::new(10.0, 10.0, 1.0), &mut v, &mut f);
    (v, f)
}

/// The inverted frame claimed to be a solid, bypassing the check (what an importer that
/// trusts a consistently wound surface would hand over).
fn fake_solid_frame() -> TriMesh {
    let (v, f) = inverted_frame();
    TriMesh { closed: true, solid: true, ..TriMesh::surface(v, &f, "frame").unwrap() }
}

#[test]
fn winding_number_counts_shells() {
    let two = boxes_mesh(&[([0.0; 3], [2.0, 1.0, 1.0]), ([1.0, 0.0, 0.0], [3.0, 1.0, 1.0])]);
    assert_eq!(two.winding(Vec3::new(0.5, 0.5, 0.5)), Some(1));
    assert_eq!(two.winding(Vec3::new(1.5, 0.5, 0.5)), Some(2));
    assert_eq!(two.winding(Vec3::new(3.5, 0.5, 0.5)), Some(0));
    assert_eq!(two.winding(Vec3::new(0.0, 0.5, 0.5)), None, "on the surface");
    let hollow = hollow_box();
    assert_eq!(hollow.winding(Vec3::splat(1.5)), Some(1));
    assert_eq!(hollow.winding(Vec3::ZERO), Some(0), "the cavity");
}

#[test]
fn front_windings_are_zero_on_a_solid_and_tell_overlaps_and_cavities() {
    let b = box_mesh([0.0; 3], [1.0, 2.0, 3.0]);
    assert!(b.solid);
    assert!(b.front_windings().iter().all(|&w| w == Some(0)));
    // overlapping outward shells: faces inside the other shell have the solid in front
    let two = boxes_mesh(&[([0.0; 3], [2.0, 1.0, 1.0]), ([1.0, 0.0, 0.0], [3.0, 1.0, 1.0])]);
    let fronts = two.front_windings();
    assert!(fronts.iter().all(|w| matches!(w, Some(0) | Some(1))), "{fronts:?}");
    assert!(fronts.contains(&Some(1)));
    // a box inside another sharing its top and bottom planes: its top and bottom lie on
    // the other's, and are told just in front of them
    let inner = boxes_mesh(&[([0.0; 3], [3.0, 3.0, 1.0]), ([1.0, 1.0, 0.0], [2.0, 2.0, 1.0])]);
    assert!(inner.solid);
    let fronts = inner.front_windings();
    assert!(fronts.iter().all(|w| matches!(w, Some(0) | Some(1))), "{fronts:?}");
    // a cavity's faces point into it: winding 0 there
    assert!(hollow_box().front_windings().iter().all(|&w| w == Some(0)));
}

#[test]
fn an_inverted_shell_glued_to_another_is_no_solid() {
    let (v, f) = inverted_frame();
    let surface = TriMesh::surface(v.clone(), &f, "frame").unwrap();
    let fronts = TriMesh { closed: true, ..surface }.front_windings();
    // the floor's faces outside the wall have the floor (winding −1) in front of them
    assert!(fronts.contains(&Some(-1)), "{fronts:?}");
    let err = TriMesh::new(v, &f, "frame").unwrap_err().to_string();
    assert!(err.contains("bounds no solid"), "{err}");
    // one inside-out box alone is no solid either
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::ZERO, Vec3::ONE, &mut v, &mut f);
    for t in &mut f {
        t.swap(1, 2);
    }
    assert!(TriMesh::new(v, &f, "inside out").is_err());
}

/// The physical truth for the frame and a robot box: the robot meets the floor or the
/// wall (their union as boxes).
fn frame_blocks(robot: &Aabb, p: Vec3) -> bool {
    let at = Aabb::new(robot.min + p, robot.max + p);
    let floor = Aabb::new(Vec3::ZERO, Vec3::new(10.0, 1.0, 10.0));
    let wall = Aabb::new(Vec3::ZERO, Vec3::new(10.0, 10.0, 1.0));
    at.overlaps(&floor) || at.overlaps(&wall)
}

#[test]
fn verification_refuses_false_walls_of_a_solid_that_is_not_one() {
    let robot = Aabb::new(Vec3::splat(-0.3), Vec3::splat(0.3));
    let src = ExactSource::new(vec![fake_solid_frame()], box_mesh([-0.3; 3], [0.3; 3]).negated(), 0.0, None);
    let region = Aabb::new(Vec3::new(-1.0, -1.0, -1.0), Vec3::new(11.0, 4.0, 11.0));
    let oct = Octree::build(&src, &region, 0.25, 1 << 22).unwrap();
    let mut rng = Lcg(11);
    let (mut false_full, mut verified) = (0, 0);
    let mut budget = usize::MAX;
    for leaf in oct.leaves.iter().filter(|l| l.label == Label::Full) {
        let cell = oct.cell_box(leaf);
        let wrong = (0..16).map(|_| rng.point(&cell)).any(|p| !frame_blocks(&robot, p));
        let shown = src.verify_box(&cell, &mut budget);
        if wrong {
            false_full += 1;
            assert!(shown.is_none(), "a false FULL cell {cell:?} passed verification");
        }
        if shown.is_some() {
            verified += 1;
            for _ in 0..16 {
                let p = rng.point(&cell);
                assert!(frame_blocks(&robot, p), "verified cell {cell:?} holds free {p:?}");
            }
        }
    }
    assert!(false_full > 0, "the trusted inverted frame should give false FULL cells");
    assert!(verified > 0);
}

#[test]
fn verification_shows_true_walls_by_pieces_and_nesting() {
    // a thick block and a small robot: FULL cells deep inside need nesting, cells at the
    // surface pieces or splits
    let src = ExactSource::new(vec![box_mesh([0.0; 3], [4.0, 4.0, 4.0])], box_mesh([-0.2; 3], [0.2; 3]).negated(), 0.0, None);
    let mut budget = 100_000;
    let deep = Aabb::new(Vec3::splat(1.0), Vec3::splat(3.0));
    assert!(matches!(src.verify_box(&deep, &mut budget), Some(Witness::Nested { k: 0 })));
    let skin = Aabb::new(Vec3::new(-0.1, 1.0, 1.0), Vec3::new(0.6, 3.0, 3.0));
    assert!(src.verify_box(&skin, &mut budget).is_some(), "a box across the contact shell");
    let partly_free = Aabb::new(Vec3::new(-0.5, 1.0, 1.0), Vec3::new(0.5, 3.0, 3.0));
    assert!(src.verify_box(&partly_free, &mut budget).is_none());
    let mut none = 0;
    assert!(src.verify_box(&deep, &mut none).is_none(), "no budget, no proof");
}

#[test]
fn a_surface_contains_nothing_in_verification() {
    // the same block as a surface: a robot wholly inside it meets no triangle
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::ZERO, Vec3::splat(4.0), &mut v, &mut f);
    let src = ExactSource::new(vec![TriMesh::surface(v, &f, "block").unwrap()], box_mesh([-0.2; 3], [0.2; 3]).negated(), 0.0, None);
    let mut budget = 100_000;
    assert!(src.verify_box(&Aabb::new(Vec3::splat(1.0), Vec3::splat(3.0)), &mut budget).is_none());
    assert!(!src.contains_point(Vec3::splat(2.0)));
    assert!(src.contains_point(Vec3::new(0.1, 2.0, 2.0)));
}

#[test]
fn an_inverted_shell_poking_out_through_a_face_is_no_solid() {
    // the winding number is -1 only in the tip above the box's top, a region in front of
    // no face sample: the crossings of the tetrahedron with the top tell it
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::ZERO, Vec3::splat(10.0), &mut v, &mut f);
    let o = v.len() as u32;
    v.extend([Vec3::new(3.0, 3.0, 8.0), Vec3::new(7.0, 3.0, 8.0), Vec3::new(5.0, 7.0, 8.0), Vec3::new(5.0, 4.3, 11.0)]);
    // outward tetrahedron faces, then reversed: an inside-out tetrahedron
    for t in [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]] {
        f.push([o + t[0], o + t[2], o + t[1]]);
    }
    let mesh = TriMesh { closed: true, ..TriMesh::surface(v.clone(), &f, "poke").unwrap() };
    assert_eq!(mesh.winding(Vec3::new(5.0, 4.3, 10.5)), Some(-1));
    assert!(!mesh.crossings().is_empty());
    let err = TriMesh::new(v, &f, "poke").unwrap_err().to_string();
    assert!(err.contains("crossings"), "{err}");
}

/// A box with a cavity whose corner touches a small box inside the solid: one shell by
/// its corners, two by its edges; the cavity is a hole.
fn cavity_touching_a_box() -> TriMesh {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::ZERO, Vec3::splat(10.0), &mut v, &mut f);
    let cavity = f.len();
    push_box(Vec3::splat(5.0), Vec3::splat(7.0), &mut v, &mut f);
    for t in &mut f[cavity..] {
        t.swap(1, 2);
    }
    push_box(Vec3::splat(7.0), Vec3::splat(9.9), &mut v, &mut f);
    TriMesh::new(v, &f, "cavity and box").unwrap()
}

#[test]
fn a_cavity_joined_to_a_box_at_a_corner_stays_a_hole() {
    let src = ExactSource::new(vec![cavity_touching_a_box()], box_mesh([-0.3; 3], [0.3; 3]).negated(), 0.0, None);
    let truth = |p: Vec3| {
        let meets = p.cmpge(Vec3::splat(-0.3)).all() && p.cmple(Vec3::splat(10.3)).all();
        let in_cavity = p.cmpgt(Vec3::splat(5.3)).all() && p.cmplt(Vec3::splat(6.7)).all();
        meets && !in_cavity
    };
    let mut rng = Lcg(3);
    let region = Aabb::new(Vec3::splat(-1.0), Vec3::splat(11.0));
    for _ in 0..3000 {
        let p = rng.point(&region);
        assert_eq!(src.contains_point(p), truth(p), "{p:?}");
    }
    assert!(!src.segment_is_free(Vec3::splat(6.0), Vec3::new(6.0, 6.0, 9.0), 0.0));
    let oct = Octree::build(&src, &Aabb::new(Vec3::splat(4.0), Vec3::splat(8.0)), 0.05, 1 << 22).unwrap();
    for leaf in oct.leaves.iter().filter(|l| l.label != Label::Mixed) {
        let cell = oct.cell_box(leaf);
        for _ in 0..4 {
            let p = rng.point(&cell);
            assert_eq!(truth(p), leaf.label == Label::Full, "{:?} leaf {cell:?} at {p:?}", leaf.label);
        }
    }
}

#[test]
fn crossings_inside_are_told_where_shells_overlap_and_not_on_one_shell() {
    // an L of two bars overlapping at its corner: no face has the solid in front of its
    // samples, but the bars' faces cross inside the other bar
    let l = boxes_mesh(&[([0.0; 3], [2.0, 0.5, 0.5]), ([0.0; 3], [0.5, 2.0, 0.5])]);
    let crossings = l.crossings();
    assert!(!crossings.is_empty());
    assert_eq!(l.crossings_inside(&crossings), crossings.len(), "every crossing is inside both bars");
    assert!(l.crossing_windings(&crossings).iter().all(|&w| w == Some(0)), "outside both in front");
    let one = box_mesh([0.0; 3], [1.0, 2.0, 3.0]);
    assert_eq!(one.crossings_inside(&one.crossings()), 0);
}

/// A box 1e-5 across at (1, 1, 1) whose top face carries a needle along its diagonal
/// from corner 4 to corner 7: a triangle (4, m, 7) with `m` at the diagonal's middle,
/// moved off it by `dy` in y, the top triangle on its other side split at `m`.
fn box_with_a_needle(dy: f64) -> TriMesh {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::splat(1.0), Vec3::splat(1.0 + 1e-5), &mut v, &mut f);
    let m = v.len() as u32;
    v.push(Vec3::new((v[4].x + v[7].x) / 2.0, (v[4].y + v[7].y) / 2.0 + dy, v[4].z));
    let top = f.iter().position(|t| *t == [4, 5, 7]).expect("the top's first triangle");
    f[top] = [4, 5, m];
    f.extend([[5, 7, m], [4, m, 7]]);
    TriMesh::new(v, &f, "needle box").unwrap()
}

#[test]
fn a_needle_whose_normal_is_rounding_has_no_front() {
    // moved up in y, the needle's normal (a rounding's worth of cross product) points
    // into the box: asked in front of it, the box would count it a face inside a solid
    for dy in [2.2e-16, -2.2e-16] {
        let mesh = box_with_a_needle(dy);
        let needle = mesh.tris.len() - 1;
        assert!(mesh.tris[needle].n != Vec3::ZERO, "its normal is a unit vector of noise (dy {dy})");
        let fronts = mesh.front_windings();
        assert_eq!(fronts[needle], Some(0), "the needle bounds nothing (dy {dy})");
        assert!(fronts.iter().all(|w| *w == Some(0)), "{fronts:?}");
    }
    // a short edge's true sliver is no needle: kept as a face with a front
    for dy in [1e-9, 1e-13] {
        // (1e-13: twenty times the roundings' worth)
        let sliver = box_with_a_needle(dy);
        assert!(!sliver.is_degenerate(&sliver.tris[sliver.tris.len() - 1]), "dy {dy}");
    }
}

/// A unit box with a triangular prism standing on one of its edges on the box's top: two
/// shells that touch along a line inside the top face.
fn prism_on_its_edge() -> TriMesh {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::ZERO, Vec3::ONE, &mut v, &mut f);
    let o = v.len() as u32;
    for y in [0.2, 0.8] {
        v.extend([Vec3::new(0.5, y, 1.0), Vec3::new(0.7, y, 1.5), Vec3::new(0.3, y, 1.5)]);
    }
    let (a, b) = (o, o + 3); // the two ends' triangles
    f.extend([[a, a + 2, a + 1], [b, b + 1, b + 2]]);
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        f.extend([[a + i, a + j, b + j], [a + i, b + j, b + i]]);
    }
    for t in f.iter_mut().skip(12) {
        t.swap(1, 2); // outward
    }
    TriMesh::new(v, &f, "prism on a box").unwrap()
}

#[test]
fn sheets_that_touch_along_a_line_do_not_cross() {
    let mesh = prism_on_its_edge();
    assert!(mesh.crossings().is_empty(), "{:?}", mesh.crossings());
    assert!(mesh.front_windings().iter().all(|w| *w == Some(0)));
    // pushed into the box by a little, the prism's slanted faces cross the top
    let (mut v, f) = (mesh.vertices.clone(), mesh.faces.clone());
    for p in v.iter_mut().skip(8) {
        p.z -= 0.01;
    }
    let sunk = TriMesh::new(v, &f, "prism sunk into a box").unwrap();
    assert!(!sunk.crossings().is_empty());
}

/// A box `[0, 2]² × [0, 1]` and a prism along y whose cross-section is a square turned
/// 45°, its side corners exactly on the box's top (`z = 1`): each of its faces touches
/// the top along an edge, the face across on the top's other side, so its sheet passes
/// through the top there.
fn diamond_through_a_box_top() -> TriMesh {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::ZERO, Vec3::new(2.0, 2.0, 1.0), &mut v, &mut f);
    let o = v.len() as u32;
    let section = [(1.0, 0.5), (1.5, 1.0), (1.0, 1.5), (0.5, 1.0)]; // (x, z), counter-clockwise seen from -y
    for y in [0.5, 1.5] {
        v.extend(section.iter().map(|&(x, z)| Vec3::new(x, y, z)));
    }
    let (a, b) = (o, o + 4);
    f.extend([[a, a + 1, a + 2], [a, a + 2, a + 3], [b, b + 2, b + 1], [b, b + 3, b + 2]]);
    for k in 0..4 {
        let (i, j) = (k, (k + 1) % 4);
        f.extend([[a + i, b + i, b + j], [a + i, b + j, a + j]]);
    }
    let mesh = TriMesh::surface(v.clone(), &f, "diamond").unwrap();
    let outward = mesh.tris.iter().skip(12).all(|t| (t.p[0] - Vec3::new(1.0, 1.0, 1.0)).dot(t.n) >= -1e-12);
    if !outward {
        for t in f.iter_mut().skip(12) {
            t.swap(1, 2);
        }
    }
    TriMesh::new(v, &f, "diamond through a box's top").unwrap()
}

#[test]
fn a_sheet_passing_through_a_face_along_its_own_edges_crosses_it() {
    let mesh = diamond_through_a_box_top();
    let crossings = mesh.crossings();
    assert!(!crossings.is_empty());
    // the shells overlap: the solid is on both sides of both faces behind the crossings
    assert!(mesh.crossings_inside(&crossings) > 0);
}
