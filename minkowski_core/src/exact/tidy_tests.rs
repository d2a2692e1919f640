//! Tests of the tidiness check that lets a clean solid skip the cleaning.

use super::exact_tests::push_box;
use super::tidy::{tidy_shells, tidy_windings, TidyLimits};
use super::*;

/// The cleaning's tolerances for a part of size about 1 (`planner.tolerances`' defaults).
const LIMITS: TidyLimits = TidyLimits { merge: 1e-9, degenerate_area: 1e-12, zero_volume: 1e-12, fold_angle: 1e-3, coplanar: 1e-5 };

fn faces_itself(mesh: &TriMesh, shells: &[u32], limits: &TidyLimits) -> bool {
    mesh.faces_itself(shells, limits)
}

fn boxes(list: &[([f64; 3], [f64; 3])]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    for &(lo, hi) in list {
        push_box(Vec3::from_array(lo), Vec3::from_array(hi), &mut v, &mut f);
    }
    (v, f)
}

fn unit_box() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    boxes(&[([0.0; 3], [1.0, 0.6, 0.4])])
}

#[test]
fn a_clean_box_and_two_apart_are_tidy_with_their_shells_numbered() {
    let (v, f) = unit_box();
    assert_eq!(tidy_shells(&v, &f, &LIMITS), Ok(vec![0; 12]));
    let (v, f) = boxes(&[([0.0; 3], [1.0; 3]), ([2.0, 0.0, 0.0], [3.0, 1.0, 1.0])]);
    let shells = tidy_shells(&v, &f, &LIMITS).unwrap();
    assert_eq!(shells, [vec![0; 12], vec![1; 12]].concat());
    let mesh = TriMesh::new(v, &f, "boxes").unwrap();
    assert!(!faces_itself(&mesh, &shells, &LIMITS));
}

#[test]
fn each_thing_the_cleaning_would_change_makes_a_mesh_untidy() {
    let (v, f) = unit_box();
    let untidy = |v: &[Vec3], f: &[[u32; 3]]| tidy_shells(v, f, &LIMITS).unwrap_err();

    let mut unused = v.clone();
    unused.push(Vec3::splat(5.0));
    assert_eq!(untidy(&unused, &f), "a vertex is not used");

    let mut turned = f.clone();
    turned[3].swap(1, 2);
    assert_eq!(untidy(&v, &turned), "a directed edge is used twice");

    let mut open = f.clone();
    open.pop();
    assert_eq!(untidy(&v, &open), "an edge is not used once in each direction");

    let mut repeated = f.clone();
    repeated.push([f[0][1], f[0][2], f[0][0]]);
    assert_eq!(untidy(&v, &repeated), "a triangle repeats another's corners");

    let inside_out: Vec<[u32; 3]> = f.iter().map(|t| [t[0], t[2], t[1]]).collect();
    assert_eq!(untidy(&v, &inside_out), "a shell is flat or inside out");

    let (cavity_v, mut cavity_f) = boxes(&[([0.0; 3], [4.0; 3]), ([1.0; 3], [2.0; 3])]);
    cavity_f[12..].iter_mut().for_each(|t| t.swap(1, 2));
    assert_eq!(untidy(&cavity_v, &cavity_f), "a shell is flat or inside out", "a cavity is reported as a change");

    // the same box with one corner split in two copies a hair apart
    let mut split_v = v.clone();
    split_v.push(v[7] + Vec3::new(0.5e-9, 0.0, 0.0));
    let mut split_f = f.clone();
    let user = split_f.iter().position(|t| t.contains(&7)).unwrap();
    split_f[user] = split_f[user].map(|i| if i == 7 { 8 } else { i });
    assert_eq!(untidy(&split_v, &split_f), "an edge is not used once in each direction");
}

#[test]
fn vertices_within_the_merge_distance_and_flat_shells_make_a_mesh_untidy() {
    // two boxes touching at a corner but for a gap below the merge distance
    let (v, f) = boxes(&[([0.0; 3], [1.0; 3]), ([1.0 + 5e-10, 1.0, 1.0], [2.0; 3])]);
    assert_eq!(tidy_shells(&v, &f, &LIMITS), Err("two vertices lie within the merge distance"));
    let (v, f) = boxes(&[([0.0; 3], [1.0; 3]), ([1.0 + 5e-9, 1.0, 1.0], [2.0; 3])]);
    assert!(tidy_shells(&v, &f, &LIMITS).is_ok(), "ten times farther: apart");

    let (v, f) = boxes(&[([0.0; 3], [1.0, 1.0, 1e-12])]);
    assert_eq!(tidy_shells(&v, &f, &LIMITS), Err("a shell is flat or inside out"));
}

#[test]
fn degenerate_triangles_are_tidy_only_in_a_shell_that_has_others() {
    // the box's top (corners 4 (0, 0), 5 (1, 0), 6 (0, .6), 7 (1, .6) at z = .4) fanned
    // from the middle of its edge 4-5, and a zero-area sliver 4, 5, mid closing that edge
    let (mut v, f) = unit_box();
    let mut f: Vec<[u32; 3]> = f.into_iter().filter(|t| !t.iter().all(|&k| v[k as usize].z == 0.4)).collect();
    v.push((v[4] + v[5]) / 2.0);
    f.extend([[4, 8, 6], [8, 5, 7], [8, 7, 6], [4, 5, 8]]);
    let shells = tidy_shells(&v, &f, &LIMITS).unwrap();
    assert_eq!(shells, vec![0; 14]);
    let mesh = TriMesh::new(v, &f, "fanned").unwrap();
    assert!(!faces_itself(&mesh, &shells, &LIMITS));
}

#[test]
fn a_slab_thinner_than_the_coplanar_distance_faces_itself() {
    for (thickness, facing) in [(1e-6, true), (1e-3, false)] {
        let (v, f) = boxes(&[([0.0; 3], [1.0, 1.0, thickness])]);
        let limits = TidyLimits { zero_volume: 1e-15, ..LIMITS };
        let shells = tidy_shells(&v, &f, &limits).unwrap();
        let mesh = TriMesh::new(v, &f, "slab").unwrap();
        assert_eq!(faces_itself(&mesh, &shells, &limits), facing, "thickness {thickness}");
    }
    // the same thin slab turned so that its faces' normals lie across the direction that
    // sorts normals up and down (both of its faces are listed both ways)
    let g = Vec3::new(0.577_350_269_189_625_8, 0.618_033_988_749_894_8, 0.532_088_886_237_956_1).normalize();
    let n = g.cross(Vec3::Z).normalize();
    let (u, w) = (Vec3::Z, n.cross(Vec3::Z));
    let (v, f) = boxes(&[([0.0; 3], [1.0, 1.0, 1e-6])]);
    let turned: Vec<Vec3> = v.iter().map(|p| u * p.x + w * p.y + n * p.z).collect();
    let limits = TidyLimits { zero_volume: 1e-15, ..LIMITS };
    let shells = tidy_shells(&turned, &f, &limits).unwrap();
    let mesh = TriMesh::new(turned, &f, "turned slab").unwrap();
    assert!(faces_itself(&mesh, &shells, &limits));
    // two slabs stacked with a hair between them are two shells: they may rest on each other
    let (v, f) = boxes(&[([0.0; 3], [1.0, 1.0, 0.5]), ([0.0, 0.0, 0.5 + 1e-6], [1.0, 1.0, 1.0])]);
    let shells = tidy_shells(&v, &f, &LIMITS).unwrap();
    let mesh = TriMesh::new(v, &f, "stacked").unwrap();
    assert!(!faces_itself(&mesh, &shells, &LIMITS));
}

#[test]
fn the_tidy_windings_are_the_checked_ones() {
    let apart: &[([f64; 3], [f64; 3])] = &[([0.0; 3], [1.0; 3]), ([2.0, 0.0, 0.0], [3.0, 1.0, 1.0])];
    let overlapping: &[([f64; 3], [f64; 3])] = &[([0.0; 3], [2.0, 1.0, 1.0]), ([1.0, 0.2, 0.3], [3.0, 1.5, 1.5])];
    let nested: &[([f64; 3], [f64; 3])] = &[([0.0; 3], [4.0; 3]), ([1.0; 3], [2.0; 3])];
    for list in [apart, overlapping, nested] {
        let (v, f) = boxes(list);
        let tidy = tidy_windings(v.clone(), &f, &LIMITS, "boxes").expect("tidy");
        let checked = TriMesh::checked_windings(v, &f, "boxes").unwrap();
        assert_eq!(tidy.fronts, checked.fronts);
        assert_eq!(tidy.wedges, checked.wedges);
        assert_eq!(tidy.crossings_inside, checked.crossings_inside);
        assert!(tidy.solid.is_ok() && checked.solid.is_ok());
    }
    let (v, f) = boxes(overlapping);
    assert!(!tidy_windings(v, &f, &LIMITS, "boxes").unwrap().wedges.is_empty(), "the overlap has crossings");
    let (v, f) = boxes(nested);
    assert!(tidy_windings(v, &f, &LIMITS, "boxes").unwrap().fronts[12..].iter().all(|&w| w == Some(1)), "the inner box is inside the outer");
}
