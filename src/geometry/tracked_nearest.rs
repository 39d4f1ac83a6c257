//! [`TrackedNearest`]: the nearest indexed point of each of a fixed list of query points that move
//! a little at a time — ICP's source points under each new pose — asked of the k-d tree again only
//! when the move could have changed the answer.
//!
//! Each query point keeps the index of its nearest point `j`, the position it was last seen at,
//! and a lower bound `L` on its distance to every *other* indexed point (at a query: the distance
//! to the second nearest, [`PointIndex::nearest_two`]). A move by δ lowers that bound to `L − δ`
//! (triangle inequality). At the new position:
//! - if the distance to `j` is below the lowered bound, `j` is still the strictly nearest point;
//! - else if both lie beyond the gate, no indexed point is within the gate;
//! - else the tree is asked again.
//!
//! Both tests keep a margin of [`MARGIN_M`] against the rounding of `f32` distances, so the
//! answers are those of [`PointIndex::nearest`] query by query (its squared distance computed the
//! same way), only cheaper: in ICP's late iterations the points move by micrometres.

use nalgebra::Point3;

use super::nearest::PointIndex;

/// Safety margin of both tests, metres: far above the rounding of `f32` distances between points
/// within tens of metres of the origin (about 1e-6 m), far below any spacing of real points.
pub const MARGIN_M: f32 = 1e-5;

/// What one query point knows since it last asked the tree.
#[derive(Debug, Clone, Copy)]
struct Track {
    /// Where the point was when `others_at_least` held.
    position: Point3<f32>,
    /// Its nearest indexed point when it last asked.
    nearest: usize,
    /// A lower bound on its distance from `position` to every indexed point but `nearest`.
    others_at_least: f32,
}

/// The nearest indexed point of each of a fixed list of moving query points (see the module doc).
#[derive(Debug, Clone)]
pub struct TrackedNearest {
    tracks: Vec<Option<Track>>,
    queries: usize,
}

impl TrackedNearest {
    /// A tracker of `count` query points, none located yet.
    pub fn new(count: usize) -> Self {
        Self {
            tracks: vec![None; count],
            queries: 0,
        }
    }

    /// How many times the tree has been asked so far.
    pub fn queries(&self) -> usize {
        self.queries
    }

    /// The nearest point of `index` to query point `i` now at `at`, with its squared distance,
    /// when that distance is at most `gate_d2`; `None` when no indexed point is that close. Equals
    /// `Some(index.nearest(at)).filter(|(_, d2)| d2 <= gate_d2)`.
    pub fn nearest_within(
        &mut self,
        i: usize,
        at: &Point3<f32>,
        index: &PointIndex,
        gate_d2: f32,
    ) -> Option<(usize, f32)> {
        if let Some(track) = &mut self.tracks[i] {
            let others_at_least = track.others_at_least - distance(at, &track.position);
            let d2 = squared_distance(&index.point(track.nearest), at);
            let d = d2.sqrt();
            if d + MARGIN_M < others_at_least {
                track.position = *at;
                track.others_at_least = others_at_least;
                return (d2 <= gate_d2).then_some((track.nearest, d2));
            }
            let gate = gate_d2.sqrt();
            if d > gate + MARGIN_M && others_at_least > gate + MARGIN_M {
                track.position = *at;
                track.others_at_least = others_at_least;
                return None;
            }
        }
        self.queries += 1;
        let (nearest, d2, second_d2) = index.nearest_two(at);
        self.tracks[i] = Some(Track {
            position: *at,
            nearest,
            others_at_least: second_d2.sqrt(),
        });
        (d2 <= gate_d2).then_some((nearest, d2))
    }
}

/// Squared distance summed over x, y, z in that order (as the k-d tree sums it).
fn squared_distance(a: &Point3<f32>, b: &Point3<f32>) -> f32 {
    let (dx, dy, dz) = (a.x - b.x, a.y - b.y, a.z - b.z);
    dx * dx + dy * dy + dz * dz
}

fn distance(a: &Point3<f32>, b: &Point3<f32>) -> f32 {
    squared_distance(a, b).sqrt()
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn cloud(rng: &mut ChaCha8Rng, n: usize) -> Vec<Point3<f32>> {
        (0..n)
            .map(|_| Point3::new(rng.random::<f32>(), rng.random::<f32>(), rng.random::<f32>() * 0.5))
            .collect()
    }

    #[test]
    fn answers_equal_the_trees_at_every_step_of_a_slow_drift() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let indexed = cloud(&mut rng, 2_000);
        let index = PointIndex::new(&indexed).expect("non-empty");
        let mut queries = cloud(&mut rng, 300);
        let mut tracker = TrackedNearest::new(queries.len());
        let gate_d2 = 0.02f32 * 0.02;
        let steps = 40;
        for step in 0..steps {
            // Steps shrinking from 5 mm to 5 µm, as ICP's do.
            let size = 0.005 * 0.8f32.powi(step);
            for (i, q) in queries.iter_mut().enumerate() {
                q.x += size * ((i % 7) as f32 - 3.0) / 3.0;
                q.y += size * ((i % 5) as f32 - 2.0) / 2.0;
                let expected = Some(index.nearest(q)).filter(|&(_, d2)| d2 <= gate_d2);
                assert_eq!(
                    tracker.nearest_within(i, q, &index, gate_d2),
                    expected,
                    "step {step} point {i}"
                );
            }
        }
        let asked = tracker.queries();
        assert!(asked >= queries.len(), "every point asks once");
        assert!(
            asked < queries.len() * steps as usize / 4,
            "late steps reuse answers: {asked} queries for {} lookups",
            queries.len() * steps as usize
        );
    }

    #[test]
    fn a_jump_past_the_bound_asks_the_tree_again() {
        let indexed = vec![Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)];
        let index = PointIndex::new(&indexed).expect("non-empty");
        let mut tracker = TrackedNearest::new(1);
        assert_eq!(
            tracker.nearest_within(0, &Point3::new(0.1, 0.0, 0.0), &index, 4.0),
            Some((0, 0.010000001))
        );
        assert_eq!(
            tracker
                .nearest_within(0, &Point3::new(0.2, 0.0, 0.0), &index, 4.0)
                .map(|h| h.0),
            Some(0)
        );
        assert_eq!(
            tracker.queries(),
            1,
            "a 10 cm move towards a point 90 cm away keeps the answer"
        );
        assert_eq!(
            tracker
                .nearest_within(0, &Point3::new(0.9, 0.0, 0.0), &index, 4.0)
                .map(|h| h.0),
            Some(1)
        );
        assert_eq!(tracker.queries(), 2);
    }

    #[test]
    fn points_beyond_the_gate_stay_beyond_it_without_asking() {
        let indexed = vec![Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.0)];
        let index = PointIndex::new(&indexed).expect("non-empty");
        let mut tracker = TrackedNearest::new(1);
        let gate_d2 = 0.1 * 0.1;
        assert_eq!(
            tracker.nearest_within(0, &Point3::new(0.0, 0.5, 0.0), &index, gate_d2),
            None
        );
        assert_eq!(
            tracker.nearest_within(0, &Point3::new(0.01, 0.5, 0.0), &index, gate_d2),
            None
        );
        assert_eq!(tracker.queries(), 1, "equidistant, both far beyond the gate");
        assert_eq!(
            tracker
                .nearest_within(0, &Point3::new(0.0, 0.95, 0.0), &index, gate_d2)
                .map(|h| h.0),
            Some(1)
        );
        assert_eq!(tracker.queries(), 2);
    }
}
