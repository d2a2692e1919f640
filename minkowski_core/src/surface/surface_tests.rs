use super::*;
use crate::minkowski::PolytopeSet;
use crate::octree::Octree;
use crate::polytope::ConvexPolytope;

#[test]
fn kuhn_split_has_19_edges_and_fills_the_cube() {
    assert_eq!(cell_edges().len(), 19);
    let vol: i64 = tets()
        .iter()
        .map(|t| {
            let v = corner(t[0]);
            det3(sub(corner(t[1]), v), sub(corner(t[2]), v), sub(corner(t[3]), v)).abs()
        })
        .sum();
    assert_eq!(vol, 6, "six tetrahedra of volume 1/6");
}

#[test]
fn every_sign_case_gives_the_expected_triangle_count() {
    for (tn, cases) in case_table().iter().enumerate() {
        for (m, tris) in cases.iter().enumerate() {
            let n_in = (m as u8).count_ones();
            let want = match n_in {
                0 | 4 => 0,
                1 | 3 => 1,
                _ => 2,
            };
            assert_eq!(tris.len(), want, "tet {tn} mask {m}");
        }
    }
}

#[test]
fn empty_band_gives_empty_surface() {
    let pts: Vec<Vec3> = (0..8).map(|k| Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64)).collect();
    let set = PolytopeSet::new(vec![ConvexPolytope::from_points(&pts)]);
    let mut oct = Octree::build(&set, &set.aabb, 0.25, 100000).unwrap();
    oct.leaves.retain(|l| l.label != crate::octree::Label::Mixed);
    let s = extract(&oct, &set, &super::ResolvedCells::default());
    assert!(s.faces.is_empty() && s.vertices.is_empty());
}
