//! The map's category fields (METHOD.md §5): one per subcategory with more than one member,
//! trained as one batch. While streaming, every re-registration may change the membership; the
//! set then follows the [`field_plan`](super::field_plan): a subcategory continues the field it
//! shares most members with (network and kept codes), members new to a field get fresh codes,
//! and a field that fails to remap starts over. Single-member subcategories keep their
//! per-object fields.

use std::collections::BTreeMap;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::class_registration::RegisteredSubcategory;
use super::field_plan::{PlannedField, plan_category_fields};
use super::held_frames::{FrameHoldConfig, FramePolicy, FrameSymmetry, frame_change};
use super::nocs::NocsFrame;
use crate::error::Result;
use crate::field::AdamWConfig;
use crate::field::category::CategoryFieldConfig;
use crate::field::category::{CATEGORY_HIDDEN, CategoryBatch, CategoryField, CategorySamples, MemberCodes};
use crate::field::free_space::CarveCounts;
use crate::field::{RaySamplerConfig, RaySamples};
use crate::ids::{FrameIndex, ObjectId};
use crate::rng::{RngStream, seeded_rng};
use crate::training::{BatchPlan, FieldFacts, LastSeen, StreamPhase, category_field_facts};

/// Where a member sits in the category fields: its field, its code, its NOCS frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MemberPlace {
    /// Index of its field in the batch.
    pub field: usize,
    /// Its member (code) index in that field.
    pub member: usize,
    /// Its normalised frame at the latest registration.
    pub nocs: NocsFrame,
}

/// Rays a member sampled for one step of its category field (in the world frame, relative to
/// its own field's origin).
#[derive(Debug, Clone)]
pub struct MemberRays {
    /// Its place in the category fields.
    pub place: MemberPlace,
    /// The origin of its per-object field (the rays' frame).
    pub origin: Point3<f32>,
    /// The rays.
    pub rays: RaySamples,
}

/// The category fields and what they are keyed and seeded by.
#[derive(Debug)]
pub struct CategoryFieldSet {
    /// One field per multi-member subcategory, trained together.
    pub batch: CategoryBatch,
    /// Per field, its members in code order.
    pub members: Vec<Vec<ObjectId>>,
    /// Per field, its creation number (its key in the step scheduler; kept while the field
    /// continues under a new membership).
    pub ids: Vec<u32>,
    /// Latest total loss per field.
    pub losses: Vec<f32>,
    /// Per field, its members' samples inside their meshed boxes and how many carved free space,
    /// since its membership last changed.
    pub carve: Vec<CarveCounts>,
    /// Fields created so far (seeds the next one's generator).
    pub fields_created: u32,
    /// Membership changes applied so far (seeds the fresh codes of the next one).
    pub remaps: u32,
    /// Every member's place after the latest [`follow`](Self::follow).
    pub places: BTreeMap<ObjectId, MemberPlace>,
    /// Members whose frame a registration replaced while they stayed in their field (each got a
    /// fresh code), so far.
    pub frames_replaced: u32,
    /// Fields a membership change ended, in the order it happened.
    pub retired: Vec<RetiredField>,
}

/// A category field a membership change ended.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RetiredField {
    /// Its creation number.
    pub id: u32,
    /// Its members then, in code order.
    pub members: Vec<ObjectId>,
    /// The membership change that ended it (1 = the first).
    pub remap: u32,
    /// Why.
    pub cause: Retirement,
}

/// Why a category field ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Retirement {
    /// No subcategory of the new membership continued it.
    Dropped,
    /// Its codes could not be remapped; a fresh field took its members.
    Restarted,
}

impl CategoryFieldSet {
    /// No fields yet.
    pub fn new(optimiser: AdamWConfig) -> Self {
        Self {
            batch: CategoryBatch::new(optimiser),
            members: Vec::new(),
            ids: Vec::new(),
            losses: Vec::new(),
            carve: Vec::new(),
            fields_created: 0,
            remaps: 0,
            places: BTreeMap::new(),
            frames_replaced: 0,
            retired: Vec::new(),
        }
    }

    /// Brings the fields in step with `subcategories` (every class's, in any order; fields are
    /// ordered by representative) and returns every member's place. Fields are created from
    /// `seed` with `codes`; nothing changes when the membership did not. A
    /// member whose frame moved beyond `frames`' tolerance gets a fresh code (`held_frames`).
    pub fn follow<'a>(
        &mut self,
        subcategories: impl IntoIterator<Item = &'a RegisteredSubcategory>,
        seed: u64,
        codes: MemberCodes,
        frames: &FrameHoldConfig,
    ) -> BTreeMap<ObjectId, MemberPlace> {
        let mut groups: Vec<&RegisteredSubcategory> =
            subcategories.into_iter().filter(|g| g.members.len() > 1).collect();
        groups.sort_by_key(|g| g.representative);
        let wanted: Vec<Vec<ObjectId>> = groups.iter().map(|g| g.members.keys().copied().collect()).collect();
        let nocs: BTreeMap<ObjectId, NocsFrame> = groups.iter().flat_map(|g| g.frames()).collect();
        let moved = self.moved_frames(&nocs, frames);
        if wanted != self.members || !moved.is_empty() {
            let mut plan = plan_category_fields(&self.members, &wanted);
            for field in &mut plan {
                for (id, code) in field.members.iter().zip(&mut field.codes) {
                    if moved.contains(id) && code.take().is_some() {
                        self.frames_replaced += 1;
                        tracing::info!(object = %id, "member's frame replaced: fresh code");
                    }
                }
            }
            self.apply_plan(&plan, seed, codes);
            if wanted != self.members {
                self.members = wanted;
                self.losses = vec![f32::NAN; self.members.len()];
                self.carve = vec![CarveCounts::default(); self.members.len()];
            }
        }
        let mut places = BTreeMap::new();
        for (field, members) in self.members.iter().enumerate() {
            for (member, id) in members.iter().enumerate() {
                if let Some(&nocs) = nocs.get(id) {
                    places.insert(*id, MemberPlace { field, member, nocs });
                }
            }
        }
        self.places.clone_from(&places);
        places
    }

    /// The members whose frame in `nocs` lies beyond `cfg`'s tolerance of the one they train in
    /// now (none when frames are rebuilt at every registration).
    fn moved_frames(&self, nocs: &BTreeMap<ObjectId, NocsFrame>, cfg: &FrameHoldConfig) -> Vec<ObjectId> {
        if cfg.policy == FramePolicy::Rebuild {
            return Vec::new();
        }
        nocs.iter()
            .filter(|(id, frame)| {
                self.places
                    .get(id)
                    .is_some_and(|p| !frame_change(&p.nocs, frame, FrameSymmetry::None).within(cfg))
            })
            .map(|(id, _)| *id)
            .collect()
    }

    /// Rebuilds the batch as `plan` says: continued fields keep their network and remap their
    /// codes (a field whose remap fails starts over), the others start fresh.
    fn apply_plan(&mut self, plan: &[PlannedField], seed: u64, codes: MemberCodes) {
        let mut old: Vec<Option<CategoryField>> = Vec::new();
        while let Some(field) = self.batch.remove(0) {
            old.push(Some(field));
        }
        let mut codes_rng = seeded_rng(seed, RngStream::CategoryCodes(self.remaps));
        self.remaps += 1;
        let old_ids = std::mem::take(&mut self.ids);
        for planned in plan {
            let continued = planned
                .continues
                .and_then(|i| Some((old.get_mut(i).and_then(Option::take)?, *old_ids.get(i)?, i)));
            let (field, id) = match continued {
                Some((mut field, id, i)) => match field.remap_members(&planned.codes, &mut codes_rng) {
                    Ok(()) => (field, id),
                    Err(e) => {
                        tracing::warn!(error = %e, "category field restarted");
                        self.retire(id, i, Retirement::Restarted);
                        self.new_field(seed, codes, planned.members.len())
                    }
                },
                None => self.new_field(seed, codes, planned.members.len()),
            };
            self.batch.push(field);
            self.ids.push(id);
            tracing::info!(
                field = self.batch.len() - 1,
                members = ?planned.members,
                continues = ?planned.continues,
                "category field"
            );
        }
        for (i, field) in old.iter().enumerate() {
            if let (Some(_), Some(&id)) = (field, old_ids.get(i)) {
                self.retire(id, i, Retirement::Dropped);
            }
        }
    }

    /// Records that field `id` (index `index` before this membership change) ended.
    fn retire(&mut self, id: u32, index: usize, cause: Retirement) {
        let members = self.members.get(index).cloned().unwrap_or_default();
        tracing::info!(field = id, ?members, ?cause, "category field ended");
        self.retired.push(RetiredField {
            id,
            members,
            remap: self.remaps,
            cause,
        });
    }

    /// A fresh category field (the next one created) with `members` members, and its number.
    fn new_field(&mut self, seed: u64, codes: MemberCodes, members: usize) -> (CategoryField, u32) {
        let id = self.fields_created;
        let mut rng = seeded_rng(seed, RngStream::CategoryField(id));
        self.fields_created += 1;
        (
            CategoryField::new(CATEGORY_HIDDEN, codes.dim, 1.0, members, &mut rng).with_shape_codes(codes.shape),
            id,
        )
    }

    /// The step scheduler's facts of every field, from when each member was last seen
    /// (`(field, last seen)` pairs, any order).
    pub fn facts(
        &self,
        members_last_seen: impl IntoIterator<Item = (usize, LastSeen)>,
        phase: StreamPhase,
        this_tick: &[FrameIndex],
    ) -> Vec<(usize, FieldFacts)> {
        let mut last_seen: Vec<Vec<Option<LastSeen>>> = vec![Vec::new(); self.members.len()];
        for (field, seen) in members_last_seen {
            if let Some(list) = last_seen.get_mut(field) {
                list.push(Some(seen));
            }
        }
        self.ids
            .iter()
            .zip(last_seen)
            .map(|(&id, seen)| category_field_facts(id, seen, phase, this_tick))
            .enumerate()
            .collect()
    }

    /// Per field, how its members draw their rays for a step in a map of `objects` objects:
    /// `object_rays` with the rays per member the category-field settings give (the
    /// reference's budget shares a category's rays among its members).
    pub fn member_rays(
        &self,
        objects: usize,
        cfg: &CategoryFieldConfig,
        object_rays: &RaySamplerConfig,
    ) -> Vec<RaySamplerConfig> {
        let member_count: usize = self.members.iter().map(Vec::len).sum();
        let categories = self.members.len() + objects.saturating_sub(member_count);
        self.members
            .iter()
            .map(|m| object_rays.with_rays_per_step(cfg.rays_per_member(m.len(), objects, categories)))
            .collect()
    }

    /// One step of the fields `plan` names, on the rays their members sampled (any order; they
    /// join their field's samples in member order): moves each member's rays into its NOCS frame (a member whose rays do not fit is skipped,
    /// with a warning), trains, and records the losses and carving counts. Returns each planned field's total
    /// loss, in plan order.
    pub fn train_step(&mut self, plan: &BatchPlan, mut sampled: Vec<MemberRays>) -> Result<Vec<f32>> {
        sampled.sort_by_key(|m| (m.place.field, m.place.member));
        let active = &plan.indices;
        let mut samples = vec![CategorySamples::default(); active.len()];
        for MemberRays { place, origin, rays } in sampled {
            let Ok(k) = active.binary_search(&place.field) else {
                continue;
            };
            if let Some(c) = self.carve.get_mut(place.field) {
                *c = *c + rays.carve;
            }
            let nocs_from_world = place.nocs.world_from_nocs.inverse();
            if let Err(e) = samples[k].push_member_rays(rays, place.member, &origin, &nocs_from_world) {
                tracing::warn!(field = place.field, member = place.member, error = %e, "member rays skipped");
            }
        }
        let losses = self
            .batch
            .train_step_scaled(active, &plan.learning_rate_scales, &samples)?;
        Ok(active
            .iter()
            .zip(losses)
            .map(|(&k, loss)| {
                self.losses[k] = loss.total;
                loss.total
            })
            .collect())
    }
}

#[cfg(test)]
#[path = "field_set_tests.rs"]
mod tests;
