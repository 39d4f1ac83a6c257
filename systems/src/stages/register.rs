//! Register stage: a class's representative, its members' registrations and its subcategories are
//! recomputed when the class gains a member or a member's cloud has grown enough — not every
//! frame (`catmap::categories::class_update`). Members wait until their fields have trained.

use bevy_ecs::prelude::*;
use catmap::categories::class_registration::ClassRegistration;
use catmap::categories::class_update::{
    ClassMember, ClassReadiness, ClassUpdate, MemberField, class_readiness, update_class,
};
use catmap::objects::object_bounds::ShapeRule;
use catmap::{ClassId, ObjectId};

use crate::components::{
    Category, FieldLoss, FieldSlot, Keyframes, Membership, ObjectBounds, ObjectCloud, Reliability, Subcategories,
};
use crate::resources::{Fields, ObjectIndex, Settings, StageTimes};

/// The components a class member contributes.
type MemberParts = (
    &'static ObjectCloud,
    &'static ObjectBounds,
    &'static FieldSlot,
    &'static FieldLoss,
    Option<&'static Reliability>,
    &'static Keyframes,
);

/// Re-registers every class that is due (classes in id order) and writes its subcategories, its
/// members' memberships and their new uncertainty spheres.
pub fn register_categories(
    settings: Res<Settings>,
    fields: Res<Fields>,
    index: Res<ObjectIndex>,
    mut categories: Query<(Entity, &Category, Option<&mut Subcategories>)>,
    objects: Query<MemberParts>,
    mut times: ResMut<StageTimes>,
    mut commands: Commands,
) {
    let config = &settings.0;
    if !config.categories.enabled || !config.fields.enabled {
        return;
    }
    let due = Due {
        steps: config.field_steps_before_registration(),
        growth: config.categories.reregister_growth,
        shape: config.objects.shape_rule(),
    };
    let registration = &config.categories;
    for (entity, category, previous) in &mut categories {
        let class = category.class;
        let Some((members, last)) = due_class(category, previous.as_deref(), &index, &objects, &due) else {
            continue;
        };
        match update_class(class, &members, &last, &fields.objects, registration, config.seed) {
            Ok(update) => {
                times.add("uncertainty", update.uncertainty_time);
                times.add("register", update.register_time);
                let record = write_back(class, update, &index, &mut commands);
                match previous {
                    Some(mut previous) => *previous = record,
                    None => {
                        commands.entity(entity).insert(record);
                    }
                }
            }
            Err(e) => tracing::warn!(class = %class, error = %e, "class registration failed"),
        }
    }
}

/// When a class is due for registration, and what its members' shapes leave out.
struct Due {
    /// Field steps every member needs first.
    steps: u64,
    /// Cloud growth that registers a class again.
    growth: f32,
    /// Which cloud voxels make a member's shape (`objects.box_min_voxel_points`,
    /// `objects.shape_voxels`).
    shape: ShapeRule,
}

/// The class's members and its latest registration when the class is due for registration
/// (`class_readiness`); `None` otherwise.
fn due_class<'a>(
    category: &Category,
    previous: Option<&Subcategories>,
    index: &ObjectIndex,
    objects: &'a Query<MemberParts>,
    due: &Due,
) -> Option<(Vec<ClassMember<'a>>, ClassRegistration)> {
    let members: Vec<_> = category
        .members
        .iter()
        .map(|id| class_member(*id, index, objects, due.shape))
        .collect();
    let registered = previous.map(|p| &p.registered_points);
    if class_readiness(&members, registered, due.steps, due.growth) != ClassReadiness::Due {
        return None;
    }
    let last = previous.map_or_else(ClassRegistration::default, |p| p.registration());
    Some((members.into_iter().flatten().collect(), last))
}

/// Member `id` as registration reads it: `None` until it has a box and a field.
fn class_member<'a>(
    id: ObjectId,
    index: &ObjectIndex,
    objects: &'a Query<MemberParts>,
    shape: ShapeRule,
) -> Option<ClassMember<'a>> {
    let (cloud, bounds, slot, loss, stored, keyframes) = objects.get(*index.0.get(&id)?).ok()?;
    Some(ClassMember {
        id,
        cloud: &cloud.0,
        shape,
        bounds: bounds.oriented_box,
        field: MemberField {
            index: slot.index,
            origin: slot.origin,
            steps: loss.steps,
        },
        stored: stored.map(|r| &r.0),
        keyframes: Some(&keyframes.0),
    })
}

/// Inserts the members' new spheres and memberships; returns the class's new record.
fn write_back(class: ClassId, update: ClassUpdate, index: &ObjectIndex, commands: &mut Commands) -> Subcategories {
    for (id, reliability) in update.new_reliabilities {
        commands.entity(index.0[&id]).insert(Reliability(reliability));
    }
    let groups = update.registration.groups;
    for (subcategory, group) in groups.iter().enumerate() {
        for (id, member) in &group.members {
            commands.entity(index.0[id]).insert(Membership {
                class,
                subcategory,
                representative: group.representative,
                member: *member,
            });
        }
    }
    let summary: Vec<(ObjectId, Vec<ObjectId>)> = groups
        .iter()
        .map(|g| (g.representative, g.members.keys().copied().collect()))
        .collect();
    tracing::info!(class = %class, subcategories = ?summary, "class registered");
    Subcategories {
        groups,
        registered_points: update.registered_points,
        pairs: update.registration.pairs,
    }
}
