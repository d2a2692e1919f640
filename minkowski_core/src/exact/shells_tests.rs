//! Tests of closed shells (mod 2) and the witness that a connected part crosses one.

use super::exact_tests::{push_box, Lcg};
use super::shells::Shells;
use super::*;

/// Two boxes glued by a shared cap, as OMPL.app's escape ring is: `[0,1]³` without its
/// `x = 1` face, `[1,3]×[0,1]²` without its `x = 1` face, and that face once (its edges
/// used by three triangles); the second box inside out when `flip`. A surface.
fn glued(flip: bool) -> TriMesh {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::ZERO, Vec3::ONE, &mut v, &mut f);
    let cap = [f[10], f[11]]; // push_box's x = hi quad
    f.truncate(10);
    let (mut v2, mut f2) = (Vec::new(), Vec::new());
    push_box(Vec3::new(1.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0), &mut v2, &mut f2);
    f2.drain(8..10); // its x = lo quad
    let o = v.len() as u32;
    f.extend(f2.iter().map(|t| {
        let t = t.map(|i| i + o);
        if flip {
            [t[0], t[2], t[1]]
        } else {
            t
        }
    }));
    v.extend(v2);
    f.extend(cap);
    TriMesh::surface(v, &f, "glued").unwrap()
}

/// A thin strip (two triangles) along y from `y0` to `y1`, at x in [-0.05, 0.05], z = 0.
fn strip(y0: f64, y1: f64) -> TriMesh {
    let v = vec![Vec3::new(-0.05, y0, 0.0), Vec3::new(0.05, y0, 0.0), Vec3::new(0.05, y1, 0.0), Vec3::new(-0.05, y1, 0.0)];
    TriMesh::surface(v, &[[0, 1, 2], [0, 2, 3]], "strip").unwrap()
}

/// The closed box `[-1, 1]³` taken as a surface.
fn hollow_cube() -> TriMesh {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::splat(-1.0), Vec3::ONE, &mut v, &mut f);
    TriMesh::surface(v, &f, "hollow cube").unwrap()
}

/// Brute force: whether some triangle of `a` meets some triangle of `p − b`.
fn triangles_meet(a: &TriMesh, b: &TriMesh, p: Vec3) -> bool {
    a.tris.iter().any(|t| b.tris.iter().any(|s| pair_contains_point(t, s, 0.0, p)))
}

#[test]
fn cells_glued_by_a_shared_cap_are_three_shells_whatever_their_orientation() {
    for flip in [false, true] {
        let mesh = glued(flip);
        let shells = Shells::of(&mesh);
        let sizes: Vec<usize> = shells.shells.iter().map(|s| s.tris.len()).collect();
        assert_eq!(sizes, vec![20, 12, 12], "the outer shell (no cap), then each box with the cap; flip {flip}");
        let (first, second) = (Vec3::splat(0.5), Vec3::new(2.0, 0.5, 0.5));
        let odd = |s: usize, q: Vec3| shells.shells[s].mesh.parity(q);
        assert_eq!((odd(0, first), odd(0, second)), (Some(true), Some(true)));
        let own: Vec<(Option<bool>, Option<bool>)> = (1..3).map(|s| (odd(s, first), odd(s, second))).collect();
        assert!(own.contains(&(Some(true), Some(false))) && own.contains(&(Some(false), Some(true))), "{own:?}");
    }
}

#[test]
fn an_open_surface_has_no_shell() {
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_box(Vec3::ZERO, Vec3::ONE, &mut v, &mut f);
    f.pop();
    assert!(Shells::of(&TriMesh::surface(v, &f, "open").unwrap()).shells.is_empty());
    assert!(Shells::of(&strip(0.0, 1.0)).shells.is_empty());
}

#[test]
fn a_strip_through_a_hollow_cube_is_pierced_at_every_translation_of_a_box() {
    let (cube, long) = (hollow_cube(), strip(-10.0, 10.0));
    let (of_cube, of_strip) = (Shells::of(&cube), Shells::of(&long));
    let cell = Aabb::new(Vec3::splat(-0.3), Vec3::splat(0.3));
    // the cube is its own reflection: B = −R = the cube
    let found = of_cube.pierce(&cell, &long, &of_strip).expect("the strip crosses the cube's faces");
    assert!(of_cube.shells[found.shell].mesh.parity(cell.center() - found.x) == Some(true));
    assert!(found.y.y.abs() == 10.0, "the far vertex is an end of the strip: {:?}", found.y);
    let mut rng = Lcg(3);
    for _ in 0..500 {
        let p = rng.point(&cell);
        assert!(triangles_meet(&long, &cube, p), "{p:?}");
    }
    // too wide a box: no ball of the cube holds it
    assert_eq!(of_cube.pierce(&Aabb::new(Vec3::splat(-1.2), Vec3::splat(1.2)), &long, &of_strip), None);
}

#[test]
fn a_strip_inside_the_cube_is_no_witness_and_touches_nothing() {
    let (cube, short) = (hollow_cube(), strip(-0.5, 0.5));
    let cell = Aabb::new(Vec3::splat(-0.2), Vec3::splat(0.2));
    assert_eq!(Shells::of(&cube).pierce(&cell, &short, &Shells::of(&short)), None);
    assert!(!triangles_meet(&short, &cube, Vec3::ZERO));
}

#[test]
fn certificates_of_surfaces_use_the_witness_and_it_holds() {
    // a surface robot of two glued boxes, one inside out (no solid), around a long strip
    let robot = glued(true);
    let long = strip(-10.0, 10.0);
    let walls = Aabb::new(Vec3::splat(-20.0), Vec3::splat(20.0));
    let src = ExactSource::new(vec![long.clone()], robot.negated(), 0.0, Some(walls));
    assert!(!src.b.solid && src.full_witness);
    // translations p with the strip (x = 0, z = 0) inside the first box of p − B = p + R
    let cell = Aabb::new(Vec3::new(-0.7, -0.2, -0.7), Vec3::new(-0.3, 0.2, -0.3));
    let mut budget = 64;
    let parts = src.verify_box_witnesses(&cell, &mut budget).expect("shown blocked");
    assert!(parts.iter().all(|(_, w)| matches!(w, BoxWitness::Pierced { shell_of_b: true, .. })), "{parts:?}");
    let mut rng = Lcg(9);
    for _ in 0..300 {
        let p = rng.point(&cell);
        assert!(triangles_meet(&long, &src.b, p), "{p:?}");
    }
}
