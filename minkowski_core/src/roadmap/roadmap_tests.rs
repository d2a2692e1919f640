use super::*;
use crate::math::{Aabb, Vec3};
use crate::minkowski::PolytopeSet;
use crate::octree::{Label, Octree};
use crate::polytope::ConvexPolytope;
use std::collections::BTreeSet;

fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> ConvexPolytope {
    let pts: Vec<Vec3> = (0..8).map(|k| Vec3::new([lo[0], hi[0]][k & 1], [lo[1], hi[1]][(k >> 1) & 1], [lo[2], hi[2]][(k >> 2) & 1])).collect();
    ConvexPolytope::from_points(&pts)
}

/// A closed box shell (walls of thickness `t`) around the cavity `[-1, 1]^3`; the walls
/// overlap along the edges (a cell across a seam of two touching pieces is MIXED).
fn sealed_shell(t: f64) -> Vec<ConvexPolytope> {
    let (a, b) = (1.0, 1.0 + t);
    vec![
        cuboid([-b, -b, -b], [-a, b, b]),
        cuboid([a, -b, -b], [b, b, b]),
        cuboid([-b, -b, -b], [b, -a, b]),
        cuboid([-b, a, -b], [b, b, b]),
        cuboid([-b, -b, -b], [b, b, -a]),
        cuboid([-b, -b, a], [b, b, b]),
    ]
}

fn small_octree() -> (PolytopeSet, Octree) {
    let set = PolytopeSet::new(vec![cuboid([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]), cuboid([1.5, 0.2, 0.1], [2.0, 0.7, 0.9])]);
    let region = Aabb::new(Vec3::splat(-0.5), Vec3::new(2.5, 1.5, 1.5));
    let oct = Octree::build(&set, &region, 0.2, 1_000_000).unwrap();
    (set, oct)
}

fn volume(oct: &Octree) -> f64 {
    oct.leaves.iter().map(|l| oct.cell_box(l).extent().element_product()).sum()
}

#[test]
fn locate_finds_the_leaf_containing_a_point() {
    let (_, oct) = small_octree();
    let idx = LeafIndex::new(&oct);
    assert_eq!(idx.len(), oct.leaves.len());
    for (i, l) in oct.leaves.iter().enumerate() {
        let b = oct.cell_box(l);
        assert_eq!(idx.locate(&oct, b.center()), Some(i));
        let j = idx.locate(&oct, b.min).unwrap();
        assert!(oct.cell_box(&oct.leaves[j]).contains_point(b.min));
    }
    let root = oct.root_box();
    assert_eq!(idx.locate(&oct, root.min - Vec3::splat(1e-9)), None);
    assert_eq!(idx.locate(&oct, root.max + Vec3::splat(1e-9)), None);
    assert!(idx.locate(&oct, root.max).is_some());
}

#[test]
fn neighbors_are_exactly_the_leaves_sharing_a_face() {
    let (_, oct) = small_octree();
    let idx = LeafIndex::new(&oct);
    let n = oct.leaves.len();
    assert!(n > 100 && n < 20_000, "{n}");
    let mut by_nb: BTreeSet<(usize, usize)> = BTreeSet::new();
    let mut out = Vec::new();
    for u in 0..n {
        out.clear();
        neighbors(&oct, &idx, u, &mut out);
        for m in &out {
            let f = shared_face(&oct, u, m.leaf).expect("a neighbour shares a face");
            assert!((f.center() - m.portal).length() < 1e-9, "portal is the shared face's centre");
            assert!(by_nb.insert((u, m.leaf)), "reported twice");
        }
    }
    // brute force over all pairs
    let mut brute = BTreeSet::new();
    for u in 0..n {
        for v in 0..n {
            if u != v && shared_face(&oct, u, v).is_some() {
                brute.insert((u, v));
            }
        }
    }
    assert_eq!(by_nb, brute);
    // every pair once in face_adjacency
    let pairs = face_adjacency(&oct, &idx, |_| true);
    let once: BTreeSet<(usize, usize)> = pairs.iter().map(|p| (p.a.min(p.b) as usize, p.a.max(p.b) as usize)).collect();
    assert_eq!(once.len(), pairs.len());
    assert_eq!(once.len() * 2, brute.len());
    for p in &pairs {
        let f = shared_face(&oct, p.a as usize, p.b as usize).unwrap();
        assert!((f.center() - p.portal).length() < 1e-9);
    }
}

#[test]
fn shared_face_needs_positive_area() {
    let (_, oct) = small_octree();
    let idx = LeafIndex::new(&oct);
    let n = oct.leaves.len();
    // leaves that meet only along an edge or a corner do not share a face
    for u in 0..n.min(300) {
        for v in 0..n {
            if let Some(f) = shared_face(&oct, u, v) {
                let e = f.extent();
                let flat = (0..3).filter(|&k| e[k] == 0.0).count();
                assert_eq!(flat, 1);
                assert!((0..3).filter(|&k| e[k] > 0.0).count() == 2);
            }
        }
    }
    let _ = idx;
}

#[test]
fn components_separate_a_sealed_cavity() {
    let set = PolytopeSet::new(sealed_shell(0.5));
    let region = Aabb::new(Vec3::splat(-2.0), Vec3::splat(2.0));
    let oct = Octree::build(&set, &region, 0.1, 1_000_000).unwrap();
    let idx = LeafIndex::new(&oct);
    let free = |i: usize| oct.leaves[i].label != Label::Full;
    let pairs = face_adjacency(&oct, &idx, free);
    let labels = components(oct.leaves.len(), &pairs, free);
    let inside = labels[idx.locate(&oct, Vec3::ZERO).unwrap()];
    let outside = labels[idx.locate(&oct, Vec3::splat(1.8)).unwrap()];
    assert_ne!(inside, u32::MAX);
    assert_ne!(inside, outside);
    // labels are numbered in order of first leaf
    let mut seen = Vec::new();
    for &l in &labels {
        if l != u32::MAX && !seen.contains(&l) {
            assert_eq!(l as usize, seen.len());
            seen.push(l);
        }
    }
}

#[test]
fn rescale_and_refine_keep_a_tiling_with_exact_labels() {
    let (set, oct) = small_octree();
    let vol = volume(&oct);
    let mut oct = rescale(oct, 3).unwrap();
    assert!((volume(&oct) - vol).abs() < 1e-9 * vol);
    let mut idx = LeafIndex::new(&oct);
    for round in 0..3 {
        let targets: Vec<usize> = (0..oct.leaves.len()).filter(|&i| oct.leaves[i].label == Label::Mixed).collect();
        let stats = refine(&set, &mut oct, &mut idx, &targets, 1, 10_000_000).unwrap();
        assert_eq!(stats.refined, targets.len(), "round {round}");
        assert_eq!(stats.created, 8 * targets.len());
        assert_eq!(idx.len(), oct.leaves.len());
        assert!((volume(&oct) - vol).abs() < 1e-9 * vol);
    }
    // nothing left to split at the floor
    let targets: Vec<usize> = (0..oct.leaves.len()).collect();
    assert_eq!(refine(&set, &mut oct, &mut idx, &targets, 1, 10_000_000).unwrap().refined, 0);
    for (i, l) in oct.leaves.iter().enumerate() {
        let b = oct.cell_box(l);
        assert_eq!(idx.get(l.level, l.ijk), Some(i));
        match l.label {
            Label::Full => assert!(set.polys.iter().any(|p| p.contains_box(&b))),
            Label::Empty => assert!(set.polys.iter().all(|p| !p.overlaps_box(&b))),
            Label::Mixed => assert_eq!(l.level, 0),
        }
    }
    // the refined tree agrees with one built at the floor directly, cell by cell in volume
    let direct = Octree::build(&set, &Aabb::new(Vec3::splat(-0.5), Vec3::new(2.5, 1.5, 1.5)), 0.2 / 8.0, 10_000_000).unwrap();
    let mixed = |o: &Octree| o.leaves.iter().filter(|l| l.label == Label::Mixed).count();
    // different lattice offsets: counts agree only roughly
    let (a, b) = (mixed(&oct) as f64, mixed(&direct) as f64);
    assert!((a / b - 1.0).abs() < 0.5, "{a} vs {b}");
}

#[test]
fn refine_respects_the_leaf_budget() {
    let (set, oct) = small_octree();
    let mut oct = rescale(oct, 2).unwrap();
    let mut idx = LeafIndex::new(&oct);
    let before = oct.leaves.len();
    let targets: Vec<usize> = (0..oct.leaves.len()).collect();
    let err = refine(&set, &mut oct, &mut idx, &targets, 2, before + 10).unwrap_err();
    assert!(matches!(err, crate::error::CoreError::ResourceLimit { .. }));
    assert_eq!(oct.leaves.len(), before);
    assert!(rescale(oct, 30).is_err());
}

#[test]
fn refine_respects_the_record_budget() {
    let (set, oct) = small_octree();
    let mut oct = rescale(oct, 2).unwrap();
    let mut idx = LeafIndex::new(&oct);
    let (leaves, words) = (oct.leaves.len(), oct.cands.len());
    let targets: Vec<usize> = (0..oct.leaves.len()).collect();
    let err = refine_within(&set, &mut oct, &mut idx, &targets, 2, 10_000_000, words + 1).unwrap_err();
    assert!(matches!(err, crate::error::CoreError::RecordLimit { .. }), "{err}");
    assert_eq!((oct.leaves.len(), oct.cands.len()), (leaves, words));
    assert!(refine_within(&set, &mut oct, &mut idx, &targets, 2, 10_000_000, usize::MAX).unwrap().refined > 0);
}

#[test]
fn astar_goes_around_an_obstacle_through_empty_leaves() {
    let set = PolytopeSet::new(vec![cuboid([-0.5, -2.0, -2.0], [0.5, 1.0, 2.0])]);
    let region = Aabb::new(Vec3::splat(-2.0), Vec3::splat(2.0));
    let oct = Octree::build(&set, &region, 0.1, 1_000_000).unwrap();
    let idx = LeafIndex::new(&oct);
    let (a, b) = (Vec3::new(-1.5, 0.0, 0.0), Vec3::new(1.5, 0.0, 0.0));
    let (s, g) = (idx.locate(&oct, a).unwrap(), idx.locate(&oct, b).unwrap());
    let empty = |i: usize| (oct.leaves[i].label == Label::Empty).then_some(1.0);
    let r = astar(&oct, &idx, &[(s, 0.0)], &[(g, 0.0)], b, empty).expect("a path above the wall");
    assert_eq!(r.leaves[0], s);
    assert_eq!(*r.leaves.last().unwrap(), g);
    assert_eq!(r.portals.len(), r.leaves.len() - 1);
    for w in r.leaves.windows(2) {
        assert!(shared_face(&oct, w[0], w[1]).is_some());
    }
    // it has to climb over y = 1
    assert!(r.portals.iter().any(|p| p.y > 1.0));
    // every segment centre -> portal -> centre is free
    for (k, p) in r.portals.iter().enumerate() {
        let (c0, c1) = (oct.cell_box(&oct.leaves[r.leaves[k]]).center(), oct.cell_box(&oct.leaves[r.leaves[k + 1]]).center());
        assert!(set.segment_is_free(c0, *p) && set.segment_is_free(*p, c1));
    }
    // no path when the wall spans everything
    let set2 = PolytopeSet::new(vec![cuboid([-0.5, -100.0, -100.0], [0.5, 100.0, 100.0])]);
    let oct2 = Octree::build(&set2, &region, 0.1, 1_000_000).unwrap();
    let idx2 = LeafIndex::new(&oct2);
    let (s2, g2) = (idx2.locate(&oct2, a).unwrap(), idx2.locate(&oct2, b).unwrap());
    assert!(astar(&oct2, &idx2, &[(s2, 0.0)], &[(g2, 0.0)], b, |i| (oct2.leaves[i].label != Label::Full).then_some(1.0)).is_none());
}

/// Plan through a slot of width `w` in a wall, refining the channel: the loop the Python
/// planner runs.
fn plan_through_slot(w: f64) -> (CSpace, Option<Vec<Vec3>>, usize) {
    let h = 0.5 * w;
    let wall = vec![cuboid([-0.5, -5.0, -5.0], [0.5, -h, 5.0]), cuboid([-0.5, h, -5.0], [0.5, 5.0, 5.0])];
    let bounds = Aabb::new(Vec3::splat(-3.0), Vec3::splat(3.0));
    let mut cs = CSpace::build(&wall, bounds, 1e-4, 6.0 / 64.0, 0.0, 5_000_000).unwrap();
    let (a, b) = (Vec3::new(-2.0, 1.0, 0.3), Vec3::new(2.0, -1.0, -0.2));
    for round in 0..40 {
        let (sa, ga) = (cs.attach(a, 2), cs.attach(b, 2));
        if let Some((pts, _)) = cs.free_path(a, b, &sa, &ga) {
            return (cs, Some(pts), round);
        }
        let Some(ch) = cs.channel(a, b, 2.0, true) else { return (cs, None, round) };
        cs.refine(&ch.leaves, true, 1, 5_000_000).unwrap();
    }
    (cs, None, 40)
}

#[test]
fn cspace_refines_the_channel_through_a_narrow_slot() {
    let (cs, pts, rounds) = plan_through_slot(0.01);
    let pts = pts.expect("a path through the slot");
    assert!(rounds > 3 && rounds < 40, "{rounds}");
    for w in pts.windows(2) {
        assert!(cs.segment_is_free(w[0], w[1], 0.0), "segment {:?} -> {:?}", w[0], w[1]);
    }
    // local refinement: far fewer leaves than a uniform grid at the reached size
    assert!(cs.oct.leaves.len() < 400_000, "{}", cs.oct.leaves.len());
    // the path stays in the bounds (walls)
    assert!(pts.iter().all(|p| cs.bounds.contains_point(*p)));
    assert!(cs.segment_is_free(pts[0], pts[1], 0.0));
    assert!(cs.certificate(pts[0], *pts.last().unwrap()).is_none());
}

#[test]
fn cspace_walls_and_margin() {
    let bounds = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
    let cs = CSpace::build(&[cuboid([-0.2, -0.2, -0.2], [0.2, 0.2, 0.2])], bounds, 1e-3, 0.1, 0.05, 1_000_000).unwrap();
    assert_eq!(cs.n_obstacle, 1);
    assert_eq!(cs.obstacles.len(), 7);
    assert!(cs.obstacles.contains_point(Vec3::new(0.24, 0.0, 0.0)), "grown by the margin");
    assert!(!cs.obstacles.contains_point(Vec3::new(0.26, 0.0, 0.0)));
    assert!(cs.obstacles.contains_point(Vec3::new(1.01, 0.0, 0.0)), "outside the bounds is a wall");
    assert!(!cs.segment_is_free(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.5, 0.0, 0.0), 0.0));
    // margin test on segments
    let (a, b) = (Vec3::new(-0.5, 0.3, 0.0), Vec3::new(0.5, 0.3, 0.0));
    assert!(cs.segment_is_free(a, b, 0.0));
    assert!(cs.segment_is_free(a, b, 0.01));
    assert!(!cs.segment_is_free(a, b, 0.06));
    // every leaf outside the bounds is FULL
    for l in &cs.oct.leaves {
        let bx = cs.oct.cell_box(l);
        if (0..3).any(|k| bx.min[k] > 1.0 || bx.max[k] < -1.0) {
            assert_eq!(l.label, Label::Full);
        }
    }
    assert_eq!(cs.floor(), 1e-3);
    assert_eq!(cs.coarse_level, 6, "coarse cells are the floor times a power of two, at most h_coarse");
}

#[test]
fn certificate_walls_in_a_sealed_cavity() {
    let bounds = Aabb::new(Vec3::splat(-3.0), Vec3::splat(3.0));
    let cs = CSpace::build(&sealed_shell(0.3), bounds, 1e-3, 6.0 / 32.0, 0.0, 5_000_000).unwrap();
    let cert = cs.certificate(Vec3::ZERO, Vec3::splat(2.0)).expect("separate components");
    assert!(cert.walls_around_start);
    assert!(!cert.start_component.is_empty() && cert.goal_component_size > cert.start_component.len());
    assert!(!cert.walls.is_empty());
    let walls: BTreeSet<usize> = cert.walls.iter().map(|w| w.0).collect();
    for &(w, prim) in &cert.walls {
        let b = cs.oct.cell_box(&cs.oct.leaves[w]);
        assert_eq!(cs.oct.leaves[w].label, Label::Full);
        assert!(prim < cs.n_obstacle, "walls of the cavity are obstacle primitives");
        let crate::roadmap::Obstacles::Union(set) = &cs.obstacles else { panic!("union source") };
        assert!(set.polys[prim].contains_box(&b));
    }
    // the component's neighbours are all in it or walls
    let comp: BTreeSet<usize> = cert.start_component.iter().copied().collect();
    for &i in &comp {
        for m in cs.neighbors(i) {
            assert!(comp.contains(&m.leaf) || walls.contains(&m.leaf));
        }
    }
    assert!(cs.certificate(Vec3::ZERO, Vec3::new(0.5, 0.5, -0.5)).is_none());
}

#[test]
fn shortcut_keeps_segments_free_and_shortens() {
    let (cs, pts, _) = plan_through_slot(0.05);
    let pts = pts.unwrap();
    let len = |p: &[Vec3]| p.windows(2).map(|w| (w[1] - w[0]).length()).sum::<f64>();
    let short = cs.shortcut(&pts, 1e-3, 4);
    assert!(short.len() < pts.len() && short.len() >= 3, "{} -> {}", pts.len(), short.len());
    assert!(len(&short) <= len(&pts));
    assert_eq!(short[0], pts[0]);
    assert_eq!(short.last(), pts.last());
    for w in short.windows(2) {
        assert!(cs.segment_is_free(w[0], w[1], 0.0));
    }
}

#[test]
fn enclosure_of_a_sealed_cavity_needs_no_goal() {
    let bounds = Aabb::new(Vec3::splat(-3.0), Vec3::splat(3.0));
    let cs = CSpace::build(&sealed_shell(0.3), bounds, 1e-3, 6.0 / 32.0, 0.0, 5_000_000).unwrap();
    let inside = cs.enclosure(Vec3::ZERO).expect("the start is free");
    assert!(inside.walls_around_start && inside.verified && inside.goal_component_size == 0);
    assert!(!inside.walls.is_empty());
    assert!(inside.walls.iter().all(|&(_, prim)| prim < cs.n_obstacle), "walled by the shell alone");
    // the same component as the two-point certificate's
    let cert = cs.certificate(Vec3::ZERO, Vec3::splat(2.0)).unwrap();
    assert_eq!(inside.start_component, cert.start_component);
    // outside the shell, the component reaches the bounds: walls outside them take part
    let outside = cs.enclosure(Vec3::splat(2.0)).unwrap();
    assert!(outside.walls.iter().any(|&(_, prim)| prim >= cs.n_obstacle && prim != usize::MAX));
    // a start in a FULL leaf has no enclosure
    assert!(cs.enclosure(Vec3::new(1.15, 0.0, 0.0)).is_none());
}
