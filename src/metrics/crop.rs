//! Which surface samples enter the metrics: the crop to the ground-truth object's box.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::geometry::oriented_box::OrientedBox;

/// vMAP enlarges the ground-truth box by `1 / VMAP_BOX_FILL` for its crop.
pub const VMAP_BOX_FILL: f32 = 0.9;
/// Numerical slack of the crop, metres: samples on the box faces stay inside despite rounding.
pub const CROP_TOLERANCE_M: f32 = 1e-4;

/// How predicted (and ground-truth) samples are cropped to the ground-truth object's
/// minimum-volume oriented box before distances are taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Crop {
    /// The paper's protocol: accuracy uses the predicted samples inside the box (no
    /// enlargement); completion uses all predicted samples.
    #[default]
    Paper,
    /// vMAP's protocol: both sample sets are cropped to the box enlarged by 1/0.9, for
    /// accuracy and completion alike.
    Vmap,
}

impl Crop {
    /// Short lowercase name (`paper`, `vmap`).
    pub fn name(self) -> &'static str {
        match self {
            Crop::Paper => "paper",
            Crop::Vmap => "vmap",
        }
    }
}

impl std::fmt::Display for Crop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The sample sets the distances are taken on, after cropping.
#[derive(Debug, Clone, PartialEq)]
pub struct CroppedSamples {
    /// Predicted samples for accuracy (predicted → ground truth).
    pub prediction_for_accuracy: Vec<Point3<f32>>,
    /// Predicted samples completion is measured against (ground truth → predicted).
    pub prediction_for_completion: Vec<Point3<f32>>,
    /// Ground-truth samples, both as accuracy reference and completion queries.
    pub ground_truth: Vec<Point3<f32>>,
}

impl Crop {
    /// Crops the samples of one object with its ground-truth box `gt_box`.
    pub fn apply(
        self,
        gt_box: &OrientedBox,
        prediction: Vec<Point3<f32>>,
        ground_truth: Vec<Point3<f32>>,
    ) -> CroppedSamples {
        match self {
            Crop::Paper => CroppedSamples {
                prediction_for_accuracy: inside(gt_box, &prediction),
                prediction_for_completion: prediction,
                ground_truth,
            },
            Crop::Vmap => {
                let enlarged = OrientedBox {
                    half_extents: gt_box.half_extents / VMAP_BOX_FILL,
                    ..*gt_box
                };
                let prediction = inside(&enlarged, &prediction);
                CroppedSamples {
                    prediction_for_accuracy: prediction.clone(),
                    prediction_for_completion: prediction,
                    ground_truth: inside(&enlarged, &ground_truth),
                }
            }
        }
    }
}

/// The points of `points` inside `b` (up to [`CROP_TOLERANCE_M`]).
fn inside(b: &OrientedBox, points: &[Point3<f32>]) -> Vec<Point3<f32>> {
    points
        .iter()
        .filter(|p| b.contains(p, CROP_TOLERANCE_M))
        .copied()
        .collect()
}

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Vector3};

    use super::*;

    fn unit_box() -> OrientedBox {
        OrientedBox {
            world_from_box: Isometry3::identity(),
            half_extents: Vector3::repeat(0.5),
        }
    }

    #[test]
    fn the_paper_crop_only_trims_predictions_for_accuracy() {
        let prediction = vec![Point3::new(0.0, 0.0, 0.0), Point3::new(0.53, 0.0, 0.0)];
        let cropped = Crop::Paper.apply(&unit_box(), prediction.clone(), vec![Point3::origin()]);
        assert_eq!(
            cropped.prediction_for_accuracy,
            vec![Point3::origin()],
            "0.53 lies outside the 0.5 box"
        );
        assert_eq!(
            cropped.prediction_for_completion, prediction,
            "completion sees every predicted sample"
        );
    }

    #[test]
    fn the_vmap_crop_enlarges_the_box_and_trims_both_sets() {
        let prediction = vec![Point3::new(0.53, 0.0, 0.0), Point3::new(0.6, 0.0, 0.0)];
        let ground_truth = vec![Point3::new(0.0, 0.54, 0.0), Point3::new(0.0, 0.0, 0.7)];
        let cropped = Crop::Vmap.apply(&unit_box(), prediction, ground_truth);
        assert_eq!(
            cropped.prediction_for_accuracy,
            vec![Point3::new(0.53, 0.0, 0.0)],
            "the box reaches 0.5/0.9 ≈ 0.556"
        );
        assert_eq!(cropped.prediction_for_completion, cropped.prediction_for_accuracy);
        assert_eq!(cropped.ground_truth, vec![Point3::new(0.0, 0.54, 0.0)]);
    }

    #[test]
    fn crops_serialise_as_lowercase_names() {
        assert_eq!(serde_json::to_string(&Crop::Vmap).expect("serialisable"), "\"vmap\"");
        assert_eq!(Crop::Paper.to_string(), "paper");
    }
}
