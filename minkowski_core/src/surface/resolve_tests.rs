//! Cells resolved by planes: answers carried between the regions of a cut are the answers
//! point queries give, and they spare most of the queries (about 7 in 8 on a torus ⊕
//! sphere, 19 in 20 when the parts of planes outside their candidates' boxes were still
//! pieces to answer: leaving those out halves the regions to answer, and the carries lose
//! them as stepping stones, about 13% more queries there); those parts are no boundary
//! (the surface is the same without them); resolutions kept from one extraction give the
//! next the same surface.

use super::resolve::resolve_cell;
use crate::exact::exact_tests::{boxes_mesh, sphere_mesh, torus_mesh};
use crate::exact::ExactSource;
use crate::math::{Aabb, Vec3};
use crate::octree::{CellSource, Label, Octree};
use crate::surface::planar::{Cut, EVERYWHERE, MAX_PLANES};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The exact source, counting its point queries; with `carry` off, every segment may meet
/// the boundary, so each region of a cut is queried; with `unbounded`, its cuts keep no
/// candidates' extents, so every part of a plane in the cell is a piece.
struct Counted<'a> {
    src: &'a ExactSource,
    carry: bool,
    unbounded: bool,
    queries: AtomicUsize,
}

impl<'a> Counted<'a> {
    fn new(src: &'a ExactSource, carry: bool, unbounded: bool) -> Self {
        Counted { src, carry, unbounded, queries: AtomicUsize::new(0) }
    }
}

impl CellSource for Counted<'_> {
    fn root_records(&self) -> Vec<u32> {
        self.src.root_records()
    }
    fn classify(&self, cell: &Aabb, cand: &[u32], finest: bool, out: &mut Vec<u32>) -> Label {
        self.src.classify(cell, cand, finest, out)
    }
    fn cell_contains(&self, cand: &[u32], p: Vec3) -> bool {
        self.queries.fetch_add(1, Ordering::Relaxed);
        self.src.cell_contains(cand, p)
    }
    fn boundary_intervals(&self, cand: &[u32], a: Vec3, b: Vec3, out: &mut Vec<(f64, f64)>) {
        if self.carry {
            self.src.boundary_intervals(cand, a, b, out);
        } else {
            out.clear();
            out.push((0.0, 1.0));
        }
    }
    fn solid_intervals(&self, a: Vec3, b: Vec3, sa: bool, sb: bool, bnd: &[(f64, f64)], out: &mut Vec<(f64, f64)>) {
        self.src.solid_intervals(a, b, sa, sb, bnd, out)
    }
    fn plane_cut(&self, own: &[u32]) -> Option<Cut> {
        let mut cut = self.src.plane_cut(own)?;
        if self.unbounded {
            cut.extents = [EVERYWHERE; MAX_PLANES];
        }
        Some(cut)
    }
}

#[test]
fn carried_region_answers_are_the_point_queries_answers() {
    for (src, h) in &curved_and_flat_sums() {
        let oct = Octree::build_resolving_planes(src, &src.aabb, *h, 4_000_000, &[], &super::ResolvedCells::default()).unwrap();
        let (carried, queried) = (Counted::new(src, true, false), Counted::new(src, false, false));
        let (mut cells, mut polygons) = (0, 0);
        for leaf in oct.leaves.iter().filter(|l| l.label == Label::Mixed) {
            let (cell, recs) = (oct.cell_box(leaf), oct.records(leaf));
            let with = resolve_cell(&carried, &cell, recs, 1, None);
            let without = resolve_cell(&queried, &cell, recs, 1, None);
            assert_eq!(with.is_some(), without.is_some(), "cell {cell:?}");
            if let (Some(a), Some(b)) = (with, without) {
                assert_eq!(a.polys, b.polys, "cell {cell:?}");
                cells += 1;
                polygons += a.polys.len();
            }
        }
        let (q_with, q_without) = (carried.queries.into_inner(), queried.queries.into_inner());
        assert!(cells > 50 && polygons > 5 * cells, "{cells} cells resolved, {polygons} polygons");
        assert!(6 * q_with < q_without, "{q_with} queries with carrying, {q_without} without");
    }
}

/// Two sums whose cells many planes cut (curved ⊕ curved: many planes and regions; the
/// flat faces, edges and corners of an L of two boxes rounded by a sphere), and the cell
/// size of their octrees.
fn curved_and_flat_sums() -> [(ExactSource, f64); 2] {
    [
        (ExactSource::new(vec![torus_mesh(10.0, 3.0, 24, 12)], sphere_mesh(0.9, 12, 7), 0.0, None), 0.15),
        (ExactSource::new(vec![boxes_mesh(&[([0.0; 3], [4.0, 1.0, 1.0]), ([0.0; 3], [1.0, 3.0, 1.0])])], sphere_mesh(0.3, 12, 7), 0.0, None), 0.05),
    ]
}

#[test]
fn parts_of_planes_outside_their_candidates_boxes_are_no_boundary() {
    // (and a step 1e-7 high on a box's top: its two planes are taken as one in cells
    // above 1e-3, and parts of it outside the step's facets are left out)
    let step = ExactSource::new(vec![boxes_mesh(&[([0.0; 3], [4.0, 1.0, 1.0]), ([1.0, 0.0, 0.0], [3.0, 1.0, 1.0 + 1e-7])])], sphere_mesh(0.3, 12, 7), 0.0, None);
    let [curved, flat] = curved_and_flat_sums();
    for (src, h) in [curved, flat, (step, 0.05)] {
        let oct = Octree::build_resolving_planes(&src, &src.aabb, h, 4_000_000, &[], &super::ResolvedCells::default()).unwrap();
        // (no carrying: every region of a piece is queried, so the counts are the regions)
        let (bounded, unbounded) = (Counted::new(&src, false, false), Counted::new(&src, false, true));
        let (mut cells, mut only_bounded) = (0, 0);
        for leaf in oct.leaves.iter().filter(|l| l.label == Label::Mixed) {
            let (cell, recs) = (oct.cell_box(leaf), oct.records(leaf));
            let with = resolve_cell(&bounded, &cell, recs, 1, None);
            let without = resolve_cell(&unbounded, &cell, recs, 1, None);
            match (with, without) {
                (Some(a), Some(b)) => {
                    assert_eq!(a.polys, b.polys, "cell {cell:?}");
                    cells += 1;
                }
                // a part left out can refuse no cell (too thin to tell its sides) any
                // more: the cell's surface is the one its sub-cells give
                (Some(a), None) => {
                    let deeper = resolve_cell(&unbounded, &cell, recs, 4, None).expect("resolved in sub-cells");
                    let (area_a, area_d) = (vector_area(&a.polys), vector_area(&deeper.polys));
                    assert!((area_a - area_d).length() <= 1e-9 * cell.extent().max_element().powi(2), "cell {cell:?}: {area_a} against {area_d}");
                    only_bounded += 1;
                }
                (None, Some(_)) => panic!("cell {cell:?} is refused only with the extents"),
                (None, None) => {}
            }
        }
        let (q_bounded, q_unbounded) = (bounded.queries.into_inner(), unbounded.queries.into_inner());
        assert!(cells > 50, "{cells} cells resolved ({only_bounded} only with the extents)");
        assert!(q_bounded < q_unbounded, "{q_bounded} regions answered within the extents, {q_unbounded} without");
    }
}

/// The sum of the polygons' vector areas (for closed pieces of one surface in a cell,
/// what a different cutting of the same surface gives too).
fn vector_area(polys: &[Vec<Vec3>]) -> Vec3 {
    polys.iter().map(|p| (1..p.len().saturating_sub(1)).map(|k| (p[k] - p[0]).cross(p[k + 1] - p[0]) * 0.5).fold(Vec3::ZERO, |a, b| a + b)).fold(Vec3::ZERO, |a, b| a + b)
}

#[test]
fn a_second_extraction_takes_the_kept_resolutions_and_gives_the_same_surface() {
    let src = ExactSource::new(vec![torus_mesh(10.0, 3.0, 24, 12)], sphere_mesh(0.9, 12, 7), 0.0, None);
    // (the octree resolves the cells it keeps into a cache of its own here)
    let oct = Octree::build_resolving_planes(&src, &src.aabb, 0.15, 4_000_000, &[], &super::ResolvedCells::default()).unwrap();
    let kept = super::ResolvedCells::default();
    let first = super::extract(&oct, &src, &kept);
    assert!(first.planar_cells > 100, "{} plane-resolved cells", first.planar_cells);
    let counted = || Counted::new(&src, true, false);
    let (again_src, fresh_src) = (counted(), counted());
    let again = super::extract(&oct, &again_src, &kept);
    let fresh = super::extract(&oct, &fresh_src, &super::ResolvedCells::default());
    for s in [&again, &fresh] {
        assert_eq!((&s.vertices, &s.faces, s.planar_cells), (&first.vertices, &first.faces, first.planar_cells));
    }
    // with the kept resolutions only the sampled band queries points
    assert_eq!(again_src.queries.load(Ordering::Relaxed), first.point_queries);
    assert!(fresh_src.queries.load(Ordering::Relaxed) > first.point_queries + 100);
}

#[test]
fn the_extraction_takes_the_surfaces_the_octree_resolved() {
    let src = ExactSource::new(vec![torus_mesh(10.0, 3.0, 24, 12)], sphere_mesh(0.9, 12, 7), 0.0, None);
    let counted = || Counted::new(&src, true, false);
    let (shared_src, fresh_src) = (counted(), counted());
    let shared = super::ResolvedCells::default();
    let oct = Octree::build_resolving_planes(&shared_src, &src.aabb, 0.15, 4_000_000, &[], &shared).unwrap();
    let built = shared_src.queries.swap(0, Ordering::Relaxed);
    let with = super::extract(&oct, &shared_src, &shared);
    let without = super::extract(&oct, &fresh_src, &super::ResolvedCells::default());
    assert_eq!((&with.vertices, &with.faces), (&without.vertices, &without.faces));
    assert!(with.planar_cells > 100, "{} plane-resolved cells", with.planar_cells);
    // every cell above the finest level with a surface was resolved (a point query at
    // least: its first region) by the build, and not again
    let above = oct
        .leaves
        .iter()
        .filter(|l| l.label == Label::Mixed && l.level > 0)
        .filter(|l| shared.get(&super::cell_key(&oct.cell_box(l), oct.records(l), 0)).is_some_and(|c| c.is_some_and(|c| !c.polys.is_empty())))
        .count();
    let (q_with, q_without) = (shared_src.queries.into_inner(), fresh_src.queries.into_inner());
    assert!(built > 0 && above > 100, "{built} queries building, {above} cells resolved above the finest level");
    assert!(q_with + above <= q_without, "{q_with} queries with the build's cache, {q_without} without");
}

#[test]
fn regions_take_the_answer_the_build_knew_at_a_corner_and_give_the_same_surface() {
    let src = ExactSource::new(vec![torus_mesh(10.0, 3.0, 24, 12)], sphere_mesh(0.9, 12, 7), 0.0, None);
    // (every MIXED leaf is a finest cell here: the sampled build)
    let oct = Octree::build(&src, &src.aabb, 0.15, 4_000_000).unwrap();
    let counted = || Counted::new(&src, true, false);
    let (told, untold) = (counted(), counted());
    let mut cells = 0;
    for leaf in oct.leaves.iter().filter(|l| l.label == Label::Mixed && l.level == 0) {
        let (cell, recs) = (oct.cell_box(leaf), oct.records(leaf));
        let known = oct.known_corner(leaf);
        let (q, inside) = known.expect("every finest MIXED leaf has a parent that answered");
        assert!(cell.contains_point(q), "{q} is a corner of {cell:?}");
        assert_eq!(inside, src.cell_contains(&[], q), "the build's answer at {q}");
        let with = resolve_cell(&told, &cell, recs, 1, known);
        let without = resolve_cell(&untold, &cell, recs, 1, None);
        assert_eq!(with.as_ref().map(|c| &c.polys), without.as_ref().map(|c| &c.polys), "cell {cell:?}");
        cells += usize::from(with.is_some());
    }
    let (q_told, q_untold) = (told.queries.into_inner(), untold.queries.into_inner());
    assert!(cells > 100, "{cells} cells resolved");
    // (a cell's regions beyond the boundary from the corner still need one)
    assert!(5 * q_told < 3 * q_untold, "{q_told} queries with the corners known, {q_untold} without");
}
