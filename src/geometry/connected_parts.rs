//! The parts of a point set that hang together: points joined when they lie in the same or in
//! touching cells of a grid (26-neighbourhood), grouped into connected parts.
//!
//! An object is one body (a lamp whose pole a depth camera lost is two, each a large share of
//! it); what a segmenter adds to it in a frame or two — a mask bled onto a wall metres behind, a
//! spurious blob given to it — lies apart from it and is a small share of its points.

use std::collections::HashMap;

use nalgebra::Point3;

use crate::objects::observed_cloud::pack_voxel;

/// Integer cell of `p` on a grid of `cell_m`.
fn cell_of(p: &Point3<f32>, cell_m: f32) -> [i64; 3] {
    [p.x, p.y, p.z].map(|x| (x / cell_m).floor() as i64)
}

/// The connected parts of `points` on a grid of `cell_m` (26-neighbourhood), each a list of
/// indices into `points` in increasing order; parts ordered by their first index.
pub fn connected_parts(points: &[Point3<f32>], cell_m: f32) -> Vec<Vec<usize>> {
    let cells: Vec<[i64; 3]> = points.iter().map(|p| cell_of(p, cell_m)).collect();
    let mut first_in_cell: HashMap<u64, usize> = HashMap::new();
    let mut parent: Vec<usize> = (0..points.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    fn join(parent: &mut [usize], a: usize, b: usize) {
        let (ra, rb) = (root(parent, a), root(parent, b));
        if ra != rb {
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            parent[hi] = lo;
        }
    }
    for (i, c) in cells.iter().enumerate() {
        match first_in_cell.get(&pack_voxel(*c)) {
            Some(&j) => join(&mut parent, i, j),
            None => {
                first_in_cell.insert(pack_voxel(*c), i);
            }
        }
    }
    for (i, c) in cells.iter().enumerate() {
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(&j) = first_in_cell.get(&pack_voxel([c[0] + dx, c[1] + dy, c[2] + dz])) {
                        join(&mut parent, i, j);
                    }
                }
            }
        }
    }
    let mut parts: Vec<Vec<usize>> = Vec::new();
    let mut part_of_root: HashMap<usize, usize> = HashMap::new();
    for i in 0..points.len() {
        let r = root(&mut parent, i);
        let k = *part_of_root.entry(r).or_insert_with(|| {
            parts.push(Vec::new());
            parts.len() - 1
        });
        parts[k].push(i);
    }
    parts
}

/// The points of the parts of `points` (on a grid of `cell_m`) holding at least `min_share` of
/// them; all of them when no part does.
pub fn main_parts(points: Vec<Point3<f32>>, cell_m: f32, min_share: f32) -> Vec<Point3<f32>> {
    let parts = connected_parts(&points, cell_m);
    let least = (min_share * points.len() as f32).ceil() as usize;
    let mut kept: Vec<usize> = parts.into_iter().filter(|p| p.len() >= least).flatten().collect();
    if kept.is_empty() {
        return points;
    }
    kept.sort_unstable();
    kept.into_iter().map(|i| points[i]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line of `n` points from `start` along x, `step_m` apart.
    fn line(start: [f32; 3], n: usize, step_m: f32) -> Vec<Point3<f32>> {
        (0..n)
            .map(|i| Point3::new(start[0] + i as f32 * step_m, start[1], start[2]))
            .collect()
    }

    #[test]
    fn points_within_a_cell_of_each_other_are_one_part_and_a_gap_of_two_cells_splits() {
        let mut points = line([0.0, 0.0, 0.0], 50, 0.01);
        // 5.5 cm on from the last point: two 3 cm cells on, so not touching.
        points.extend(line([0.545, 0.0, 0.0], 10, 0.01));
        let parts = connected_parts(&points, 0.03);
        assert_eq!(parts.len(), 2);
        assert_eq!(parts[0], (0..50).collect::<Vec<_>>());
        assert_eq!(parts[1], (50..60).collect::<Vec<_>>());
        // 2 cm on joins them (the next cell, or the same one).
        let mut near = line([0.0, 0.0, 0.0], 50, 0.01);
        near.extend(line([0.51, 0.0, 0.0], 10, 0.01));
        assert_eq!(connected_parts(&near, 0.03).len(), 1);
    }

    #[test]
    fn a_small_part_far_away_is_dropped_and_large_parts_are_kept() {
        // A body of 200 points, a second body of 40 (a lamp's shade apart from its base), and a
        // speck of 5 points 3 m away.
        let mut points = line([0.0, 0.0, 0.0], 200, 0.005);
        points.extend(line([0.0, 0.0, 1.0], 40, 0.005));
        points.extend(line([3.0, 2.0, 0.0], 5, 0.005));
        let kept = main_parts(points.clone(), 0.03, 0.05);
        assert_eq!(kept.len(), 240);
        assert!(kept.iter().all(|p| p.x < 2.0));
        // No part holds half: every point stays.
        assert_eq!(main_parts(points, 0.03, 0.9).len(), 245);
    }
}
