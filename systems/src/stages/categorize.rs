//! Categorize stage: one category entity per class, listing its objects.

use bevy_ecs::prelude::*;
use catmap::{ClassId, ObjectId};

use crate::components::{Category, Object, ObjectClass};
use crate::resources::CategoryIndex;

/// Rebuilds category membership when an object appears, its majority class changes or it was
/// merged into another (its entity gone); spawns a
/// category entity for each class seen for the first time.
pub fn update_categories(
    changed: Query<(), Changed<ObjectClass>>,
    mut merged: RemovedComponents<Object>,
    objects: Query<(&Object, &ObjectClass)>,
    mut categories: Query<&mut Category>,
    mut index: ResMut<CategoryIndex>,
    mut commands: Commands,
) {
    let merged = merged.read().count() > 0;
    if changed.is_empty() && !merged {
        return;
    }
    let mut members: std::collections::BTreeMap<ClassId, Vec<ObjectId>> = std::collections::BTreeMap::new();
    for (object, class) in &objects {
        members.entry(class.0).or_default().push(object.id);
    }
    for (class, entity) in &index.0 {
        if let Ok(mut category) = categories.get_mut(*entity) {
            let list = members.remove(class).unwrap_or_default();
            category.set_if_neq(Category {
                class: *class,
                members: sorted(list),
            });
        }
    }
    for (class, list) in members {
        let entity = commands
            .spawn(Category {
                class,
                members: sorted(list),
            })
            .id();
        tracing::debug!(class = %class, "new category");
        index.0.insert(class, entity);
    }
}

fn sorted(mut ids: Vec<ObjectId>) -> Vec<ObjectId> {
    ids.sort_unstable();
    ids
}
