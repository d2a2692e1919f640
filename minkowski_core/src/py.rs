//! The Python binding: converts numpy arrays, releases the GIL for native work, and maps
//! [`CoreError`] to the exception classes of `planner.errors` in one place.

use crate::error::CoreError;
use crate::math::{Aabb, Vec3};
use crate::minkowski::{pairwise_sums, PolytopeSet, SumKind};
use crate::octree::Octree;
use crate::polytope::ConvexPolytope;
use crate::union::{approximate_union, UnionParams};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

pyo3::import_exception!(planner.errors, InvalidMeshError);
pyo3::import_exception!(planner.errors, InvalidParameterError);
pyo3::import_exception!(planner.errors, ResourceLimitError);
pyo3::import_exception!(planner.errors, GeometryError);

impl From<CoreError> for PyErr {
    fn from(e: CoreError) -> PyErr {
        let msg = e.to_string();
        match e {
            CoreError::NonFinite { .. } | CoreError::Degenerate { .. } | CoreError::Empty { .. } => InvalidMeshError::new_err(msg),
            CoreError::InvalidParameter { .. } => InvalidParameterError::new_err(msg),
            CoreError::ResourceLimit { .. } => ResourceLimitError::new_err(msg),
        }
    }
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
        let polys = py.detach(move || {
            pts.par_iter()
                .enumerate()
                .map(|(i, p)| ConvexPolytope::try_from_points(p, &format!("piece {i}")))
                .collect::<Result<Vec<_>, _>>()
        })?;
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
    fn polytope<'py>(&self, py: Python<'py>, i: usize) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>)> {
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
    let params = UnionParams { eps, max_cells, max_refinements, simplify };
    let r = py.detach(move || approximate_union(&set, &params))?;
    let d = PyDict::new(py);
    let s = &r.surface;
    d.set_item("vertices", to_array2(s.vertices.iter().map(|v| v.to_array())).into_pyarray(py))?;
    let flat: Vec<i64> = s.faces.iter().flat_map(|f| f.iter().map(|&x| x as i64)).collect();
    d.set_item("faces", Array2::from_shape_vec((s.faces.len(), 3), flat).expect("m x 3").into_pyarray(py))?;
    d.set_item("h", r.h)?;
    d.set_item("error_bound", r.error_bound)?;
    d.set_item("refinements", r.refinements)?;
    d.set_item("band_cells", s.band_cells)?;
    d.set_item("lattice_points", s.lattice_points)?;
    d.set_item("edges", s.edges)?;
    d.set_item("complex_edges", s.complex_edges)?;
    d.set_item("complex_cells", s.complex_cells)?;
    d.set_item("unresolved_cells", s.unresolved_cells)?;
    d.set_item("inconsistent_edges", s.inconsistent_edges)?;
    d.set_item("cells_per_level", r.level_counts.iter().map(|c| c.to_vec()).collect::<Vec<_>>())?;
    d.set_item("seconds_octree", r.seconds_octree)?;
    d.set_item("seconds_surface", r.seconds_surface)?;
    d.set_item("seconds_simplify", r.seconds_simplify)?;
    d.set_item("triangles_extracted", r.triangles_extracted)?;
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
    let oct = py.detach(move || Octree::build(set.as_ref(), &region, h, max_cells))?;
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

/// Number of worker threads the native core uses.
#[pyfunction]
fn num_threads() -> usize {
    rayon::current_num_threads()
}

#[pymodule]
fn _minkowski_core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<Primitives>()?;
    m.add_function(wrap_pyfunction!(union_surface, m)?)?;
    m.add_function(wrap_pyfunction!(build_octree, m)?)?;
    m.add_function(wrap_pyfunction!(num_threads, m)?)?;
    Ok(())
}
