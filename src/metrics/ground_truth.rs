//! The ground truth an evaluation scores against: which objects there are, their meshes, and
//! their classes.
//!
//! ```text
//! gt_dir/gt_meshes/obj_{id}.ply   ground truth (or gt_dir/obj_{id}.ply when there is no gt_meshes/)
//! gt_dir/scene.json               optional; read only when it is catmap's own (`catmap synth`)
//! ```
//!
//! Only the meshes are required. An object's class comes from, in order:
//! 1. the classes the caller knows ([`ObjectClasses`]: a catmap run's voted classes, so the
//!    per-class tables are right on any dataset);
//! 2. catmap's own `scene.json` ([`SceneDescription`]), which also gives each object's observed
//!    surface fraction;
//! 3. otherwise the class is [`UNKNOWN_CLASS`].
//!
//! A `scene.json` of another schema (a dataset's own file of that name) or one that is not JSON
//! is not an error: it is ignored, and [`SceneFile::Foreign`] says why, for the caller to log.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::error::{CatmapError, Result};
use crate::ids::{ClassId, ObjectId};
use crate::synth::description::SceneDescription;

/// Class name of objects whose class is not known.
pub const UNKNOWN_CLASS: &str = "unknown";

/// One object's class: its id and the name the tables group by.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClassLabel {
    /// Semantic class id.
    pub class: ClassId,
    /// Class name.
    pub name: String,
}

/// The classes of a set of objects, by object id (e.g. a catmap run's voted classes).
pub type ObjectClasses = BTreeMap<ObjectId, ClassLabel>;

/// What the ground-truth folder's `scene.json` turned out to be.
#[derive(Debug, Clone, PartialEq)]
pub enum SceneFile {
    /// There is no `scene.json`.
    Absent,
    /// catmap's own description of the scene (classes, designs, poses, observed fractions).
    Catmap(SceneDescription),
    /// A file of another schema, or not JSON: ignored.
    Foreign {
        /// The file.
        path: PathBuf,
        /// Why it is not catmap's (the parser's message, with its line).
        reason: String,
    },
}

/// One ground-truth object found on disk.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruthEntry {
    /// Instance id (from the file name `obj_{id}.ply`).
    pub id: ObjectId,
    /// Semantic class, when known (see the module doc).
    pub class: Option<ClassId>,
    /// Class name, or [`UNKNOWN_CLASS`].
    pub class_name: String,
    /// Share of the object's surface that some frame sees, from catmap's `scene.json`.
    pub observed_surface_fraction: Option<f32>,
    /// The mesh file.
    pub mesh_path: PathBuf,
}

/// The ground-truth objects of a folder, in id order, and what its `scene.json` was.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruth {
    /// The objects.
    pub entries: Vec<GroundTruthEntry>,
    /// The folder's `scene.json`.
    pub scene_file: SceneFile,
}

impl GroundTruth {
    /// Lists the ground-truth meshes of `gt_dir` (see the module doc) and labels each object
    /// with its class: from `known` first, else from catmap's `scene.json`. Errors when the
    /// folder is missing, cannot be listed, or holds no `obj_{id}.ply`.
    pub fn load(gt_dir: &Path, known: &ObjectClasses) -> Result<Self> {
        if !gt_dir.is_dir() {
            return Err(CatmapError::layout(gt_dir, "ground-truth folder does not exist"));
        }
        let nested = gt_dir.join("gt_meshes");
        let mesh_dir = if nested.is_dir() { nested } else { gt_dir.to_owned() };
        let scene_file = read_scene_file(&gt_dir.join("scene.json"));
        let mut ids: Vec<ObjectId> = std::fs::read_dir(&mesh_dir)
            .map_err(|e| CatmapError::io(&mesh_dir, e))?
            .filter_map(|entry| entry.ok()?.file_name().to_str().and_then(parse_mesh_file_name))
            .collect();
        ids.sort_unstable();
        ids.dedup();
        if ids.is_empty() {
            return Err(CatmapError::layout(
                &mesh_dir,
                "no ground-truth meshes named obj_{id}.ply",
            ));
        }
        let described = |id: ObjectId| match &scene_file {
            SceneFile::Catmap(scene) => scene.objects.iter().find(|o| o.id == id.0),
            SceneFile::Absent | SceneFile::Foreign { .. } => None,
        };
        let entries = ids
            .into_iter()
            .map(|id| {
                let description = described(id);
                let label = known.get(&id).cloned().or_else(|| {
                    description.map(|o| ClassLabel {
                        class: ClassId(o.class),
                        name: o.class_name.clone(),
                    })
                });
                GroundTruthEntry {
                    id,
                    class: label.as_ref().map(|l| l.class),
                    class_name: label.map_or_else(|| UNKNOWN_CLASS.to_owned(), |l| l.name),
                    observed_surface_fraction: description.map(|o| o.observed_surface_fraction),
                    mesh_path: mesh_dir.join(mesh_file_name(id)),
                }
            })
            .collect();
        Ok(Self { entries, scene_file })
    }
}

/// `obj_{id}.ply`.
pub fn mesh_file_name(id: ObjectId) -> String {
    format!("obj_{id}.ply")
}

/// The id in a file name `obj_{id}.ply`.
pub(crate) fn parse_mesh_file_name(name: &str) -> Option<ObjectId> {
    name.strip_prefix("obj_")?
        .strip_suffix(".ply")?
        .parse()
        .ok()
        .map(ObjectId)
}

/// Reads `path` as catmap's scene description; anything else is [`SceneFile::Foreign`].
fn read_scene_file(path: &Path) -> SceneFile {
    if !path.is_file() {
        return SceneFile::Absent;
    }
    let foreign = |reason: String| SceneFile::Foreign {
        path: path.to_owned(),
        reason,
    };
    match std::fs::read_to_string(path) {
        Err(e) => foreign(format!("unreadable: {e}")),
        Ok(text) => match serde_json::from_str::<SceneDescription>(&text) {
            Ok(scene) => SceneFile::Catmap(scene),
            Err(e) if e.is_syntax() || e.is_eof() => foreign(format!("not JSON: {e}")),
            Err(e) => foreign(format!("not catmap's scene description: {e}")),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::primitives::cuboid;

    fn gt_folder(ids: &[u32]) -> tempfile::TempDir {
        let gt = tempfile::tempdir().expect("temp dir");
        for id in ids {
            let path = gt.path().join(format!("gt_meshes/obj_{id}.ply"));
            cuboid([0.0; 3], [0.2; 3]).write_ply(&path).expect("writable temp dir");
        }
        gt
    }

    fn chair() -> ClassLabel {
        ClassLabel {
            class: ClassId(20),
            name: "chair".to_owned(),
        }
    }

    /// catmap's own scene.json for objects 1 (a table seen at 70 %) and 2.
    const CATMAP_SCENE: &str = r#"{"seed": 0, "preset": "small", "objects": [
        {"id": 1, "class": 80, "class_name": "table", "design": "dining_table",
         "world_from_object": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "observed_surface_fraction": 0.7},
        {"id": 2, "class": 20, "class_name": "chair", "design": "ladder_back_chair",
         "world_from_object": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "observed_surface_fraction": 0.5}]}"#;

    #[test]
    fn without_scene_json_only_the_known_classes_are_named() {
        let gt = gt_folder(&[2, 10]);
        std::fs::write(gt.path().join("gt_meshes/notes.txt"), "ignored").expect("write");
        let known = ObjectClasses::from([(ObjectId(10), chair())]);
        let truth = GroundTruth::load(gt.path(), &known).expect("valid folder");
        assert_eq!(truth.scene_file, SceneFile::Absent);
        let names: Vec<(u32, &str)> = truth.entries.iter().map(|e| (e.id.0, e.class_name.as_str())).collect();
        assert_eq!(
            names,
            [(2, UNKNOWN_CLASS), (10, "chair")],
            "id order; obj_2 is not known"
        );
        assert_eq!(truth.entries[1].class, Some(ClassId(20)));
        assert_eq!(truth.entries[1].mesh_path, gt.path().join("gt_meshes/obj_10.ply"));
    }

    #[test]
    fn catmap_scene_json_names_classes_and_observed_fractions_but_known_classes_win() {
        let gt = gt_folder(&[1, 2]);
        std::fs::write(gt.path().join("scene.json"), CATMAP_SCENE).expect("write");
        let known = ObjectClasses::from([(
            ObjectId(1),
            ClassLabel {
                class: ClassId(18),
                name: "cabinet".to_owned(),
            },
        )]);
        let truth = GroundTruth::load(gt.path(), &known).expect("valid folder");
        assert!(
            matches!(truth.scene_file, SceneFile::Catmap(_)),
            "{:?}",
            truth.scene_file
        );
        let e = &truth.entries;
        assert_eq!(
            (e[0].class_name.as_str(), e[0].observed_surface_fraction),
            ("cabinet", Some(0.7)),
            "the known class wins; the fraction comes from scene.json"
        );
        assert_eq!(
            (e[1].class, e[1].class_name.as_str(), e[1].observed_surface_fraction),
            (Some(ClassId(20)), "chair", Some(0.5)),
            "scene.json names what is not known"
        );
    }

    #[test]
    fn a_foreign_or_broken_scene_json_is_ignored_with_its_reason() {
        let known = ObjectClasses::from([(ObjectId(3), chair())]);
        for (text, reason) in [
            (r#"{"objects": [{"instance": 3, "label": "chair"}]}"#, "missing field"),
            ("objects: 3 chairs\n", "not JSON"),
            ("", "not JSON"),
        ] {
            let gt = gt_folder(&[3]);
            std::fs::write(gt.path().join("scene.json"), text).expect("write");
            let truth = GroundTruth::load(gt.path(), &known).expect("the meshes suffice");
            let SceneFile::Foreign { path, reason: why } = &truth.scene_file else {
                panic!("{text:?} is not catmap's: {:?}", truth.scene_file);
            };
            assert!(path.ends_with("scene.json") && why.contains(reason), "{text:?}: {why}");
            assert_eq!(truth.entries[0].class_name, "chair", "classes still come from the map");
            assert_eq!(truth.entries[0].observed_surface_fraction, None);
        }
    }

    #[test]
    fn missing_folders_and_empty_ground_truth_are_named_in_errors() {
        let dir = tempfile::tempdir().expect("temp dir");
        let missing = dir.path().join("nope");
        let err = GroundTruth::load(&missing, &ObjectClasses::new()).expect_err("no folder");
        assert!(err.to_string().contains("nope"), "{err}");
        let err = GroundTruth::load(dir.path(), &ObjectClasses::new()).expect_err("no meshes");
        assert!(err.to_string().contains("obj_{id}.ply"), "{err}");
    }

    #[test]
    fn mesh_file_names_parse_only_object_ids() {
        assert_eq!(parse_mesh_file_name("obj_12.ply"), Some(ObjectId(12)));
        assert_eq!(parse_mesh_file_name("obj_x.ply"), None);
        assert_eq!(parse_mesh_file_name("obj_3.ply.tmp"), None);
        assert_eq!(mesh_file_name(ObjectId(12)), "obj_12.ply");
    }
}
