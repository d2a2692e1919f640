//! Errors of the native core. Each variant says what went wrong and how to fix it.

use thiserror::Error;

/// Everything the core can refuse or fail at. Geometry problems are data, not panics.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CoreError {
    /// Input coordinates or parameters contain NaN or infinity. Fix: clean the input.
    #[error("{what}: non-finite value (NaN or inf) in the input")]
    NonFinite {
        /// Which input.
        what: String,
    },
    /// A convex piece has fewer than 4 points or all its points lie in a plane, so it
    /// bounds no volume. Fix: drop the piece or repair the mesh it came from.
    #[error("{what}: degenerate convex piece ({detail}); a piece must span a volume")]
    Degenerate {
        /// Which input.
        what: String,
        /// Why.
        detail: String,
    },
    /// A parameter is out of range (e.g. eps <= 0). Fix: pass a positive, finite value.
    #[error("{name} = {value}: {detail}")]
    InvalidParameter {
        /// Parameter name.
        name: String,
        /// Offending value.
        value: f64,
        /// What is allowed.
        detail: String,
    },
    /// The grid would need more cells than the budget allows. Fix: a larger eps, or raise
    /// the memory limit the cell budget comes from, if the memory is there.
    #[error("the octree needs more than {budget} cells at cell size {cell_size:.3e} ({detail}); use a larger eps or raise the memory limit")]
    ResourceLimit {
        /// The cell budget that was exceeded.
        budget: usize,
        /// Finest cell size asked for.
        cell_size: f64,
        /// Context.
        detail: String,
    },
    /// The octree's candidate records (what each boundary cell keeps of the parts) would
    /// need more memory than allowed. Fix: a larger cell size, a larger memory limit, or the
    /// decomposition source.
    #[error("the octree's boundary cells would keep more than {gib:.2} GiB of candidate records at cell size {cell_size:.3e} ({detail}); raise the memory limit, use a larger cell size or the decomposition source (exact: false)")]
    RecordLimit {
        /// The memory budget of the records, in GiB.
        gib: f64,
        /// Finest cell size asked for.
        cell_size: f64,
        /// Context.
        detail: String,
    },
    /// A triangle mesh cannot be used as a solid (open, inconsistently oriented, bad
    /// indices). Fix: repair the mesh (close holes, orient the triangles outward).
    #[error("{what}: {detail}")]
    InvalidGeometry {
        /// Which input.
        what: String,
        /// Why.
        detail: String,
    },
    /// The exact source would hold more boundary candidates (reduced-convolution facets)
    /// than its budget allows, so more memory than allowed. Fix: the decomposition
    /// source, simpler meshes, or a larger memory limit if the memory is there.
    #[error("{what}: the boundary convolution needs more than {} (more than {budget} facets of about {bytes_per_facet} bytes; {found} found before stopping); raise the memory limit, or use the decomposition source (exact: false) or simpler meshes", memory_text((*.budget as f64) * (*.bytes_per_facet as f64)))]
    FacetLimit {
        /// Which pair.
        what: String,
        /// Facets found when it stopped.
        found: usize,
        /// The budget.
        budget: usize,
        /// Memory per facet.
        bytes_per_facet: usize,
    },
    /// The time limit ([`crate::deadline`]) passed during a long step; nothing it would
    /// have changed was changed. Fix: a longer time limit, or larger cells.
    #[error("time limit reached during the {during}")]
    TimeLimit {
        /// The step it stopped.
        during: String,
    },
    /// There are no primitives to work on. Fix: give at least one convex piece per operand.
    #[error("{what}: no convex pieces given")]
    Empty {
        /// Which input.
        what: String,
    },
}

/// Result alias of the core.
pub type CoreResult<T> = Result<T, CoreError>;

/// `bytes` as a reader takes them in: GiB to two decimals from 0.1 GiB, MiB below (so a
/// small limit does not read "0.00 GiB").
fn memory_text(bytes: f64) -> String {
    const GIB: f64 = 1_073_741_824.0;
    if bytes >= 0.1 * GIB {
        format!("{:.2} GiB", bytes / GIB)
    } else {
        format!("{:.2} MiB", bytes / 1_048_576.0)
    }
}
