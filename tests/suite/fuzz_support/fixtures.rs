//! Tiny valid dataset folders kept in memory (relative path → bytes), written to a temporary
//! folder whose files the fuzz targets edit and restore.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use image::{ImageBuffer, ImageFormat, Luma, Rgb};
use tempfile::TempDir;

/// A dataset folder's files: relative path → content.
pub type FileSet = BTreeMap<String, Vec<u8>>;

/// Replica fixture size (the camera of its `intrinsics.json`).
pub const REPLICA_SIZE: (u32, u32) = (16, 12);
/// ScanNet fixture depth size (a 10-pixel border leaves 12×8).
pub const SCANNET_DEPTH_SIZE: (u32, u32) = (32, 28);

fn encode<P: image::Pixel<Subpixel = S> + image::PixelWithColorType, S: image::Primitive>(
    image: &ImageBuffer<P, Vec<S>>,
    format: ImageFormat,
) -> Vec<u8>
where
    [S]: image::EncodableLayout,
{
    let mut bytes = Vec::new();
    image
        .write_to(&mut Cursor::new(&mut bytes), format)
        .expect("in-memory encoding of a valid image");
    bytes
}

/// A 16-bit grey PNG of `size` with pixel values `f(u, v)`.
pub fn grey16_png((w, h): (u32, u32), f: impl Fn(u32, u32) -> u16) -> Vec<u8> {
    encode(
        &ImageBuffer::<Luma<u16>, _>::from_fn(w, h, |u, v| Luma([f(u, v)])),
        ImageFormat::Png,
    )
}

/// An 8-bit grey PNG.
pub fn grey8_png((w, h): (u32, u32), f: impl Fn(u32, u32) -> u8) -> Vec<u8> {
    encode(
        &ImageBuffer::<Luma<u8>, _>::from_fn(w, h, |u, v| Luma([f(u, v)])),
        ImageFormat::Png,
    )
}

/// An 8-bit RGB image as PNG or JPEG.
pub fn rgb_image((w, h): (u32, u32), format: ImageFormat, f: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
    encode(&ImageBuffer::<Rgb<u8>, _>::from_fn(w, h, |u, v| Rgb(f(u, v))), format)
}

/// Replica layout, `frames` frames of 16×12: a chair (class 20, instance 3) on a floor strip
/// (class 40), depth 1 m + 1 cm per column, poses turning about z.
pub fn replica_files(frames: usize) -> FileSet {
    let size = REPLICA_SIZE;
    let label = |u: u32, v: u32| match (u, v) {
        (_, 9..) => (40u8, 5u16),
        (3..11, 2..=7) => (20, 3),
        _ => (0, 0),
    };
    let mut files = FileSet::new();
    for i in 0..frames {
        let k = i as u8;
        files.insert(
            format!("rgb/rgb_{i}.png"),
            rgb_image(size, ImageFormat::Png, |u, v| [u as u8 * 9, v as u8 * 11, k]),
        );
        files.insert(
            format!("depth/depth_{i}.png"),
            grey16_png(size, |u, _| 1000 + 10 * u as u16),
        );
        files.insert(
            format!("semantic_class/semantic_class_{i}.png"),
            grey8_png(size, |u, v| label(u, v).0),
        );
        files.insert(
            format!("semantic_instance/semantic_instance_{i}.png"),
            grey16_png(size, |u, v| label(u, v).1),
        );
    }
    let traj: String = (0..frames)
        .map(|i| {
            let (s, c) = (0.1 * i as f64).sin_cos();
            format!("{c} {} 0 {i} {s} {c} 0 0.5 0 0 1 1.2 0 0 0 1\n", -s)
        })
        .collect();
    files.insert("traj_w_c.txt".to_owned(), traj.into_bytes());
    let json = r#"{"width": 16, "height": 12, "fx": 12.0, "fy": 12.5, "cx": 7.5, "cy": 5.5, "depth_scale": 1000.0}"#;
    files.insert("intrinsics.json".to_owned(), json.as_bytes().to_vec());
    files
}

/// ScanNet layout, frames numbered 0..`frames`: 32×28 depth, 64×56 colour (JPEG) and labels.
pub fn scannet_files(frames: usize) -> FileSet {
    let (w, h) = SCANNET_DEPTH_SIZE;
    let labels = |u: u32, v: u32| match (u / 2, v / 2) {
        (12..20, 10..18) => (2u8, 5u16),
        (24.., _) => (4, 1),
        _ => (0, 0),
    };
    let mut files = FileSet::new();
    for n in 0..frames {
        files.insert(
            format!("color/{n}.jpg"),
            rgb_image((2 * w, 2 * h), ImageFormat::Jpeg, |u, _| {
                if u < w { [200, 30, 30] } else { [30, 30, 200] }
            }),
        );
        files.insert(
            format!("depth/{n}.png"),
            grey16_png((w, h), |u, v| (500 + 10 * u + 20 * v) as u16),
        );
        files.insert(
            format!("instance-filt/{n}.png"),
            grey8_png((2 * w, 2 * h), |u, v| labels(u, v).0),
        );
        files.insert(
            format!("label-filt/{n}.png"),
            grey16_png((2 * w, 2 * h), |u, v| labels(u, v).1),
        );
        files.insert(
            format!("pose/{n}.txt"),
            format!("1 0 0 {n}\n0 1 0 0\n0 0 1 0\n0 0 0 1\n").into_bytes(),
        );
    }
    let k = "20 0 15.5 0\n0 21 13.5 0\n0 0 1 0\n0 0 0 1\n";
    files.insert("intrinsic/intrinsic_depth.txt".to_owned(), k.as_bytes().to_vec());
    files
}

/// TUM RGB-D fixture size (the camera of its `intrinsics.json`).
pub const TUM_SIZE: (u32, u32) = (16, 12);

/// Timestamps of TUM fixture frame `i` as written: colour image at 1 s + i / 30 s, depth image
/// 4 ms later, pose 2 ms earlier.
pub fn tum_stamps(i: usize) -> [String; 3] {
    let t = 1.0 + i as f64 / 30.0;
    [t, t + 0.004, t - 0.002].map(|s| format!("{s:.6}"))
}

/// TUM RGB-D layout with masks, `frames` frames of 16×12: the Replica fixture's chair and floor,
/// depth 1 m + 1 cm per column in units of 0.2 mm, poses turning about z; a pose between frames.
pub fn tum_files(frames: usize) -> FileSet {
    let label = |u: u32, v: u32| match (u, v) {
        (_, 9..) => (40u8, 5u16),
        (3..11, 2..=7) => (20, 3),
        _ => (0, 0),
    };
    let mut files = FileSet::new();
    let mut rgb_txt = "# color images\n# timestamp filename\n".to_owned();
    let mut depth_txt = "# depth maps\n# timestamp filename\n".to_owned();
    let mut groundtruth = "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n".to_owned();
    for i in 0..frames {
        let [rgb, depth, pose] = tum_stamps(i);
        let k = i as u8;
        rgb_txt += &format!("{rgb} rgb/{rgb}.png\n");
        depth_txt += &format!("{depth} depth/{depth}.png\n");
        let (s, c) = (0.05 * i as f64).sin_cos();
        groundtruth += &format!("{pose} {i} 0.5 1.2 0 0 {s} {c}\n");
        groundtruth += &format!("{:.6} {i}.5 0.5 1.2 0 0 {s} {c}\n", 1.016 + i as f64 / 30.0);
        files.insert(
            format!("rgb/{rgb}.png"),
            rgb_image(TUM_SIZE, ImageFormat::Png, |u, v| [u as u8 * 9, v as u8 * 11, k]),
        );
        files.insert(
            format!("depth/{depth}.png"),
            grey16_png(TUM_SIZE, |u, _| 5000 + 50 * u as u16),
        );
        files.insert(format!("class/{rgb}.png"), grey8_png(TUM_SIZE, |u, v| label(u, v).0));
        files.insert(
            format!("instance/{rgb}.png"),
            grey16_png(TUM_SIZE, |u, v| label(u, v).1),
        );
    }
    files.insert("rgb.txt".to_owned(), rgb_txt.into_bytes());
    files.insert("depth.txt".to_owned(), depth_txt.into_bytes());
    files.insert("groundtruth.txt".to_owned(), groundtruth.into_bytes());
    let json = r#"{"width": 16, "height": 12, "fx": 12.0, "fy": 12.5, "cx": 7.5, "cy": 5.5}"#;
    files.insert("intrinsics.json".to_owned(), json.as_bytes().to_vec());
    files
}

/// One edit of a fixture folder.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FolderEdit {
    /// The file's content is replaced.
    Replace {
        /// Relative path.
        path: String,
        /// New content.
        bytes: Vec<u8>,
    },
    /// The file is deleted.
    Delete {
        /// Relative path.
        path: String,
    },
    /// The file is renamed.
    Rename {
        /// Relative path before.
        from: String,
        /// Relative path after.
        to: String,
    },
    /// The file is replaced by an empty folder of the same name.
    Folder {
        /// Relative path.
        path: String,
    },
}

impl FolderEdit {
    /// The relative paths the edit touches.
    pub fn paths(&self) -> Vec<&str> {
        match self {
            Self::Replace { path, .. } | Self::Delete { path } | Self::Folder { path } => vec![path],
            Self::Rename { from, to } => vec![from, to],
        }
    }

    /// A short description, and the content for replacements (saved with crashing inputs).
    pub fn describe(&self) -> (String, Vec<u8>) {
        match self {
            Self::Replace { path, bytes } => (format!("replace {path}"), bytes.clone()),
            Self::Delete { path } => (format!("delete {path}"), Vec::new()),
            Self::Rename { from, to } => (format!("rename {from} to {to}"), Vec::new()),
            Self::Folder { path } => (format!("folder in place of {path}"), Vec::new()),
        }
    }
}

/// A fixture written to a temporary folder.
pub struct Folder {
    dir: TempDir,
    pristine: FileSet,
}

impl Folder {
    /// Writes `files` to a new temporary folder.
    pub fn new(files: FileSet) -> Self {
        let dir = tempfile::tempdir().expect("temp dir");
        let folder = Self { dir, pristine: files };
        for path in folder.pristine.keys() {
            folder.restore_one(path);
        }
        folder
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        self.dir.path()
    }

    /// The pristine files.
    pub fn files(&self) -> &FileSet {
        &self.pristine
    }

    fn full(&self, relative: &str) -> PathBuf {
        self.dir.path().join(relative)
    }

    /// Applies `edit` to the folder.
    pub fn apply(&self, edit: &FolderEdit) {
        match edit {
            FolderEdit::Replace { path, bytes } => std::fs::write(self.full(path), bytes).expect("write"),
            FolderEdit::Delete { path } => std::fs::remove_file(self.full(path)).expect("delete"),
            FolderEdit::Rename { from, to } => std::fs::rename(self.full(from), self.full(to)).expect("rename"),
            FolderEdit::Folder { path } => {
                std::fs::remove_file(self.full(path)).expect("delete");
                std::fs::create_dir(self.full(path)).expect("mkdir");
            }
        }
    }

    /// Applies `edit` until the returned guard drops (also when the reader panics).
    pub fn apply_until_dropped<'a>(&'a self, edit: &'a FolderEdit) -> Restore<'a> {
        self.apply(edit);
        Restore { folder: self, edit }
    }

    /// Undoes `edit`: every path it touched is removed and rewritten from the pristine files.
    pub fn restore(&self, edit: &FolderEdit) {
        for path in edit.paths() {
            self.restore_one(path);
        }
    }

    fn restore_one(&self, relative: &str) {
        let full = self.full(relative);
        if full.is_dir() {
            std::fs::remove_dir_all(&full).expect("remove folder");
        } else if full.exists() {
            std::fs::remove_file(&full).expect("remove file");
        }
        if let Some(bytes) = self.pristine.get(relative) {
            std::fs::create_dir_all(full.parent().expect("a file in a folder")).expect("mkdir");
            std::fs::write(&full, bytes).expect("write");
        }
    }
}

/// Undoes an edit when dropped.
pub struct Restore<'a> {
    folder: &'a Folder,
    edit: &'a FolderEdit,
}

impl Drop for Restore<'_> {
    fn drop(&mut self) {
        self.folder.restore(self.edit);
    }
}
