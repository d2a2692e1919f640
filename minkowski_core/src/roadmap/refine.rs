//! Local refinement of an octree: [`rescale`] puts it on a finer lattice (same cells,
//! leaves at higher levels), [`refine`] splits chosen MIXED leaves in place.
//!
//! A split cell classifies its children against its own candidate records (primitive and
//! the facet planes that cut it): a plane that separates a child drops the primitive, a
//! plane that no longer cuts it is dropped, a primitive with no plane left contains the
//! child (FULL). Children of an EMPTY or FULL verdict are exact, as in the octree build.

use super::index::LeafIndex;
use crate::error::{CoreError, CoreResult};
use crate::math::{Aabb, Vec3};
use crate::octree::{lattice_cell, record_budget, record_limit, CellSource, Label, Leaf, Octree, MAX_DEPTH};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// What a [`refine`] call did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RefineStats {
    /// Leaves split.
    pub refined: usize,
    /// Leaves created (replacing the split ones).
    pub created: usize,
    /// Created leaves per label (`Label as usize`).
    pub by_label: [usize; 3],
}

/// The same octree on a lattice `2^k` times finer: identical cells, `h / 2^k`, leaves at
/// level `+ k`, so that [`refine`] can split its finest leaves `k` more times.
///
/// # Errors
/// [`CoreError::ResourceLimit`] when the root would exceed `2^MAX_DEPTH` finest cells.
pub fn rescale(mut oct: Octree, k: u8) -> CoreResult<Octree> {
    if oct.depth as u32 + k as u32 > MAX_DEPTH {
        return Err(CoreError::ResourceLimit {
            budget: 0,
            cell_size: oct.h / (1u64 << k) as f64,
            detail: format!("the lattice addresses at most 2^{MAX_DEPTH} cells per side; {} levels asked", oct.depth as u32 + k as u32),
        });
    }
    oct.h /= (1u64 << k) as f64;
    oct.depth += k;
    for l in &mut oct.leaves {
        l.level += k;
        for c in &mut l.ijk {
            *c <<= k;
        }
    }
    Ok(oct)
}

struct Classifier<'a> {
    src: &'a dyn CellSource,
    origin: Vec3,
    h: f64,
}

impl Classifier<'_> {
    fn cell(&self, ijk: [u32; 3], level: u8) -> Aabb {
        lattice_cell(self.origin, self.h, ijk, level)
    }

    /// Filter the candidate records `cand` against `cell` into `out`; the cell's label.
    fn classify(&self, cell: &Aabb, cand: &[u32], finest: bool, out: &mut Vec<u32>) -> Label {
        out.clear();
        self.src.classify(cell, cand, finest, out)
    }

    /// Split `(level, ijk)` into its children, recursing into MIXED children down to `stop`.
    fn split(&self, ijk: [u32; 3], level: u8, cand: &[u32], stop: u8, out: &mut Vec<(Leaf, Vec<u32>)>) {
        let half = 1u32 << (level - 1);
        let mut own = Vec::with_capacity(cand.len());
        for c in 0..8u32 {
            let child = [ijk[0] + (c & 1) * half, ijk[1] + ((c >> 1) & 1) * half, ijk[2] + ((c >> 2) & 1) * half];
            let label = self.classify(&self.cell(child, level - 1), cand, level == 1, &mut own);
            if label == Label::Mixed && level - 1 > stop {
                self.split(child, level - 1, &own, stop, out);
            } else {
                let list = if label == Label::Mixed { own.clone() } else { Vec::new() };
                out.push((Leaf { ijk: child, level: level - 1, label, cand_start: 0, cand_len: 0, corner_sign: None }, list));
            }
        }
    }
}

/// Split each MIXED leaf of `targets` (ids into `oct.leaves`; others, duplicates and leaves
/// at level 0 are skipped) `levels` times (MIXED children only, never below level 0).
/// The first child takes the split leaf's id, the others are appended, so ids of untouched
/// leaves stay valid; `index` is updated. Parallel over targets; deterministic.
///
/// # Errors
/// [`CoreError::ResourceLimit`] when the octree would exceed `max_leaves` leaves,
/// [`CoreError::RecordLimit`] when its candidate records would pass [`record_budget`],
/// [`CoreError::TimeLimit`] when the time limit ([`crate::deadline`]) passed before every
/// target was split (nothing is changed then).
pub fn refine<S: CellSource>(source: &S, oct: &mut Octree, index: &mut LeafIndex, targets: &[usize], levels: u8, max_leaves: usize) -> CoreResult<RefineStats> {
    refine_within(source, oct, index, targets, levels, max_leaves, record_budget())
}

/// [`refine`] with at most `max_words` candidate-record words in the octree.
pub(crate) fn refine_within<S: CellSource>(
    source: &S,
    oct: &mut Octree,
    index: &mut LeafIndex,
    targets: &[usize],
    levels: u8,
    max_leaves: usize,
    max_words: usize,
) -> CoreResult<RefineStats> {
    let mut todo: Vec<usize> = targets.iter().copied().filter(|&t| t < oct.leaves.len() && oct.leaves[t].label == Label::Mixed && oct.leaves[t].level > 0).collect();
    todo.sort_unstable();
    todo.dedup();
    let cls = Classifier { src: source, origin: oct.origin, h: oct.h };
    let levels = levels.max(1);
    let timed_out = AtomicBool::new(false);
    let parts: Vec<Vec<(Leaf, Vec<u32>)>> = {
        let oct_ref: &Octree = oct;
        todo.par_iter()
            .map(|&t| {
                if timed_out.load(Ordering::Relaxed) || crate::deadline::passed() {
                    timed_out.store(true, Ordering::Relaxed);
                    return Vec::new();
                }
                let leaf = oct_ref.leaves[t];
                let s = leaf.cand_start as usize;
                let cand = &oct_ref.cands[s..s + leaf.cand_len as usize];
                let mut out = Vec::new();
                cls.split(leaf.ijk, leaf.level, cand, leaf.level.saturating_sub(levels), &mut out);
                out
            })
            .collect()
    };
    if timed_out.load(Ordering::Relaxed) {
        return Err(CoreError::TimeLimit { during: "roadmap refinement".into() });
    }
    let created: usize = parts.iter().map(|p| p.len()).sum();
    if oct.leaves.len() - todo.len() + created > max_leaves {
        return Err(CoreError::ResourceLimit { budget: max_leaves, cell_size: oct.h, detail: "roadmap leaves during refinement".into() });
    }
    let new_words: usize = parts.iter().flatten().map(|(_, list)| list.len()).sum();
    if oct.cands.len() + new_words > max_words {
        return Err(record_limit(max_words, oct.h, "roadmap refinement"));
    }
    let mut stats = RefineStats { refined: todo.len(), created, by_label: [0; 3] };
    for (&t, children) in todo.iter().zip(parts) {
        let old = oct.leaves[t];
        index.remove(old.level, old.ijk);
        for (j, (mut leaf, list)) in children.into_iter().enumerate() {
            stats.by_label[leaf.label as usize] += 1;
            leaf.cand_start = oct.cands.len() as u32;
            leaf.cand_len = list.len() as u32;
            oct.cands.extend_from_slice(&list);
            let id = if j == 0 {
                oct.leaves[t] = leaf;
                t
            } else {
                oct.leaves.push(leaf);
                oct.leaves.len() - 1
            };
            index.insert(leaf.level, leaf.ijk, id);
        }
    }
    Ok(stats)
}
