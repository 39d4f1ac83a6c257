//! The streaming mapper end to end: frames pushed and streamed, degenerate scenes, checkpoints,
//! the Rerun recording, category fields while streaming, the run's phases, live replay.

mod checkpoint_resume;
mod degenerate_scenes;
mod failed_step;
mod live_mapping;
mod mapper_pipeline;
mod object_merges;
mod online_category;
mod rerun_recording;
mod run_phases;
