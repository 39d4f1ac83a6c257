//! Nearest-neighbour distances between point sets (a k-d tree over the reference points).
//!
//! Used wherever a distance "from each point of P to the closest point of Q" is needed: cloud
//! accuracy against ground truth, Chamfer scores, metrics; and, by index, the closest point and
//! the points within a radius (registration, normals, FPFH).

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::Point3;
use rayon::prelude::*;

use crate::error::{CatmapError, Result};

/// A fixed set of reference points that answers nearest-distance queries.
pub struct PointIndex {
    tree: ImmutableKdTree<f32, 3>,
    points: Vec<[f32; 3]>,
}

impl std::fmt::Debug for PointIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PointIndex").field("points", &self.tree.size()).finish()
    }
}

impl PointIndex {
    /// Indexes `points`. Errors on an empty or non-finite set.
    pub fn new(points: &[Point3<f32>]) -> Result<Self> {
        if points.is_empty() {
            return Err(CatmapError::too_few("points to index", 1, 0));
        }
        if points.iter().any(|p| !p.coords.iter().all(|x| x.is_finite())) {
            return Err(CatmapError::NonFinitePoint {
                what: "a point set to index".into(),
            });
        }
        let raw: Vec<[f32; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        let tree = ImmutableKdTree::new_from_slice(&raw)
            .map_err(|e| CatmapError::Invariant(format!("cannot build a k-d tree of finite points: {e:?}")))?;
        Ok(Self { tree, points: raw })
    }

    /// Distance from `p` to the closest indexed point.
    pub fn nearest_distance(&self, p: &Point3<f32>) -> f32 {
        self.tree
            .query(&[p.x, p.y, p.z])
            .nearest_one::<SquaredEuclidean<f32>>()
            .execute()
            .distance
            .sqrt()
    }

    /// Distances from each query point to the closest indexed point (in parallel, in query order).
    pub fn nearest_distances(&self, queries: &[Point3<f32>]) -> Vec<f32> {
        queries.par_iter().map(|p| self.nearest_distance(p)).collect()
    }

    /// Mean distance from the query points to the indexed set (0 for no queries).
    pub fn mean_distance(&self, queries: &[Point3<f32>]) -> f32 {
        if queries.is_empty() {
            return 0.0;
        }
        let sum: f64 = self.nearest_distances(queries).iter().map(|&d| f64::from(d)).sum();
        (sum / queries.len() as f64) as f32
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

    /// The closest point to `p` as [`Self::nearest`] answers it, its squared distance, and the
    /// squared distance to the second closest (infinite with one point indexed).
    pub fn nearest_two(&self, p: &Point3<f32>) -> (usize, f32, f32) {
        let two = std::num::NonZeroUsize::MIN.saturating_add(1);
        let hits = self
            .tree
            .query(&[p.x, p.y, p.z])
            .nearest_n::<SquaredEuclidean<f32>>(two)
            .execute();
        match hits.as_slice() {
            [first, second, ..] if first.distance < second.distance => {
                (first.item as usize, first.distance, second.distance)
            }
            [_, second, ..] => {
                // Two at one distance: the one the plain query picks.
                let (nearest, d2) = self.nearest(p);
                (nearest, d2, second.distance)
            }
            _ => {
                let (nearest, d2) = self.nearest(p);
                (nearest, d2, f32::INFINITY)
            }
        }
    }

    /// The `i`-th indexed point.
    pub fn point(&self, i: usize) -> Point3<f32> {
        let [x, y, z] = self.points[i];
        Point3::new(x, y, z)
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
    fn distances_match_brute_force() {
        let reference: Vec<Point3<f32>> = (0..200)
            .map(|i| Point3::new((i % 10) as f32, (i / 10) as f32 * 0.5, 0.3))
            .collect();
        let index = PointIndex::new(&reference).expect("non-empty");
        for q in [
            Point3::new(0.2, 0.1, 0.0),
            Point3::new(7.7, 3.3, 1.0),
            Point3::new(-5.0, 20.0, 0.3),
        ] {
            let brute = reference.iter().map(|r| (r - q).norm()).fold(f32::INFINITY, f32::min);
            assert!((index.nearest_distance(&q) - brute).abs() < 1e-5);
        }
    }

    #[test]
    fn empty_and_non_finite_sets_are_rejected() {
        assert!(PointIndex::new(&[]).is_err());
        assert!(PointIndex::new(&[Point3::new(f32::NAN, 0.0, 0.0)]).is_err());
    }

    #[test]
    fn queries_match_brute_force() {
        let points: Vec<Point3<f32>> = (0..60)
            .map(|i| Point3::new((i % 4) as f32 * 0.1, (i / 4 % 5) as f32 * 0.1, (i / 20) as f32 * 0.1))
            .collect();
        let index = PointIndex::new(&points).expect("non-empty");
        let q = Point3::new(0.12, 0.21, 0.09);
        let brute_nearest = (0..points.len())
            .min_by(|&a, &b| (points[a] - q).norm().total_cmp(&(points[b] - q).norm()))
            .expect("non-empty");
        assert_eq!(index.nearest(&q).0, brute_nearest);
        let brute_within: Vec<usize> = (0..points.len()).filter(|&i| (points[i] - q).norm() <= 0.15).collect();
        assert_eq!(index.within(&q, 0.15), brute_within);
    }
}
