//! [`ClassClouds`]: the pairwise registrations of one class, over its thinned clouds, each pair
//! started as [`RegistrationStart`] says when the class's previous registration had it.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use nalgebra::{Isometry3, Point3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::config::RegistrationStart;
use super::pair_cache::{CachedPair, PairCache, PairPoints, PairSearches, PairVersions};
use crate::categories::subcategories::{MIN_LOOKED_AT_SHARE, PairRegistration, ReversePoints};
use crate::error::{CatmapError, Result};
use crate::ids::ObjectId;
use crate::objects::observed_space::ObservedSpace;
use crate::registration::{
    RegistrationConfig, half_max_extent, normalised_one_way_chamfer, one_way_chamfer, refine_registration,
    register_to_representative,
};

/// Whether a warm-started registration scoring `warm` may stand in for the full search, given the
/// pair's stored score.
pub fn warm_start_holds(warm: f32, stored: f32, tolerance: f32) -> bool {
    warm.is_finite() && warm <= stored * (1.0 + tolerance)
}

/// Pairwise registration over a class's thinned clouds.
pub(super) struct ClassClouds<'a> {
    /// Thinned clouds, by member.
    pub clouds: &'a BTreeMap<ObjectId, Vec<Point3<f32>>>,
    /// Sizes of the members' observed clouds now.
    pub sizes: &'a BTreeMap<ObjectId, usize>,
    /// Versions of the members' observed clouds now.
    pub versions: &'a BTreeMap<ObjectId, u64>,
    /// Where each member's views looked, computed when first asked.
    pub looked: super::LookedAt<'a>,
    /// The pairs the class's previous registration answered: kept as they were when both clouds
    /// are unchanged, otherwise where a `warm` or `reuse` start begins.
    pub cache: &'a PairCache,
    pub cfg: &'a RegistrationConfig,
    pub seed: u64,
    /// Where a pair registered before starts.
    pub start: RegistrationStart,
    pub warm_tolerance: f32,
    /// `Reuse`: how much both clouds may have grown for an alignment to be kept.
    pub growth: f32,
    /// Every pair answered so far.
    answered: Mutex<PairCache>,
    /// Reverse distances measured in this registration, by pair and points (each pair has one
    /// alignment here, the one [`PairRegistration::register`] answered).
    reverse: Mutex<BTreeMap<(ObjectId, ObjectId, ReversePoints), f32>>,
    /// What `looked` answered so far, by member.
    spaces: Mutex<BTreeMap<ObjectId, Option<Arc<ObservedSpace>>>>,
}

impl<'a> ClassClouds<'a> {
    /// Pairs over `clouds` (thinned) of members whose observed clouds have `sizes` and
    /// `versions` now.
    pub fn new(
        clouds: &'a BTreeMap<ObjectId, Vec<Point3<f32>>>,
        sizes: &'a BTreeMap<ObjectId, usize>,
        versions: &'a BTreeMap<ObjectId, u64>,
        looked: super::LookedAt<'a>,
        cache: &'a PairCache,
        cfg: &'a super::CategoryConfig,
        seed: u64,
    ) -> Self {
        Self {
            clouds,
            sizes,
            versions,
            looked,
            cache,
            cfg: &cfg.registration,
            seed,
            start: cfg.registration_start,
            warm_tolerance: cfg.warm_start_tolerance,
            growth: cfg.reregister_growth,
            answered: Mutex::new(PairCache::default()),
            reverse: Mutex::new(BTreeMap::new()),
            spaces: Mutex::new(BTreeMap::new()),
        }
    }

    /// Where `id`'s views looked: asked of `looked` the first time, kept after.
    fn space_of(&self, id: ObjectId) -> Option<Arc<ObservedSpace>> {
        let lock = || self.spaces.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(known) = lock().get(&id) {
            return known.clone();
        }
        let space = (self.looked)(id).map(Arc::new);
        lock().insert(id, space.clone());
        space
    }

    fn cloud(&self, id: ObjectId) -> Result<&[Point3<f32>]> {
        self.clouds
            .get(&id)
            .map(Vec::as_slice)
            .ok_or_else(|| CatmapError::missing(format!("the cloud of object {id}")))
    }

    /// Every pair answered, for the next registration of the class.
    pub fn into_answered(self) -> PairCache {
        self.answered
            .into_inner()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    fn versions_of(&self, source: ObjectId, template: ObjectId) -> PairVersions {
        let version = |id| self.versions.get(&id).copied().unwrap_or(0);
        PairVersions {
            source: version(source),
            template: version(template),
        }
    }

    /// Keeps an answer of the first search and returns it.
    fn record(
        &self,
        source: ObjectId,
        template: ObjectId,
        answer: (Isometry3<f32>, f32),
        found_at: PairPoints,
    ) -> (Isometry3<f32>, f32) {
        self.record_after(source, template, answer, found_at, PairSearches::First)
    }

    /// Keeps an answer that went through `searches` and returns it.
    fn record_after(
        &self,
        source: ObjectId,
        template: ObjectId,
        answer: (Isometry3<f32>, f32),
        found_at: PairPoints,
        searches: PairSearches,
    ) -> (Isometry3<f32>, f32) {
        let cached = CachedPair {
            template_from_source: answer.0,
            chamfer: answer.1,
            versions: self.versions_of(source, template),
            found_at,
            searches,
        };
        let mut answered = self.answered.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        answered.0.insert((source, template), cached);
        answer
    }

    /// The answer this registration already gave for the pair, if it did.
    fn answered_now(&self, source: ObjectId, template: ObjectId) -> Option<(Isometry3<f32>, f32)> {
        self.answered_pair(source, template)
            .map(|c| (c.template_from_source, c.chamfer))
    }

    fn answered_pair(&self, source: ObjectId, template: ObjectId) -> Option<CachedPair> {
        let answered = self.answered.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        answered.0.get(&(source, template)).copied()
    }

    /// The second search of member `source` to its representative `template`, keeping
    /// `keep_fraction` of the pairs ([`super::SecondSearch`]): the pair's answer in this
    /// registration becomes the better of the two searches, and the better alignment is returned
    /// when the second search found it. Nothing is searched for a pair this registration did not
    /// answer, or whose answer went through the second search already (on the same clouds, or
    /// kept from nearly the same ones).
    pub fn search_again(
        &self,
        source: ObjectId,
        template: ObjectId,
        keep_fraction: f32,
    ) -> Result<Option<(Isometry3<f32>, f32)>> {
        let Some(first) = self.answered_pair(source, template) else {
            return Ok(None);
        };
        if first.searches == PairSearches::Second {
            return Ok(None);
        }
        let cfg = RegistrationConfig {
            keep_fraction,
            ..self.cfg.clone()
        };
        let second = self.search_with(source, template, &cfg)?;
        let improved = second.score < first.chamfer;
        tracing::debug!(source = %source, template = %template, first = first.chamfer, second = second.score, "pair searched again");
        let (answer, found_at) = if improved {
            let now = self.points_now(source, template);
            ((second.template_from_source(), second.score), now)
        } else {
            ((first.template_from_source, first.chamfer), first.found_at)
        };
        let answer = self.record_after(source, template, answer, found_at, PairSearches::Second);
        Ok(improved.then_some(answer))
    }

    /// The full multi-start search (one random stream per ordered pair, so results do not depend
    /// on the order pairs are tried).
    fn search(&self, source: ObjectId, template: ObjectId) -> Result<crate::registration::Registration> {
        self.search_with(source, template, self.cfg)
    }

    fn search_with(
        &self,
        source: ObjectId,
        template: ObjectId,
        cfg: &RegistrationConfig,
    ) -> Result<crate::registration::Registration> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream((u64::from(source.0) << 32) | u64::from(template.0));
        let started = std::time::Instant::now();
        let found = register_to_representative(self.cloud(source)?, self.cloud(template)?, cfg, &mut rng)?;
        tracing::debug!(
            source = %source,
            template = %template,
            coarse_points = ?found.trace.coarse_points,
            fine_points = ?found.trace.fine_points,
            seconds = started.elapsed().as_secs_f64(),
            "pair searched"
        );
        Ok(found)
    }
}

impl ClassClouds<'_> {
    /// The pair's cloud sizes today.
    fn points_now(&self, source: ObjectId, template: ObjectId) -> PairPoints {
        let size = |id| self.sizes.get(&id).copied().unwrap_or(0);
        PairPoints {
            source: size(source),
            template: size(template),
        }
    }

    /// The pair's stored alignment, rescored on today's clouds, when neither cloud grew by more
    /// than `growth` since it was found (on nearly the same clouds the search would find the same
    /// alignment); `None` otherwise.
    fn kept(&self, source: ObjectId, template: ObjectId, now: PairPoints) -> Option<Result<(Isometry3<f32>, f32)>> {
        let stored = self.cache.0.get(&(source, template))?;
        if !stored.found_at.still_hold(now, self.growth) {
            return None;
        }
        let (s, t) = match (self.cloud(source), self.cloud(template)) {
            (Ok(s), Ok(t)) => (s, t),
            (Err(e), _) | (_, Err(e)) => return Some(Err(e)),
        };
        let pose = stored.template_from_source;
        let aligned: Vec<Point3<f32>> = s.iter().map(|p| pose * p).collect();
        Some(
            normalised_one_way_chamfer(&aligned, t)
                .map(|score| self.record_after(source, template, (pose, score), stored.found_at, stored.searches)),
        )
    }
}

impl PairRegistration for ClassClouds<'_> {
    fn register(&self, source: ObjectId, template: ObjectId) -> Result<(Isometry3<f32>, f32)> {
        if let Some(answer) = self.answered_now(source, template) {
            // Asked again in this registration (the best-explanation pass asks the greedy
            // pass's pairs again): the same clouds, the same answer.
            return Ok(answer);
        }
        let (s, t) = (self.cloud(source)?, self.cloud(template)?);
        let now = self.points_now(source, template);
        if let Some(cached) = self
            .cache
            .unchanged(source, template, self.versions_of(source, template))
        {
            // Both clouds as they were: the search would return exactly this.
            tracing::debug!(source = %source, template = %template, "pair unchanged");
            let answer = (cached.template_from_source, cached.chamfer);
            return Ok(self.record_after(source, template, answer, cached.found_at, cached.searches));
        }
        let previous = self.cache.0.get(&(source, template));
        if self.start == RegistrationStart::Reuse
            && let Some(answer) = self.kept(source, template, now)
        {
            return answer;
        }
        let warm = match previous {
            Some(stored) if self.start == RegistrationStart::Warm => {
                let warm = refine_registration(s, t, &stored.template_from_source, self.cfg)?;
                if warm_start_holds(warm.score, stored.chamfer, self.warm_tolerance) {
                    let answer = (warm.template_from_source(), warm.score);
                    return Ok(self.record(source, template, answer, now));
                }
                Some(warm)
            }
            _ => None,
        };
        let full = self.search(source, template)?;
        let best = match warm {
            Some(warm) if warm.score < full.score => warm,
            _ => full,
        };
        Ok(self.record(source, template, (best.template_from_source(), best.score), now))
    }

    /// The best-explanation pass's pairs keep their alignment while neither cloud grew by more
    /// than `reregister_growth` since it was found (as `reuse` does for every pair): which
    /// candidate explains a member best is decided on alignments at most that stale, and the
    /// greedy pass's pairs are searched as `start` says.
    fn register_again(&self, source: ObjectId, template: ObjectId) -> Result<(Isometry3<f32>, f32)> {
        if let Some(answer) = self.answered_now(source, template) {
            return Ok(answer);
        }
        let now = self.points_now(source, template);
        if self
            .cache
            .unchanged(source, template, self.versions_of(source, template))
            .is_none()
            && let Some(answer) = self.kept(source, template, now)
        {
            return answer;
        }
        self.register(source, template)
    }

    fn reverse_chamfer(
        &self,
        source: ObjectId,
        template: ObjectId,
        template_from_source: &Isometry3<f32>,
        points: ReversePoints,
    ) -> f32 {
        let lock = || self.reverse.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(&known) = lock().get(&(source, template, points)) {
            return known;
        }
        let (Ok(s), Ok(t)) = (self.cloud(source), self.cloud(template)) else {
            return f32::INFINITY;
        };
        let aligned: Vec<Point3<f32>> = s.iter().map(|p| template_from_source * p).collect();
        let looked = match points {
            ReversePoints::All => None,
            ReversePoints::LookedAt => self.space_of(source),
        };
        let distance = match looked {
            Some(space) => {
                let source_from_template = template_from_source.inverse();
                reverse_where_looked(t, &aligned, |p| space.looked_at(&(source_from_template * p)))
            }
            None => normalised_one_way_chamfer(t, &aligned).unwrap_or(f32::INFINITY),
        };
        lock().insert((source, template, points), distance);
        distance
    }
}

/// The normalised distance from `template` to `aligned` over the template points where
/// `looked_at` holds, divided by the scale of the whole template; over every point when fewer
/// than [`MIN_LOOKED_AT_SHARE`] of them qualify ([`ReversePoints::LookedAt`]).
fn reverse_where_looked(
    template: &[Point3<f32>],
    aligned: &[Point3<f32>],
    looked_at: impl Fn(&Point3<f32>) -> bool,
) -> f32 {
    let kept: Vec<Point3<f32>> = template.iter().copied().filter(|p| looked_at(p)).collect();
    if (kept.len() as f32) < MIN_LOOKED_AT_SHARE * template.len() as f32 || kept.is_empty() {
        return normalised_one_way_chamfer(template, aligned).unwrap_or(f32::INFINITY);
    }
    let scale = half_max_extent(template);
    match one_way_chamfer(&kept, aligned) {
        Ok(d) if scale > 0.0 => d / scale,
        _ => f32::INFINITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reverse_distance_reads_only_the_parts_the_member_looked_at() {
        // The template: a seat (z = 0) and a back (x = 0, z up to 1). The member: the seat only.
        let seat: Vec<Point3<f32>> = (0..=10)
            .flat_map(|i| (0..=10).map(move |j| Point3::new(i as f32 * 0.1, j as f32 * 0.1, 0.0)))
            .collect();
        let back: Vec<Point3<f32>> = (0..=10)
            .flat_map(|j| (1..=10).map(move |k| Point3::new(0.0, j as f32 * 0.1, k as f32 * 0.1)))
            .collect();
        let template: Vec<Point3<f32>> = seat.iter().chain(&back).copied().collect();
        // Views that saw the back's space free: the member lacks the back.
        let everything = reverse_where_looked(&template, &seat, |_| true);
        assert!(everything > 0.2, "the back is far from the seat: {everything}");
        // Views that never faced the back: its space lies behind the member's surface.
        let seen_from_above_only = reverse_where_looked(&template, &seat, |p| p.z < 0.05);
        assert!(seen_from_above_only < 1e-6, "{seen_from_above_only}");
        // Too few points looked at: every point is read.
        let corner_only = reverse_where_looked(&template, &seat, |p| p.x < 0.05 && p.y < 0.05 && p.z < 0.05);
        assert_eq!(corner_only, everything);
    }

    #[test]
    fn a_warm_start_holds_only_when_it_scores_no_worse_than_stored_within_tolerance() {
        assert!(warm_start_holds(0.05, 0.05, 0.1));
        assert!(warm_start_holds(0.055, 0.05, 0.1));
        assert!(!warm_start_holds(0.056, 0.05, 0.1));
        assert!(!warm_start_holds(f32::NAN, 0.05, 0.1));
        assert!(!warm_start_holds(f32::INFINITY, f32::INFINITY, 0.1));
    }
}
