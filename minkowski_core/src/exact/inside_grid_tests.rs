//! Tests of the inside grid and the nested-vertex test that uses it.

use super::exact_tests::{box_mesh, hollow_box, torus_mesh, Lcg};
use super::inside_grid::{InsideGrid, Span, MAX_VOXELS};
use super::*;

/// Random boxes in and around `mesh`, of half sizes up to `rel` of its longest side (for
/// the finest voxels, 1/256 of it, and the coarser levels).
fn random_boxes(mesh: &TriMesh, n: usize, seed: u64, rel: f64) -> Vec<Aabb> {
    let mut rng = Lcg(seed);
    let around = mesh.aabb.inflated(0.1 * mesh.aabb.diagonal());
    let scale = mesh.aabb.extent().max_element();
    (0..n)
        .map(|_| {
            let c = rng.point(&around);
            // sizes spread over orders of magnitude
            let size = rel * scale * rng.next().powi(3);
            let h = Vec3::new(rng.next(), rng.next(), rng.next()) * size + Vec3::splat(1e-6 * scale);
            Aabb::new(c - h, c + h)
        })
        .collect()
}

/// `n` separate triangles of side `size` along the x axis at height `y` (one every 0.1),
/// each its own shell.
fn push_strip(n: usize, y: f64, size: f64, v: &mut Vec<Vec3>, f: &mut Vec<[u32; 3]>) {
    for i in 0..n {
        let x = 0.1 * i as f64;
        let k = v.len() as u32;
        v.extend([Vec3::new(x, y, 0.0), Vec3::new(x + size, y, 0.0), Vec3::new(x, y + size, 0.0)]);
        f.push([k, k + 1, k + 2]);
    }
}

#[test]
fn the_grid_answers_as_the_exact_box_test_or_not_at_all() {
    for (mesh, seed, rel) in [(torus_mesh(3.0, 1.0, 48, 24), 1, 0.02), (hollow_box(), 2, 0.02), (torus_mesh(3.0, 1.0, 48, 24), 3, 0.5)] {
        let grid = InsideGrid::new(&mesh, MAX_VOXELS);
        let (mut told, mut inside, mut outside) = (0, 0, 0);
        for b in random_boxes(&mesh, 20_000, seed, rel) {
            let exact = mesh.contains_box(&b);
            let mut queries = usize::MAX;
            if let Some(answer) = grid.box_inside(&mesh, &b, &mut queries) {
                assert_eq!(answer, exact, "{b:?}");
                told += 1;
                inside += answer as usize;
            }
            match grid.span(&mesh, &b) {
                Span::Inside => assert!(exact, "{b:?}"),
                Span::Outside => {
                    assert!(!mesh.meets_box(&b) && !mesh.contains(b.center()), "{b:?}");
                    outside += 1;
                }
                Span::Crossing => assert!(!exact && mesh.meets_box(&b), "{b:?}: crosses the boundary"),
                Span::TouchesOutside => assert!(!exact, "{b:?}"),
                Span::TouchesInside | Span::Unknown => {}
            }
        }
        // the grid tells most boxes; both answers occur
        assert!(told > 15_000 && inside > 500 && outside > 1_000, "told {told}, inside {inside}, outside {outside}");
    }
}

#[test]
fn boxes_on_voxel_faces_and_at_the_mesh_box_are_covered() {
    // a unit cube: its box is the grid's, so voxel faces fall on round coordinates and
    // boxes reach the grid's last voxel face
    let cube = box_mesh([0.0; 3], [1.0; 3]);
    let grid = InsideGrid::new(&cube, MAX_VOXELS);
    let mut queries = usize::MAX;
    for b in [
        Aabb::new(Vec3::splat(0.25), Vec3::splat(0.5)),
        Aabb::new(Vec3::splat(0.5), Vec3::splat(0.75)),
        Aabb::new(Vec3::splat(0.9), Vec3::splat(1.0)),
        Aabb::new(Vec3::ZERO, Vec3::splat(0.1)),
        Aabb::new(Vec3::splat(0.9), Vec3::splat(1.1)),
        Aabb::new(Vec3::splat(1.0), Vec3::splat(1.2)),
    ] {
        let answer = grid.box_inside(&cube, &b, &mut queries);
        assert!(answer.is_none_or(|a| a == cube.contains_box(&b)), "{b:?}: {answer:?}");
    }
}

#[test]
fn vertices_beyond_a_sample_are_asked_through_the_grid_for_the_planner_with_surfaces() {
    // a long thin bar (a surface, as an open robot is) with one end deep in a box: only
    // the bar's far vertices show the cells near the box's middle FULL, which the sample
    // of twelve vertices does not hold
    let target = box_mesh([-1.0; 3], [1.0; 3]);
    let (mut v, mut f) = (Vec::new(), Vec::new());
    exact_tests::push_box(Vec3::new(0.0, -0.01, -0.01), Vec3::new(20.0, 0.01, 0.01), &mut v, &mut f);
    // extra vertices along the bar, so that a sample skips the ends
    push_strip(200, 0.02, 0.1, &mut v, &mut f);
    let bar = TriMesh::surface(v, &f, "bar").unwrap();
    let walls = Some(Aabb::new(Vec3::splat(-30.0), Vec3::splat(30.0)));
    let src = ExactSource::new(vec![target.clone()], bar.negated(), 0.0, walls);
    assert!(src.nested_first());
    // translations t with the bar's end (x = 20) in the target: t.x near -20
    let cell = Aabb::new(Vec3::new(-20.3, -0.2, -0.2), Vec3::new(-19.9, 0.2, 0.2));
    let sampled = ExactSource::new(vec![target], bar.negated(), 0.0, None);
    assert!(!sampled.nested_first() && !sampled.vertex_nested(0, &cell), "a sample misses the far end");
    assert!(src.vertex_nested(0, &cell), "the bar's end vertices lie in the box for every t");
    let witness = src.box_shown(&cell);
    assert_eq!(witness, Some(Witness::Nested { k: 0 }), "re-verified the same way");
    // and never claims what is not so: a cell where no vertex lies inside for every t
    let apart = Aabb::new(Vec3::new(-22.5, -0.2, -0.2), Vec3::new(-21.5, 0.2, 0.2));
    assert!(!src.vertex_nested(0, &apart));
}

#[test]
fn nested_cells_found_through_the_grid_are_nested_for_some_vertex() {
    // soundness against the exhaustive exact test: a torus (solid obstacle) and an open
    // ring of triangles (a surface robot), random cells
    let torus = torus_mesh(3.0, 1.0, 32, 16);
    let ring = torus_mesh(1.5, 0.3, 16, 8);
    let robot = TriMesh::surface(ring.vertices.clone(), &ring.faces, "ring").unwrap();
    let walls = Some(Aabb::new(Vec3::splat(-20.0), Vec3::splat(20.0)));
    let src = ExactSource::new(vec![torus.clone()], robot.clone(), 0.0, walls);
    assert!(src.nested_first());
    let mut found = 0;
    for cell in random_boxes(&torus, 3_000, 7, 0.02) {
        let nested = src.vertex_nested(0, &cell);
        let exhaustive = robot.vertices.iter().any(|&v| torus.contains_box(&Aabb::new(cell.min - v, cell.max - v)));
        assert!(!nested || exhaustive, "{cell:?}");
        found += nested as usize;
    }
    assert!(found > 100, "{found}");
}

#[test]
fn a_solid_robot_is_asked_through_its_own_grid() {
    // the roles swapped: a solid bar (the robot) and a surface plate with many vertices
    // (an obstacle); cells where a far vertex of the plate lies in the bar are nested
    let (mut v, mut f) = (Vec::new(), Vec::new());
    exact_tests::push_box(Vec3::new(-0.05, -0.05, -0.05), Vec3::new(0.05, 0.05, 0.05), &mut v, &mut f);
    let bar = TriMesh::new(v, &f, "bar").unwrap();
    let (mut v, mut f) = (Vec::new(), Vec::new());
    push_strip(300, 1.0, 0.05, &mut v, &mut f);
    let strip = TriMesh::surface(v, &f, "strip").unwrap();
    let walls = Some(Aabb::new(Vec3::splat(-50.0), Vec3::splat(50.0)));
    let src = ExactSource::new(vec![strip.clone()], bar.negated(), 0.0, walls);
    assert!(src.nested_first());
    // B = −bar: at translation p, p − B = p + bar holds the strip's corner (25, 1, 0) when
    // p is within 0.05 of it
    let cell = Aabb::new(Vec3::new(24.99, 0.99, -0.01), Vec3::new(25.01, 1.01, 0.01));
    assert!(src.vertex_nested(0, &cell));
    assert_eq!(src.box_shown(&cell), Some(Witness::Nested { k: 0 }));
    let sampled = ExactSource::new(vec![strip], bar.negated(), 0.0, None);
    assert!(!sampled.vertex_nested(0, &cell), "a sample misses the far corners");
}

#[test]
fn a_vertex_no_triangle_uses_is_never_the_nested_one() {
    // a surface robot with a stray vertex (kept by importers) placed so that it would lie
    // deep in the obstacle: it is no part of the robot, so nothing is nested
    let target = box_mesh([-1.0; 3], [1.0; 3]);
    let v = vec![Vec3::new(5.0, 0.0, 0.0), Vec3::new(5.1, 0.0, 0.0), Vec3::new(5.0, 0.1, 0.0), Vec3::ZERO];
    let robot = TriMesh::surface(v, &[[0, 1, 2]], "robot with a stray vertex").unwrap();
    let cell = Aabb::new(Vec3::splat(-0.1), Vec3::splat(0.1));
    for walls in [None, Some(Aabb::new(Vec3::splat(-20.0), Vec3::splat(20.0)))] {
        let src = ExactSource::new(vec![target.clone()], robot.clone(), 0.0, walls);
        assert!(!src.vertex_nested(0, &cell), "walls {walls:?}");
        assert_eq!(src.box_shown(&cell), None);
    }
}
