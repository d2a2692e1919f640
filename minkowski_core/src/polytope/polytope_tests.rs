use super::*;
use crate::error::CoreError;
use crate::math::{Aabb, Vec3};

fn cube(c: Vec3, r: f64) -> ConvexPolytope {
    let mut pts = Vec::new();
    for k in 0..8 {
        let s = Vec3::new(if k & 1 == 1 { r } else { -r }, if k & 2 == 2 { r } else { -r }, if k & 4 == 4 { r } else { -r });
        pts.push(c + s);
    }
    ConvexPolytope::from_points(&pts)
}

#[test]
fn cube_has_six_merged_facets_and_exact_volume() {
    let p = cube(Vec3::ZERO, 1.0);
    assert_eq!(p.normals.len(), 6);
    assert_eq!(p.vertices.len(), 8);
    assert!((p.volume() - 8.0).abs() < 1e-12);
    for (n, d) in p.normals.iter().zip(&p.offsets) {
        assert!((n.length() - 1.0).abs() < 1e-12);
        assert!((d - 1.0).abs() < 1e-12, "offset {d}");
    }
}

#[test]
fn signed_distance_matches_closed_form() {
    let p = cube(Vec3::ZERO, 1.0);
    assert!((p.signed_distance(Vec3::ZERO) + 1.0).abs() < 1e-12);
    assert!((p.signed_distance(Vec3::new(0.5, 0.2, 0.0)) + 0.5).abs() < 1e-12);
    assert!((p.signed_distance(Vec3::new(3.0, 0.0, 0.0)) - 2.0).abs() < 1e-12);
    // corner region: Euclidean distance to the corner, not the plane bound
    let q = Vec3::new(2.0, 2.0, 2.0);
    assert!((p.signed_distance(q) - 3f64.sqrt()).abs() < 1e-12);
    assert!(p.plane_distance(q) < p.signed_distance(q));
    // edge region
    assert!((p.signed_distance(Vec3::new(2.0, 2.0, 0.0)) - 2f64.sqrt()).abs() < 1e-12);
}

#[test]
fn box_queries() {
    let p = cube(Vec3::ZERO, 1.0);
    assert!(p.contains_box(&Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5))));
    assert!(!p.contains_box(&Aabb::new(Vec3::splat(0.5), Vec3::splat(1.5))));
    assert!(p.overlaps_box(&Aabb::new(Vec3::splat(0.5), Vec3::splat(1.5))));
    assert!(!p.overlaps_box(&Aabb::new(Vec3::splat(1.1), Vec3::splat(1.5))));
    // a tilted polytope: octahedron |x|+|y|+|z| <= 1 and a box near its face, outside it
    let oct = ConvexPolytope::from_points(&[Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]);
    assert_eq!(oct.normals.len(), 8);
    assert!(!oct.overlaps_box(&Aabb::new(Vec3::splat(0.4), Vec3::splat(0.6))));
    assert!(oct.overlaps_box(&Aabb::new(Vec3::splat(0.2), Vec3::splat(0.4))));
}

#[test]
fn segment_clipping_is_exact() {
    let p = cube(Vec3::ZERO, 1.0);
    let (t0, t1) = p.clip_segment(Vec3::new(-3.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0)).unwrap();
    assert!((t0 - 1.0 / 3.0).abs() < 1e-12 && (t1 - 2.0 / 3.0).abs() < 1e-12);
    assert!(p.clip_segment(Vec3::new(-3.0, 1.5, 0.0), Vec3::new(3.0, 1.5, 0.0)).is_none());
    // grazing along a face counts as touching (closed sets)
    assert!(p.clip_segment(Vec3::new(-3.0, 1.0, 0.0), Vec3::new(3.0, 1.0, 0.0)).is_some());
}

#[test]
fn degenerate_and_non_finite_input_are_errors() {
    let flat = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.3, 0.6, 0.0)];
    assert!(matches!(ConvexPolytope::try_from_points(&flat, "flat"), Err(CoreError::Degenerate { .. })));
    let few = [Vec3::ZERO, Vec3::X, Vec3::Y];
    assert!(matches!(ConvexPolytope::try_from_points(&few, "few"), Err(CoreError::Degenerate { .. })));
    let nan = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(f64::NAN, 0.0, 1.0)];
    assert!(matches!(ConvexPolytope::try_from_points(&nan, "nan"), Err(CoreError::NonFinite { .. })));
    let same = [Vec3::ONE; 5];
    assert!(ConvexPolytope::try_from_points(&same, "same").is_err());
}

#[test]
fn hull_of_many_points_contains_them_all() {
    // deterministic pseudo-random points in a ball
    let mut x: u64 = 0x9E3779B97F4A7C15;
    let mut rnd = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let pts: Vec<Vec3> = (0..2000).map(|_| Vec3::new(rnd(), rnd(), rnd())).filter(|p| p.length() < 1.0).collect();
    let p = ConvexPolytope::from_points(&pts);
    for q in &pts {
        assert!(p.plane_distance(*q) <= 1e-9);
    }
    for v in &p.vertices {
        assert!(p.plane_distance(*v).abs() <= 1e-9, "hull vertex on the boundary");
    }
}

/// Two boxes tilted the same way (30° about y, from float32 mesh data): the hull of their
/// difference has near-coplanar points that give sliver hull triangles; they must join a
/// neighbouring facet, not fail as a "zero-area facet" (found by the assembly tests).
#[test]
fn tilted_box_difference_has_no_zero_area_facet() {
    let a = [
        [1.2165063509461096, -0.3499999940395355, 1.6070508075688774],
        [1.2165063509461096, 0.3499999940395355, 1.6070508075688774],
        [0.16650635020105162, -0.3499999940395355, -0.21160254166892228],
        [0.2531088854175818, -0.3499999940395355, -0.26160253868869005],
        [0.16650635020105162, 0.3499999940395355, -0.21160254166892228],
        [1.3031088861626396, 0.3499999940395355, 1.5570508105491097],
        [1.3031088861626396, -0.3499999940395355, 1.5570508105491097],
        [0.2531088854175818, 0.3499999940395355, -0.26160253868869005],
    ];
    let b = [
        [0.3267949166621554, -0.20000000298023224, 0.9660254052745548],
        [0.3267949166621554, 0.20000000298023224, 0.9660254052745548],
        [-0.17320508333784457, -0.20000000298023224, 0.1000000014901161],
        [0.17320508333784457, -0.20000000298023224, -0.1000000014901161],
        [-0.17320508333784457, 0.20000000298023224, 0.1000000014901161],
        [0.6732050833378445, 0.20000000298023224, 0.7660254022943226],
        [0.6732050833378445, -0.20000000298023224, 0.7660254022943226],
        [0.17320508333784457, 0.20000000298023224, -0.1000000014901161],
    ];
    let mut pts = Vec::new();
    for p in &a {
        for q in &b {
            pts.push(Vec3::from_array(*p) - Vec3::from_array(*q));
        }
    }
    let poly = ConvexPolytope::try_from_points(&pts, "difference").expect("a valid hull");
    // every point satisfies every facet plane, and the facets are those of a tilted box sum
    for p in &pts {
        assert!(poly.plane_distance(*p) <= 1e-9, "{}", poly.plane_distance(*p));
    }
    assert!(poly.normals.len() <= 6 + 8, "{} facets", poly.normals.len());
    let bx = Aabb::from_points(&pts);
    assert!(poly.volume() > 0.0 && poly.volume() <= bx.extent().x * bx.extent().y * bx.extent().z);
}

/// Every facet's offset is the largest `n · v` over all hull vertices, bit for bit as a
/// scan over every vertex gives it (the BVH's branch and bound prunes, never changes it),
/// on random clouds, a fine sphere and a cloud with many near-coplanar points.
#[test]
fn facet_offsets_are_the_exact_support_over_every_vertex() {
    let mut x = 7u64;
    let mut next = move || {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut clouds: Vec<Vec<Vec3>> = (0..6).map(|k| (0..50 + 100 * k).map(|_| Vec3::new(next(), next(), next())).collect()).collect();
    clouds.push(
        (0..2000)
            .map(|i| {
                let (t, z) = (i as f64 * 2.399963, 1.0 - 2.0 * (i as f64 + 0.5) / 2000.0);
                Vec3::new((1.0 - z * z).sqrt() * t.cos(), (1.0 - z * z).sqrt() * t.sin(), z)
            })
            .collect(),
    );
    // a box's faces with points scattered on them (coplanar up to rounding)
    clouds.push(
        (0..600)
            .map(|i| {
                let mut p = Vec3::new(next(), next(), next());
                p[i % 3] = if i % 2 == 0 { 0.5 } else { -0.5 };
                p
            })
            .collect(),
    );
    for (k, cloud) in clouds.iter().enumerate() {
        let h = ConvexPolytope::from_points(cloud);
        for (n, &d) in h.normals.iter().zip(&h.offsets) {
            let scan = h.vertices.iter().map(|v| n.dot(*v)).fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(d.to_bits(), scan.to_bits(), "cloud {k}: {d} against {scan}");
        }
    }
}
