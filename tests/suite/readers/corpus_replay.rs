//! Replays the corpus of bad inputs in `tests/corpus/`: every file must be refused with an error
//! that names the file and gives the reason listed for it in `tests/corpus/expected.toml` — never
//! a panic, never an accepted frame.
//!
//! Layout: `png/NAME` is decoded on its own as RGB, 8-bit grey and 16-bit grey; `config/NAME` is
//! loaded as a config file; `replica/SLOT/NAME`, `scannet/SLOT/NAME` and `tum/SLOT/NAME` replace
//! the file `SLOT` (e.g. `traj_w_c.txt`, `pose/0.txt`, `rgb.txt`) of a small valid dataset folder,
//! which is then opened and read frame by frame. Inputs the fuzzers (`tests/suite/readers/fuzz_readers.rs`) found are kept here with the
//! iteration that found them in their name.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::fuzz_support::fixtures::{FileSet, Folder, FolderEdit, replica_files, scannet_files, tum_files};
use catmap::MapperConfig;
use catmap::dataset::FrameSource;
use catmap::dataset::images::{grey_from_bytes, grey16_from_bytes, rgb_from_bytes};
use catmap::dataset::replica::{ReplicaOptions, ReplicaSequence};
use catmap::dataset::scannet::{ScanNetOptions, ScanNetSequence};
use catmap::dataset::tum::{TumOptions, TumSequence};

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus")
}

/// Every corpus file, relative to the corpus folder, with `/` separators.
fn corpus_files() -> Vec<String> {
    fn walk(dir: &Path, root: &Path, out: &mut Vec<String>) {
        for entry in std::fs::read_dir(dir).expect("corpus folder") {
            let path = entry.expect("corpus entry").path();
            if path.is_dir() {
                walk(&path, root, out);
            } else if path.file_name().is_some_and(|n| n != "expected.toml") {
                let relative = path.strip_prefix(root).expect("inside the corpus");
                let parts: Vec<_> = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
                out.push(parts.join("/"));
            }
        }
    }
    let mut files = Vec::new();
    walk(&corpus_dir(), &corpus_dir(), &mut files);
    files.sort();
    files
}

fn expectations() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(corpus_dir().join("expected.toml")).expect("tests/corpus/expected.toml");
    toml::from_str(&text).expect("expected.toml maps corpus files to reasons")
}

/// The error a dataset folder gives with `slot` replaced by `bytes`: opening it, or the first frame
/// that fails. `None` when every frame was read.
fn folder_error<S: FrameSource>(
    files: FileSet,
    slot: &str,
    bytes: Vec<u8>,
    open: impl Fn(&Path) -> catmap::Result<S>,
) -> Option<String> {
    let folder = Folder::new(files);
    folder.apply(&FolderEdit::Replace {
        path: slot.to_owned(),
        bytes,
    });
    let sequence = match open(folder.path()) {
        Ok(sequence) => sequence,
        Err(e) => return Some(e.to_string()),
    };
    (0..sequence.len()).find_map(|position| sequence.read_frame(position).err().map(|e| e.to_string()))
}

/// The errors one corpus file gives (one per decoder for images), each with the file name it
/// must mention; an `Err` when it was accepted.
fn replay(relative: &str) -> Result<Vec<(String, String)>, String> {
    let path = corpus_dir().join(relative);
    let bytes = std::fs::read(&path).expect("corpus file");
    let (kind, rest) = relative.split_once('/').expect("KIND/...");
    let slot = rest.rsplit_once('/').map_or(rest, |(slot, _)| slot);
    let slot_name = slot.rsplit('/').next().unwrap_or(slot).to_owned();
    let accepted = || format!("{relative} was accepted");
    match kind {
        "png" => {
            let name = path.file_name().expect("file").to_string_lossy().into_owned();
            let errors = [
                rgb_from_bytes(&bytes, &path).err(),
                grey_from_bytes(&bytes, &path).err(),
                grey16_from_bytes(&bytes, &path).err(),
            ];
            errors
                .into_iter()
                .map(|e| e.map(|e| (e.to_string(), name.clone())).ok_or_else(accepted))
                .collect()
        }
        "config" => {
            let name = path.file_name().expect("file").to_string_lossy().into_owned();
            let err = MapperConfig::load(&path).err().ok_or_else(accepted)?;
            Ok(vec![(err.to_string(), name)])
        }
        "replica" => {
            let open = |dir: &Path| ReplicaSequence::open(dir, &ReplicaOptions::default());
            let err = folder_error(replica_files(3), slot, bytes, open).ok_or_else(accepted)?;
            Ok(vec![(err, slot_name)])
        }
        "scannet" => {
            let open = |dir: &Path| ScanNetSequence::open(dir, &ScanNetOptions::default());
            let err = folder_error(scannet_files(2), slot, bytes, open).ok_or_else(accepted)?;
            Ok(vec![(err, slot_name)])
        }
        "tum" => {
            let open = |dir: &Path| TumSequence::open(dir, &TumOptions::default());
            let err = folder_error(tum_files(3), slot, bytes, open).ok_or_else(accepted)?;
            Ok(vec![(err, slot_name)])
        }
        other => Err(format!("{relative}: unknown corpus kind {other:?}")),
    }
}

#[test]
fn the_pristine_fixtures_are_read_without_error() {
    let replica = Folder::new(replica_files(3));
    let sequence = ReplicaSequence::open(replica.path(), &ReplicaOptions::default()).expect("valid Replica fixture");
    assert_eq!(sequence.len(), 3);
    (0..3).for_each(|p| drop(sequence.read_frame(p).expect("valid frame")));
    let scannet = Folder::new(scannet_files(2));
    let sequence = ScanNetSequence::open(scannet.path(), &ScanNetOptions::default()).expect("valid ScanNet fixture");
    assert_eq!(sequence.len(), 2);
    (0..2).for_each(|p| drop(sequence.read_frame(p).expect("valid frame")));
    let tum = Folder::new(tum_files(3));
    let sequence = TumSequence::open(tum.path(), &TumOptions::default()).expect("valid TUM fixture");
    assert_eq!(sequence.len(), 3);
    (0..3).for_each(|p| drop(sequence.read_frame(p).expect("valid frame")));
}

#[test]
fn every_corpus_input_is_refused_naming_the_file_and_the_reason() {
    let expected = expectations();
    let files = corpus_files();
    assert!(files.len() >= 30, "the corpus holds {} files", files.len());
    let mut problems = Vec::new();
    for relative in &files {
        let Some(reason) = expected.get(relative) else {
            let got = replay(relative);
            problems.push(format!("{relative}: not in expected.toml (it gives {got:?})"));
            continue;
        };
        match replay(relative) {
            Err(e) => problems.push(e),
            Ok(errors) => {
                for (message, name) in errors {
                    if !message.contains(&name) || !message.contains(reason.as_str()) {
                        problems.push(format!("{relative}: expected {name:?} and {reason:?} in: {message}"));
                    }
                }
            }
        }
    }
    for listed in expected.keys().filter(|k| !files.contains(k)) {
        problems.push(format!("{listed}: listed in expected.toml but missing"));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
