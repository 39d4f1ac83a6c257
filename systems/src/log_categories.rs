//! Rerun logging of the category phase: each category field's loss under
//! `world/categories/{k}/loss`, and each member's code norms under
//! `world/objects/{id}/shape_code_norm` and `…/texture_code_norm`, on the `category_step` timeline.

use bevy_ecs::prelude::*;

use crate::components::CategorySlot;
use crate::components::Object;
use crate::log_rerun::{Rerun, paths, warn_on_error};
use crate::resources::CategoryFields;

/// The timeline of the category phase.
pub const CATEGORY_TIMELINE: &str = "category_step";

/// Logs the latest losses and code norms (after each chunk of category steps).
pub fn log_category_training(rerun: Res<Rerun>, fields: Res<CategoryFields>, members: Query<(&Object, &CategorySlot)>) {
    if fields.steps_done == 0 {
        return;
    }
    rerun.0.set_time_sequence(CATEGORY_TIMELINE, fields.steps_done as i64);
    for (k, loss) in fields.losses.iter().enumerate() {
        let path = format!("world/categories/{k}/loss");
        warn_on_error(
            rerun.0.log(path.as_str(), &rerun::Scalars::single(f64::from(*loss))),
            &path,
        );
    }
    let norm = |code: Option<&[f32]>| code.map_or(0.0, |c| c.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>().sqrt());
    for (object, slot) in &members {
        let Some(field) = fields.batch.field(slot.field) else {
            continue;
        };
        for (name, value) in [
            ("shape_code_norm", norm(field.shape_code(slot.member))),
            ("texture_code_norm", norm(field.texture_code(slot.member))),
        ] {
            let path = format!("{}/{name}", paths::object(object.id));
            warn_on_error(rerun.0.log(path.as_str(), &rerun::Scalars::single(value)), &path);
        }
    }
}
