//! The scene's ground truth as data: what `scene.json` holds.

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

use super::furniture::Design;
use super::preset::Preset;
use super::scene::SyntheticScene;
use super::sensor_noise::SensorSettings;
use crate::dataset::class_names::replica_class_name;

/// Seed, preset and every object's ground truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneDescription {
    /// Generator seed.
    pub seed: u64,
    /// Preset name.
    pub preset: Preset,
    /// Objects in id order.
    pub objects: Vec<ObjectDescription>,
    /// The depth camera's and segmenter's imperfections (exact when absent).
    #[serde(default)]
    pub sensor: SensorSettings,
}

/// Ground truth of one object.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectDescription {
    /// Instance id in `semantic_instance` images.
    pub id: u32,
    /// Replica class id.
    pub class: u32,
    /// Human-readable class name.
    pub class_name: String,
    /// Design name; equal designs are identical shapes.
    pub design: Design,
    /// Object → world transform as a row-major 4×4 matrix (a list of rows).
    pub world_from_object: [[f32; 4]; 4],
    /// Fraction of the surface seen in at least one frame.
    pub observed_surface_fraction: f32,
}

impl SceneDescription {
    /// Describes `scene` (computes its observed-surface fractions if not done yet).
    pub fn of(scene: &SyntheticScene) -> Self {
        let observed = scene.observed_surface_fraction();
        let objects = scene
            .objects()
            .iter()
            .map(|o| ObjectDescription {
                id: o.id.0,
                class: o.class().0,
                class_name: replica_class_name(o.class()).unwrap_or("unknown").to_owned(),
                design: o.design,
                world_from_object: row_major(&o.world_from_object),
                observed_surface_fraction: observed.get(&o.id).copied().unwrap_or(0.0),
            })
            .collect();
        Self {
            seed: scene.seed(),
            preset: scene.preset(),
            objects,
            sensor: scene.sensor(),
        }
    }
}

/// The homogeneous matrix of `transform` as rows.
pub fn row_major(transform: &Isometry3<f32>) -> [[f32; 4]; 4] {
    let m = transform.to_homogeneous();
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn row_major_puts_the_translation_in_the_last_column() {
        let t = Isometry3::from_parts(Translation3::new(1.0, 2.0, 3.0), UnitQuaternion::identity());
        let rows = row_major(&t);
        assert_eq!([rows[0][3], rows[1][3], rows[2][3]], [1.0, 2.0, 3.0]);
        assert_eq!(rows[3], [0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn designs_and_presets_serialise_as_lowercase_names() {
        assert_eq!(serde_json::to_string(&Design::Armchair).expect("json"), "\"armchair\"");
        assert_eq!(serde_json::to_string(&Preset::Small).expect("json"), "\"small\"");
    }
}
