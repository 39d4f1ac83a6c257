//! The one place where stage order is defined.

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, SingleThreadedExecutor};

use crate::stages::categorize::update_categories;
use crate::stages::category_fields::{sync_category_fields, train_category_fields};
use crate::stages::cleanup::despawn_consumed_frames;
use crate::stages::clouds::{accumulate_clouds, refresh_object_bounds};
use crate::stages::ingest::ingest_frames;
use crate::stages::log_camera::log_camera_frames;
use crate::stages::log_categories::log_category_training;
use crate::stages::log_rerun::{
    Rerun, log_field_losses, log_field_meshes, log_instance_legend, log_memberships, log_object_boxes,
    log_object_clouds,
};
use crate::stages::meshes::extract_preview_meshes;
use crate::stages::register::register_categories;
use crate::stages::segment::observe_frames;
use crate::stages::track::{record_background_views, record_object_views, spawn_new_objects};
use crate::stages::train::{attach_fields, queue_online_steps, train_fields};

/// The mapper's stages, in the order they run each tick.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MapperSystems {
    /// Frames leave the stream.
    Ingest,
    /// Masks are split into per-object observations.
    Segment,
    /// Objects appear and take in their views.
    Track,
    /// Observed clouds and oriented boxes grow.
    Map,
    /// Category membership follows object classes.
    Categorize,
    /// Fields appear for objects with a box; queued training steps run.
    Train,
    /// Classes are (re-)registered: representatives, subcategories, NOCS frames.
    Register,
    /// Preview meshes every few frames.
    Mesh,
    /// Rerun logging (only when a `Rerun` resource exists).
    Log,
    /// Consumed frames are despawned.
    Cleanup,
}

/// Builds the mapper's schedule: single-threaded (rayon parallelises inside systems), with
/// ambiguity detection as an error so that every order is stated here.
pub fn build_schedule() -> Schedule {
    let mut schedule = Schedule::default();
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.set_build_settings(ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..Default::default()
    });
    schedule.configure_sets(
        (
            MapperSystems::Ingest,
            MapperSystems::Segment,
            MapperSystems::Track,
            MapperSystems::Map,
            MapperSystems::Categorize,
            MapperSystems::Train,
            MapperSystems::Register,
            MapperSystems::Mesh,
            MapperSystems::Log,
            MapperSystems::Cleanup,
        )
            .chain(),
    );
    schedule.configure_sets(MapperSystems::Log.run_if(resource_exists::<Rerun>));
    schedule.add_systems((
        ingest_frames.in_set(MapperSystems::Ingest),
        observe_frames.in_set(MapperSystems::Segment),
        (spawn_new_objects, record_object_views, record_background_views)
            .chain()
            .in_set(MapperSystems::Track),
        (accumulate_clouds, refresh_object_bounds)
            .chain()
            .in_set(MapperSystems::Map),
        update_categories.in_set(MapperSystems::Categorize),
        (attach_fields, queue_online_steps, train_fields, train_category_fields)
            .chain()
            .in_set(MapperSystems::Train),
        (register_categories, sync_category_fields.run_if(online_category_mode))
            .chain()
            .in_set(MapperSystems::Register),
        extract_preview_meshes.in_set(MapperSystems::Mesh),
        (
            log_camera_frames,
            log_instance_legend,
            log_object_clouds,
            log_object_boxes,
            log_field_losses,
            log_field_meshes,
            log_memberships,
        )
            .chain()
            .in_set(MapperSystems::Log),
        despawn_consumed_frames.in_set(MapperSystems::Cleanup),
    ));
    schedule
}

/// Whether category fields follow the registrations while streaming (category mode, online).
fn online_category_mode(settings: Res<crate::resources::Settings>) -> bool {
    settings.0.category_fields.enabled && !settings.0.fields.offline
}

/// The schedule of offline training: fields for objects that lack one, the queued steps, and
/// loss logging.
pub fn build_training_schedule() -> Schedule {
    let mut schedule = Schedule::default();
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.add_systems((
        (attach_fields, train_fields, register_categories).chain(),
        (log_field_losses, log_memberships)
            .chain()
            .after(register_categories)
            .run_if(resource_exists::<Rerun>),
    ));
    schedule
}

/// The category phase: category fields from the registered subcategories, then their steps
/// beside the per-object fields' (objects outside any category field keep training).
pub fn build_category_schedule() -> Schedule {
    let mut schedule = Schedule::default();
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.add_systems((
        (sync_category_fields, ApplyDeferred, train_fields, train_category_fields).chain(),
        log_category_training
            .after(train_category_fields)
            .run_if(resource_exists::<Rerun>),
    ));
    schedule
}

/// The fast schedule's phase after the stream (online, category mode): the per-object and the
/// category fields train together as the step scheduler plans; classes still due are
/// registered and the category fields follow the registrations.
pub fn build_after_stream_schedule() -> Schedule {
    let mut schedule = Schedule::default();
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.add_systems((
        (
            attach_fields,
            train_fields,
            train_category_fields,
            register_categories,
            sync_category_fields,
        )
            .chain(),
        (log_field_losses, log_memberships, log_category_training)
            .chain()
            .after(sync_category_fields)
            .run_if(resource_exists::<Rerun>),
    ));
    schedule
}
