//! Tests of the inside grid and the nested-vertex test that uses it.

use super::exact_tests::{box_mesh, hollow_box, torus_mesh, Lcg};
use super::inside_grid::{InsideGrid, Span};
use super::*;

/// Random boxes of sizes from a tenth of a voxel to a few voxels, in and around `mesh`.
fn random_boxes(mesh: &TriMesh, n: usize, seed: u64) -> Vec<Aabb> {
    let mut rng = Lcg(seed);
    let around = mesh.aabb.inflated(0.1 * mesh.aabb.diagonal());
    let scale = mesh.aabb.extent().max_element();
    (0..n)
        .map(|_| {
            let c = rng.point(&around);
            let h = Vec3::new(rng.next(), rng.next(), rng.next()) * (0.02 * scale * rng.next()) + Vec3::splat(1e-6 * scale);
            Aabb::new(c - h, c + h)
        })
        .collect()
}

#[test]
fn the_grid_answers_as_the_exact_box_test_or_not_at_all() {
    for (mesh, seed) in [(torus_mesh(3.0, 1.0, 48, 24), 1), (hollow_box(), 2)] {
        let grid = InsideGrid::new(&mesh);
        let (mut told, mut inside, mut outside) = (0, 0, 0);
        for b in random_boxes(&mesh, 20_000, seed) {
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
        // the grid tells nearly every box; both answers occur
        assert!(told > 19_000 && inside > 1_000 && outside > 1_000, "told {told}, inside {inside}, outside {outside}");
    }
}

#[test]
fn boxes_on_voxel_faces_and_at_the_mesh_box_are_covered() {
    // a unit cube: its box is the grid's, so voxel faces fall on round coordinates and
    // boxes reach the grid's last voxel face
    let cube = box_mesh([0.0; 3], [1.0; 3]);
    let grid = InsideGrid::new(&cube);
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
fn every_vertex_is_asked_through_the_grid_for_the_planner_with_surface_pairs() {
    // a long thin bar (a surface, as an open robot is) with one end deep in a box: only
    // the bar's far vertices show the cells near the box's middle FULL, which a sample of
    // twelve vertices need not hold
    let target = box_mesh([-1.0; 3], [1.0; 3]);
    let (mut v, mut f) = (Vec::new(), Vec::new());
    exact_tests::push_box(Vec3::new(0.0, -0.01, -0.01), Vec3::new(20.0, 0.01, 0.01), &mut v, &mut f);
    // extra vertices along the bar (a strip of triangles), so that a sample skips the ends
    for i in 0..200 {
        let x = 0.1 * i as f64;
        let n = v.len() as u32;
        v.extend([Vec3::new(x, 0.02, 0.0), Vec3::new(x + 0.1, 0.02, 0.0), Vec3::new(x, 0.03, 0.0)]);
        f.push([n, n + 1, n + 2]);
    }
    let bar = TriMesh::surface(v, &f, "bar").unwrap();
    let walls = Some(Aabb::new(Vec3::splat(-30.0), Vec3::splat(30.0)));
    let src = ExactSource::new(vec![target], bar.negated(), 0.0, walls);
    assert!(src.nested_first());
    // translations t with the bar's end (x = 20) in the target: t.x near -20
    let cell = Aabb::new(Vec3::new(-20.3, -0.2, -0.2), Vec3::new(-19.9, 0.2, 0.2));
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
    for cell in random_boxes(&torus, 3_000, 7) {
        let nested = src.vertex_nested(0, &cell);
        let exhaustive = robot.vertices.iter().any(|&v| torus.contains_box(&Aabb::new(cell.min - v, cell.max - v)));
        assert!(!nested || exhaustive, "{cell:?}");
        found += nested as usize;
    }
    assert!(found > 100, "{found}");
}
