//! The synthetic scenes and the metrics that score maps against them.
//!
//! One test binary of modules (a binary per file would link the whole dependency set once each).

mod metrics_eval;
mod synth_scene;
