//! The free space around a design that the outside reaches through openings of at least a given
//! width: what a camera can look into. The inside of a closed carcass (a nightstand's panels and
//! inset drawer fronts, 5 mm to 1 cm apart) is free space too, but no camera sees into it and no
//! reconstruction can reach it; its faces are not ground truth.
//!
//! The design is voxelised on a grid of `cell_m` cells (a cell is solid when its centre lies
//! inside a part: parity of the part's crossings along the cell's vertical column). The solid
//! cells grown by `radius_cells` (a cube) close every opening narrower than about
//! `2 · radius_cells + 1` cells; the free cells the grid's border then reaches (6-connected) are
//! the outside, and the outside grown back by `radius_cells` is the reachable space — the
//! morphological opening of the free space, restricted to the part connected to the outside.
//! The grid's origin is offset by a fraction of a cell so that no cell centre lies on a part's
//! edge.

use nalgebra::{Point3, Vector3};

use crate::geometry::mesh::{Aabb, TriangleMesh};

/// Free cells around the design's bounds, beyond the closing radius.
const BORDER_CELLS: usize = 2;

/// The reachable free space of a design on a regular grid.
#[derive(Debug, Clone)]
pub struct ReachableSpace {
    /// Corner of cell (0, 0, 0).
    origin: Point3<f32>,
    /// Edge of a cell, metres.
    cell_m: f32,
    /// Cells along x, y, z.
    dims: [usize; 3],
    /// Per cell (x fastest): reached from outside.
    reached: Vec<bool>,
}

impl ReachableSpace {
    /// The reachable space around `parts` (closed meshes), or `None` when they have no vertex.
    pub fn around(parts: &[TriangleMesh], cell_m: f32, radius_cells: usize) -> Option<Self> {
        let bounds = Aabb::from_points(parts.iter().flat_map(|p| &p.vertices))?;
        let pad = (BORDER_CELLS + radius_cells + 1) as f32 * cell_m;
        let jitter = Vector3::new(0.371_9, 0.412_7, 0.290_3) * cell_m;
        let origin = bounds.min - Vector3::repeat(pad) - jitter;
        let extent = bounds.max - origin + Vector3::repeat(pad);
        let dims = [0, 1, 2].map(|a| (extent[a] / cell_m).ceil() as usize);
        let grid = Grid { dims };
        let solid = solid_cells(parts, origin, cell_m, &grid);
        let closed = grid.grown(&solid, radius_cells);
        let outside = grid.flooded_from_border(&closed);
        let reached = grid.grown(&outside, radius_cells);
        Some(Self {
            origin,
            cell_m,
            dims,
            reached,
        })
    }

    /// Whether `p` lies in the reachable space (everything beyond the grid does).
    pub fn contains(&self, p: &Point3<f32>) -> bool {
        let mut index = [0usize; 3];
        for a in 0..3 {
            let c = ((p[a] - self.origin[a]) / self.cell_m).floor();
            if c < 0.0 || c >= self.dims[a] as f32 {
                return true;
            }
            index[a] = c as usize;
        }
        self.reached[Grid { dims: self.dims }.at(index)]
    }
}

/// Index arithmetic of a grid, x fastest.
struct Grid {
    dims: [usize; 3],
}

impl Grid {
    fn len(&self) -> usize {
        self.dims.iter().product()
    }

    fn at(&self, [i, j, k]: [usize; 3]) -> usize {
        (k * self.dims[1] + j) * self.dims[0] + i
    }

    fn stride(&self, axis: usize) -> usize {
        match axis {
            0 => 1,
            1 => self.dims[0],
            _ => self.dims[0] * self.dims[1],
        }
    }

    /// `cells` grown by `radius` along each axis in turn (a cube of side `2 · radius + 1`).
    fn grown(&self, cells: &[bool], radius: usize) -> Vec<bool> {
        let mut current = cells.to_vec();
        for axis in 0..3 {
            let (n, stride) = (self.dims[axis], self.stride(axis));
            let mut next = vec![false; current.len()];
            for start in (0..self.len()).filter(|&c| (c / stride) % n == 0) {
                // A running count of set cells in the window [i − radius, i + radius].
                let value = |i: usize| current[start + i * stride] as usize;
                let mut count: usize = (0..radius.min(n)).map(value).sum();
                for i in 0..n {
                    if i + radius < n {
                        count += value(i + radius);
                    }
                    if i > radius {
                        count -= value(i - radius - 1);
                    }
                    next[start + i * stride] = count > 0;
                }
            }
            current = next;
        }
        current
    }

    /// The cells not in `blocked` that a 6-connected walk from the grid's border reaches.
    fn flooded_from_border(&self, blocked: &[bool]) -> Vec<bool> {
        let [nx, ny, nz] = self.dims;
        let mut reached = vec![false; self.len()];
        let mut queue = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let border = i == 0 || j == 0 || k == 0 || i + 1 == nx || j + 1 == ny || k + 1 == nz;
                    let c = self.at([i, j, k]);
                    if border && !blocked[c] {
                        reached[c] = true;
                        queue.push(c);
                    }
                }
            }
        }
        while let Some(c) = queue.pop() {
            let (i, j, k) = (c % nx, (c / nx) % ny, c / (nx * ny));
            let neighbours = [
                (i > 0).then(|| c - 1),
                (i + 1 < nx).then(|| c + 1),
                (j > 0).then(|| c - nx),
                (j + 1 < ny).then(|| c + nx),
                (k > 0).then(|| c - nx * ny),
                (k + 1 < nz).then(|| c + nx * ny),
            ];
            for n in neighbours.into_iter().flatten() {
                if !blocked[n] && !reached[n] {
                    reached[n] = true;
                    queue.push(n);
                }
            }
        }
        reached
    }
}

/// The cells whose centre lies inside a part: along each vertical column, a part's crossings
/// sorted by height bound the spans inside it.
fn solid_cells(parts: &[TriangleMesh], origin: Point3<f32>, cell_m: f32, grid: &Grid) -> Vec<bool> {
    let [nx, ny, nz] = grid.dims;
    let mut solid = vec![false; grid.len()];
    let bounds: Vec<Option<Aabb>> = parts.iter().map(|p| Aabb::from_points(&p.vertices)).collect();
    let centre = |i: usize, a: usize| origin[a] + (i as f32 + 0.5) * cell_m;
    let mut crossings = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (centre(i, 0), centre(j, 1));
            for (part, b) in parts.iter().zip(&bounds) {
                let Some(b) = b else { continue };
                if x < b.min.x || x > b.max.x || y < b.min.y || y > b.max.y {
                    continue;
                }
                crossings.clear();
                crossings.extend((0..part.triangles.len()).filter_map(|t| column_crossing(x, y, part.corners(t))));
                crossings.sort_by(f32::total_cmp);
                for span in crossings.chunks_exact(2) {
                    let first = ((span[0] - origin.z) / cell_m - 0.5).ceil().max(0.0) as usize;
                    let last = ((span[1] - origin.z) / cell_m - 0.5).floor();
                    if last < 0.0 {
                        continue;
                    }
                    for k in first..=(last as usize).min(nz - 1) {
                        solid[grid.at([i, j, k])] = true;
                    }
                }
            }
        }
    }
    solid
}

/// The height at which the vertical line through (x, y) crosses the triangle, if it does.
fn column_crossing(x: f32, y: f32, [a, b, c]: [Point3<f32>; 3]) -> Option<f32> {
    let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    if det.abs() < 1e-12 {
        return None;
    }
    let u = ((x - a.x) * (c.y - a.y) - (c.x - a.x) * (y - a.y)) / det;
    let v = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then(|| a.z + u * (b.z - a.z) + v * (c.z - a.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::primitives::{block, cuboid};

    /// A closed box of 2 cm panels, 0.4 m outside, with an opening of `gap` in its front panel.
    fn carcass(gap: f32) -> Vec<TriangleMesh> {
        let (outer, t) = (0.4, 0.02);
        let h = outer / 2.0;
        let mut parts = vec![
            block(0.0, 0.0, 0.0, [outer, outer, t]),
            block(0.0, 0.0, outer - t, [outer, outer, t]),
            block(-h + t / 2.0, 0.0, t, [t, outer, outer - 2.0 * t]),
            block(h - t / 2.0, 0.0, t, [t, outer, outer - 2.0 * t]),
            block(0.0, -h + t / 2.0, t, [outer - 2.0 * t, t, outer - 2.0 * t]),
        ];
        // The front panel in two halves, `gap` apart along z.
        let half = (outer - 2.0 * t - gap) / 2.0;
        parts.push(cuboid([-h + t, h - t, t], [h - t, h, t + half]));
        parts.push(cuboid([-h + t, h - t, outer - t - half], [h - t, h, outer - t]));
        parts
    }

    #[test]
    fn a_closed_carcass_hides_its_inside_and_a_wide_opening_shows_it() {
        let inside = Point3::new(0.0, 0.0, 0.2);
        let beside = Point3::new(0.0, 0.25, 0.2);
        for (gap, open) in [(0.0, false), (0.005, false), (0.01, false), (0.06, true)] {
            let space = ReachableSpace::around(&carcass(gap), 0.005, 2).expect("parts have vertices");
            assert_eq!(space.contains(&inside), open, "gap {gap} m: the inside");
            assert!(space.contains(&beside), "gap {gap} m: the space in front");
            assert!(!space.contains(&Point3::new(0.0, 0.0, 0.01)), "inside the bottom panel");
        }
    }

    #[test]
    fn free_space_next_to_a_face_is_reached_up_to_the_face() {
        let space =
            ReachableSpace::around(&[block(0.0, 0.0, 0.0, [0.3, 0.2, 0.1])], 0.005, 2).expect("a block has vertices");
        for p in [
            Point3::new(0.0, 0.0, 0.105),
            Point3::new(0.155, 0.0, 0.05),
            Point3::new(0.0, -0.105, 0.05),
            Point3::new(0.0, 0.0, -0.005),
            Point3::new(1.0, 1.0, 1.0),
        ] {
            assert!(space.contains(&p), "{p:?} is outside the block");
        }
        assert!(!space.contains(&Point3::new(0.0, 0.0, 0.05)), "the block's inside");
    }
}
