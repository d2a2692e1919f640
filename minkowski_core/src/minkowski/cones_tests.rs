//! The normal-cone filter keeps every vertex of the sum: the hull of the kept sums is the
//! hull of all of them (same vertices, same volume), on spheres, boxes (coplanar points,
//! cones of right angles) and random clouds with interior points, added and subtracted.

use super::*;

/// `n` points on a sphere (a Fibonacci spiral): every one a hull vertex.
fn sphere(n: usize, r: f64, c: Vec3) -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let (rho, t) = ((1.0 - z * z).sqrt(), golden * i as f64);
            c + Vec3::new(rho * t.cos(), rho * t.sin(), z) * r
        })
        .collect()
}

fn cloud(n: usize, seed: u64) -> Vec<Vec3> {
    let mut x = seed;
    let mut next = move || {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    (0..n).map(|_| Vec3::new(next(), 2.0 * next(), 0.7 * next())).collect()
}

fn cube(lo: f64, hi: f64) -> Vec<Vec3> {
    (0..8).map(|i| Vec3::new(if i & 1 == 0 { lo } else { hi }, if i & 2 == 0 { lo } else { hi }, if i & 4 == 0 { lo } else { hi })).collect()
}

fn all_sums(a: &[Vec3], b: &[Vec3], s: f64) -> Vec<Vec3> {
    a.iter().flat_map(|p| b.iter().map(move |q| *p + *q * s)).collect()
}

fn sorted_vertices(h: &ConvexPolytope) -> Vec<[u64; 3]> {
    let mut v: Vec<[u64; 3]> = h.triangles.iter().flatten().map(|&i| bits(h.vertices[i as usize])).collect();
    v.sort_unstable();
    v.dedup();
    v
}

#[test]
fn the_kept_sums_have_the_hull_of_all_sums() {
    let cases: Vec<(Vec<Vec3>, Vec<Vec3>)> = vec![
        (sphere(400, 1.0, Vec3::ZERO), sphere(150, 0.5, Vec3::new(3.0, 0.0, 0.0))),
        (cube(0.0, 1.0), sphere(100, 0.3, Vec3::ZERO)),
        (cube(0.0, 1.0), cube(-0.5, 0.5)),
        (cloud(60, 1), cloud(45, 2)),
        (sphere(200, 1.0, Vec3::ZERO), cloud(30, 3)),
    ];
    let mut kept_of_spheres = 0;
    for (k, (a, b)) in cases.iter().enumerate() {
        for s in [1.0, -1.0] {
            let every = ConvexPolytope::from_points(&all_sums(a, b, s));
            let kept = candidate_sums(a, &caps(a, 1.0), b, &caps(b, s), s).unwrap_or_else(|| all_sums(a, b, s));
            let hull = ConvexPolytope::from_points(&kept);
            assert_eq!(sorted_vertices(&hull), sorted_vertices(&every), "case {k}, sign {s}");
            assert!((hull.volume() - every.volume()).abs() <= 1e-12 * every.volume(), "case {k}, sign {s}");
            if k == 0 {
                kept_of_spheres = kept.len();
            }
        }
    }
    // two spheres: the vertices of the sum are about n + m of the n · m sums
    assert!(kept_of_spheres < 400 * 150 / 10, "{kept_of_spheres} of {} sums kept", 400 * 150);
}
