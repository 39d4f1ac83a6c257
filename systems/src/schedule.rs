//! The one place where the order of everything is defined: the stages of a tick, and which
//! phase of the run each runs in (`catmap::training::RunPhase`, kept as the [`CurrentPhase`]
//! resource and moved on by the tick's last stage).

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{LogLevel, ScheduleBuildSettings, SingleThreadedExecutor};
use catmap::training::RunPhase;

use crate::recording::Rerun;
use crate::resources::Settings;
use crate::run_state::{CurrentPhase, LiveTicks, TickRecord};
use crate::stages::categorize::update_categories;
use crate::stages::category_fields::{sync_category_fields, train_category_fields};
use crate::stages::cleanup::despawn_consumed_frames;
use crate::stages::clouds::{accumulate_clouds, refresh_object_bounds};
use crate::stages::ingest::ingest_frames;
use crate::stages::log_camera::log_camera_frames;
use crate::stages::log_categories::log_category_training;
use crate::stages::log_rerun::{
    log_field_losses, log_field_meshes, log_final_meshes, log_instance_legend, log_memberships, log_object_boxes,
    log_object_clouds, log_object_merges,
};
use crate::stages::log_stream::log_live_stream;
use crate::stages::merge::merge_objects;
use crate::stages::meshes::{extract_preview_meshes, final_meshes, warn_missing_meshes};
use crate::stages::register::register_categories;
use crate::stages::segment::observe_frames;
use crate::stages::tick::{advance_run_phase, queue_tick_steps, start_tick_clock, stop_train_clock};
use crate::stages::track::{record_background_views, record_object_views, spawn_new_objects};
use crate::stages::train::{attach_fields, train_fields};

/// The mapper's stages, in the order they run each tick.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MapperSystems {
    /// A live tick starts its clock.
    Tick,
    /// Frames leave the stream (while streaming).
    Ingest,
    /// Masks are split into per-object observations.
    Segment,
    /// Objects appear and take in their views.
    Track,
    /// Observed clouds grow, objects found to be one merge, oriented boxes follow.
    Map,
    /// Category membership follows object classes.
    Categorize,
    /// Fields appear for objects with a box; the steps the phase plans for the tick run.
    Train,
    /// Classes are (re-)registered: representatives, subcategories, NOCS frames; category
    /// fields follow where the phase trains them.
    Register,
    /// Preview meshes every few frames (while streaming).
    Mesh,
    /// Rerun logging (only when a `Rerun` resource exists).
    Log,
    /// Consumed frames are despawned.
    Cleanup,
    /// The final meshes (the meshing phase).
    FinalMeshes,
    /// The tick's phase records its progress; the run moves to the next phase.
    Phase,
}

/// Builds the mapper's schedule: single-threaded (rayon parallelises inside systems), with
/// ambiguity detection as an error so that every order is stated here. One schedule serves
/// every phase of the run; run conditions on [`CurrentPhase`] choose what a tick does.
pub fn build_schedule() -> Schedule {
    let mut schedule = Schedule::default();
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.set_build_settings(ScheduleBuildSettings {
        ambiguity_detection: LogLevel::Error,
        ..Default::default()
    });
    schedule.configure_sets(
        (
            MapperSystems::Tick,
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
            MapperSystems::FinalMeshes,
            MapperSystems::Phase,
        )
            .chain(),
    );
    // Objects get fields and classes register while frames come and in the training after
    // them; the camera and the map are logged while streaming.
    let (adding, streaming) = (
        in_phase(&[RunPhase::Stream, RunPhase::AfterStream]),
        in_phase(&[RunPhase::Stream]),
    );
    schedule.configure_sets(
        (
            MapperSystems::Ingest,
            MapperSystems::Segment,
            MapperSystems::Track,
            MapperSystems::Map,
            MapperSystems::Categorize,
            MapperSystems::Mesh,
            MapperSystems::Cleanup,
        )
            .run_if(streaming.clone()),
    );
    schedule.configure_sets(MapperSystems::Train.run_if(in_phase(TRAINING)));
    schedule.configure_sets(MapperSystems::Log.run_if(resource_exists::<Rerun>));
    schedule.configure_sets(MapperSystems::FinalMeshes.run_if(meshing));
    schedule.add_systems((
        start_tick_clock
            .run_if(resource_exists::<LiveTicks>)
            .in_set(MapperSystems::Tick),
        ingest_frames.in_set(MapperSystems::Ingest),
        observe_frames.in_set(MapperSystems::Segment),
        (spawn_new_objects, record_object_views, record_background_views)
            .chain()
            .in_set(MapperSystems::Track),
        (accumulate_clouds, merge_objects, refresh_object_bounds)
            .chain()
            .in_set(MapperSystems::Map),
        update_categories.in_set(MapperSystems::Categorize),
        (
            attach_fields.run_if(adding.clone()),
            queue_tick_steps,
            train_fields,
            train_category_fields,
            stop_train_clock.run_if(resource_exists::<LiveTicks>),
        )
            .chain()
            .in_set(MapperSystems::Train),
        (
            register_categories.run_if(adding.clone()),
            sync_category_fields.run_if(category_fields_follow),
        )
            .chain()
            .in_set(MapperSystems::Register),
        extract_preview_meshes.in_set(MapperSystems::Mesh),
        (
            (
                log_camera_frames,
                log_instance_legend,
                log_object_merges,
                log_object_clouds,
                log_object_boxes,
            )
                .chain()
                .run_if(streaming.clone()),
            log_field_losses.run_if(adding.clone()),
            log_field_meshes.run_if(streaming),
            log_memberships.run_if(adding.clone()),
            log_category_training.run_if(category_fields_trained_after_stream),
        )
            .chain()
            .in_set(MapperSystems::Log),
        (
            log_live_stream.run_if(resource_exists::<LiveTicks>),
            despawn_consumed_frames,
        )
            .chain()
            .in_set(MapperSystems::Cleanup),
        (
            final_meshes,
            log_final_meshes.run_if(resource_exists::<Rerun>),
            warn_missing_meshes,
        )
            .chain()
            .in_set(MapperSystems::FinalMeshes),
        advance_run_phase.in_set(MapperSystems::Phase),
    ));
    schedule
}

/// The phases whose ticks train.
const TRAINING: &[RunPhase] = &[
    RunPhase::Stream,
    RunPhase::AfterStream,
    RunPhase::CategorySetup,
    RunPhase::Categories,
];

/// Whether the run is in one of `phases`.
fn in_phase(phases: &'static [RunPhase]) -> impl FnMut(Res<CurrentPhase>) -> bool + Clone {
    move |phase| phases.contains(&phase.0)
}

/// Whether the category fields follow the registrations in this phase
/// (`catmap::training::PhasePlan::category_fields_follow`).
fn category_fields_follow(settings: Res<Settings>, phase: Res<CurrentPhase>) -> bool {
    settings.0.phase_plan().category_fields_follow(phase.0)
}

/// Whether this tick, after the stream, trained the category fields.
fn category_fields_trained_after_stream(phase: Res<CurrentPhase>, record: Res<TickRecord>) -> bool {
    phase.0 != RunPhase::Stream && record.steps.categories > 0
}

/// Whether the run meshes its fields now (a map without fields has nothing to mesh).
fn meshing(settings: Res<Settings>, phase: Res<CurrentPhase>) -> bool {
    phase.0 == RunPhase::Meshing && settings.0.fields.enabled
}
