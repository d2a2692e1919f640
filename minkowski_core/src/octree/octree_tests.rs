use super::*;
use crate::minkowski::PolytopeSet;

fn unit_cube_set() -> PolytopeSet {
    let pts: Vec<Vec3> = (0..8).map(|k| Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64)).collect();
    PolytopeSet::new(vec![ConvexPolytope::from_points(&pts)])
}

#[test]
fn leaves_tile_the_root_and_labels_are_right() {
    let set = unit_cube_set();
    let h = 0.05;
    let oct = Octree::build(&set, &set.aabb, h, 10_000_000).unwrap();
    let root = oct.root_box();
    let vol: f64 = oct.leaves.iter().map(|l| oct.cell_box(l).extent().element_product()).sum();
    assert!((vol - root.extent().element_product()).abs() < 1e-9 * vol);
    let cube = &set.polys[0];
    for l in &oct.leaves {
        let b = oct.cell_box(l);
        match l.label {
            Label::Full => assert!(cube.contains_box(&b)),
            Label::Empty => assert!(!cube.overlaps_box(&b)),
            Label::Mixed => {
                assert_eq!(l.level, 0);
                // a MIXED cell lies within one cell diagonal of the boundary
                let sd = cube.signed_distance(b.center()).abs();
                assert!(sd <= b.diagonal(), "mixed cell far from the surface: {sd}");
            }
        }
    }
    let counts = oct.level_counts();
    assert!(counts.iter().any(|c| c[Label::Full as usize] > 0));
    assert!(counts[0][Label::Mixed as usize] > 0);
}

#[test]
fn candidate_planes_are_only_those_cutting_the_cell() {
    let set = unit_cube_set();
    let oct = Octree::build(&set, &set.aabb, 0.1, 1_000_000).unwrap();
    let mut seen = 0;
    for l in oct.leaves.iter().filter(|l| l.label == Label::Mixed) {
        let b = oct.cell_box(l);
        for (prim, planes) in oct.candidates(l) {
            assert_eq!(prim, 0);
            assert!(!planes.is_empty() && planes.len() <= 3, "a cube cell is cut by at most 3 facets");
            // every kept plane really cuts the cell: corners on both sides
            for &k in planes {
                let (n, d) = (set.polys[0].normals[k as usize], set.polys[0].offsets[k as usize]);
                let (c, h) = (b.center(), b.half());
                assert!(n.dot(c) - n.abs().dot(h) <= d && n.dot(c) + n.abs().dot(h) > d);
            }
            seen += 1;
        }
    }
    assert!(seen > 0);
}

#[test]
fn cell_budget_is_enforced() {
    let set = unit_cube_set();
    let err = Octree::build(&set, &set.aabb, 1e-3, 1000).unwrap_err();
    assert!(matches!(err, CoreError::ResourceLimit { .. }), "{err}");
    assert!(Octree::build(&set, &set.aabb, 0.0, 1000).is_err());
    assert!(Octree::build(&set, &set.aabb, f64::NAN, 1000).is_err());
}

#[test]
fn record_budget_is_enforced() {
    let set = unit_cube_set();
    let full = Octree::build(&set, &set.aabb, 0.05, 1_000_000).unwrap();
    let words = full.cands.len();
    assert!(words > 0);
    let err = Octree::build_within(&set, &set.aabb, 0.05, 1_000_000, words - 1).unwrap_err();
    assert!(matches!(err, CoreError::RecordLimit { .. }), "{err}");
    assert!(err.to_string().contains("larger cell size"), "{err}");
    let exact_fit = Octree::build_within(&set, &set.aabb, 0.05, 1_000_000, words).unwrap();
    assert_eq!(exact_fit.cands.len(), words);
}
