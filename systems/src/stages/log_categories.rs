//! Rerun logging of the category phase: each category field's loss under
//! `training/loss/categories/{n}` (n: its creation number) and carving share under
//! `training/carving_share/categories/{n}`, and each member's code norms under
//! `training/shape_code_norm/objects/{id}` and `training/texture_code_norm/objects/{id}`, on the
//! `category_step` timeline.

use bevy_ecs::prelude::*;

use crate::components::CategorySlot;
use crate::components::Object;
use crate::recording::{Rerun, warn_on_error};
use crate::rerun_paths::{self as paths, CATEGORY_TIMELINE, OwnerEntity};
use crate::resources::CategoryFields;

/// Logs the latest losses and code norms (after each chunk of category steps).
pub fn log_category_training(rerun: Res<Rerun>, fields: Res<CategoryFields>, members: Query<(&Object, &CategorySlot)>) {
    if fields.steps_done == 0 {
        return;
    }
    rerun.0.set_time_sequence(CATEGORY_TIMELINE, fields.steps_done as i64);
    rerun
        .0
        .set_time(paths::WALL_CLOCK_TIMELINE, std::time::SystemTime::now());
    for (n, loss) in fields.ids.iter().zip(&fields.losses) {
        let path = paths::category_loss(*n);
        warn_on_error(
            rerun.0.log(path.as_str(), &rerun::Scalars::single(f64::from(*loss))),
            &path,
        );
    }
    for (n, counts) in fields.ids.iter().zip(&fields.carve).filter(|(_, c)| c.inside > 0) {
        let path = paths::category_carving_share(*n);
        warn_on_error(
            rerun.0.log(path.as_str(), &rerun::Scalars::single(counts.share())),
            &path,
        );
    }
    let norm = |code: Option<&[f32]>| code.map_or(0.0, |c| c.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>().sqrt());
    for (object, slot) in &members {
        let Some(field) = fields.batch.field(slot.field) else {
            continue;
        };
        for (name, value) in [
            (OwnerEntity::ShapeCodeNorm, norm(field.shape_code(slot.member))),
            (OwnerEntity::TextureCodeNorm, norm(field.texture_code(slot.member))),
        ] {
            let path = paths::of(Some(object.id), name);
            warn_on_error(rerun.0.log(path.as_str(), &rerun::Scalars::single(value)), &path);
        }
    }
}
