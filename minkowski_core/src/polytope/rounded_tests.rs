use super::*;
use std::collections::HashSet;
use std::f64::consts::PI;

fn box_polytope(size: Vec3) -> ConvexPolytope {
    let points: Vec<Vec3> =
        (0..8).map(|k| Vec3::new(if k & 1 == 1 { size.x } else { 0.0 }, if k & 2 == 2 { size.y } else { 0.0 }, if k & 4 == 4 { size.z } else { 0.0 })).collect();
    ConvexPolytope::from_points(&points)
}

/// A convex hull of points on a lumpy sphere (a fixed linear congruential sequence).
fn lumpy_polytope(count: usize) -> ConvexPolytope {
    let mut state: u64 = 12345;
    let mut next = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let points: Vec<Vec3> = (0..count)
        .map(|_| {
            let (z, phi) = (2.0 * next() - 1.0, 2.0 * PI * next());
            let ring = (1.0 - z * z).sqrt();
            Vec3::new(ring * phi.cos() * 1.3, ring * phi.sin() * 0.8, z * 0.6) * (0.9 + 0.2 * next())
        })
        .collect();
    ConvexPolytope::from_points(&points)
}

/// Every directed edge once, each with its twin: closed and consistently wound.
fn assert_closed_and_oriented(triangles: &[[u32; 3]]) {
    let mut directed = HashSet::new();
    for t in triangles {
        assert!(t[0] != t[1] && t[1] != t[2] && t[2] != t[0], "a triangle repeats a corner: {t:?}");
        for k in 0..3 {
            assert!(directed.insert((t[k], t[(k + 1) % 3])), "edge ({}, {}) is used twice the same way", t[k], t[(k + 1) % 3]);
        }
    }
    for &(a, b) in &directed {
        assert!(directed.contains(&(b, a)), "edge ({a}, {b}) has no twin");
    }
}

fn volume(vertices: &[Vec3], triangles: &[[u32; 3]]) -> f64 {
    triangles.iter().map(|t| vertices[t[0] as usize].dot(vertices[t[1] as usize].cross(vertices[t[2] as usize])) / 6.0).sum()
}

/// Points of every triangle on a barycentric grid (corners, edge points, inner points).
fn samples(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut out = Vec::new();
    for t in triangles {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5), (1.0 / 3.0, 1.0 / 3.0), (0.2, 0.6)] {
            out.push(a + (b - a) * u + (c - a) * v);
        }
    }
    out
}

fn mesh_distance(vertices: &[Vec3], triangles: &[[u32; 3]], p: Vec3) -> f64 {
    triangles.iter().map(|t| point_triangle_distance2(p, vertices[t[0] as usize], vertices[t[1] as usize], vertices[t[2] as usize])).fold(f64::INFINITY, f64::min).sqrt()
}

/// The output's points are within the bound of `r` from the polytope (exact distance),
/// and the exact offset's boundary points in many directions within the bound of the
/// output.
fn assert_bound_holds_both_ways(poly: &ConvexPolytope, radius: f64, out: &Rounded) {
    let slack = 1e-12;
    for p in samples(&out.vertices, &out.triangles) {
        let d = poly.signed_distance(p);
        assert!((d - radius).abs() <= out.bound + slack, "output point {p:?} at {d}, radius {radius} bound {}", out.bound);
    }
    let golden = PI * (3.0 - 5f64.sqrt());
    for k in 0..400 {
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / 400.0;
        let ring = (1.0 - z * z).sqrt();
        let u = Vec3::new(ring * (golden * k as f64).cos(), ring * (golden * k as f64).sin(), z);
        let support = poly.vertices.iter().copied().max_by(|a, b| a.dot(u).total_cmp(&b.dot(u))).expect("vertices");
        let exact = support + u * radius;
        let d = mesh_distance(&out.vertices, &out.triangles, exact);
        assert!(d <= out.bound + slack, "exact boundary point {exact:?} is {d} from the output, bound {}", out.bound);
    }
}

#[test]
fn a_grown_box_is_closed_flat_on_its_faces_and_within_its_bound() {
    let (size, radius) = (Vec3::new(1.0, 0.6, 0.4), 0.1);
    let poly = box_polytope(size);
    for tol in [2e-2, 1e-3, 1e-4] {
        let out = rounded(&poly, radius, tol, 0.0, 10_000_000).expect("rounded");
        assert!(out.bound <= tol && out.bound > 0.0, "chord {} for tol {tol}", out.bound);
        assert_closed_and_oriented(&out.triangles);
        assert_bound_holds_both_ways(&poly, radius, &out);
        // the six faces are the box's moved out by exactly r: 12 triangles on those planes
        let on_faces = out
            .triangles
            .iter()
            .filter(|t| {
                let [a, b, c] = t.map(|i| out.vertices[i as usize]);
                poly.normals.iter().zip(&poly.offsets).any(|(n, d)| [a, b, c].iter().all(|p| n.dot(*p) == d + radius))
            })
            .count();
        assert_eq!(on_faces, 12, "tol {tol}");
        // Steiner's formula between the offsets by r -+ chord, which hold and are held by it
        let steiner = |r: f64| {
            size.x * size.y * size.z + 2.0 * r * (size.x * size.y + size.y * size.z + size.z * size.x) + PI * r * r * (size.x + size.y + size.z) + 4.0 / 3.0 * PI * r * r * r
        };
        let v = volume(&out.vertices, &out.triangles);
        assert!(steiner(radius - out.bound) <= v && v <= steiner(radius + out.bound), "volume {v}, tol {tol}");
    }
}

#[test]
fn a_grown_lumpy_polytope_is_closed_and_within_its_bound_both_ways() {
    let poly = lumpy_polytope(60);
    let out = rounded(&poly, 0.3, 2e-3, 0.0, 10_000_000).expect("rounded");
    assert!(out.bound <= 2e-3);
    assert_closed_and_oriented(&out.triangles);
    assert_bound_holds_both_ways(&poly, 0.3, &out);
}

#[test]
fn the_round_points_straddle_the_exact_offset() {
    // the sag is split: the round parts reach out past r and dip in below it, each by
    // about half the chord a sphere inscribed in the same points would leave
    let poly = lumpy_polytope(30);
    let (radius, tol) = (0.5, 1e-2);
    let out = rounded(&poly, radius, tol, 0.0, 10_000_000).expect("rounded");
    let distances: Vec<f64> = samples(&out.vertices, &out.triangles).into_iter().map(|p| poly.signed_distance(p)).collect();
    let most = distances.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let least = distances.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(most - radius > 0.5 * out.bound, "outward {} of chord {}", most - radius, out.bound);
    assert!(radius - least > 0.5 * out.bound, "inward {} of chord {}", radius - least, out.bound);
    assert!(out.scale > 1.0);
}

#[test]
fn a_tolerance_too_fine_for_the_budget_or_not_positive_is_refused() {
    let poly = box_polytope(Vec3::ONE);
    assert!(matches!(rounded(&poly, 1.0, 1e-9, 0.0, 1000), Err(CoreError::InvalidParameter { .. })));
    assert!(matches!(rounded(&poly, 1.0, 0.0, 0.0, 1000), Err(CoreError::InvalidParameter { .. })));
    assert!(matches!(rounded(&poly, f64::NAN, 1e-3, 0.0, 1000), Err(CoreError::InvalidParameter { .. })));
}

#[test]
fn facets_meeting_almost_flat_are_welded_and_the_move_is_in_the_bound() {
    // a box with one corner moved 1e-7 out of a face: that face is two facets meeting at
    // about 1e-7 rad, their corners moved out by r = 0.1 about 1e-8 apart
    let mut points: Vec<Vec3> = (0..8).map(|k| Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64)).collect();
    points[7].x += 1e-7;
    let poly = ConvexPolytope::from_points(&points);
    let (radius, within) = (0.1, 1e-7);
    assert!(rounded(&poly, radius, 1e-3, 0.0, 10_000_000).expect("unwelded").narrowest * radius < within);
    let out = rounded(&poly, radius, 1e-3, within, 10_000_000).expect("welded");
    assert!(out.welded > 0.0 && out.welded < within && out.bound <= 1e-3);
    assert_closed_and_oriented(&out.triangles);
    assert_bound_holds_both_ways(&poly, radius, &out);
    for (i, p) in out.vertices.iter().enumerate() {
        for q in &out.vertices[i + 1..] {
            assert!((*p - *q).length() >= within, "points {p:?} and {q:?} closer than {within}");
        }
    }
}

#[test]
fn a_faceted_cylinders_thin_rim_cones_take_few_triangles_within_the_bound() {
    // a 96-gon prism (as a CAD cylinder is exported): each rim corner's cone is a thin
    // three-sided one, its short arc (between two sides, 0.065 rad) in one piece; zipped
    // along its two long arcs it takes 3 triangles, where a fan from its axis takes 8
    let sides = 96;
    let points: Vec<Vec3> = (0..2 * sides)
        .map(|k| {
            let a = 2.0 * PI * (k % sides) as f64 / sides as f64;
            Vec3::new(a.cos(), a.sin(), if k < sides { 0.0 } else { 3.0 })
        })
        .collect();
    let poly = ConvexPolytope::from_points(&points);
    let out = rounded(&poly, 0.5, 0.05, 0.0, 10_000_000).expect("rounded");
    assert_closed_and_oriented(&out.triangles);
    assert_bound_holds_both_ways(&poly, 0.5, &out);
    let rims = 2 * sides;
    let flat_and_strips = 2 * (sides - 2) + 2 * sides + 2 * sides + rims * 2 * 2;
    assert!(out.triangles.len() <= flat_and_strips + 3 * rims, "{} triangles", out.triangles.len());
}

#[test]
fn a_finely_faceted_ball_at_a_coarse_tolerance_fans_its_narrow_cones() {
    // 400 hull points on a lumpy sphere: every corner's cone is narrower than the step,
    // so each is a fan of its facets' moved corners
    let poly = lumpy_polytope(400);
    let out = rounded(&poly, 0.3, 0.05, 0.0, 10_000_000).expect("rounded");
    assert_closed_and_oriented(&out.triangles);
    assert_bound_holds_both_ways(&poly, 0.3, &out);
    assert!(out.vertices.len() <= 3 * poly.triangles.len(), "{} points for {} facets", out.vertices.len(), poly.triangles.len());
}

#[test]
fn sharp_corners_whose_normals_average_past_a_right_angle_are_tessellated() {
    // a flat tetrahedron: at its sharp corners the mean of the facet normals lies more
    // than 90 degrees from one of them; the cone's enclosing-ball centre does not
    let points = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.3, 0.3, 0.1)];
    let poly = ConvexPolytope::from_points(&points);
    let out = rounded(&poly, 0.05, 1e-3, 0.0, 10_000_000).expect("rounded");
    assert_closed_and_oriented(&out.triangles);
    assert_bound_holds_both_ways(&poly, 0.05, &out);
}

#[test]
fn an_obtuse_cones_apex_is_moved_off_the_side_its_enclosing_ball_centre_lies_on() {
    // two normals 0.3 rad apart and a third near their arc's middle: the smallest ball
    // enclosing them is centred on that arc, an apex there makes a sector of no width
    let (n0, n1) = (Vec3::new(-0.15_f64.sin(), 0.0, 0.15_f64.cos()), Vec3::new(0.15_f64.sin(), 0.0, 0.15_f64.cos()));
    let n2 = Vec3::new(0.0, 0.02, 1.0).normalize();
    let normals = [n0, n1, n2];
    let side = n0.cross(n1).normalize();
    let centre = enclosing_centre(&normals).normalize();
    assert!(side.dot(centre).abs() < 1e-6, "the enclosing centre {centre} is on the side");
    let axis = interior_axis(&normals).expect("an inside");
    // the cap's width across that side is about 0.02 rad: the apex is well off it
    assert!(side.dot(axis) * side.dot(n2) > 0.0 && side.dot(axis).abs() > 0.002, "apex {axis} too near the side");
    for (j, k) in [(1, 2), (2, 0)] {
        let other = normals[j].cross(normals[k]).normalize();
        assert!(other.dot(axis) * other.dot(n0 + n1 + n2) > 0.0, "apex {axis} outside side {j}-{k}");
    }
}

#[test]
fn thin_slabs_obtuse_corners_are_tessellated_within_the_bound() {
    // random points in a 1 x 1 x 0.05 slab: many corners' cones are obtuse, thin ones
    let mut state: u64 = 777;
    let mut next = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..12 {
        let points: Vec<Vec3> = (0..40).map(|_| Vec3::new(next(), next(), 0.05 * next())).collect();
        let poly = ConvexPolytope::from_points(&points);
        let out = rounded(&poly, 0.1, 1e-3, 0.0, 10_000_000).expect("rounded");
        assert_closed_and_oriented(&out.triangles);
        assert_bound_holds_both_ways(&poly, 0.1, &out);
        assert!(out.triangles.len() < 10_000, "{} triangles: the step was halved for folds", out.triangles.len());
    }
}
