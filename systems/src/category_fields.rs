//! Category phase (`catmap run --mode category`): once the classes are registered, every
//! subcategory with more than one member gets one category field (METHOD.md §5) whose members
//! are its objects, each sampled in its own NOCS frame; all category fields train as one batch.
//! Single-member subcategories keep their per-object fields.

use bevy_ecs::prelude::*;
use catmap::field::category::{CategoryBatch, CategoryField, CategorySamples};
use catmap::field::{AdamWConfig, sample_training_rays};
use catmap::nocs::NocsFrame;
use catmap::rng::{RngStream, seeded_rng};
use rayon::prelude::*;

use crate::components::{FieldRng, FieldSlot, Keyframes, Object, Subcategories};
use crate::resources::{Settings, StageTimes};

/// The category fields and their members.
#[derive(Resource, Debug)]
pub struct CategoryFields {
    /// One field per multi-member subcategory, trained together.
    pub batch: CategoryBatch,
    /// Per field, its members in code order.
    pub members: Vec<Vec<Entity>>,
    /// Steps queued and not yet run.
    pub pending: u64,
    /// Steps run.
    pub steps_done: u64,
    /// Latest total loss per field.
    pub losses: Vec<f32>,
}

impl CategoryFields {
    /// No fields yet.
    pub fn new(optimiser: AdamWConfig) -> Self {
        Self {
            batch: CategoryBatch::new(optimiser),
            members: Vec::new(),
            pending: 0,
            steps_done: 0,
            losses: Vec::new(),
        }
    }
}

/// A member's place in a category field.
#[derive(Component, Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CategorySlot {
    /// Index of the category field.
    pub field: usize,
    /// The member's code index.
    pub member: usize,
    /// The member's NOCS frame.
    pub nocs: NocsFrame,
}

/// Creates the category fields from the registered subcategories (classes in id order), once:
/// membership is fixed for the category phase.
pub fn attach_category_fields(
    settings: Res<Settings>,
    mut fields: ResMut<CategoryFields>,
    categories: Query<&Subcategories>,
    objects: Query<(Entity, &Object)>,
    mut commands: Commands,
) {
    let cfg = &settings.0.category_fields;
    if !cfg.enabled || !fields.members.is_empty() {
        return;
    }
    let entity_of: std::collections::BTreeMap<_, _> = objects.iter().map(|(e, o)| (o.id, e)).collect();
    let mut groups: Vec<_> = categories.iter().flat_map(|s| s.groups.iter()).collect();
    groups.sort_by_key(|g| g.representative);
    for group in groups.into_iter().filter(|g| g.members.len() > 1) {
        let k = fields.members.len();
        let mut rng = seeded_rng(settings.0.seed, RngStream::CategoryField(k as u32));
        let field = CategoryField::new(
            catmap::field::category::CATEGORY_HIDDEN,
            cfg.code_dim,
            1.0,
            group.members.len(),
            &mut rng,
        );
        fields.batch.push(field);
        let mut members = Vec::new();
        for (member, (id, registered)) in group.members.iter().enumerate() {
            let Some(&entity) = entity_of.get(id) else { continue };
            commands.entity(entity).insert(CategorySlot {
                field: k,
                member,
                nocs: registered.nocs,
            });
            members.push(entity);
        }
        tracing::info!(field = k, representative = %group.representative, members = members.len(), "category field created");
        fields.members.push(members);
    }
    let n = fields.members.len();
    fields.losses = vec![f32::NAN; n];
}

/// Runs the queued category steps: every member samples its rays from its keyframes (members in
/// parallel, each from its own generator), moves them into its NOCS frame, and all category
/// fields train in one batched step.
pub fn train_category_fields(
    settings: Res<Settings>,
    mut fields: ResMut<CategoryFields>,
    mut members: Query<(&Keyframes, &FieldSlot, &CategorySlot, &mut FieldRng)>,
    mut times: ResMut<StageTimes>,
) {
    if fields.pending == 0 || fields.members.is_empty() {
        fields.pending = 0;
        return;
    }
    let _timer = times.start("category_train");
    let rays_cfg = settings
        .0
        .fields
        .object_rays
        .with_rays_per_step(settings.0.category_fields.rays_per_member);
    let fields = &mut *fields;
    for _ in 0..std::mem::take(&mut fields.pending) {
        let mut work: Vec<_> = members.iter_mut().collect();
        work.sort_by_key(|(_, _, slot, _)| (slot.field, slot.member));
        let sampled: Vec<_> = work
            .par_iter_mut()
            .map(|(keyframes, field_slot, slot, rng)| {
                let window = &keyframes.0;
                let views: Vec<_> = window.slots().iter().map(|s| &s.data).collect();
                let rays =
                    sample_training_rays(&views, window.recent_slots(), &field_slot.origin, &rays_cfg, &mut rng.0);
                (slot.field, slot.member, field_slot.origin, slot.nocs, rays)
            })
            .collect();
        let mut samples = vec![CategorySamples::default(); fields.members.len()];
        for (field, member, origin, nocs, rays) in sampled {
            let nocs_from_world = nocs.world_from_nocs.inverse();
            if let Err(e) = samples[field].push_member_rays(rays, member, &origin, &nocs_from_world) {
                tracing::warn!(field, member, error = %e, "member rays skipped");
            }
        }
        match fields.batch.train_step(&samples) {
            Ok(losses) => fields.losses = losses.iter().map(|l| l.total).collect(),
            Err(e) => tracing::warn!(error = %e, "category training step skipped"),
        }
        fields.steps_done += 1;
    }
}
