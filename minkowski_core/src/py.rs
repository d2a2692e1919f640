//! The Python binding: converts numpy arrays, releases the GIL for native work, and maps
//! [`CoreError`] to the exception classes of `planner.errors` in one place.

use crate::error::CoreError;
use crate::exact::tidy::{tidy_windings, TidyLimits};
use crate::exact::{ExactSource, TriMesh};
use crate::math::{Aabb, Vec3};
use crate::minkowski::{pairwise_sums, PolytopeSet, SumKind};
use crate::octree::Octree;
use crate::polytope::ConvexPolytope;
use crate::union::{approximate_solid, approximate_union, UnionParams, UnionResult};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

pyo3::import_exception!(planner.errors, InvalidMeshError);
pyo3::import_exception!(planner.errors, InvalidParameterError);
pyo3::import_exception!(planner.errors, ResourceLimitError);
pyo3::import_exception!(planner.errors, GeometryError);
pyo3::import_exception!(planner.errors, TimeLimitError);

impl From<CoreError> for PyErr {
    fn from(e: CoreError) -> PyErr {
        let msg = e.to_string();
        match e {
            CoreError::NonFinite { .. } | CoreError::Degenerate { .. } | CoreError::Empty { .. } | CoreError::InvalidGeometry { .. } => InvalidMeshError::new_err(msg),
            CoreError::InvalidParameter { .. } => InvalidParameterError::new_err(msg),
            CoreError::ResourceLimit { .. } | CoreError::FacetLimit { .. } | CoreError::RecordLimit { .. } => ResourceLimitError::new_err(msg),
            CoreError::TimeLimit { .. } => TimeLimitError::new_err(msg),
        }
    }
}

/// How often a thread waiting for native work checks Python's signals.
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// `work` run with the GIL released, as `py.detach` runs it, answering Ctrl+C: the calling
/// thread checks Python's signals every [`SIGNAL_POLL`] while `work` runs on another; when a
/// signal's handler raises (KeyboardInterrupt), the work is cancelled
/// ([`crate::deadline::cancel`]), waited for, and that error returned. Work that a cancel
/// touched while it ran (another call's Ctrl+C) returns KeyboardInterrupt too.
fn interruptible<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    use std::sync::atomic::{AtomicBool, Ordering};
    let waiting = std::thread::current();
    let done = AtomicBool::new(false); // set before the wake-up, so no wait outlasts the work
    let cancels = crate::deadline::watch_cancels();
    std::thread::scope(|scope| {
        let worker = scope.spawn(|| {
            let out = work();
            done.store(true, Ordering::Release);
            waiting.unpark();
            out
        });
        loop {
            py.detach(|| {
                if !done.load(Ordering::Acquire) {
                    std::thread::park_timeout(SIGNAL_POLL);
                }
            });
            if done.load(Ordering::Acquire) {
                let out = joined(worker);
                return if cancels.touched() { Err(cancelled_elsewhere()) } else { Ok(out) };
            }
            if let Err(interrupt) = py.check_signals() {
                crate::deadline::cancel();
                py.detach(|| drop(worker.join()));
                crate::deadline::uncancel();
                return Err(interrupt);
            }
        }
    })
}

/// The error of a call that a Ctrl+C in another of the process's native calls cancelled
/// (one flag stops them all): what it made may be half done.
fn cancelled_elsewhere() -> PyErr {
    pyo3::exceptions::PyKeyboardInterrupt::new_err("cancelled: Ctrl+C stopped the native work running at the time")
}

/// The result of a finished worker thread (its panic resumed here).
fn joined<T>(worker: std::thread::ScopedJoinHandle<'_, T>) -> T {
    worker.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}

fn points_of(a: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<Vec<Vec3>> {
    let shape = a.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(InvalidMeshError::new_err(format!("{what}: expected an (n, 3) array of points, got shape {shape:?}")));
    }
    let v = a.as_array();
    Ok(v.rows().into_iter().map(|r| Vec3::new(r[0], r[1], r[2])).collect())
}

fn vec3_of(a: &PyReadonlyArray1<'_, f64>, what: &str) -> PyResult<Vec3> {
    let v = a.as_array();
    if v.len() != 3 {
        return Err(InvalidParameterError::new_err(format!("{what}: expected 3 coordinates, got {}", v.len())));
    }
    Ok(Vec3::new(v[0], v[1], v[2]))
}

fn to_array2(rows: impl ExactSizeIterator<Item = [f64; 3]>) -> Array2<f64> {
    let n = rows.len();
    let flat: Vec<f64> = rows.flat_map(|r| r.into_iter()).collect();
    Array2::from_shape_vec((n, 3), flat).expect("n x 3")
}

/// A union of convex primitives (for a C-obstacle: the pairwise sums M_ij) with a BVH.
#[pyclass(frozen, module = "planner._minkowski_core")]
pub struct Primitives {
    inner: Arc<PolytopeSet>,
}

#[pymethods]
impl Primitives {
    /// All pairwise sums conv{p ± q} of the convex pieces `pieces_a` and `pieces_b`
    /// (lists of (n, 3) float64 vertex arrays); `subtract=True` gives A ⊕ (−B).
    #[staticmethod]
    #[pyo3(signature = (pieces_a, pieces_b, subtract=false))]
    fn pairwise_sums(py: Python<'_>, pieces_a: Vec<PyReadonlyArray2<'_, f64>>, pieces_b: Vec<PyReadonlyArray2<'_, f64>>, subtract: bool) -> PyResult<Self> {
        let a = pieces_a.iter().enumerate().map(|(i, p)| points_of(p, &format!("operand A piece {i}"))).collect::<PyResult<Vec<_>>>()?;
        let b = pieces_b.iter().enumerate().map(|(i, p)| points_of(p, &format!("operand B piece {i}"))).collect::<PyResult<Vec<_>>>()?;
        let kind = if subtract { SumKind::Subtract } else { SumKind::Add };
        let polys = py.detach(move || pairwise_sums(&a, &b, kind))?;
        Ok(Primitives { inner: Arc::new(PolytopeSet::new(polys)) })
    }

    /// The convex hulls of `pieces` (a list of (n, 3) float64 arrays) as primitives.
    #[staticmethod]
    fn from_pieces(py: Python<'_>, pieces: Vec<PyReadonlyArray2<'_, f64>>) -> PyResult<Self> {
        let pts = pieces.iter().enumerate().map(|(i, p)| points_of(p, &format!("piece {i}"))).collect::<PyResult<Vec<_>>>()?;
        if pts.is_empty() {
            return Err(CoreError::Empty { what: "pieces".into() }.into());
        }
        let polys = py.detach(move || pts.par_iter().enumerate().map(|(i, p)| ConvexPolytope::try_from_points(p, &format!("piece {i}"))).collect::<Result<Vec<_>, _>>())?;
        Ok(Primitives { inner: Arc::new(PolytopeSet::new(polys)) })
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    /// (2, 3) array: the box around all primitives.
    #[getter]
    fn bounds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let b = self.inner.aabb;
        to_array2([b.min.to_array(), b.max.to_array()].into_iter()).into_pyarray(py)
    }

    /// Number of facets of each primitive, (n,) int64.
    fn facet_counts<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        self.inner.polys.iter().map(|p| p.normals.len() as i64).collect::<Vec<_>>().into_pyarray(py)
    }

    /// Vertices, (n, 3), and boundary triangles, (m, 3), of primitive `i`.
    fn polytope<'py>(&self, py: Python<'py>, i: usize) -> PyResult<MeshArrays<'py>> {
        let p = self.inner.polys.get(i).ok_or_else(|| InvalidParameterError::new_err(format!("primitive index {i} out of range")))?;
        let v = to_array2(p.vertices.iter().map(|v| v.to_array())).into_pyarray(py);
        let flat: Vec<i64> = p.triangles.iter().flat_map(|t| t.iter().map(|&x| x as i64)).collect();
        let f = Array2::from_shape_vec((p.triangles.len(), 3), flat).expect("m x 3").into_pyarray(py);
        Ok((v, f))
    }

    /// Whether each of `points` (n, 3) lies in the union (closed), (n,) bool.
    fn contains<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let pts = points_of(&points, "points")?;
        let set = self.inner.clone();
        let out: Vec<bool> = py.detach(move || pts.par_iter().map(|p| set.contains_point(*p)).collect());
        Ok(out.into_pyarray(py))
    }

    /// Signed distance of each of `points` (n, 3) to the union, (n,): exact outside; inside,
    /// minus the largest depth in one primitive (a lower bound on the true depth).
    fn signed_distance<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pts = points_of(&points, "points")?;
        let set = self.inner.clone();
        let out: Vec<f64> = py.detach(move || pts.par_iter().map(|p| set.signed_distance(*p)).collect());
        Ok(out.into_pyarray(py))
    }

    /// Whether the closed segment a → b misses every primitive (exact clipping).
    fn segment_is_free(&self, a: PyReadonlyArray1<'_, f64>, b: PyReadonlyArray1<'_, f64>) -> PyResult<bool> {
        Ok(self.inner.segment_is_free(vec3_of(&a, "a")?, vec3_of(&b, "b")?))
    }

    /// Parameter intervals of the segment a → b inside the union, as a list of (t0, t1).
    fn segment_intervals(&self, a: PyReadonlyArray1<'_, f64>, b: PyReadonlyArray1<'_, f64>) -> PyResult<Vec<(f64, f64)>> {
        Ok(self.inner.segment_intervals(vec3_of(&a, "a")?, vec3_of(&b, "b")?))
    }
}

/// Approximate the boundary of the union of `prims` with a closed, manifold,
/// outward-oriented triangle mesh whose two-sided Hausdorff distance to the true boundary
/// is `error_bound`: `eps` when every band cell resolves the boundary, `2 eps` with
/// unresolved cells, `inf` while complex cells remain (the grid is halved up to
/// `max_refinements` times for those). `simplify` collapses the interiors of planar
/// patches (same surface, fewer triangles). Returns a dict with `vertices` (n, 3), `faces`
/// (m, 3), `h`, `error_bound` and statistics.
#[pyfunction]
#[pyo3(signature = (prims, eps, max_cells=8_000_000, max_refinements=2, simplify=true))]
fn union_surface<'py>(py: Python<'py>, prims: &Primitives, eps: f64, max_cells: usize, max_refinements: u32, simplify: bool) -> PyResult<Bound<'py, PyDict>> {
    let set = prims.inner.clone();
    let params = UnionParams { eps, max_cells, max_refinements, simplify, planes: true };
    let r = interruptible(py, move || approximate_union(&set, &params))??;
    surface_dict(py, &r)
}

/// The offset of the solid `mesh` (a [`CheckedMesh`] checked as a solid) by `radius`:
/// `{x : dist(x, P) <= r}` for `r > 0`, the erosion `{x in P : dist(x, boundary) >= |r|}`
/// for `r < 0`, as a closed surface at resolution `eps` with its two-sided error bound (a
/// dict as `union_surface`'s). A surface (checked as one) grows as its triangles do:
/// `{x : dist(x, triangles) <= r}`, `r > 0`. `refine_creases`: refine the surface where it
/// sags from the offset (its creases).
#[pyfunction]
#[pyo3(signature = (mesh, radius, eps, max_cells=8_000_000, max_refinements=2, simplify=true, refine_creases=true))]
#[allow(clippy::too_many_arguments)]
fn offset_surface<'py>(
    py: Python<'py>,
    mesh: &CheckedMesh,
    radius: f64,
    eps: f64,
    max_cells: usize,
    max_refinements: u32,
    simplify: bool,
    refine_creases: bool,
) -> PyResult<Bound<'py, PyDict>> {
    if !(radius.is_finite() && radius != 0.0) {
        return Err(InvalidParameterError::new_err(format!("radius = {radius}: must be a non-zero finite number")));
    }
    if !mesh.inner.solid && radius < 0.0 {
        return Err(InvalidParameterError::new_err("mesh: checked as a surface; an erosion needs a solid".to_string()));
    }
    let solid = mesh.inner.clone();
    let params = UnionParams { eps, max_cells, max_refinements, simplify, planes: true };
    let r = interruptible(py, move || {
        let mut src = crate::offset::OffsetSource::new(solid.as_ref(), radius);
        src.refine_creases = refine_creases;
        approximate_solid(&src, &src.aabb, &params)
    })??;
    surface_dict(py, &r)
}

/// The offset of the convex hull of `points` by `radius`, tessellated along the hull's
/// own facets, edges and vertices with its two-sided bound within `tol`, points closer
/// than `weld` welded ([`crate::polytope::rounded`]): a dict of `vertices`, `faces`,
/// `bound` (two-sided, the weld included), `scale`, `step`, `narrowest` and `welded`.
#[pyfunction]
#[pyo3(signature = (points, radius, tol, weld=0.0, max_triangles=20_000_000))]
fn rounded_polytope<'py>(py: Python<'py>, points: PyReadonlyArray2<'py, f64>, radius: f64, tol: f64, weld: f64, max_triangles: usize) -> PyResult<Bound<'py, PyDict>> {
    let points = points_of(&points, "points")?;
    let out = py.detach(move || {
        let poly = crate::polytope::ConvexPolytope::try_from_points(&points, "hull corners")?;
        crate::polytope::rounded(&poly, radius, tol, weld, max_triangles)
    })?;
    let d = mesh_dict(py, &out.vertices, &out.triangles)?;
    d.set_item("bound", out.bound)?;
    d.set_item("scale", out.scale)?;
    d.set_item("step", out.step)?;
    d.set_item("narrowest", out.narrowest)?;
    d.set_item("welded", out.welded)?;
    Ok(d)
}

/// A dict with a mesh's `vertices` ((n, 3) float64) and `faces` ((m, 3) int64).
fn mesh_dict<'py>(py: Python<'py>, vertices: &[Vec3], triangles: &[[u32; 3]]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("vertices", to_array2(vertices.iter().map(|v| v.to_array())).into_pyarray(py))?;
    let flat: Vec<i64> = triangles.iter().flat_map(|f| f.iter().map(|&x| x as i64)).collect();
    d.set_item("faces", Array2::from_shape_vec((triangles.len(), 3), flat).expect("m x 3").into_pyarray(py))?;
    Ok(d)
}

fn surface_dict<'py>(py: Python<'py>, r: &UnionResult) -> PyResult<Bound<'py, PyDict>> {
    let s = &r.surface;
    let d = mesh_dict(py, &s.vertices, &s.faces)?;
    d.set_item("h", r.h)?;
    d.set_item("error_bound", r.error_bound)?;
    d.set_item("refinements", r.refinements)?;
    d.set_item("band_cells", s.band_cells)?;
    d.set_item("lattice_points", s.lattice_points)?;
    d.set_item("edges", s.edges)?;
    d.set_item("complex_edges", s.complex_edges)?;
    d.set_item("complex_cells", s.complex_cells)?;
    d.set_item("unresolved_cells", s.unresolved_cells)?;
    d.set_item("silent_cells", s.silent_cells)?;
    d.set_item("slivers_apart", s.slivers_apart)?;
    d.set_item("inconsistent_edges", s.inconsistent_edges)?;
    d.set_item("cells_per_level", r.level_counts.iter().map(|c| c.to_vec()).collect::<Vec<_>>())?;
    d.set_item("seconds_octree", r.seconds_octree)?;
    d.set_item("seconds_surface", r.seconds_surface)?;
    d.set_item("seconds_simplify", r.seconds_simplify)?;
    d.set_item("triangles_extracted", r.triangles_extracted)?;
    d.set_item("planar_cells", s.planar_cells)?;
    d.set_item("planar_pieces", s.planar_pieces)?;
    d.set_item("planar_regions", s.regions.merged_planes)?;
    d.set_item("planar_fanned", s.regions.fanned_planes)?;
    d.set_item("planar_unfolded", s.regions.unfolded)?;
    d.set_item("planar_straight_dropped", s.regions.straight_dropped)?;
    d.set_item("planar_deviation", s.planar_deviation)?;
    d.set_item("planes_fallback_edges", r.planes_fallback_edges)?;
    d.set_item("sag_rounds", r.sag.rounds)?;
    d.set_item("sag_tested", r.sag.tested)?;
    d.set_item("sag_splits", r.sag.splits)?;
    d.set_item("sag_flips", r.sag.flips)?;
    d.set_item("sag_folds_refused", r.sag.folds_refused)?;
    d.set_item("sag_left", r.sag.sag_left)?;
    d.set_item("sag_covering", r.sag.covering)?;
    d.set_item("seconds_sag", r.seconds_sag)?;
    // the bound by where it comes from: plane-resolved cells (0: exact), the sampled band
    // (the grid's), and cells where the lattice may have missed boundary (their reach);
    // vertices moved apart where sheets touched add to the planes' (they are in the join)
    let grid = crate::union::grid_error_bound(r.h);
    d.set_item("bound_planes", s.planar_deviation + s.sheets_apart)?;
    d.set_item("bound_sampled", if s.band_cells > 0 { grid } else { 0.0 })?;
    d.set_item("bound_missed", r.missed_reach)?;
    d.set_item("holes_closed", s.loops_closed)?;
    d.set_item("sheets_unzipped", s.sheets_unzipped)?;
    d.set_item("sheets_apart", s.sheets_apart)?;
    Ok(d)
}

/// Build the octree over `prims` covering `bounds` ((2, 3); default: the primitives' box)
/// with finest cell size `h`. Returns a dict with `origin`, `h`, `depth`, and per leaf
/// `ijk` (n, 3) lattice corner, `level` (n,) (size 2**level · h) and `label` (n,)
/// (0 EMPTY, 1 FULL, 2 MIXED), plus `seconds`.
#[pyfunction]
#[pyo3(signature = (prims, h, bounds=None, max_cells=40_000_000))]
fn build_octree<'py>(py: Python<'py>, prims: &Primitives, h: f64, bounds: Option<PyReadonlyArray2<'py, f64>>, max_cells: usize) -> PyResult<Bound<'py, PyDict>> {
    let region = match bounds {
        Some(b) => {
            let p = points_of(&b, "bounds")?;
            if p.len() != 2 || !(p[0].cmplt(p[1]).all()) {
                return Err(InvalidParameterError::new_err("bounds: expected [[min x, y, z], [max x, y, z]] with min < max"));
            }
            Aabb::new(p[0], p[1])
        }
        None => prims.inner.aabb,
    };
    let set = prims.inner.clone();
    let t0 = Instant::now();
    let oct = interruptible(py, move || Octree::build(set.as_ref(), &region, h, max_cells))??;
    let seconds = t0.elapsed().as_secs_f64();
    let d = PyDict::new(py);
    d.set_item("origin", oct.origin.to_array().to_vec())?;
    d.set_item("h", oct.h)?;
    d.set_item("depth", oct.depth)?;
    let n = oct.leaves.len();
    let ijk: Vec<u32> = oct.leaves.iter().flat_map(|l| l.ijk).collect();
    d.set_item("ijk", numpy::ndarray::Array2::from_shape_vec((n, 3), ijk).expect("n x 3").into_pyarray(py))?;
    d.set_item("level", oct.leaves.iter().map(|l| l.level).collect::<Vec<u8>>().into_pyarray(py))?;
    d.set_item("label", oct.leaves.iter().map(|l| l.label as u8).collect::<Vec<u8>>().into_pyarray(py))?;
    d.set_item("seconds", seconds)?;
    Ok(d)
}

/// A solid (`solid`: closed, winding number never negative; checked) or a surface (any
/// triangles) from (vertices (n, 3) float64, faces (m, 3) int64).
fn mesh_of(v: &PyReadonlyArray2<'_, f64>, f: &PyReadonlyArray2<'_, i64>, what: &str, solid: bool) -> PyResult<TriMesh> {
    let (verts, faces) = arrays_of(v, f, what)?;
    Ok(if solid { TriMesh::new(verts, &faces, what)? } else { TriMesh::surface(verts, &faces, what)? })
}

/// The vertices and faces of a mesh argument, checked for shape and index range.
fn arrays_of(v: &PyReadonlyArray2<'_, f64>, f: &PyReadonlyArray2<'_, i64>, what: &str) -> PyResult<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let verts = points_of(v, &format!("{what} vertices"))?;
    let fa = f.as_array();
    if fa.ncols() != 3 {
        return Err(InvalidMeshError::new_err(format!("{what} faces: expected shape (m, 3), got {:?}", f.shape())));
    }
    let mut faces = Vec::with_capacity(fa.nrows());
    for row in fa.rows() {
        if row.iter().any(|&x| x < 0 || x >= verts.len() as i64) {
            return Err(InvalidMeshError::new_err(format!("{what} faces: index out of range 0..{} in {row:?}", verts.len())));
        }
        faces.push([row[0] as u32, row[1] as u32, row[2] as u32]);
    }
    Ok((verts, faces))
}

/// A part's triangle mesh, checked once (a solid: closed, outward, winding number never
/// negative; a surface: any finite triangles) with its BVH, for [`ExactSum`] and
/// `CSpace.exact` to take without checking it again.
#[pyclass(frozen, module = "planner._minkowski_core")]
pub struct CheckedMesh {
    inner: Arc<TriMesh>,
}

#[pymethods]
impl CheckedMesh {
    /// Check vertices (n, 3) and faces (m, 3) as a solid (or, with `solid=False`, a
    /// surface); `name` names the mesh in errors.
    #[new]
    #[pyo3(signature = (vertices, faces, solid=true, name="mesh"))]
    fn new(vertices: PyReadonlyArray2<'_, f64>, faces: PyReadonlyArray2<'_, i64>, solid: bool, name: &str) -> PyResult<Self> {
        Ok(CheckedMesh { inner: Arc::new(mesh_of(&vertices, &faces, name, solid)?) })
    }

    /// Whether it was checked as a solid.
    #[getter]
    fn solid(&self) -> bool {
        self.inner.solid
    }

    /// Number of triangles.
    #[getter]
    fn triangles(&self) -> usize {
        self.inner.tris.len()
    }

    /// `−M`: negated vertices, triangles reversed (a solid stays a solid).
    fn negated(&self) -> CheckedMesh {
        CheckedMesh { inner: Arc::new(self.inner.negated()) }
    }
}

/// A mesh argument: a [`CheckedMesh`], or (vertices, faces) arrays checked here.
#[derive(FromPyObject)]
enum MeshArg<'py> {
    Checked(PyRef<'py, CheckedMesh>),
    Arrays((PyReadonlyArray2<'py, f64>, PyReadonlyArray2<'py, i64>)),
}

impl MeshArg<'_> {
    /// The mesh, as a solid or a surface as `solid` asks (a [`CheckedMesh`] must agree).
    fn mesh(&self, what: &str, solid: bool) -> PyResult<TriMesh> {
        match self {
            MeshArg::Arrays((v, f)) => mesh_of(v, f, what, solid),
            MeshArg::Checked(m) if m.inner.solid == solid => Ok(m.inner.as_ref().clone()),
            MeshArg::Checked(m) => {
                let kind = if m.inner.solid { "a solid" } else { "a surface" };
                Err(InvalidParameterError::new_err(format!("{what}: checked as {kind}, but solid={solid} was asked")))
            }
        }
    }
}

/// The winding number just in front of every triangle of the closed mesh (vertices (n, 3),
/// faces (m, 3)): (m,) int64, with the smallest int64 where it could not be told (the
/// triangle lies on others). The mesh bounds a solid when none is negative. Parallel.
#[pyfunction]
fn front_windings<'py>(py: Python<'py>, vertices: PyReadonlyArray2<'py, f64>, faces: PyReadonlyArray2<'py, i64>) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let mesh = closed_mesh(&vertices, &faces)?;
    let out: Vec<i64> = py.detach(|| mesh.front_windings().into_iter().map(|w| w.unwrap_or(i64::MIN)).collect());
    Ok(out.into_pyarray(py))
}

/// The winding number in the wedge in front of both triangles of every crossing of two
/// triangles of the closed mesh (vertices (n, 3), faces (m, 3)): (k,) int64, the smallest
/// int64 where it could not be told. With the front windings, the mesh bounds a solid when
/// none is negative. Parallel.
#[pyfunction]
fn crossing_windings<'py>(py: Python<'py>, vertices: PyReadonlyArray2<'py, f64>, faces: PyReadonlyArray2<'py, i64>) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let mesh = closed_mesh(&vertices, &faces)?;
    let out: Vec<i64> = py.detach(|| {
        let crossings = mesh.crossings();
        mesh.crossing_windings(&crossings).into_iter().map(|w| w.unwrap_or(i64::MIN)).collect()
    });
    Ok(out.into_pyarray(py))
}

/// The winding numbers of the closed mesh (vertices (n, 3), faces (m, 3)), as
/// [`front_windings`] and [`crossing_windings`] give them, how many crossings have the
/// solid on both sides of both triangles (shells that overlap), and its [`CheckedMesh`]
/// as a solid when no winding is negative or untold (else `None`): one check where the
/// three calls would make three. `name` names the mesh in errors. Parallel.
#[pyfunction]
#[pyo3(signature = (vertices, faces, name="mesh"))]
#[allow(clippy::type_complexity)]
fn solid_windings<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, i64>,
    name: &str,
) -> PyResult<(Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<i64>>, usize, Option<CheckedMesh>)> {
    let (verts, tris) = arrays_of(&vertices, &faces, name)?;
    let windings = py.detach(|| TriMesh::checked_windings(verts, &tris, name))?;
    let told = |ws: Vec<Option<i64>>| ws.into_iter().map(|w| w.unwrap_or(i64::MIN)).collect::<Vec<i64>>().into_pyarray(py);
    let checked = windings.solid.ok().map(|mesh| CheckedMesh { inner: Arc::new(mesh) });
    Ok((told(windings.fronts), told(windings.wedges), windings.crossings_inside, checked))
}

/// [`solid_windings`] for a mesh that is already tidy (see [`crate::exact::tidy`]): on
/// which the cleaning before the winding check would change nothing, with `limits` the
/// cleaning's tolerances in the mesh's units (merge distance, degenerate area, flat
/// volume, fold angle, coplanar distance). `None` when the mesh is not tidy or no solid:
/// the caller's full cleaning and checks then say why. Parallel.
#[pyfunction]
#[pyo3(signature = (vertices, faces, limits, name="mesh"))]
#[allow(clippy::type_complexity)]
fn tidy_solid_windings<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, i64>,
    limits: (f64, f64, f64, f64, f64),
    name: &str,
) -> PyResult<Option<(Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<i64>>, usize, CheckedMesh)>> {
    let (verts, tris) = arrays_of(&vertices, &faces, name)?;
    let (merge, degenerate_area, zero_volume, fold_angle, coplanar) = limits;
    let limits = TidyLimits { merge, degenerate_area, zero_volume, fold_angle, coplanar };
    let found = py.detach(|| tidy_windings(verts, &tris, &limits, name));
    let Some(windings) = found else { return Ok(None) };
    let told = |ws: Vec<Option<i64>>| ws.into_iter().map(|w| w.unwrap_or(i64::MIN)).collect::<Vec<i64>>().into_pyarray(py);
    let Ok(mesh) = windings.solid else { return Ok(None) };
    Ok(Some((told(windings.fronts), told(windings.wedges), windings.crossings_inside, CheckedMesh { inner: Arc::new(mesh) })))
}

/// The winding numbers of `points` (k, 3) for the closed mesh (vertices (n, 3), faces
/// (m, 3)): (k,) int64, the smallest int64 for points on the surface. Parallel.
#[pyfunction]
fn winding_numbers<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, i64>,
    points: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let mesh = closed_mesh(&vertices, &faces)?;
    let pts = points_of(&points, "points")?;
    let out: Vec<i64> = py.detach(|| pts.par_iter().map(|p| mesh.winding(*p).unwrap_or(i64::MIN)).collect());
    Ok(out.into_pyarray(py))
}

/// The triangle counts of the closed shells (mod 2: every edge, vertices welded, used an
/// even number of times; orientation aside) that the triangles (faces (m, 3) of vertices
/// (n, 3)) hold, most first: closed patches, and open ones whose boundaries cancel, as the
/// exact source's witnesses find them. Cheap: no lattice is made.
#[pyfunction]
fn closed_shell_sizes(vertices: PyReadonlyArray2<'_, f64>, faces: PyReadonlyArray2<'_, i64>) -> PyResult<Vec<usize>> {
    let mesh = mesh_of(&vertices, &faces, "mesh", false)?;
    Ok(crate::exact::shells::closed_shells(&mesh.vertices, &mesh.faces).iter().map(Vec::len).collect())
}

/// A mesh checked to be closed and consistently oriented (no winding check).
fn closed_mesh(vertices: &PyReadonlyArray2<'_, f64>, faces: &PyReadonlyArray2<'_, i64>) -> PyResult<TriMesh> {
    let surface = mesh_of(vertices, faces, "mesh", false)?;
    TriMesh::check_closed(&surface.faces, "mesh")?;
    Ok(TriMesh { closed: true, ..surface })
}

/// The exact Minkowski sum `A ⊕ B` of two closed triangle meshes (boundary convolution,
/// no decomposition): exact membership and segment queries, and its surface.
#[pyclass(frozen, module = "planner._minkowski_core")]
pub struct ExactSum {
    inner: Arc<ExactSource>,
    /// Built with `pieces`: point and segment queries only.
    pieces: bool,
}

impl ExactSum {
    /// Refuse `what` of a sum made for one depth query (`depth_near`): its facets beyond
    /// that query's reach were left out, so the answer could be wrong.
    fn whole(&self, what: &str) -> PyResult<()> {
        match self.inner.region {
            Some(_) => Err(InvalidParameterError::new_err(format!(
                "{what}: this sum was made for one depth query (depth_near) and kept only the facets near its point; make it without depth_near"
            ))),
            None => Ok(()),
        }
    }
}

#[pymethods]
impl ExactSum {
    /// `A ⊕ B` for `a` and `b` given as (vertices (n, 3), faces (m, 3)): solids (closed,
    /// outward, winding number never negative; checked) unless `a_solid` / `b_solid` is
    /// false (a surface: any triangles, containment does not count); or as
    /// [`CheckedMesh`]es, not checked again.
    #[new]
    // max_facets: boundary candidates held at most (planner.limits derives it from the
    // memory limit at FACET_BYTES each); beyond it the construction stops with a
    // ResourceLimitError, not out of memory. pieces: no reduced convolution at all, every
    // triangle-pair piece a boundary candidate found per query by the BVH pair traversal
    // (ExactSource::with_piece_fallback): built at once and in no memory beyond the meshes,
    // for point and segment queries (its surface would refine the pieces' whole shell)
    // depth_near: (point (3,), tolerance): only for the depth query there (to within that
    // tolerance): the facets beyond the cube its search can reach are left out
    // (ExactSource::try_new_for_depth); other queries are not to be asked of it.
    #[pyo3(signature = (a, b, a_solid=true, b_solid=true, max_facets=8_000_000, pieces=false, depth_near=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(py: Python<'_>, a: MeshArg<'_>, b: MeshArg<'_>, a_solid: bool, b_solid: bool, max_facets: usize, pieces: bool, depth_near: Option<(Vec<f64>, f64)>) -> PyResult<Self> {
        let ma = a.mesh("a", a_solid)?;
        let mb = b.mesh("b", b_solid)?;
        if let Some((point, tolerance)) = depth_near {
            let p = vec3_any(&point, "depth_near point")?;
            if !(a_solid && b_solid) || pieces {
                return Err(InvalidParameterError::new_err("depth_near: for the sum of two solids, with its reduced convolution".to_string()));
            }
            let inner = interruptible(py, move || ExactSource::try_new_for_depth(ma, mb, max_facets, p, tolerance))??;
            return Ok(ExactSum { inner: Arc::new(inner), pieces });
        }
        let inner = if pieces {
            interruptible(py, move || ExactSource::with_piece_fallback(vec![ma], mb, 0.0, None, 0))?
        } else {
            interruptible(py, move || ExactSource::try_new(vec![ma], mb, 0.0, None, max_facets))??
        };
        Ok(ExactSum { inner: Arc::new(inner), pieces })
    }

    /// Box around the sum, (2, 3).
    #[getter]
    fn bounds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let b = self.inner.aabb;
        to_array2([b.min.to_array(), b.max.to_array()].into_iter()).into_pyarray(py)
    }

    /// Triangle counts of `a` and `b`.
    #[getter]
    fn triangles(&self) -> (usize, usize) {
        (self.inner.obstacles[0].tris.len(), self.inner.b.tris.len())
    }

    /// Number of boundary candidates: the reduced convolution's flat facets.
    #[getter]
    fn facets(&self) -> usize {
        self.inner.facets.len()
    }

    /// Whether each of `points` (n, 3) lies in the closed sum, (n,) bool. Parallel.
    fn contains<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let pts = points_of(&points, "points")?;
        let src = self.inner.clone();
        let out: Vec<bool> = py.detach(move || pts.par_iter().map(|p| src.contains_point(*p)).collect());
        Ok(out.into_pyarray(py))
    }

    /// Whether the closed segment a → b misses the sum grown by the cube `margin`.
    #[pyo3(signature = (a, b, margin=0.0))]
    fn segment_is_free(&self, a: Vec<f64>, b: Vec<f64>, margin: f64) -> PyResult<bool> {
        self.whole("segment_is_free")?;
        Ok(self.inner.segment_is_free(vec3_any(&a, "a")?, vec3_any(&b, "b")?, margin.max(0.0)))
    }

    /// Signed distance bounds of `points` (n, 3), (n,): outside, a lower bound on the
    /// distance to the sum; inside, minus a lower bound on the depth. Parallel.
    fn signed_distance<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.whole("signed_distance")?;
        let pts = points_of(&points, "points")?;
        let src = self.inner.clone();
        let out: Vec<f64> = py.detach(move || pts.par_iter().map(|p| src.signed_distance(*p)).collect());
        Ok(out.into_pyarray(py))
    }

    /// The parameter intervals of the segment a → b inside the sum, sorted and merged.
    fn segment_intervals(&self, a: PyReadonlyArray1<'_, f64>, b: PyReadonlyArray1<'_, f64>) -> PyResult<Vec<(f64, f64)>> {
        self.whole("segment_intervals")?;
        Ok(self.inner.segment_intervals(vec3_of(&a, "a")?, vec3_of(&b, "b")?))
    }

    /// The distance from `point` (3,) to the sum's boundary as a proved interval: inside,
    /// the penetration depth to within `tolerance` (best first over cells, at most
    /// `max_cells`); outside, the separation distance (nearest facet, exact). A dict:
    /// `inside`, `lower`, `upper`, `point` (inside: proved outside, at distance `upper`;
    /// outside: the nearest point of the sum), `converged`, `cells`, `facets_tried`,
    /// `smallest_cells` (unresolved cells of the smallest size), `seconds`.
    #[pyo3(signature = (point, tolerance, max_cells=1_000_000))]
    fn depth<'py>(&self, py: Python<'py>, point: PyReadonlyArray1<'py, f64>, tolerance: f64, max_cells: usize) -> PyResult<Bound<'py, PyDict>> {
        let p = vec3_of(&point, "point")?;
        let src = self.inner.clone();
        let t0 = Instant::now();
        let r = interruptible(py, move || src.try_depth(p, tolerance, max_cells))??;
        let d = PyDict::new(py);
        d.set_item("inside", r.inside)?;
        d.set_item("lower", r.lower)?;
        d.set_item("upper", r.upper)?;
        d.set_item("point", r.point.to_array().to_vec().into_pyarray(py))?;
        d.set_item("converged", r.converged)?;
        d.set_item("cells", r.cells)?;
        d.set_item("facets_tried", r.facets_tried)?;
        d.set_item("smallest_cells", r.smallest_cells)?;
        d.set_item("seconds", t0.elapsed().as_secs_f64())?;
        Ok(d)
    }

    /// The closed surface of the sum at resolution `eps` (as `union_surface`).
    #[pyo3(signature = (eps, max_cells=8_000_000, max_refinements=2, simplify=true))]
    fn surface<'py>(&self, py: Python<'py>, eps: f64, max_cells: usize, max_refinements: u32, simplify: bool) -> PyResult<Bound<'py, PyDict>> {
        if self.pieces {
            return Err(InvalidParameterError::new_err("surface: a sum built with pieces=True answers point and segment queries only (its surface needs the reduced convolution)"));
        }
        self.whole("surface")?;
        let src = self.inner.clone();
        let params = UnionParams { eps, max_cells, max_refinements, simplify, planes: true };
        let r = interruptible(py, move || approximate_solid(src.as_ref(), &src.aabb, &params))??;
        surface_dict(py, &r)
    }
}

/// Number of worker threads the native core uses.
#[pyfunction]
fn num_threads() -> usize {
    rayon::current_num_threads()
}

/// Set the octree's candidate-record budget (bytes; the caller's memory limit's share, see
/// planner.limits) for every build and refinement that follows; returns the previous one.
#[pyfunction]
fn set_record_budget(bytes: usize) -> usize {
    let word = std::mem::size_of::<u32>();
    crate::octree::set_record_budget(bytes / word) * word
}

/// Stop the octree builds and refinements that follow `seconds` from now (None: never),
/// with planner.errors.TimeLimitError; see planner.deadline.
#[pyfunction]
#[pyo3(signature = (seconds=None))]
fn set_time_limit(seconds: Option<f64>) -> PyResult<()> {
    let after = match seconds {
        Some(s) if s.is_nan() => return Err(InvalidParameterError::new_err("seconds = NaN: must be a number")),
        Some(s) => Some(std::time::Duration::from_secs_f64(s.clamp(0.0, 1e9))),
        None => None,
    };
    crate::deadline::set_deadline(after);
    Ok(())
}

/// Bytes of the fixed-size records the budgets count: {"leaf", "record_word", "facet"}.
#[pyfunction]
fn budget_units(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("leaf", std::mem::size_of::<crate::octree::Leaf>())?;
    d.set_item("record_word", std::mem::size_of::<u32>())?;
    d.set_item("facet", crate::exact::FACET_BYTES)?;
    d.set_item("max_record_words", crate::octree::MAX_RECORD_WORDS)?;
    Ok(d)
}

#[pymodule]
fn _minkowski_core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // start the worker threads with the module, not inside the first call that asks for
    // them (about a millisecond: as much as validating a box takes)
    rayon::current_num_threads();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<Primitives>()?;
    m.add_function(wrap_pyfunction!(union_surface, m)?)?;
    m.add_function(wrap_pyfunction!(offset_surface, m)?)?;
    m.add_function(wrap_pyfunction!(rounded_polytope, m)?)?;
    m.add_function(wrap_pyfunction!(build_octree, m)?)?;
    m.add_function(wrap_pyfunction!(num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(set_record_budget, m)?)?;
    m.add_function(wrap_pyfunction!(set_time_limit, m)?)?;
    m.add_function(wrap_pyfunction!(budget_units, m)?)?;
    m.add_function(wrap_pyfunction!(front_windings, m)?)?;
    m.add_function(wrap_pyfunction!(solid_windings, m)?)?;
    m.add_function(wrap_pyfunction!(tidy_solid_windings, m)?)?;
    m.add_function(wrap_pyfunction!(crossing_windings, m)?)?;
    m.add_function(wrap_pyfunction!(winding_numbers, m)?)?;
    m.add_function(wrap_pyfunction!(closed_shell_sizes, m)?)?;
    m.add_class::<PyCSpace>()?;
    m.add_class::<ExactSum>()?;
    m.add_class::<CheckedMesh>()?;
    Ok(())
}

// ---------------------------------------------------------------------------------------
// The planner's C-space: octree roadmap, refinement, attachment, certificate.
// ---------------------------------------------------------------------------------------

fn vec3_any(p: &[f64], what: &str) -> PyResult<Vec3> {
    if p.len() != 3 || p.iter().any(|x| !x.is_finite()) {
        return Err(InvalidParameterError::new_err(format!("{what}: expected 3 finite coordinates, got {p:?}")));
    }
    Ok(Vec3::new(p[0], p[1], p[2]))
}

/// The translational C-space of a planning problem: the C-obstacle primitives `prims`
/// (or none), grown by `margin` (cube), walls filling everything outside `bounds`
/// ((2, 3)), and an octree built with cells of about `h_coarse` that refinement can split
/// down to `h_floor` (raised if the lattice would be too deep: see `floor`). Primitive
/// indices below `n_obstacle_prims` are those of `prims`; the six walls follow.
#[pyclass(name = "CSpace", module = "planner._minkowski_core")]
pub struct PyCSpace {
    inner: crate::roadmap::CSpace,
    max_leaves: usize,
    /// Per obstacle, whether its reduced convolution was taken from a given pair sum.
    reused: Vec<bool>,
}

impl PyCSpace {
    fn leaf_id(&self, i: usize) -> PyResult<usize> {
        if i < self.inner.oct.leaves.len() {
            Ok(i)
        } else {
            Err(InvalidParameterError::new_err(format!("leaf index {i} out of range ({} leaves)", self.inner.oct.leaves.len())))
        }
    }
}

/// Vertices (n, 3) and triangles (m, 3) of a mesh.
type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

/// Facet normals (k, 3) and offsets (k,) of a primitive.
type Planes<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>);

fn search_dict<'py>(py: Python<'py>, cs: &crate::roadmap::CSpace, r: &crate::roadmap::SearchResult) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("leaves", r.leaves.clone())?;
    d.set_item("cost", r.cost)?;
    d.set_item("expanded", r.expanded)?;
    d.set_item("min_leaf_size", r.leaves.iter().map(|&i| cs.leaf_size(i)).fold(f64::INFINITY, f64::min))?;
    Ok(d)
}

#[pymethods]
impl PyCSpace {
    #[new]
    #[pyo3(signature = (prims, bounds, h_floor, h_coarse, margin=0.0, max_leaves=20_000_000))]
    fn new(py: Python<'_>, prims: Option<&Primitives>, bounds: PyReadonlyArray2<'_, f64>, h_floor: f64, h_coarse: f64, margin: f64, max_leaves: usize) -> PyResult<Self> {
        let b = points_of(&bounds, "bounds")?;
        if b.len() != 2 {
            return Err(InvalidParameterError::new_err("bounds: expected [[min x, y, z], [max x, y, z]]"));
        }
        let region = Aabb::new(b[0], b[1]);
        let set = prims.map(|p| p.inner.clone());
        let inner = interruptible(py, move || {
            let polys: &[ConvexPolytope] = set.as_ref().map_or(&[], |s| &s.polys);
            crate::roadmap::CSpace::build(polys, region, h_floor, h_coarse, margin, max_leaves)
        })??;
        Ok(PyCSpace { inner, max_leaves, reused: Vec::new() })
    }

    /// The C-space of the exact source: C-obstacles `O_k ⊕ (−R)` of the meshes `obstacles`
    /// (list of (vertices (n, 3), faces (m, 3))) for the mesh `robot`, grown by `margin`,
    /// without decomposition. Meshes are solids (checked) unless `solid` (one flag per
    /// obstacle) or `robot_solid` says they are surfaces. Obstacle `k` is primitive `k`;
    /// the six walls follow. `reuse`: per obstacle, an `ExactSum` of it and the reflected
    /// robot built before (or None), whose reduced convolution is taken instead of computed
    /// when it is of the same meshes (`reused` says which were).
    #[staticmethod]
    #[pyo3(signature = (obstacles, robot, bounds, h_floor, h_coarse, margin=0.0, max_leaves=20_000_000, solid=None, robot_solid=true, max_facets=8_000_000, reuse=None))]
    #[allow(clippy::too_many_arguments)]
    fn exact(
        py: Python<'_>,
        obstacles: Vec<MeshArg<'_>>,
        robot: MeshArg<'_>,
        bounds: PyReadonlyArray2<'_, f64>,
        h_floor: f64,
        h_coarse: f64,
        margin: f64,
        max_leaves: usize,
        solid: Option<Vec<bool>>,
        robot_solid: bool,
        max_facets: usize,
        reuse: Option<Vec<Option<Bound<'_, ExactSum>>>>,
    ) -> PyResult<Self> {
        let b = points_of(&bounds, "bounds")?;
        if b.len() != 2 {
            return Err(InvalidParameterError::new_err("bounds: expected [[min x, y, z], [max x, y, z]]"));
        }
        let region = Aabb::new(b[0], b[1]);
        let solid = solid.unwrap_or_else(|| vec![true; obstacles.len()]);
        if solid.len() != obstacles.len() {
            return Err(InvalidParameterError::new_err(format!("solid: {} flags for {} obstacles", solid.len(), obstacles.len())));
        }
        let mut meshes = Vec::with_capacity(obstacles.len());
        for (k, o) in obstacles.iter().enumerate() {
            meshes.push(o.mesh(&format!("obstacle {k}"), solid[k])?);
        }
        let r = robot.mesh("robot", robot_solid)?;
        let given: Vec<Option<Arc<ExactSource>>> = reuse.unwrap_or_default().iter().map(|g| g.as_ref().map(|g| g.get().inner.clone())).collect();
        let (inner, reused) =
            interruptible(py, move || crate::roadmap::CSpace::build_exact_reusing(meshes, &r, region, h_floor, h_coarse, margin, max_leaves, max_facets, &given))??;
        Ok(PyCSpace { inner, max_leaves, reused })
    }

    /// Per obstacle, whether its reduced convolution was taken from a pair sum given to
    /// `exact` (`reuse`) instead of computed; empty for other C-spaces.
    #[getter]
    fn reused(&self) -> Vec<bool> {
        self.reused.clone()
    }

    /// Whether the C-obstacles come from the exact source (no decomposition).
    #[getter]
    fn is_exact(&self) -> bool {
        self.inner.obstacles.is_exact()
    }

    fn __len__(&self) -> usize {
        self.inner.oct.leaves.len()
    }

    /// Number of obstacle primitives (the six walls follow them).
    #[getter]
    fn n_obstacle_prims(&self) -> usize {
        self.inner.n_obstacle
    }

    /// Number of primitives, walls included.
    #[getter]
    fn n_primitives(&self) -> usize {
        self.inner.obstacles.len()
    }

    /// Finest cell size refinement can reach.
    #[getter]
    fn floor(&self) -> f64 {
        self.inner.floor()
    }

    /// Level of the coarse cells (size `floor * 2**coarse_level`).
    #[getter]
    fn coarse_level(&self) -> u8 {
        self.inner.coarse_level
    }

    /// Root level (the root cell is `floor * 2**depth` wide).
    #[getter]
    fn depth(&self) -> u8 {
        self.inner.oct.depth
    }

    /// Position of lattice point (0, 0, 0), (3,).
    #[getter]
    fn origin<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.oct.origin.to_array().to_vec().into_pyarray(py)
    }

    /// The growth of the obstacle primitives.
    #[getter]
    fn margin(&self) -> f64 {
        self.inner.margin
    }

    /// All leaves: dict with `ijk` (n, 3) lattice corners, `level` (n,) (size
    /// `floor * 2**level`) and `label` (n,) (0 EMPTY, 1 FULL, 2 MIXED).
    fn leaves<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let oct = &self.inner.oct;
        let d = PyDict::new(py);
        let n = oct.leaves.len();
        let ijk: Vec<u32> = oct.leaves.iter().flat_map(|l| l.ijk).collect();
        d.set_item("ijk", numpy::ndarray::Array2::from_shape_vec((n, 3), ijk).expect("n x 3").into_pyarray(py))?;
        d.set_item("level", oct.leaves.iter().map(|l| l.level).collect::<Vec<u8>>().into_pyarray(py))?;
        d.set_item("label", oct.leaves.iter().map(|l| l.label as u8).collect::<Vec<u8>>().into_pyarray(py))?;
        Ok(d)
    }

    /// `(label, level)` of leaf `i`.
    fn leaf(&self, i: usize) -> PyResult<(u8, u8)> {
        let l = self.inner.oct.leaves[self.leaf_id(i)?];
        Ok((l.label as u8, l.level))
    }

    /// Closed box of leaf `i`, (2, 3).
    fn cell_box<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let b = self.inner.oct.cell_box(&self.inner.oct.leaves[self.leaf_id(i)?]);
        Ok(to_array2([b.min.to_array(), b.max.to_array()].into_iter()).into_pyarray(py))
    }

    /// The leaf containing `point`, or None outside the root cell.
    fn locate(&self, point: Vec<f64>) -> PyResult<Option<usize>> {
        Ok(self.inner.locate(vec3_any(&point, "point")?))
    }

    /// Leaves sharing a face of positive area with leaf `i`: list of (leaf, portal), the
    /// portal being the centre of the shared face.
    fn neighbors(&self, i: usize) -> PyResult<Vec<(usize, [f64; 3])>> {
        Ok(self.inner.neighbors(self.leaf_id(i)?).into_iter().map(|m| (m.leaf, m.portal.to_array())).collect())
    }

    /// Face-adjacent pairs of leaves whose labels are both in `labels`: (pairs (m, 2)
    /// int64, portals (m, 3)), each pair once.
    fn adjacency<'py>(&self, py: Python<'py>, labels: Vec<u8>) -> (Bound<'py, PyArray2<i64>>, Bound<'py, PyArray2<f64>>) {
        let cs = &self.inner;
        let pairs = py.detach(|| crate::roadmap::face_adjacency(&cs.oct, &cs.index, |i| labels.contains(&(cs.oct.leaves[i].label as u8))));
        let flat: Vec<i64> = pairs.iter().flat_map(|p| [p.a as i64, p.b as i64]).collect();
        let a = Array2::from_shape_vec((pairs.len(), 2), flat).expect("m x 2").into_pyarray(py);
        (a, to_array2(pairs.iter().map(|p| p.portal.to_array())).into_pyarray(py))
    }

    /// Component of every leaf among the leaves whose label is in `labels` (face
    /// adjacency, union-find), (n,) int64, -1 for the others; numbered in leaf order.
    fn components<'py>(&self, py: Python<'py>, labels: Vec<u8>) -> Bound<'py, PyArray1<i64>> {
        let cs = &self.inner;
        let out = py.detach(|| {
            let member = |i: usize| labels.contains(&(cs.oct.leaves[i].label as u8));
            let pairs = crate::roadmap::face_adjacency(&cs.oct, &cs.index, member);
            crate::roadmap::components(cs.oct.leaves.len(), &pairs, member)
        });
        out.into_iter().map(|c| if c == u32::MAX { -1 } else { c as i64 }).collect::<Vec<_>>().into_pyarray(py)
    }

    /// Whether each of `points` (n, 3) lies in a primitive (walls included), (n,) bool.
    fn contains<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let pts = points_of(&points, "points")?;
        Ok(pts.iter().map(|p| self.inner.obstacles.contains_point(*p)).collect::<Vec<_>>().into_pyarray(py))
    }

    /// Signed distance of each of `points` (n, 3) to the primitives (walls included):
    /// exact outside, minus the largest depth in one primitive inside.
    fn signed_distance<'py>(&self, py: Python<'py>, points: PyReadonlyArray2<'py, f64>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let pts = points_of(&points, "points")?;
        Ok(pts.iter().map(|p| self.inner.obstacles.signed_distance(*p)).collect::<Vec<_>>().into_pyarray(py))
    }

    /// `(primitive, depth)` for every primitive containing `point`; depth is the distance
    /// to that primitive's nearest facet plane.
    fn containing(&self, point: Vec<f64>) -> PyResult<Vec<(usize, f64)>> {
        Ok(self.inner.containing(vec3_any(&point, "point")?))
    }

    /// Whether the closed segment a → b stays farther than `margin` from every primitive
    /// (exact clipping; for margin > 0 against facet planes pushed out by `margin`).
    #[pyo3(signature = (a, b, margin=0.0))]
    fn segment_is_free(&self, a: Vec<f64>, b: Vec<f64>, margin: f64) -> PyResult<bool> {
        Ok(self.inner.segment_is_free(vec3_any(&a, "a")?, vec3_any(&b, "b")?, margin))
    }

    /// How `point` joins the roadmap: list of (EMPTY leaf, entry point, cost), see the
    /// Rust `CSpace::attach`; empty when in a FULL leaf or nothing is reachable.
    #[pyo3(signature = (point, rings=2))]
    fn attach(&self, point: Vec<f64>, rings: usize) -> PyResult<Vec<(usize, [f64; 3], f64)>> {
        let p = vec3_any(&point, "point")?;
        Ok(self.inner.attach(p, rings).into_iter().map(|a| (a.leaf, a.via.to_array(), a.cost)).collect())
    }

    /// Shortest roadmap path through EMPTY leaves from `start` to `goal` (attached with
    /// `rings`): dict with `waypoints` (n, 3) (every segment exactly free), `leaves`,
    /// `cost`, `expanded`, `min_leaf_size`; None when not connected through EMPTY leaves.
    #[pyo3(signature = (start, goal, rings=2))]
    fn free_path<'py>(&self, py: Python<'py>, start: Vec<f64>, goal: Vec<f64>, rings: usize) -> PyResult<Option<Bound<'py, PyDict>>> {
        let (s, g) = (vec3_any(&start, "start")?, vec3_any(&goal, "goal")?);
        let cs = &self.inner;
        let found = py.detach(|| {
            let (sa, ga) = (cs.attach(s, rings), cs.attach(g, rings));
            if sa.is_empty() || ga.is_empty() {
                return None;
            }
            cs.free_path(s, g, &sa, &ga)
        });
        let Some((pts, r)) = found else { return Ok(None) };
        let d = search_dict(py, cs, &r)?;
        d.set_item("waypoints", to_array2(pts.iter().map(|p| p.to_array())).into_pyarray(py))?;
        Ok(Some(d))
    }

    /// Cheapest channel of non-FULL leaves from the leaf of `start` to that of `goal`
    /// (MIXED leaves cost `1 + penalty` per length; with `refinable_only`, MIXED leaves
    /// at the floor are avoided): dict with `leaves`, `cost`, `expanded`,
    /// `min_leaf_size`, or None.
    #[pyo3(signature = (start, goal, penalty=2.0, refinable_only=true))]
    fn channel<'py>(&self, py: Python<'py>, start: Vec<f64>, goal: Vec<f64>, penalty: f64, refinable_only: bool) -> PyResult<Option<Bound<'py, PyDict>>> {
        let (s, g) = (vec3_any(&start, "start")?, vec3_any(&goal, "goal")?);
        let cs = &self.inner;
        match py.detach(|| cs.channel(s, g, penalty, refinable_only)) {
            Some(r) => Ok(Some(search_dict(py, cs, &r)?)),
            None => Ok(None),
        }
    }

    /// Split the MIXED leaves above the floor among `leaves` (with `ring`, also their MIXED
    /// neighbours) `levels` times. Returns dict `refined`, `created`, `by_label` (3 counts).
    /// Raises ResourceLimitError beyond the leaf budget, TimeLimitError when the time limit
    /// (set_time_limit) passed (nothing changed then).
    #[pyo3(signature = (leaves, ring=true, levels=1))]
    fn refine<'py>(&mut self, py: Python<'py>, leaves: Vec<usize>, ring: bool, levels: u8) -> PyResult<Bound<'py, PyDict>> {
        let max = self.max_leaves;
        let cs = &mut self.inner;
        let st = interruptible(py, move || cs.refine(&leaves, ring, levels, max))??;
        let d = PyDict::new(py);
        d.set_item("refined", st.refined)?;
        d.set_item("created", st.created)?;
        d.set_item("by_label", st.by_label.to_vec())?;
        Ok(d)
    }

    /// Leaves per level (list index) and label ([EMPTY, FULL, MIXED]).
    fn level_counts(&self) -> Vec<[usize; 3]> {
        self.inner.level_counts()
    }

    /// (EMPTY leaves, pairs of face-adjacent EMPTY leaves): the roadmap's size.
    fn roadmap_size(&self, py: Python<'_>) -> (usize, usize) {
        let cs = &self.inner;
        py.detach(|| cs.roadmap_size())
    }

    /// Shorten `waypoints` (n, 3) greedily with segment tests at `margin` (see the Rust
    /// `CSpace::shortcut`); (m, 3), same ends.
    #[pyo3(signature = (waypoints, margin=0.0, passes=3))]
    fn shortcut<'py>(&self, py: Python<'py>, waypoints: PyReadonlyArray2<'py, f64>, margin: f64, passes: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let pts = points_of(&waypoints, "waypoints")?;
        let cs = &self.inner;
        let out = py.detach(|| cs.shortcut(&pts, margin, passes));
        Ok(to_array2(out.iter().map(|p| p.to_array())).into_pyarray(py))
    }

    /// When the leaves of `start` and `goal` lie in different components of the EMPTY ∪
    /// MIXED leaves, the certificate as a dict: `walls_around_start` (which component is
    /// walled off), `start_component_size`, `goal_component_size`, `n_components`,
    /// `component_leaves` (the walled component's leaves), `wall_leaves` (n,) int64 (FULL
    /// leaves face-adjacent to it), `verified` (every wall leaf re-verified by an exact test
    /// that does not trust the labels), `wall_prims` (n,) int64 (a primitive containing each,
    /// -1 if none was found), `wall_boxes` (n, 2, 3). None when they are connected.
    fn certificate<'py>(&self, py: Python<'py>, start: Vec<f64>, goal: Vec<f64>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let (s, g) = (vec3_any(&start, "start")?, vec3_any(&goal, "goal")?);
        let cs = &self.inner;
        let Some(c) = py.detach(|| cs.certificate(s, g)) else { return Ok(None) };
        let comp: Vec<usize> = if c.walls_around_start {
            c.start_component.clone()
        } else {
            let lg = cs.locate(g).map(|i| c.labels[i]).unwrap_or(u32::MAX);
            (0..c.labels.len()).filter(|&i| lg != u32::MAX && c.labels[i] == lg).collect()
        };
        certificate_dict(py, cs, &c, comp).map(Some)
    }

    /// The component of the EMPTY ∪ MIXED leaves holding `start` and the FULL leaves around
    /// it, as a dict like :meth:`certificate`'s (`walls_around_start` True,
    /// `goal_component_size` 0): with `verified` and every `wall_prims` entry below
    /// `n_obstacle_prims` (none a wall outside the bounds), no path leaves the component.
    /// None when `start` is outside the root or in a FULL leaf.
    fn enclosure<'py>(&self, py: Python<'py>, start: Vec<f64>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let s = vec3_any(&start, "start")?;
        let cs = &self.inner;
        let Some(c) = py.detach(|| cs.enclosure(s)) else { return Ok(None) };
        let comp = c.start_component.clone();
        certificate_dict(py, cs, &c, comp).map(Some)
    }

    /// Facet planes of primitive `i` (walls included): (normals (k, 3), offsets (k,));
    /// inside is `normals @ x <= offsets`.
    fn primitive_planes<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Planes<'py>> {
        let crate::roadmap::Obstacles::Union(set) = &self.inner.obstacles else {
            return Err(InvalidParameterError::new_err("the exact source has no convex primitives"));
        };
        let p = set.polys.get(i).ok_or_else(|| InvalidParameterError::new_err(format!("primitive index {i} out of range")))?;
        Ok((to_array2(p.normals.iter().map(|n| n.to_array())).into_pyarray(py), p.offsets.clone().into_pyarray(py)))
    }
}

/// A [`crate::roadmap::Certificate`] as the dict `CSpace.certificate` and `CSpace.enclosure`
/// return; `comp`: the walled component's leaves.
fn certificate_dict<'py>(py: Python<'py>, cs: &crate::roadmap::CSpace, c: &crate::roadmap::Certificate, comp: Vec<usize>) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("walls_around_start", c.walls_around_start)?;
    d.set_item("verified", c.verified)?;
    d.set_item("start_component_size", c.start_component.len())?;
    d.set_item("goal_component_size", c.goal_component_size)?;
    d.set_item("n_components", c.n_components)?;
    d.set_item("component_leaves", comp)?;
    d.set_item("wall_leaves", c.walls.iter().map(|w| w.0 as i64).collect::<Vec<_>>().into_pyarray(py))?;
    d.set_item("wall_prims", c.walls.iter().map(|w| if w.1 == usize::MAX { -1 } else { w.1 as i64 }).collect::<Vec<_>>().into_pyarray(py))?;
    let flat: Vec<f64> = c
        .walls
        .iter()
        .flat_map(|w| {
            let b = cs.oct.cell_box(&cs.oct.leaves[w.0]);
            [b.min.to_array(), b.max.to_array()].into_iter().flatten()
        })
        .collect();
    d.set_item("wall_boxes", numpy::ndarray::Array3::from_shape_vec((c.walls.len(), 2, 3), flat).expect("n x 2 x 3").into_pyarray(py))?;
    let witnesses = PyList::empty(py);
    let mut shells: Vec<ShellKey> = Vec::new();
    for w in &c.witnesses {
        match w {
            None => witnesses.append(py.None())?,
            Some(w) => witnesses.append(wall_witness_list(py, w, &mut shells)?)?,
        }
    }
    d.set_item("wall_witnesses", witnesses)?;
    d.set_item("shells", shell_list(py, cs, &shells)?)?;
    Ok(d)
}

/// A closed shell a witness names: (whether it is the robot's, its obstacle (0 for the
/// robot's), index among the mesh's shells).
type ShellKey = (bool, usize, usize);

/// The shells the witnesses name, in the order they were first named, each a dict: `of`
/// ("robot" or "obstacle"), `obstacle` (its index, for an obstacle's), `triangles`
/// (n, 3, 3) in the robot's frame or the obstacle's.
fn shell_list<'py>(py: Python<'py>, cs: &crate::roadmap::CSpace, keys: &[ShellKey]) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    let crate::roadmap::Obstacles::Exact(src) = &cs.obstacles else { return Ok(out) };
    for &(of_robot, k, si) in keys {
        let shell = &src.shells_of((!of_robot).then_some(k)).shells[si];
        let sign = if of_robot { -1.0 } else { 1.0 };
        let flat: Vec<f64> = shell.mesh.tris.iter().flat_map(|t| reflected(&t.p, sign).into_iter().flatten()).collect();
        let d = PyDict::new(py);
        d.set_item("of", if of_robot { "robot" } else { "obstacle" })?;
        d.set_item("obstacle", k)?;
        d.set_item("triangles", numpy::ndarray::Array3::from_shape_vec((shell.mesh.tris.len(), 3, 3), flat).expect("n x 3 x 3").into_pyarray(py))?;
        out.append(d)?;
    }
    Ok(out)
}

/// A triangle's corners times `sign`, reordered when reflected (the robot's own triangle
/// from `B = −R`'s).
fn reflected(p: &[Vec3; 3], sign: f64) -> [[f64; 3]; 3] {
    let order = if sign < 0.0 { [p[0], p[2], p[1]] } else { *p };
    order.map(|v| (v * sign).to_array())
}

/// A wall leaf's witness as a list of dicts, one per part of its box, in the robot's
/// terms (the C-space's `B` is the robot reflected): `kind` "triangles" (at every
/// translation `t` of `box`, `robot_triangle + t` meets `obstacle_triangle`),
/// "robot_vertex" (`vertex + t` lies in the solid obstacle), "obstacle_vertex" (`vertex`
/// lies in the solid robot placed at `t`), "robot_shell" (`point`, on the obstacle's
/// `point_triangle`, lies in the odd region of the robot's closed shell `shell` placed at
/// `t`, and the obstacle's `far_vertex`, connected to it, outside that shell's box),
/// "obstacle_shell" (the robot's `point + t` in the odd region of the obstacle's shell,
/// its `far_vertex + t` outside), "bounds" (`side`: beyond the bounds) or "primitive" (a
/// convex primitive of the decomposition holds the box). `shells` collects the shells
/// named (`shell` indexes it).
fn wall_witness_list<'py>(py: Python<'py>, w: &crate::roadmap::WallWitness, shells: &mut Vec<ShellKey>) -> PyResult<Bound<'py, PyList>> {
    use crate::exact::BoxWitness;
    let out = PyList::empty(py);
    let parts = match w {
        crate::roadmap::WallWitness::Primitive(k) => {
            let d = PyDict::new(py);
            d.set_item("kind", "primitive")?;
            d.set_item("primitive", *k)?;
            out.append(d)?;
            return Ok(out);
        }
        crate::roadmap::WallWitness::Exact(parts) => parts,
    };
    for (bx, why) in parts {
        let d = PyDict::new(py);
        d.set_item("box", vec![bx.min.to_array(), bx.max.to_array()])?;
        match why {
            BoxWitness::Piece { k, a, b, .. } => {
                d.set_item("kind", "triangles")?;
                d.set_item("obstacle", *k)?;
                d.set_item("obstacle_triangle", vec![a[0].to_array(), a[1].to_array(), a[2].to_array()])?;
                d.set_item("robot_triangle", reflected(b, -1.0))?;
            }
            BoxWitness::VertexOfB { k, v } => {
                d.set_item("kind", "robot_vertex")?;
                d.set_item("obstacle", *k)?;
                d.set_item("vertex", (-*v).to_array())?;
            }
            BoxWitness::VertexOfA { k, v } => {
                d.set_item("kind", "obstacle_vertex")?;
                d.set_item("obstacle", *k)?;
                d.set_item("vertex", v.to_array())?;
            }
            BoxWitness::Wall { side } => {
                d.set_item("kind", "bounds")?;
                d.set_item("side", *side)?;
            }
            BoxWitness::Pierced { k, shell_of_b, shell, x, tri, y } => {
                // a robot shell is one whichever obstacle crosses it
                let key = (*shell_of_b, if *shell_of_b { 0 } else { *k }, *shell);
                let index = shells.iter().position(|s| *s == key).unwrap_or_else(|| {
                    shells.push(key);
                    shells.len() - 1
                });
                // the shell's owner: B (the reflected robot) holds the obstacle's point
                let sign = if *shell_of_b { 1.0 } else { -1.0 };
                d.set_item("kind", if *shell_of_b { "robot_shell" } else { "obstacle_shell" })?;
                d.set_item("obstacle", *k)?;
                d.set_item("shell", index)?;
                d.set_item("point", (*x * sign).to_array())?;
                d.set_item("point_triangle", reflected(tri, sign))?;
                d.set_item("far_vertex", (*y * sign).to_array())?;
            }
        }
        out.append(d)?;
    }
    Ok(out)
}
