//! Coarse-to-fine sampling of a grid: which samples of the fine grid the field must be evaluated
//! at for marching cubes to find the surface.
//!
//! The fine grid is cut into blocks of `block` × `block` × `block` cells (the last block along an
//! axis may be shorter). The field is first evaluated at the blocks' corners only (the coarse
//! grid: every `block`-th sample along each axis, and the last one). A block is *refined* when
//! its 8 corners do not all lie confidently on one side of the level — some corner reads at
//! least `level − margin` and some at most `level + margin` — or when one of its 26 neighbours
//! is. Every fine sample of a refined block is evaluated; the other samples take the trilinear
//! interpolation of their block's corners, which stays on the corners' side, so cells of
//! unrefined blocks hold no surface.
//!
//! The mesh then equals the dense extraction's exactly (same triangles, same order), unless the
//! surface enters a block none of whose own or neighbouring corners read within `margin` of the
//! level — a feature thinner than the coarse spacing whose field never comes near the level at a
//! coarse sample. [`CoarseToFine`] holds the coarse values and the refined blocks.

use nalgebra::Point3;

use super::sample_grid::SampleGrid;
use crate::error::Result;

/// Hands `push_layer` every z-layer of `grid` in order (x fastest), calling `evaluate` (points in
/// the grid's frame) only at the coarse samples and in the refined blocks (see the module doc).
pub fn sample_coarse_to_fine(
    grid: &SampleGrid,
    block: usize,
    level: f32,
    margin: f32,
    mut evaluate: impl FnMut(&[Point3<f32>]) -> Result<Vec<f32>>,
    mut push_layer: impl FnMut(&[f32]) -> Result<()>,
) -> Result<()> {
    let coarse = CoarseToFine::coarse_grid(grid, block);
    let mut points = Vec::with_capacity(coarse.layer_len());
    let mut values = Vec::with_capacity(coarse.layer_len() * coarse.axes[2].len());
    for &k in &coarse.axes[2] {
        points.clear();
        for &j in &coarse.axes[1] {
            for &i in &coarse.axes[0] {
                points.push(grid.position(i as f64, j as f64, k as f64));
            }
        }
        values.extend(evaluate(&points)?);
    }
    let plan = CoarseToFine::new(coarse, values, level, margin);
    let mut layer = vec![0.0f32; grid.layer_len()];
    let mut wanted = Vec::new();
    for k in 0..grid.dims[2] {
        points.clear();
        wanted.clear();
        for j in 0..grid.dims[1] {
            for i in 0..grid.dims[0] {
                let at = i + grid.dims[0] * j;
                if plan.must_evaluate(i, j, k) {
                    points.push(grid.position(i as f64, j as f64, k as f64));
                    wanted.push(at);
                } else {
                    layer[at] = plan.interpolated(i, j, k);
                }
            }
        }
        if !points.is_empty() {
            for (at, v) in wanted.iter().zip(evaluate(&points)?) {
                layer[*at] = v;
            }
        }
        push_layer(&layer)?;
    }
    Ok(())
}

/// Samples of one axis on the coarse grid: `0, block, 2·block, …` and the last sample.
fn coarse_indices(samples: usize, block: usize) -> Vec<usize> {
    let mut indices: Vec<usize> = (0..samples).step_by(block.max(1)).collect();
    if indices.last() != Some(&(samples - 1)) {
        indices.push(samples - 1);
    }
    indices
}

/// Per fine sample of one axis: the blocks it belongs to (`first..=last`; two on a block border,
/// one inside) and where it sits in the first (0 at its start, 1 at its end).
#[derive(Debug, Clone, Copy, PartialEq)]
struct AxisPlace {
    first: usize,
    last: usize,
    along: f32,
}

fn axis_places(coarse: &[usize]) -> Vec<AxisPlace> {
    let samples = coarse.last().map_or(0, |&n| n + 1);
    let blocks = coarse.len().saturating_sub(1).max(1);
    (0..samples)
        .map(|i| {
            // The block whose span [coarse[b], coarse[b + 1]] holds i, the lower one on a border.
            let b = coarse.partition_point(|&c| c <= i).saturating_sub(1).min(blocks - 1);
            let (start, end) = (coarse[b], coarse.get(b + 1).copied().unwrap_or(coarse[b]));
            let along = if end > start {
                (i - start) as f32 / (end - start) as f32
            } else {
                0.0
            };
            let first = if i == start && b > 0 { b - 1 } else { b };
            let last = b;
            AxisPlace { first, last, along }
        })
        .collect()
}

/// The coarse samples of a grid and which of its blocks are refined.
#[derive(Debug, Clone)]
pub struct CoarseToFine {
    /// The coarse grid's samples along x, y, z (indices into the fine grid).
    coarse: [Vec<usize>; 3],
    /// Field values at the coarse samples, x fastest.
    values: Vec<f32>,
    /// Blocks along x, y, z.
    blocks: [usize; 3],
    /// Refined flag per block, x fastest.
    refined: Vec<bool>,
    places: [Vec<AxisPlace>; 3],
}

impl CoarseToFine {
    /// The coarse grid of `grid` with blocks of `block` cells (≥ 1; 1 evaluates every sample).
    pub fn coarse_grid(grid: &SampleGrid, block: usize) -> SampleGridIndices {
        SampleGridIndices {
            axes: [0, 1, 2].map(|k| coarse_indices(grid.dims[k], block)),
        }
    }

    /// From the field's `values` at the coarse samples of `coarse` (x fastest), the blocks to
    /// refine for the surface `level` (see the module doc).
    pub fn new(coarse: SampleGridIndices, values: Vec<f32>, level: f32, margin: f32) -> Self {
        let axes = coarse.axes;
        let blocks = [0, 1, 2].map(|k| axes[k].len().saturating_sub(1).max(1));
        let n = [axes[0].len(), axes[1].len(), axes[2].len()];
        let value =
            |i: usize, j: usize, k: usize| values[i.min(n[0] - 1) + n[0] * (j.min(n[1] - 1) + n[1] * k.min(n[2] - 1))];
        let mut crossed = vec![false; blocks.iter().product()];
        for bz in 0..blocks[2] {
            for by in 0..blocks[1] {
                for bx in 0..blocks[0] {
                    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                    for c in 0..8 {
                        let v = value(bx + (c & 1), by + ((c >> 1) & 1), bz + (c >> 2));
                        // NaN counts as outside, as in marching cubes.
                        let v = if v.is_nan() { f32::NEG_INFINITY } else { v };
                        lo = lo.min(v);
                        hi = hi.max(v);
                    }
                    crossed[bx + blocks[0] * (by + blocks[1] * bz)] = hi >= level - margin && lo <= level + margin;
                }
            }
        }
        let mut refined = vec![false; crossed.len()];
        for bz in 0..blocks[2] {
            for by in 0..blocks[1] {
                for bx in 0..blocks[0] {
                    if !crossed[bx + blocks[0] * (by + blocks[1] * bz)] {
                        continue;
                    }
                    for z in bz.saturating_sub(1)..=(bz + 1).min(blocks[2] - 1) {
                        for y in by.saturating_sub(1)..=(by + 1).min(blocks[1] - 1) {
                            for x in bx.saturating_sub(1)..=(bx + 1).min(blocks[0] - 1) {
                                refined[x + blocks[0] * (y + blocks[1] * z)] = true;
                            }
                        }
                    }
                }
            }
        }
        let places = [0, 1, 2].map(|k| axis_places(&axes[k]));
        Self {
            coarse: axes,
            values,
            blocks,
            refined,
            places,
        }
    }

    fn is_refined(&self, bx: usize, by: usize, bz: usize) -> bool {
        self.refined[bx + self.blocks[0] * (by + self.blocks[1] * bz)]
    }

    /// Whether fine sample `(i, j, k)` must be evaluated: it belongs to a refined block.
    pub fn must_evaluate(&self, i: usize, j: usize, k: usize) -> bool {
        let [px, py, pz] = [&self.places[0][i], &self.places[1][j], &self.places[2][k]];
        (pz.first..=pz.last)
            .any(|z| (py.first..=py.last).any(|y| (px.first..=px.last).any(|x| self.is_refined(x, y, z))))
    }

    /// The stand-in value of fine sample `(i, j, k)`: the trilinear interpolation of its block's
    /// corners.
    pub fn interpolated(&self, i: usize, j: usize, k: usize) -> f32 {
        let [px, py, pz] = [&self.places[0][i], &self.places[1][j], &self.places[2][k]];
        let n = [self.coarse[0].len(), self.coarse[1].len(), self.coarse[2].len()];
        let at = |x: usize, y: usize, z: usize| {
            self.values[x.min(n[0] - 1) + n[0] * (y.min(n[1] - 1) + n[1] * z.min(n[2] - 1))]
        };
        let (bx, by, bz) = (px.last, py.last, pz.last);
        let (tx, ty, tz) = (
            if px.first < px.last { 0.0 } else { px.along },
            if py.first < py.last { 0.0 } else { py.along },
            if pz.first < pz.last { 0.0 } else { pz.along },
        );
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let plane = |z: usize| {
            lerp(
                lerp(at(bx, by, z), at(bx + 1, by, z), tx),
                lerp(at(bx, by + 1, z), at(bx + 1, by + 1, z), tx),
                ty,
            )
        };
        lerp(plane(bz), plane(bz + 1), tz)
    }

    /// Fraction of blocks refined (for diagnostics).
    pub fn refined_fraction(&self) -> f32 {
        self.refined.iter().filter(|r| **r).count() as f32 / self.refined.len().max(1) as f32
    }
}

/// The fine-grid indices of a coarse grid's samples along x, y and z.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SampleGridIndices {
    /// Per axis, increasing fine indices (the first 0, the last the fine grid's last).
    pub axes: [Vec<usize>; 3],
}

impl SampleGridIndices {
    /// Samples of one z-layer of the coarse grid.
    pub fn layer_len(&self) -> usize {
        self.axes[0].len() * self.axes[1].len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_coarse_grid_keeps_every_block_th_sample_and_the_last() {
        assert_eq!(coarse_indices(10, 4), vec![0, 4, 8, 9]);
        assert_eq!(coarse_indices(9, 4), vec![0, 4, 8]);
        assert_eq!(coarse_indices(2, 4), vec![0, 1]);
        assert_eq!(coarse_indices(5, 1), vec![0, 1, 2, 3, 4]);
    }

    #[test]
    fn a_sample_on_a_block_border_belongs_to_both_blocks() {
        let places = axis_places(&[0, 4, 8, 9]);
        assert_eq!(
            places[0],
            AxisPlace {
                first: 0,
                last: 0,
                along: 0.0
            }
        );
        assert_eq!(
            places[2],
            AxisPlace {
                first: 0,
                last: 0,
                along: 0.5
            }
        );
        assert_eq!(
            places[4],
            AxisPlace {
                first: 0,
                last: 1,
                along: 0.0
            }
        );
        assert_eq!(
            places[8],
            AxisPlace {
                first: 1,
                last: 2,
                along: 0.0
            }
        );
        assert_eq!(
            places[9],
            AxisPlace {
                first: 2,
                last: 2,
                along: 1.0
            }
        );
    }
}
