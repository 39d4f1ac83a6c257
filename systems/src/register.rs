//! Register stage: a class's representative, its members' registrations and its subcategories are
//! recomputed when the class gains a member or a member's cloud has grown enough — not every
//! frame. Members wait until their fields have trained (uncertainty needs a trained field).

use std::collections::BTreeMap;
use std::time::Instant;

use bevy_ecs::prelude::*;
use catmap::categories::class_registration::{ClassRegistration, MemberInput, class_is_due, register_class};
use catmap::categories::uncertainty::{UncertaintyStamp, object_reliability};
use catmap::geometry::mesh::Aabb;
use catmap::rng::{RngStream, seeded_rng};
use catmap::{ClassId, ObjectId};
use nalgebra::Point3;
use rayon::prelude::*;

use crate::components::{
    Category, FieldLoss, FieldSlot, Membership, Object, ObjectBounds, ObjectCloud, Reliability, Subcategories,
};
use crate::resources::{Fields, ObjectIndex, Settings, StageTimes};

/// What one member contributes, read from its components.
struct Ready {
    entity: Entity,
    id: ObjectId,
    cloud: Vec<Point3<f32>>,
    cloud_version: u64,
    bounds: catmap::geometry::oriented_box::OrientedBox,
    slot: FieldSlot,
    stamp: UncertaintyStamp,
    /// Its sphere from an earlier registration, if one was evaluated.
    stored: Option<Reliability>,
}

/// Re-registers every class whose membership changed or whose members' clouds grew by more than
/// `categories.reregister_growth` since its last registration (classes in id order). A member's
/// uncertainty sphere is evaluated again only when its cloud or field changed materially; a pair
/// registered before starts as `categories.registration_start` says.
pub fn register_categories(
    settings: Res<Settings>,
    fields: Res<Fields>,
    index: Res<ObjectIndex>,
    mut categories: Query<(Entity, &Category, Option<&mut Subcategories>)>,
    objects: Query<(
        &Object,
        &ObjectCloud,
        Option<&ObjectBounds>,
        Option<&FieldSlot>,
        Option<&FieldLoss>,
        Option<&Reliability>,
    )>,
    mut times: ResMut<StageTimes>,
    mut commands: Commands,
) {
    let cfg = &settings.0.categories;
    if !cfg.enabled || !settings.0.fields.enabled {
        return;
    }
    let steps_needed = settings.0.field_steps_before_registration();
    let mut due: Vec<(Entity, ClassId, Vec<Ready>, ClassRegistration)> = Vec::new();
    for (entity, category, previous) in &categories {
        let mut ready = Vec::new();
        for id in &category.members {
            let Some((object, cloud, Some(bounds), Some(slot), Some(loss), stored)) =
                index.0.get(id).and_then(|e| objects.get(*e).ok())
            else {
                break;
            };
            if loss.steps < steps_needed {
                break;
            }
            ready.push(Ready {
                entity: index.0[&object.id],
                id: object.id,
                cloud: Vec::new(), // filled only when the class is due
                cloud_version: cloud.0.points_added(),
                bounds: bounds.oriented_box,
                slot: *slot,
                stamp: UncertaintyStamp {
                    cloud_points: cloud.0.len(),
                    field_steps: loss.steps,
                },
                stored: stored.cloned(),
            });
        }
        if ready.len() < category.members.len() {
            continue; // wait until every member has a trained field
        }
        let sizes: Vec<(ObjectId, usize)> = ready.iter().map(|r| (r.id, r.stamp.cloud_points)).collect();
        if class_is_due(
            previous.as_ref().map(|p| &p.registered_points),
            &sizes,
            cfg.reregister_growth,
        ) {
            for r in &mut ready {
                if let Ok((_, cloud, ..)) = objects.get(r.entity) {
                    r.cloud = cloud.0.points();
                }
            }
            let previous = previous.map_or_else(ClassRegistration::default, |p| ClassRegistration {
                groups: p.groups.clone(),
                pairs: p.pairs.clone(),
            });
            due.push((entity, category.class, ready, previous));
        }
    }
    if due.is_empty() {
        return;
    }
    let seed = settings.0.seed;
    for (category_entity, class, ready, previous) in due {
        // Uncertainty spheres (only needed to rank several members; kept while they still hold).
        let started = Instant::now();
        let reliabilities: Vec<Option<Reliability>> = if ready.len() > 1 {
            ready
                .par_iter()
                .map(|r| {
                    if let Some(stored) = r
                        .stored
                        .as_ref()
                        .filter(|s| s.stamp.still_describes(&r.stamp, cfg.uncertainty_refresh_growth))
                    {
                        return Some(stored.clone());
                    }
                    let field = fields.objects.field(r.slot.index)?;
                    // The sphere around the observed cloud's world-axis box (METHOD.md §3).
                    let aabb = Aabb::from_points(&r.cloud)?;
                    let mut rng = seeded_rng(seed, RngStream::ObjectField(r.id));
                    let sphere = object_reliability(
                        &aabb.center(),
                        &(aabb.extent() * 0.5),
                        &cfg.uncertainty,
                        &mut rng,
                        |points| field.eval_alpha_world(&r.slot.origin, points),
                    );
                    Some(Reliability { sphere, stamp: r.stamp })
                })
                .collect()
        } else {
            vec![None]
        };
        times.add("uncertainty", started.elapsed());
        let started = Instant::now();
        let inputs: Vec<MemberInput> = ready
            .iter()
            .zip(&reliabilities)
            .map(|(r, rel)| MemberInput {
                id: r.id,
                cloud: r.cloud.clone(),
                cloud_version: r.cloud_version,
                bounds: r.bounds,
                reliable_rays: rel.as_ref().map_or(0, |x| x.sphere.reliable_rays),
            })
            .collect();
        let class_seed = seed ^ (u64::from(class.0) << 32);
        let registered = register_class(&inputs, &previous, cfg, class_seed);
        times.add("register", started.elapsed());
        let ClassRegistration { groups, pairs } = match registered {
            Ok(registered) => registered,
            Err(e) => {
                tracing::warn!(class = %class, error = %e, "class registration failed");
                continue;
            }
        };
        for (r, rel) in ready.iter().zip(reliabilities) {
            if let Some(reliability) = rel
                && r.stored.as_ref() != Some(&reliability)
            {
                commands.entity(r.entity).insert(reliability);
            }
        }
        for (k, group) in groups.iter().enumerate() {
            for (id, member) in &group.members {
                if let Some(r) = ready.iter().find(|r| r.id == *id) {
                    commands.entity(r.entity).insert(Membership {
                        class,
                        subcategory: k,
                        representative: group.representative,
                        member: *member,
                    });
                }
            }
        }
        let summary: Vec<(ObjectId, Vec<ObjectId>)> = groups
            .iter()
            .map(|g| (g.representative, g.members.keys().copied().collect()))
            .collect();
        tracing::info!(class = %class, subcategories = ?summary, "class registered");
        let registered_points: BTreeMap<ObjectId, usize> = ready.iter().map(|r| (r.id, r.stamp.cloud_points)).collect();
        let record = Subcategories {
            groups,
            registered_points,
            pairs,
        };
        match categories.get_mut(category_entity) {
            Ok((_, _, Some(mut previous))) => *previous = record,
            _ => {
                commands.entity(category_entity).insert(record);
            }
        }
    }
}
