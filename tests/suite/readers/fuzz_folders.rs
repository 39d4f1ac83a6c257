//! Fuzzing of the Replica, ScanNet and TUM RGB-D folder readers (issue 6, Resilience): a small
//! valid folder with one file replaced (format-aware mutation, another file's bytes, empty),
//! deleted, renamed or turned into a folder; every frame is read. Same harness and settings as
//! `fuzz_readers.rs`:
//!
//! ```text
//! CATMAP_FUZZ_SECONDS=600 cargo test --test suite readers::fuzz_folders -- --nocapture --test-threads 1
//! ```

use std::path::Path;

use crate::fuzz_support::checks::check_frame;
use crate::fuzz_support::fixtures::{FileSet, Folder, FolderEdit, replica_files, scannet_files, tum_files};
use crate::fuzz_support::mutate::{mutate_bytes, mutate_text};
use crate::fuzz_support::png::{generate_png, mutate_png};
use crate::fuzz_support::{Execution, Verdict, fuzz, pick, rejected_naming_one_of};
use catmap::dataset::FrameSource;
use catmap::dataset::replica::{ReplicaOptions, ReplicaSequence};
use catmap::dataset::scannet::{ScanNetOptions, ScanNetSequence};
use catmap::dataset::tum::{TumOptions, TumSequence};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// A random edit of one file of `files`: a format-aware mutation, another file's content, an
/// empty file, deletion, a folder in its place, or a rename to an odd frame number.
fn folder_edit(files: &FileSet, rng: &mut ChaCha8Rng) -> FolderEdit {
    let paths: Vec<&String> = files.keys().collect();
    let path = (*pick(&paths, rng)).clone();
    let bytes = &files[&path];
    match rng.random_range(0..12) {
        0 => FolderEdit::Delete { path },
        1 => FolderEdit::Folder { path },
        2 => {
            let (dir, name) = path.rsplit_once('/').unwrap_or(("", &path));
            let digits: String = name.chars().filter(char::is_ascii_digit).collect();
            let number = *pick(
                &[
                    "01",
                    "7",
                    "-1",
                    "1.5",
                    "",
                    "18446744073709551615",
                    "99999999999999999999",
                ],
                rng,
            );
            let renamed = if digits.is_empty() {
                format!("{name}.bak")
            } else {
                name.replacen(&digits, number, 1)
            };
            let to = if dir.is_empty() {
                renamed
            } else {
                format!("{dir}/{renamed}")
            };
            if to == path {
                FolderEdit::Delete { path }
            } else {
                FolderEdit::Rename { from: path, to }
            }
        }
        3 => FolderEdit::Replace {
            bytes: files[*pick(&paths, rng)].clone(),
            path,
        },
        4 => FolderEdit::Replace {
            path,
            bytes: Vec::new(),
        },
        _ => {
            let bytes = if path.ends_with(".png") {
                match rng.random_range(0..4) {
                    0 => generate_png(rng),
                    _ => mutate_png(bytes, rng),
                }
            } else if path.ends_with(".txt") || path.ends_with(".json") {
                mutate_text(&String::from_utf8_lossy(bytes), &[], rng)
            } else {
                mutate_bytes(bytes, &[], rng)
            };
            FolderEdit::Replace { path, bytes }
        }
    }
}

/// Opens a sequence in the edited folder and reads every frame; an error must name a file the
/// edit touched, by its path in the folder (`depth/0.png`: ScanNet's file names alone repeat
/// across folders).
fn read_all<S: FrameSource>(
    folder: &Folder,
    edit: &FolderEdit,
    open: impl Fn(&Path) -> catmap::Result<S>,
) -> Execution {
    let _restore = folder.apply_until_dropped(edit);
    let needles = edit.paths();
    let sequence = match open(folder.path()) {
        Ok(sequence) => sequence,
        Err(e) => return rejected_naming_one_of(&e, &needles),
    };
    let mut verdict = Verdict::Accepted;
    for position in 0..sequence.len() {
        match sequence.read_frame(position) {
            Ok(frame) => check_frame(&frame)?,
            Err(e) => verdict = rejected_naming_one_of(&e, &needles)?,
        }
    }
    Ok(verdict)
}

#[test]
fn replica_folders_with_a_damaged_file_never_panic_and_errors_name_the_file() {
    let folder = Folder::new(replica_files(2));
    let files = folder.files().clone();
    let open = |dir: &Path| ReplicaSequence::open(dir, &ReplicaOptions::default());
    let execute = |edit: &FolderEdit| read_all(&folder, edit, open);
    fuzz(
        "replica_folder",
        |rng| folder_edit(&files, rng),
        execute,
        FolderEdit::describe,
    );
}

#[test]
fn scannet_folders_with_a_damaged_file_never_panic_and_errors_name_the_file() {
    let folder = Folder::new(scannet_files(2));
    let files = folder.files().clone();
    let open = |dir: &Path| ScanNetSequence::open(dir, &ScanNetOptions::default());
    let execute = |edit: &FolderEdit| read_all(&folder, edit, open);
    fuzz(
        "scannet_folder",
        |rng| folder_edit(&files, rng),
        execute,
        FolderEdit::describe,
    );
}

/// The TUM RGB-D reader: its three lists (`rgb.txt`, `depth.txt`, `groundtruth.txt`) mutated as
/// text, its images and masks as PNG; a colour image that loses its masks or its match in time is
/// skipped, so such edits are accepted.
#[test]
fn tum_folders_with_a_damaged_file_never_panic_and_errors_name_the_file() {
    let folder = Folder::new(tum_files(3));
    let files = folder.files().clone();
    let open = |dir: &Path| TumSequence::open(dir, &TumOptions::default());
    let execute = |edit: &FolderEdit| read_all(&folder, edit, open);
    fuzz(
        "tum_folder",
        |rng| folder_edit(&files, rng),
        execute,
        FolderEdit::describe,
    );
}
