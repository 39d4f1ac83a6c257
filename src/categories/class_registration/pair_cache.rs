//! [`PairCache`]: every pair a class registration answered, kept so that the next registration
//! of the class does not search a pair again whose two clouds have not changed since.
//!
//! A pair's search depends only on its two thinned clouds, the registration settings and the
//! class's seed (one random stream per ordered pair), so on unchanged clouds it would return
//! exactly what it returned before: answering from the cache changes no result. A cloud is
//! identified by its *version* (the observed cloud's count of points added, which changes with
//! every point that moves a centroid or adds a voxel). Rejected pairs — a member tried against a
//! representative whose subcategory it did not join — are kept as well: with several
//! subcategories they are most of the pairs.

use std::collections::BTreeMap;

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use crate::ids::ObjectId;

/// The versions of a pair's two clouds (source = the member, template = the representative).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PairVersions {
    /// The member's cloud.
    pub source: u64,
    /// The representative's cloud.
    pub template: u64,
}

/// One answered pair.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CachedPair {
    /// The member's pose in the representative's frame.
    pub template_from_source: Isometry3<f32>,
    /// Its normalised one-way Chamfer distance.
    pub chamfer: f32,
    /// The cloud versions it was answered at.
    pub versions: PairVersions,
    /// The cloud sizes its alignment was found at (older than `versions` when a `reuse` start
    /// kept an alignment found on smaller clouds).
    pub found_at: PairPoints,
    /// Which searches its answer went through.
    #[serde(default)]
    pub searches: PairSearches,
}

/// Which searches a pair's answer went through.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PairSearches {
    /// The multi-start search (or a warm start, or an alignment kept from before).
    #[default]
    First,
    /// Also the second search of a member to its representative
    /// ([`super::SecondSearch`]): the better of the two is the answer.
    Second,
}

/// Answered pairs of one class, by (member, representative).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PairCache(pub BTreeMap<(ObjectId, ObjectId), CachedPair>);

impl PairCache {
    /// The pair's answer when both clouds are still at the versions it was answered at.
    pub fn unchanged(&self, source: ObjectId, template: ObjectId, now: PairVersions) -> Option<&CachedPair> {
        self.0.get(&(source, template)).filter(|c| c.versions == now)
    }

    /// Pairs held.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether no pair is held.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// The sizes of a (member, representative) pair's observed clouds when its alignment was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PairPoints {
    /// Points of the member's cloud.
    pub source: usize,
    /// Points of the representative's cloud.
    pub template: usize,
}

impl PairPoints {
    /// Whether an alignment found at these sizes still stands for clouds of sizes `now`: neither
    /// grew by more than `growth` (a fraction).
    pub fn still_hold(&self, now: PairPoints, growth: f32) -> bool {
        let within = |then: usize, now: usize| now as f64 <= then as f64 * (1.0 + f64::from(growth));
        within(self.source, now.source) && within(self.template, now.template)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pair_is_answered_from_the_cache_only_while_both_clouds_are_unchanged() {
        let (a, b) = (ObjectId(1), ObjectId(2));
        let versions = PairVersions {
            source: 10,
            template: 20,
        };
        let cached = CachedPair {
            template_from_source: Isometry3::translation(0.1, 0.0, 0.0),
            chamfer: 0.03,
            versions,
            found_at: PairPoints {
                source: 100,
                template: 200,
            },
            searches: PairSearches::First,
        };
        let cache = PairCache(BTreeMap::from([((a, b), cached)]));
        assert_eq!(cache.unchanged(a, b, versions), Some(&cached));
        assert_eq!(
            cache.unchanged(b, a, versions),
            None,
            "the other direction is another pair"
        );
        let moved = |source, template| PairVersions { source, template };
        assert_eq!(cache.unchanged(a, b, moved(11, 20)), None, "the member's cloud changed");
        assert_eq!(
            cache.unchanged(a, b, moved(10, 21)),
            None,
            "the representative's cloud changed"
        );
    }

    #[test]
    fn an_alignment_stands_while_neither_cloud_grew_by_more_than_the_growth() {
        let then = PairPoints {
            source: 1_000,
            template: 500,
        };
        let now = |source, template| PairPoints { source, template };
        assert!(then.still_hold(now(1_200, 600), 0.2), "20 % is not more than 20 %");
        assert!(!then.still_hold(now(1_201, 500), 0.2), "the member's cloud grew");
        assert!(
            !then.still_hold(now(1_000, 601), 0.2),
            "the representative's cloud grew"
        );
    }
}
