//! The streaming mapper end to end: frames pushed and streamed, degenerate scenes, checkpoints,
//! the Rerun recording, category fields while streaming.
//!
//! One test binary of modules (a binary per file would link the whole dependency set once each).

mod checkpoint_resume;
mod degenerate_scenes;
mod mapper_pipeline;
mod online_category;
mod rerun_recording;
