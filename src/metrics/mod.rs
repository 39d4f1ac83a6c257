//! Object-level reconstruction metrics (METHOD.md §6), as the paper and vMAP report them.
//!
//! Per object, 10 000 points are sampled uniformly on the predicted and on the ground-truth
//! mesh ([`score_object`]):
//! - **accuracy** \[cm\]: mean distance predicted → ground truth, over the predicted samples
//!   inside the ground-truth object's minimum-volume oriented box;
//! - **completion** \[cm\]: mean distance ground truth → predicted (prediction uncropped);
//! - **completion ratio** \[%\]: share of ground-truth samples within 5 cm (and within 1 cm).
//!
//! [`Crop::Vmap`] instead crops both sample sets to the box enlarged by 1/0.9. Objects without
//! prediction are reported as missing. [`EvaluationReport`] aggregates per class and over
//! objects, serialises with serde, and renders as Markdown ([`render_markdown`]);
//! [`evaluate_ground_truth`] evaluates a folder of `obj_{id}.ply` meshes against a
//! [`GroundTruth`] (its meshes and the objects' classes).

pub mod association_purity;
pub mod compare;
pub mod crop;
pub mod eval_dirs;
pub mod ground_truth;
pub mod markdown;
pub mod object_matching;
pub mod object_scores;
pub mod report;

pub use crop::Crop;
pub use eval_dirs::{evaluate_dirs, evaluate_ground_truth, prediction_path};
pub use ground_truth::{
    ClassLabel, GroundTruth, GroundTruthEntry, ObjectClasses, SceneFile, UNKNOWN_CLASS, mesh_file_name,
};
pub use markdown::render_markdown;
pub use object_scores::{ObjectScores, PredictionStatus, SAMPLES_PER_MESH, score_object};
pub use report::{EvalSettings, EvaluationReport, MetricSummary, ObjectGroup, ObjectMetrics};
