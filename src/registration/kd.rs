//! A k-d tree (kiddo) over a fixed cloud that answers "which point is closest" and "which points
//! lie within r", by index. [`crate::nearest::PointIndex`] answers distances only.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::Point3;

use crate::error::{CatmapError, Result};

/// Nearest-neighbour and radius queries over `points`, returning indices into `points`.
pub struct KdIndex {
    tree: ImmutableKdTree<f32, 3>,
}

impl std::fmt::Debug for KdIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KdIndex").field("points", &self.tree.size()).finish()
    }
}

impl KdIndex {
    /// Indexes `points` (non-empty and finite; callers check with
    /// [`check_cloud`](super::cloud::check_cloud)).
    pub fn new(points: &[Point3<f32>]) -> Result<Self> {
        let raw: Vec<[f32; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        let tree = ImmutableKdTree::new_from_slice(&raw)
            .map_err(|e| CatmapError::Degenerate(format!("cannot build a k-d tree: {e:?}")))?;
        Ok(Self { tree })
    }

    /// Index of the point closest to `p` and the squared distance to it.
    pub fn nearest(&self, p: &Point3<f32>) -> (usize, f32) {
        let hit = self
            .tree
            .query(&[p.x, p.y, p.z])
            .nearest_one::<SquaredEuclidean<f32>>()
            .execute();
        (hit.item as usize, hit.distance)
    }

    /// Indices of the points within `radius` of `p` (inclusive), in increasing index order.
    pub fn within(&self, p: &Point3<f32>, radius: f32) -> Vec<usize> {
        let mut found: Vec<usize> = self
            .tree
            .query(&[p.x, p.y, p.z])
            .within::<SquaredEuclidean<f32>>(radius * radius)
            .unsorted()
            .execute()
            .into_iter()
            .map(|hit| hit.item as usize)
            .collect();
        found.sort_unstable();
        found
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_match_brute_force() {
        let points: Vec<Point3<f32>> = (0..60)
            .map(|i| Point3::new((i % 4) as f32 * 0.1, (i / 4 % 5) as f32 * 0.1, (i / 20) as f32 * 0.1))
            .collect();
        let index = KdIndex::new(&points).expect("non-empty");
        let q = Point3::new(0.12, 0.21, 0.09);
        let brute_nearest = (0..points.len())
            .min_by(|&a, &b| (points[a] - q).norm().total_cmp(&(points[b] - q).norm()))
            .expect("non-empty");
        assert_eq!(index.nearest(&q).0, brute_nearest);
        let brute_within: Vec<usize> = (0..points.len()).filter(|&i| (points[i] - q).norm() <= 0.15).collect();
        assert_eq!(index.within(&q, 0.15), brute_within);
    }
}
