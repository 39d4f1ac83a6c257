//! The synthetic scenes and the metrics that score maps against them.

mod metrics_eval;
mod synth_scene;
