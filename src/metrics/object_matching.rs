//! Pairing predicted objects with ground-truth objects by geometry, for runs whose object ids are
//! not the dataset's (per-frame masks associated into objects, `EvalSettings::pairing =
//! "geometry"`).
//!
//! Each predicted mesh is sampled ([`MATCH_SAMPLES`] area-uniform points, the prediction's own
//! stream of the seed). A sample votes for the ground-truth object whose surface samples lie
//! nearest, when within [`MATCH_DISTANCE_M`]; farther samples vote for none. A prediction's
//! **purity** is its top object's share of its votes: how much of what it holds comes from one
//! ground-truth object. A vote stands for its share of the prediction's surface area, so each
//! ground-truth object is paired with the prediction whose surface lies on it over the largest
//! area, among those whose top object it is (ties: the lower id): a whole object made with some
//! stray surface outweighs a clean fragment of it. The other predictions are extra (duplicates,
//! fragments, or objects the ground truth does not have).

use std::collections::BTreeMap;

use nalgebra::Point3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::geometry::mesh::TriangleMesh;
use crate::geometry::nearest::PointIndex;
use crate::ids::ObjectId;
use crate::rng::{RngStream, seeded_rng};

/// Samples per mesh for the pairing.
pub const MATCH_SAMPLES: usize = 2000;
/// A sample farther than this from every ground-truth surface votes for none, metres.
pub const MATCH_DISTANCE_M: f32 = 0.05;

/// How predicted objects are paired with ground-truth objects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pairing {
    /// By id: `obj_{id}.ply` against the ground truth's `obj_{id}.ply` (consistent ids).
    #[default]
    ById,
    /// By geometry (module doc).
    Geometry,
}

/// One prediction's votes.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictionVotes {
    /// The prediction.
    pub prediction: ObjectId,
    /// The ground-truth object most of its samples lie on, if any lies within reach.
    pub top: Option<ObjectId>,
    /// Votes for `top`.
    pub top_votes: usize,
    /// Area of its surface that lies on `top` (its votes' share of its samples times its area), m².
    pub top_area_m2: f32,
    /// Share of its voting samples that voted for `top` (0 when none voted).
    pub purity: f32,
}

/// The pairing of a scene.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GeometryPairing {
    /// Ground-truth id → its prediction and that prediction's purity.
    pub paired: BTreeMap<ObjectId, (ObjectId, f32)>,
    /// Predictions paired with no ground-truth object.
    pub extra: Vec<ObjectId>,
}

/// Every prediction's votes against the ground truth (module doc).
pub fn vote(
    predictions: &[(ObjectId, TriangleMesh)],
    truths: &[(ObjectId, TriangleMesh)],
    seed: u64,
) -> Result<Vec<PredictionVotes>> {
    let mut truth_points: Vec<Point3<f32>> = Vec::new();
    let mut owner: Vec<ObjectId> = Vec::new();
    for (id, mesh) in truths {
        let mut rng = seeded_rng(seed, RngStream::Object(*id));
        let samples = mesh.sample_surface(MATCH_SAMPLES * 4, &mut rng).unwrap_or_default();
        owner.extend(std::iter::repeat_n(*id, samples.len()));
        truth_points.extend(samples);
    }
    if truth_points.is_empty() {
        return Ok(predictions.iter().map(|(id, _)| no_votes(*id)).collect());
    }
    let index = PointIndex::new(&truth_points)?;
    Ok(predictions
        .par_iter()
        .map(|(id, mesh)| {
            let mut rng = seeded_rng(seed, RngStream::Object(*id));
            let samples = mesh.sample_surface(MATCH_SAMPLES, &mut rng).unwrap_or_default();
            let mut votes: BTreeMap<ObjectId, usize> = BTreeMap::new();
            for p in &samples {
                let (nearest, distance) = index.nearest(p);
                if distance <= MATCH_DISTANCE_M {
                    *votes.entry(owner[nearest]).or_default() += 1;
                }
            }
            let total: usize = votes.values().sum();
            let top = votes.iter().max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)));
            match top {
                None => no_votes(*id),
                Some((&truth, &n)) => PredictionVotes {
                    prediction: *id,
                    top: Some(truth),
                    top_votes: n,
                    top_area_m2: n as f32 / samples.len() as f32 * mesh.area(),
                    purity: n as f32 / total as f32,
                },
            }
        })
        .collect())
}

fn no_votes(prediction: ObjectId) -> PredictionVotes {
    PredictionVotes {
        prediction,
        top: None,
        top_votes: 0,
        top_area_m2: 0.0,
        purity: 0.0,
    }
}

/// Pairs each ground-truth object with the prediction whose surface lies on it over the largest
/// area (module doc).
pub fn pair(votes: &[PredictionVotes]) -> GeometryPairing {
    let mut best: BTreeMap<ObjectId, &PredictionVotes> = BTreeMap::new();
    for v in votes {
        let Some(truth) = v.top else { continue };
        let better = best.get(&truth).is_none_or(|b| {
            v.top_area_m2 > b.top_area_m2 || (v.top_area_m2 == b.top_area_m2 && v.prediction < b.prediction)
        });
        if better {
            best.insert(truth, v);
        }
    }
    let paired: BTreeMap<ObjectId, (ObjectId, f32)> = best
        .iter()
        .map(|(&truth, v)| (truth, (v.prediction, v.purity)))
        .collect();
    let taken: Vec<ObjectId> = paired.values().map(|&(p, _)| p).collect();
    let extra = votes
        .iter()
        .map(|v| v.prediction)
        .filter(|p| !taken.contains(p))
        .collect();
    GeometryPairing { paired, extra }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::primitives::cuboid;

    fn boxes() -> Vec<(ObjectId, TriangleMesh)> {
        vec![
            (ObjectId(1), cuboid([0.0, 0.0, 0.0], [0.5, 0.5, 0.9])),
            (ObjectId(2), cuboid([2.0, 0.0, 0.0], [2.5, 0.5, 0.9])),
            (ObjectId(3), cuboid([4.0, 0.0, 0.0], [5.0, 1.0, 0.7])),
        ]
    }

    #[test]
    fn predictions_under_other_ids_pair_with_their_objects_and_a_duplicate_is_extra() {
        let truths = boxes();
        let predictions = vec![
            (ObjectId(7), truths[2].1.clone()),
            (ObjectId(8), truths[0].1.clone()),
            (ObjectId(9), cuboid([2.0, 0.0, 0.0], [2.5, 0.5, 0.5])), // half of object 2
            (ObjectId(12), truths[1].1.clone()),
            (ObjectId(13), cuboid([9.0, 9.0, 0.0], [9.5, 9.5, 0.5])), // nothing there
        ];
        let votes = vote(&predictions, &truths, 3).expect("meshes sample");
        assert!(votes[..4].iter().all(|v| v.purity == 1.0), "{votes:?}");
        assert_eq!(votes[4].top, None);
        let pairing = pair(&votes);
        let paired: Vec<(u32, u32)> = pairing.paired.iter().map(|(t, (p, _))| (t.0, p.0)).collect();
        assert_eq!(paired, [(1, 8), (2, 12), (3, 7)], "the whole box outvotes the half");
        assert_eq!(pairing.extra, [ObjectId(9), ObjectId(13)]);
    }

    #[test]
    fn a_whole_object_with_stray_surface_outweighs_a_clean_fragment_of_it() {
        let truths = boxes();
        // A clean slab of object 3's top (every sample on it) and the whole object with as much
        // surface again far from everything (half its samples vote).
        let fragment = cuboid([4.0, 0.0, 0.68], [4.3, 0.3, 0.7]);
        let stray = cuboid([4.0, 5.0, 0.0], [5.0, 6.0, 0.7]);
        let whole = TriangleMesh::merged([&truths[2].1, &stray]);
        let predictions = vec![(ObjectId(4), fragment), (ObjectId(6), whole)];
        let votes = vote(&predictions, &truths, 2).expect("meshes sample");
        assert_eq!(votes[0].purity, 1.0, "{votes:?}");
        assert!(
            votes[1].top_votes < votes[0].top_votes,
            "more samples on the fragment: {votes:?}"
        );
        let pairing = pair(&votes);
        assert_eq!(pairing.paired[&ObjectId(3)].0, ObjectId(6), "{votes:?}");
        assert_eq!(pairing.extra, [ObjectId(4)]);
    }

    #[test]
    fn a_prediction_spanning_two_objects_has_the_purity_of_its_larger_share() {
        // Box 1 (0.5 × 0.5 × 0.9 m, 2.30 m² of surface) merged with box 3 (1 × 1 × 0.7 m,
        // 4.80 m²): the prediction is box 3's, by 4.80 / 7.10 = 0.68 of its surface.
        let truths = boxes();
        let merged = TriangleMesh::merged([&truths[0].1, &truths[2].1]);
        let votes = vote(&[(ObjectId(5), merged)], &truths, 1).expect("meshes sample");
        assert_eq!(votes[0].top, Some(ObjectId(3)), "{votes:?}");
        assert!((0.63..0.73).contains(&votes[0].purity), "{votes:?}");
        let reversed = TriangleMesh::merged([&truths[2].1, &truths[0].1]);
        let votes = vote(&[(ObjectId(5), reversed)], &truths, 1).expect("meshes sample");
        assert_eq!(votes[0].top, Some(ObjectId(3)), "either order: {votes:?}");
    }
}
