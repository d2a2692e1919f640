//! The offset of a convex polytope `P` by a ball of radius `r`, tessellated along `P`'s
//! own structure (seed §5.2), with no hull computed: each facet moved out by `r` (exactly
//! flat), each edge's cylinder as a strip of parallelograms over its dihedral arc, each
//! vertex's sphere patch over its normal cone as a fan of graded rows of triangles.
//!
//! The bound. A point `x` of a vertex `v`'s patch is `v + w` with `w` in `v`'s normal cone
//! (the cone is convex and every corner of the patch's triangles lies in it), so
//! `dist(x, P) = |w|`; a point of an edge's strip is an edge point plus such a `w` in the
//! edge's normal wedge. The round parts' points lie at radius `r s`, the facets' corners
//! at `r`, so on a triangle `|w|` lies between the centre's distance to it and `r s`: the
//! two-sided bound is `max(r (s - 1), r - min_T dist(centre, T))`, measured on the
//! triangles themselves. `s = 2 / (1 + c)` (`c` the least such distance at `s = 1`,
//! relative to `r`) puts the chords' sag half outside, half inside. Each patch is a radial
//! graph over its cone (checked: every triangle of a region faces the same way), so every
//! true boundary point `v + r u` has a point of the output on its ray within the same
//! interval: the bound holds both ways.
//!
//! Facets meeting at a tiny angle (a float32 file's nearly coplanar triangles) put their
//! moved corners `r` times that angle apart; points closer than the caller's weld
//! distance are welded ([`super::weld`]), and the bound adds how far that moved them.

use super::hull::ConvexPolytope;
use super::queries::point_triangle_distance2;
use super::weld::weld;
use crate::error::{CoreError, CoreResult};
use crate::math::Vec3;
use crate::util::FastMap;

/// Widest angle (radians) between neighbouring round points, whatever the tolerance.
const MAX_STEP: f64 = std::f64::consts::FRAC_PI_2;

/// Most tries at a finer step when the measured bound exceeds the tolerance.
const MAX_TRIES: usize = 8;

/// The offset's closed, outward triangle mesh and what its bound was measured from.
#[derive(Clone, Debug)]
pub struct Rounded {
    /// Output vertices.
    pub vertices: Vec<Vec3>,
    /// Output triangles (outward winding).
    pub triangles: Vec<[u32; 3]>,
    /// Two-sided bound of `|dist(x, P) - r|` over the output (0 on the flat parts): the
    /// chords' sag and the weld's move ([`Rounded::welded`]).
    pub bound: f64,
    /// Radius factor `s` of the round points.
    pub scale: f64,
    /// Angular step (radians) between neighbouring round points.
    pub step: f64,
    /// Least angle between the normals of two facets that meet (radians): their moved
    /// corners are `r` times that apart.
    pub narrowest: f64,
    /// How far welding points closer than asked moved the surface (part of `bound`).
    pub welded: f64,
}

/// A finished mesh: its points, its triangles and how far welding moved them.
type Finished = (Vec<Vec3>, Vec<[u32; 3]>, f64);

/// The feature a triangle's points are nearest to.
#[derive(Clone, Copy, Debug)]
enum Centre {
    /// A facet (its unit normal): its points are exactly `r` out.
    Facet(Vec3),
    /// An edge through `a` with unit direction `e`.
    Edge { a: Vec3, e: Vec3 },
    /// A vertex.
    Vertex(Vec3),
}

/// An output point: `base + radius * dir`, with the radius `r` at a facet's corner and
/// `r s` elsewhere.
#[derive(Clone, Copy, Debug)]
struct Node {
    base: Vec3,
    dir: Vec3,
    corner: bool,
}

/// The offset of `poly` by `radius > 0` with its two-sided bound within `tol`, on at most
/// `max_triangles` triangles, its points closer than `weld_within` welded (see
/// [`super::weld`]; the bound adds how far that moved them).
///
/// # Errors
/// [`CoreError::InvalidParameter`] for a radius or tolerance that is not positive and
/// finite, or when the tolerance needs more than `max_triangles`;
/// [`CoreError::Degenerate`] when `P`'s structure is not that of a convex polytope (a
/// facet meeting a vertex twice, a normal cone wider than a hemisphere), or the weld opens
/// the surface or turns a triangle over.
pub fn rounded(poly: &ConvexPolytope, radius: f64, tol: f64, weld_within: f64, max_triangles: usize) -> CoreResult<Rounded> {
    for (name, value) in [("radius", radius), ("tol", tol)] {
        #[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN must be refused
        if !(value > 0.0 && value.is_finite()) {
            return Err(CoreError::InvalidParameter { name: name.into(), value, detail: "must be positive and finite".into() });
        }
    }
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN must be refused
    if !(weld_within >= 0.0 && weld_within.is_finite()) {
        return Err(CoreError::InvalidParameter { name: "weld".into(), value: weld_within, detail: "must be finite and not negative".into() });
    }
    let structure = Structure::of(poly)?;
    let mut step = (0.9 * (12.0 * tol / radius).sqrt()).min(MAX_STEP);
    let mut budget = tol;
    for _ in 0..MAX_TRIES {
        let estimate = structure.estimated_triangles(step);
        if estimate > max_triangles as f64 {
            return Err(CoreError::InvalidParameter {
                name: "eps".into(),
                value: tol,
                detail: format!("the rounded polytope would need about {estimate:.0} triangles, more than {max_triangles}"),
            });
        }
        let mesh = Tessellation::build(poly, &structure, step)?;
        let (scale, chord) = mesh.balanced(radius);
        if chord <= budget {
            let Some((vertices, triangles, welded)) = mesh.into_welded(radius, scale, weld_within)? else {
                step *= 0.5; // a patch folds over: finer rows fold less
                continue;
            };
            if chord + welded <= tol {
                return Ok(Rounded { vertices, triangles, bound: chord + welded, scale, step, narrowest: structure.narrowest, welded });
            }
            budget = tol - welded;
            if budget <= 0.0 {
                return Err(CoreError::InvalidParameter {
                    name: "eps".into(),
                    value: tol,
                    detail: format!("welding points within {weld_within:.3e} moved the surface by {welded:.3e}, past it"),
                });
            }
        }
        step *= 0.9 * (budget / chord).sqrt();
    }
    Err(CoreError::InvalidParameter { name: "eps".into(), value: tol, detail: format!("the rounded polytope's chords stay wider after {MAX_TRIES} finer steps") })
}

/// `P`'s edges (each with the facets on its two sides) and vertices (each with its facets
/// in cyclic order), from its triangles and their facet ids.
struct Structure {
    /// `(a, b, left facet, right facet)`, `a < b`.
    edges: Vec<(u32, u32, u32, u32)>,
    /// Per vertex, its facets in cyclic order (empty for a vertex inside a facet).
    cones: Vec<Vec<u32>>,
    narrowest: f64,
}

impl Structure {
    fn of(poly: &ConvexPolytope) -> CoreResult<Self> {
        let degenerate = |detail: String| CoreError::Degenerate { what: "convex polytope".into(), detail };
        let mut across: FastMap<(u32, u32), usize> = FastMap::with_capacity_and_hasher(poly.triangles.len() * 3, Default::default());
        for (t, tri) in poly.triangles.iter().enumerate() {
            for k in 0..3 {
                across.insert((tri[k], tri[(k + 1) % 3]), t);
            }
        }
        let facet = |t: usize| poly.triangle_facet[t];
        let mut edges = Vec::new();
        let mut narrowest = std::f64::consts::PI;
        let mut first_triangle = vec![usize::MAX; poly.vertices.len()];
        for (t, tri) in poly.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                first_triangle[a as usize] = first_triangle[a as usize].min(t);
                let twin = *across.get(&(b, a)).ok_or_else(|| degenerate(format!("edge ({a}, {b}) has one side")))?;
                if a < b && facet(t) != facet(twin) {
                    edges.push((a, b, facet(t), facet(twin)));
                    narrowest = narrowest.min(angle(poly.normals[facet(t) as usize], poly.normals[facet(twin) as usize]));
                }
            }
        }
        let mut cones = Vec::with_capacity(poly.vertices.len());
        for (v, &start) in first_triangle.iter().enumerate() {
            cones.push(if start == usize::MAX { Vec::new() } else { Self::cone(poly, &across, v as u32, start)? });
        }
        Ok(Structure { edges, cones, narrowest })
    }

    /// The facets around `v` in cyclic order, walking its triangles from `start`.
    fn cone(poly: &ConvexPolytope, across: &FastMap<(u32, u32), usize>, v: u32, start: usize) -> CoreResult<Vec<u32>> {
        let degenerate = |detail: String| CoreError::Degenerate { what: "convex polytope".into(), detail };
        let mut facets: Vec<u32> = Vec::new();
        let mut t = start;
        for _ in 0..poly.triangles.len() {
            let tri = poly.triangles[t];
            let f = poly.triangle_facet[t];
            if facets.last() != Some(&f) {
                facets.push(f);
            }
            let k = tri.iter().position(|&x| x == v).expect("v is a corner of t");
            // triangle (v, p, q) outward: the next one around v holds the edge v -> q
            t = *across.get(&(v, tri[(k + 2) % 3])).ok_or_else(|| degenerate(format!("vertex {v}'s fan is open")))?;
            if t == start {
                break;
            }
        }
        if facets.len() > 1 && facets.first() == facets.last() {
            facets.pop();
        }
        let mut sorted = facets.clone();
        sorted.sort_unstable();
        sorted.dedup();
        if sorted.len() != facets.len() {
            return Err(degenerate(format!("a facet meets vertex {v} twice")));
        }
        Ok(if facets.len() < 3 { Vec::new() } else { facets })
    }

    /// About how many triangles a step makes: the sphere's area over a triangle's, twice
    /// over for the graded rows, plus the strips.
    fn estimated_triangles(&self, step: f64) -> f64 {
        let sphere = 8.0 * std::f64::consts::PI / (0.433 * step * step);
        sphere + 2.0 * self.edges.len() as f64 * (std::f64::consts::PI / step).ceil()
    }
}

/// The output's points and triangles for one step, before the round points' radius is
/// chosen: each triangle with the feature it is nearest to.
struct Tessellation {
    nodes: Vec<Node>,
    triangles: Vec<[u32; 3]>,
    centres: Vec<Centre>,
    /// Per region (a strip or one sector of a vertex patch), its triangles' range: each
    /// region is wound consistently in its own parameters, and must face out as a whole.
    regions: Vec<std::ops::Range<usize>>,
}

/// Keys of the shared points while building: a facet's corner at a vertex, and an arc's
/// inner points at a vertex (the arc from the lower facet id to the higher).
#[derive(Default)]
struct Shared {
    corners: FastMap<(u32, u32), u32>,
    arcs: FastMap<(u32, u32, u32), Vec<u32>>,
}

impl Tessellation {
    fn build(poly: &ConvexPolytope, structure: &Structure, step: f64) -> CoreResult<Self> {
        let mut mesh = Tessellation { nodes: Vec::new(), triangles: Vec::new(), centres: Vec::new(), regions: Vec::new() };
        let mut shared = Shared::default();
        for (t, tri) in poly.triangles.iter().enumerate() {
            let f = poly.triangle_facet[t];
            let corners = tri.map(|v| mesh.corner(poly, &mut shared, v, f));
            mesh.triangles.push(corners);
            mesh.centres.push(Centre::Facet(poly.normals[f as usize]));
        }
        for &(a, b, f, g) in &structure.edges {
            let from = mesh.arc_row(poly, &mut shared, a, f, g, step);
            let to = mesh.arc_row(poly, &mut shared, b, f, g, step);
            let (pa, pb) = (poly.vertices[a as usize], poly.vertices[b as usize]);
            let centre = Centre::Edge { a: pa, e: (pb - pa).normalize() };
            let begin = mesh.triangles.len();
            for i in 0..from.len() - 1 {
                mesh.push(centre, [from[i], from[i + 1], to[i + 1]]);
                mesh.push(centre, [from[i], to[i + 1], to[i]]);
            }
            mesh.regions.push(begin..mesh.triangles.len());
        }
        for (v, facets) in structure.cones.iter().enumerate() {
            if !facets.is_empty() {
                mesh.patch(poly, &mut shared, v as u32, facets, step)?;
            }
        }
        Ok(mesh)
    }

    fn push(&mut self, centre: Centre, tri: [u32; 3]) {
        self.triangles.push(tri);
        self.centres.push(centre);
    }

    fn node(&mut self, base: Vec3, dir: Vec3, corner: bool) -> u32 {
        self.nodes.push(Node { base, dir, corner });
        (self.nodes.len() - 1) as u32
    }

    fn corner(&mut self, poly: &ConvexPolytope, shared: &mut Shared, v: u32, f: u32) -> u32 {
        if let Some(&id) = shared.corners.get(&(v, f)) {
            return id;
        }
        let id = self.node(poly.vertices[v as usize], poly.normals[f as usize], true);
        shared.corners.insert((v, f), id);
        id
    }

    /// The points at `v` from facet `f`'s corner along the arc to facet `g`'s, the arc cut
    /// into pieces no wider than `step`.
    fn arc_row(&mut self, poly: &ConvexPolytope, shared: &mut Shared, v: u32, f: u32, g: u32, step: f64) -> Vec<u32> {
        let (lo, hi) = (f.min(g), f.max(g));
        let inner = match shared.arcs.get(&(v, lo, hi)) {
            Some(ids) => ids.clone(),
            None => {
                let (n0, n1) = (poly.normals[lo as usize], poly.normals[hi as usize]);
                let pieces = pieces(angle(n0, n1), step);
                let base = poly.vertices[v as usize];
                let ids: Vec<u32> = (1..pieces).map(|i| self.node(base, slerp(n0, n1, i as f64 / pieces as f64), false)).collect();
                shared.arcs.insert((v, lo, hi), ids.clone());
                ids
            }
        };
        let mut row = vec![self.corner(poly, shared, v, f)];
        if f == lo {
            row.extend(inner);
        } else {
            row.extend(inner.into_iter().rev());
        }
        row.push(self.corner(poly, shared, v, g));
        row
    }

    /// Vertex `v`'s sphere patch: one sector per pair of neighbouring facets, between the
    /// spokes from the cone's centre direction to the two facets' normals, in rows graded
    /// from the apex to the arc.
    fn patch(&mut self, poly: &ConvexPolytope, shared: &mut Shared, v: u32, facets: &[u32], step: f64) -> CoreResult<()> {
        let base = poly.vertices[v as usize];
        let normals: Vec<Vec3> = facets.iter().map(|&f| poly.normals[f as usize]).collect();
        let Some(axis) = interior_axis(&normals) else {
            return Err(CoreError::Degenerate { what: "convex polytope".into(), detail: format!("vertex {v}'s facet normals bound no cone with an inside") });
        };
        let rows = normals.iter().map(|&n| pieces(angle(axis, n), step)).max().unwrap_or(1);
        let arcs: Vec<Vec<u32>> = (0..facets.len()).map(|j| self.arc_row(poly, shared, v, facets[j], facets[(j + 1) % facets.len()], step)).collect();
        let begin = self.triangles.len();
        if rows == 1 && arcs.iter().all(|arc| arc.len() == 2) {
            // a cone narrower than a step with no arc points: a fan of its corners
            for j in 1..facets.len() - 1 {
                self.push(Centre::Vertex(base), [arcs[0][0], arcs[j][0], arcs[j][1]]);
            }
            self.regions.push(begin..self.triangles.len());
            return Ok(());
        }
        if let (3, Some(short)) = (facets.len(), arcs.iter().position(|arc| arc.len() == 2)) {
            // a thin three-sided cone (a float32 cylinder's rim): the two long arcs from
            // the corner opposite the short one, zipped
            let lower = &arcs[(short + 2) % 3];
            let upper: Vec<u32> = arcs[(short + 1) % 3].iter().rev().copied().collect();
            self.push(Centre::Vertex(base), [lower[0], lower[1], upper[1]]);
            self.zip_rows(Centre::Vertex(base), &lower[1..], &upper[1..]);
            self.regions.push(begin..self.triangles.len());
            return Ok(());
        }
        let apex = self.node(base, axis, false);
        let spokes: Vec<Vec<u32>> = facets
            .iter()
            .zip(&normals)
            .map(|(&f, &n)| {
                let mut spoke = vec![apex];
                spoke.extend((1..rows).map(|i| self.node(base, slerp(axis, n, i as f64 / rows as f64), false)));
                spoke.push(self.corner(poly, shared, v, f));
                spoke
            })
            .collect();
        for j in 0..facets.len() {
            let next = (j + 1) % facets.len();
            let arc = self.arc_row(poly, shared, v, facets[j], facets[next], step);
            let pieces_on_arc = arc.len() - 1;
            let begin = self.triangles.len();
            let mut lower = vec![apex];
            for (i, (&left, &right)) in spokes[j].iter().zip(&spokes[next]).enumerate().skip(1) {
                let upper = if i == rows {
                    arc.clone()
                } else {
                    let (dl, dr) = (self.nodes[left as usize].dir, self.nodes[right as usize].dir);
                    let count = (i * pieces_on_arc).div_ceil(rows).max(1);
                    let mut row = vec![left];
                    row.extend((1..count).map(|t| self.node(base, slerp(dl, dr, t as f64 / count as f64), false)));
                    row.push(right);
                    row
                };
                self.zip_rows(Centre::Vertex(base), &lower, &upper);
                lower = upper;
            }
            self.regions.push(begin..self.triangles.len());
        }
        Ok(())
    }

    /// Triangles between two rows of points running the same way, each advancing along
    /// the row whose next point comes first in its own parameter.
    fn zip_rows(&mut self, centre: Centre, lower: &[u32], upper: &[u32]) {
        let (nl, nu) = (lower.len() - 1, upper.len() - 1);
        let (mut i, mut j) = (0, 0);
        while i < nl || j < nu {
            if i < nl && (j == nu || (i + 1) * nu <= (j + 1) * nl) {
                self.push(centre, [lower[i], lower[i + 1], upper[j]]);
                i += 1;
            } else {
                self.push(centre, [lower[i], upper[j + 1], upper[j]]);
                j += 1;
            }
        }
    }

    fn position(&self, node: u32, radius: f64, scale: f64) -> Vec3 {
        let n = self.nodes[node as usize];
        n.base + n.dir * if n.corner { radius } else { radius * scale }
    }

    /// The least distance from a round triangle's feature to it.
    fn depth(&self, t: usize, radius: f64, scale: f64) -> Option<f64> {
        let [p, q, w] = self.triangles[t].map(|i| self.position(i, radius, scale));
        match self.centres[t] {
            Centre::Facet(_) => None,
            Centre::Vertex(v) => Some(point_triangle_distance2(v, p, q, w).sqrt()),
            Centre::Edge { a, e } => {
                // a strip's parallelogram: across the edge, its triangles are one segment
                let across = |x: Vec3| (x - a) - e * (x - a).dot(e);
                let (p, q, w) = (across(p), across(q), across(w));
                let (s, t) = [(p, q), (q, w), (w, p)].into_iter().max_by(|x, y| (x.0 - x.1).length_squared().total_cmp(&(y.0 - y.1).length_squared())).expect("three pairs");
                Some(segment_distance(s, t))
            }
        }
    }

    fn least_depth(&self, radius: f64, scale: f64) -> f64 {
        (0..self.triangles.len()).filter_map(|t| self.depth(t, radius, scale)).fold(radius, f64::min)
    }

    /// `(s, bound)`: the round points' radius factor that splits the sag evenly, and the
    /// two-sided bound measured with it.
    fn balanced(&self, radius: f64) -> (f64, f64) {
        let sag = self.least_depth(radius, 1.0) / radius;
        let scale = 2.0 / (1.0 + sag);
        let inside = radius - self.least_depth(radius, scale);
        (scale, inside.max(radius * (scale - 1.0)))
    }

    /// The points and triangles, each region turned to face out (away from its feature),
    /// the points closer than `within` welded: `(points, triangles, how far the weld moved
    /// them)`, or `None` when a region folds over (faces both ways).
    fn into_welded(mut self, radius: f64, scale: f64, within: f64) -> CoreResult<Option<Finished>> {
        let vertices: Vec<Vec3> = (0..self.nodes.len() as u32).map(|i| self.position(i, radius, scale)).collect();
        for region in self.regions.clone() {
            let facing: Vec<f64> = region.clone().map(|t| facing(self.centres[t], self.triangles[t].map(|i| vertices[i as usize]))).collect();
            let outward = facing.iter().all(|&f| f > 0.0);
            if !outward && !facing.iter().all(|&f| f < 0.0) {
                return Ok(None);
            }
            if !outward {
                for t in region {
                    self.triangles[t].swap(1, 2);
                }
            }
        }
        let welded = weld(&vertices, &self.triangles, within)?;
        for (w, &t) in welded.triangles.iter().zip(&welded.kept) {
            if facing(self.centres[t], w.map(|i| welded.vertices[i as usize])) <= 0.0 {
                return Err(CoreError::Degenerate { what: "rounded polytope".into(), detail: "the weld turns a triangle over".into() });
            }
        }
        Ok(Some((welded.vertices, welded.triangles, welded.moved)))
    }
}

/// A triangle's normal along the direction from its feature to its centroid (for a
/// facet, along the facet's normal).
fn facing(centre: Centre, [p, q, w]: [Vec3; 3]) -> f64 {
    let centroid = (p + q + w) / 3.0;
    let away = match centre {
        Centre::Facet(n) => n,
        Centre::Vertex(v) => centroid - v,
        Centre::Edge { a, e } => (centroid - a) - e * (centroid - a).dot(e),
    };
    (q - p).cross(w - p).dot(away)
}

/// The angle between two unit vectors.
fn angle(a: Vec3, b: Vec3) -> f64 {
    // atan2 of the cross and dot products: accurate for small and large angles alike
    a.cross(b).length().atan2(a.dot(b))
}

/// Most iterations of the smallest enclosing ball of a cone's generators.
const AXIS_ITERATIONS: usize = 200;

/// A direction well inside the cone of the unit `normals` (in cyclic order), near the
/// centre of their smallest enclosing ball ([`enclosing_centre`]), which keeps the
/// spokes short. That centre lies in the cone but on its side when two normals are its
/// diameter (an obtuse corner), and an apex there makes a sector of no width: it is
/// moved towards the area centroid of the cone's cap (fanned from it), which lies a third
/// of the cap's width or more from every side, until it is at least half as deep as
/// the centroid. `None` when no point is strictly inside every side (normals on one
/// great circle).
fn interior_axis(normals: &[Vec3]) -> Option<Vec3> {
    let centre = enclosing_centre(normals);
    let count = normals.len();
    let mut weighted = Vec3::ZERO;
    for j in 0..count {
        let (a, b) = (normals[j], normals[(j + 1) % count]);
        weighted += (centre + a + b) * (a - centre).cross(b - centre).length();
    }
    let centroid = weighted.normalize_or_zero();
    // the facets run the same way round the vertex: the inside is on the same side of
    // every arc's plane
    let mut sides: Vec<Vec3> = (0..count).map(|j| normals[j].cross(normals[(j + 1) % count]).normalize_or_zero()).collect();
    if sides.iter().map(|side| side.dot(centroid)).sum::<f64>() < 0.0 {
        sides.iter_mut().for_each(|side| *side = -*side);
    }
    let depth = |x: Vec3| sides.iter().map(|side| side.dot(x)).fold(f64::INFINITY, f64::min);
    let centre = centre.normalize_or_zero();
    let (deep, shallow) = (depth(centroid), depth(centre));
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN must be refused
    if !(deep > 0.0) {
        return None;
    }
    // depth is concave along the chord from the centre to the centroid
    let t = if shallow >= 0.5 * deep { 0.0 } else { (0.5 * deep - shallow) / (deep - shallow) };
    let axis = (centre * (1.0 - t) + centroid * t).normalize_or_zero();
    (depth(axis) > 0.0).then_some(axis)
}

/// The centre of the smallest ball enclosing the unit `normals` (Bădoiu–Clarkson
/// iterations): a convex combination of them, so inside their cone.
fn enclosing_centre(normals: &[Vec3]) -> Vec3 {
    let mut centre = normals[0];
    for k in 1..AXIS_ITERATIONS {
        // the last of the farthest, as `max_by` would pick (a plain loop: this is most of
        // the tessellation's time)
        let mut farthest = normals[0];
        let mut widest = f64::NEG_INFINITY;
        for &n in normals {
            let d = (n - centre).length_squared();
            if d >= widest {
                (farthest, widest) = (n, d);
            }
        }
        centre += (farthest - centre) / (k as f64 + 1.0);
    }
    centre
}

/// How many pieces of at most `step` an arc of `angle` takes (at least one).
fn pieces(angle: f64, step: f64) -> usize {
    ((angle / step).ceil() as usize).max(1)
}

/// The unit vector a fraction `t` of the way along the great arc from `a` to `b`.
fn slerp(a: Vec3, b: Vec3, t: f64) -> Vec3 {
    let omega = angle(a, b);
    if omega < 1e-9 {
        return (a + (b - a) * t).normalize();
    }
    ((a * ((1.0 - t) * omega).sin() + b * (t * omega).sin()) / omega.sin()).normalize()
}

/// The distance from the origin to the segment `pq`.
fn segment_distance(p: Vec3, q: Vec3) -> f64 {
    let d = q - p;
    let length2 = d.length_squared();
    let t = if length2 > 0.0 { (-p.dot(d) / length2).clamp(0.0, 1.0) } else { 0.0 };
    (p + d * t).length()
}

#[cfg(test)]
#[path = "rounded_tests.rs"]
mod tests;
