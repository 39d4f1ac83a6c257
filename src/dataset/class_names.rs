//! The names of a dataset's semantic classes, for `summary.json`, `metrics.json`, the tables and
//! the Rerun labels.
//!
//! - **Replica** (and what `catmap synth` writes): Replica's 101 classes are built in
//!   ([`REPLICA_CLASSES`], ids 1–101 as in Replica's `info_semantic.json`). A scene's own
//!   `info_semantic.json` (`"classes": [{"id": …, "name": …}, …]`), in the sequence folder or its
//!   `habitat/` subfolder, names its classes over the built-in table.
//! - **ScanNet**: the label images hold raw label ids, named by ScanNet's label map
//!   `scannetv2-labels.combined.tsv` (its `id` and `category` columns; `raw_category` where
//!   `category` is empty), looked for in the sequence folder and its parent. Without it ScanNet's
//!   classes have no names.
//!
//! A class without a name is shown as `class {id}`. A label file that cannot be read or parsed is
//! an error naming the file; [`ClassNames::find_replica`] and [`ClassNames::find_scannet`] log it
//! and go on with the built-in names, since names never change the map.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::error::{CatmapError, Result};
use crate::ids::ClassId;

/// Replica's semantic classes, id → name.
pub const REPLICA_CLASSES: [(u32, &str); 101] = [
    (1, "backpack"),
    (2, "base-cabinet"),
    (3, "basket"),
    (4, "bathtub"),
    (5, "beam"),
    (6, "beanbag"),
    (7, "bed"),
    (8, "bench"),
    (9, "bike"),
    (10, "bin"),
    (11, "blanket"),
    (12, "blinds"),
    (13, "book"),
    (14, "bottle"),
    (15, "box"),
    (16, "bowl"),
    (17, "camera"),
    (18, "cabinet"),
    (19, "candle"),
    (20, "chair"),
    (21, "chopping-board"),
    (22, "clock"),
    (23, "cloth"),
    (24, "clothing"),
    (25, "coaster"),
    (26, "comforter"),
    (27, "computer-keyboard"),
    (28, "cup"),
    (29, "cushion"),
    (30, "curtain"),
    (31, "ceiling"),
    (32, "cooktop"),
    (33, "countertop"),
    (34, "desk"),
    (35, "desk-organizer"),
    (36, "desktop-computer"),
    (37, "door"),
    (38, "exercise-ball"),
    (39, "faucet"),
    (40, "floor"),
    (41, "handbag"),
    (42, "hair-dryer"),
    (43, "handrail"),
    (44, "indoor-plant"),
    (45, "knife-block"),
    (46, "kitchen-utensil"),
    (47, "lamp"),
    (48, "laptop"),
    (49, "major-appliance"),
    (50, "mat"),
    (51, "microwave"),
    (52, "monitor"),
    (53, "mouse"),
    (54, "nightstand"),
    (55, "pan"),
    (56, "panel"),
    (57, "paper-towel"),
    (58, "phone"),
    (59, "picture"),
    (60, "pillar"),
    (61, "pillow"),
    (62, "pipe"),
    (63, "plant-stand"),
    (64, "plate"),
    (65, "pot"),
    (66, "rack"),
    (67, "refrigerator"),
    (68, "remote-control"),
    (69, "scarf"),
    (70, "sculpture"),
    (71, "shelf"),
    (72, "shoe"),
    (73, "shower-stall"),
    (74, "sink"),
    (75, "small-appliance"),
    (76, "sofa"),
    (77, "stair"),
    (78, "stool"),
    (79, "switch"),
    (80, "table"),
    (81, "table-runner"),
    (82, "tablet"),
    (83, "tissue-paper"),
    (84, "toilet"),
    (85, "toothbrush"),
    (86, "towel"),
    (87, "tv-screen"),
    (88, "tv-stand"),
    (89, "umbrella"),
    (90, "utensil-holder"),
    (91, "vase"),
    (92, "vent"),
    (93, "wall"),
    (94, "wall-cabinet"),
    (95, "wall-plug"),
    (96, "wardrobe"),
    (97, "window"),
    (98, "rug"),
    (99, "logo"),
    (100, "bag"),
    (101, "set-of-clothing"),
];

/// Replica's name of `class`, from the built-in table.
pub fn replica_class_name(class: ClassId) -> Option<&'static str> {
    REPLICA_CLASSES
        .binary_search_by_key(&class.0, |&(id, _)| id)
        .ok()
        .map(|i| REPLICA_CLASSES[i].1)
}

/// ScanNet's label map, as found beside a sequence.
pub const SCANNET_LABEL_MAP: &str = "scannetv2-labels.combined.tsv";

/// Class id → name for one dataset (see the module doc).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ClassNames {
    names: BTreeMap<u32, String>,
}

impl ClassNames {
    /// No names: every class is `class {id}`.
    pub fn none() -> Self {
        Self::default()
    }

    /// Replica's built-in table.
    pub fn replica() -> Self {
        Self {
            names: REPLICA_CLASSES
                .iter()
                .map(|&(id, name)| (id, name.to_owned()))
                .collect(),
        }
    }

    /// The name of `class`, when known.
    pub fn get(&self, class: ClassId) -> Option<&str> {
        self.names.get(&class.0).map(String::as_str)
    }

    /// The name of `class`, or `class {id}`.
    pub fn name(&self, class: ClassId) -> String {
        self.get(class).map_or_else(|| format!("class {class}"), str::to_owned)
    }

    /// Number of named classes.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// True when no class has a name.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The built-in Replica table with the classes of the Replica `info_semantic.json` at
    /// `path` named over it.
    pub fn from_replica_info(path: &Path) -> Result<Self> {
        #[derive(serde::Deserialize)]
        struct Info {
            classes: Vec<InfoClass>,
        }
        #[derive(serde::Deserialize)]
        struct InfoClass {
            id: i64,
            name: String,
        }
        let text = std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))?;
        let info: Info = serde_json::from_str(&text).map_err(|e| CatmapError::Parse {
            path: path.to_owned(),
            line: e.line(),
            reason: format!("not a Replica semantic info file: {e}"),
        })?;
        let mut names = Self::replica();
        for class in info.classes {
            let name = class.name.trim();
            if let (Ok(id), false) = (u32::try_from(class.id), name.is_empty()) {
                names.names.insert(id, name.to_owned());
            }
        }
        Ok(names)
    }

    /// The classes of ScanNet's label map at `path` (tab-separated, a header row naming the
    /// columns `id` and `category` or `raw_category`).
    pub fn from_scannet_label_map(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))?;
        let parse_error = |line: usize, reason: String| CatmapError::Parse {
            path: path.to_owned(),
            line,
            reason,
        };
        let mut lines = text.lines().enumerate();
        let header: Vec<&str> = lines
            .next()
            .map(|(_, l)| l.split('\t').map(str::trim).collect())
            .unwrap_or_default();
        let column = |name: &str| header.iter().position(|&c| c == name);
        let id_column = column("id").ok_or_else(|| parse_error(1, "the header has no `id` column".to_owned()))?;
        let name_columns: Vec<usize> = [column("category"), column("raw_category")]
            .into_iter()
            .flatten()
            .collect();
        if name_columns.is_empty() {
            return Err(parse_error(
                1,
                "the header has no `category` or `raw_category` column".to_owned(),
            ));
        }
        let mut names = BTreeMap::new();
        for (i, line) in lines {
            if line.trim().is_empty() {
                continue;
            }
            let cells: Vec<&str> = line.split('\t').map(str::trim).collect();
            let id_text = cells.get(id_column).copied().unwrap_or("");
            let id: u32 = id_text
                .parse()
                .map_err(|_| parse_error(i + 1, format!("`{id_text}` is not a label id")))?;
            let name = name_columns
                .iter()
                .filter_map(|&c| cells.get(c).copied())
                .find(|n| !n.is_empty());
            if let Some(name) = name {
                names.insert(id, name.to_owned());
            }
        }
        Ok(Self { names })
    }

    /// The names of the Replica sequence in `dir`: its `info_semantic.json` (in `dir` or
    /// `dir/habitat`) over the built-in table; the built-in table alone when there is none or it
    /// is unreadable (logged).
    pub fn find_replica(dir: &Path) -> Self {
        let candidates = [
            dir.join("info_semantic.json"),
            dir.join("habitat").join("info_semantic.json"),
        ];
        match first_file(&candidates) {
            None => Self::replica(),
            Some(path) => Self::from_replica_info(&path).unwrap_or_else(|e| {
                tracing::warn!(error = %e, "class names: Replica's built-in table instead");
                Self::replica()
            }),
        }
    }

    /// The names of the ScanNet sequence in `dir`: its label map (in `dir` or its parent); none
    /// when there is none or it is unreadable (logged).
    pub fn find_scannet(dir: &Path) -> Self {
        let mut candidates = vec![dir.join(SCANNET_LABEL_MAP)];
        if let Some(parent) = dir.parent() {
            candidates.push(parent.join(SCANNET_LABEL_MAP));
        }
        match first_file(&candidates) {
            None => Self::none(),
            Some(path) => Self::from_scannet_label_map(&path).unwrap_or_else(|e| {
                tracing::warn!(error = %e, "class names: ScanNet's classes stay numbered");
                Self::none()
            }),
        }
    }
}

fn first_file(candidates: &[PathBuf]) -> Option<PathBuf> {
    candidates.iter().find(|p| p.is_file()).cloned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_table_names_replicas_sofa_and_keeps_ids_sorted() {
        assert!(REPLICA_CLASSES.windows(2).all(|w| w[0].0 < w[1].0));
        assert_eq!(replica_class_name(ClassId(76)), Some("sofa"));
        assert_eq!(replica_class_name(ClassId(54)), Some("nightstand"));
        assert_eq!(replica_class_name(ClassId(102)), None);
        assert_eq!(ClassNames::replica().name(ClassId(76)), "sofa");
        assert_eq!(ClassNames::none().name(ClassId(76)), "class 76");
    }

    #[test]
    fn a_scenes_own_info_file_names_its_classes_over_the_table() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("habitat")).unwrap();
        let info = r#"{"classes": [{"id": 76, "name": "couch"}, {"id": 200, "name": "hammock"},
                       {"id": -1, "name": "void"}], "objects": []}"#;
        std::fs::write(dir.path().join("habitat/info_semantic.json"), info).unwrap();
        let names = ClassNames::find_replica(dir.path());
        assert_eq!(names.name(ClassId(76)), "couch");
        assert_eq!(names.name(ClassId(200)), "hammock");
        assert_eq!(names.name(ClassId(20)), "chair", "the rest from the table");
    }

    #[test]
    fn an_unreadable_info_file_is_an_error_naming_it_and_find_falls_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("info_semantic.json");
        std::fs::write(&path, "{\"classes\": 3}").unwrap();
        let error = ClassNames::from_replica_info(&path).unwrap_err().to_string();
        assert!(
            error.contains("info_semantic.json") && error.contains("Replica semantic info"),
            "{error}"
        );
        assert_eq!(ClassNames::find_replica(dir.path()), ClassNames::replica());
    }

    #[test]
    fn scannets_label_map_names_raw_ids_from_the_parent_folder() {
        let root = tempfile::tempdir().unwrap();
        let scene = root.path().join("scene0000_00");
        std::fs::create_dir(&scene).unwrap();
        let map = "id\traw_category\tcategory\tcount\tnyu40id\n\
                   2\tchair\tchair\t4000\t5\n\
                   39\tcouch\tsofa\t900\t6\n\
                   77\tpiano bench\t\t12\t39\n";
        std::fs::write(root.path().join(SCANNET_LABEL_MAP), map).unwrap();
        let names = ClassNames::find_scannet(&scene);
        assert_eq!(names.name(ClassId(39)), "sofa");
        assert_eq!(
            names.name(ClassId(77)),
            "piano bench",
            "raw_category where category is empty"
        );
        assert_eq!(names.name(ClassId(5)), "class 5");
        let bare = tempfile::tempdir().unwrap();
        assert_eq!(ClassNames::find_scannet(&bare.path().join("scene")), ClassNames::none());
    }

    #[test]
    fn a_label_map_with_a_bad_id_or_no_id_column_is_an_error_with_its_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(SCANNET_LABEL_MAP);
        std::fs::write(&path, "id\tcategory\n2\tchair\nx\tsofa\n").unwrap();
        let error = ClassNames::from_scannet_label_map(&path).unwrap_err().to_string();
        assert!(error.contains(":3:") && error.contains("`x`"), "{error}");
        std::fs::write(&path, "label\tcategory\n2\tchair\n").unwrap();
        let error = ClassNames::from_scannet_label_map(&path).unwrap_err().to_string();
        assert!(error.contains("no `id` column"), "{error}");
    }
}
