//! The checkpoint folder. `checkpoint.json` (the manifest) names one *generation*: its state file
//! `state-{g}.bin` (postcard-encoded serde data) and its tensor file `tensors-{g}.safetensors`,
//! each with its size and CRC-32. A new generation writes both files (temp + rename), then
//! replaces the manifest atomically, then deletes older generations. A kill at any moment leaves
//! either the old manifest with its intact files or the new one with its intact files; torn or
//! altered files fail the checksum and are never loaded.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::TensorStore;
use crate::atomic_file::write_atomic;
use crate::error::{CatmapError, Result};

/// The manifest's file name.
pub const MANIFEST: &str = "checkpoint.json";
/// Format tag written to (and required in) the manifest.
pub const FORMAT: &str = "catmap-checkpoint-3";

/// One file of a generation.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CheckpointFile {
    /// File name inside the checkpoint folder.
    pub name: String,
    /// Size in bytes.
    pub bytes: u64,
    /// CRC-32 (IEEE) of the content.
    pub crc32: u32,
}

/// The manifest: which generation is current and how to verify it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CheckpointManifest {
    /// Always [`FORMAT`].
    pub format: String,
    /// Generation number (increases by one per checkpoint).
    pub generation: u64,
    /// What the checkpoint holds, for people (e.g. "frame 120 of 240").
    pub label: String,
    /// The serde state.
    pub state: CheckpointFile,
    /// The tensors.
    pub tensors: CheckpointFile,
}

/// A checkpoint read back and verified.
#[derive(Debug)]
pub struct LoadedCheckpoint<T> {
    /// Its manifest.
    pub manifest: CheckpointManifest,
    /// The decoded state.
    pub state: T,
    /// The decoded tensors.
    pub tensors: TensorStore,
}

/// Writes a new generation of the checkpoint in `dir` (created if needed); returns its manifest.
pub fn write_checkpoint<T: Serialize>(
    dir: &Path,
    state: &T,
    tensors: &TensorStore,
    label: &str,
) -> Result<CheckpointManifest> {
    std::fs::create_dir_all(dir).map_err(|e| CatmapError::io(dir, e))?;
    let generation = next_generation(dir);
    let state_bytes = postcard::to_stdvec(state)
        .map_err(|e| CatmapError::checkpoint(dir, format!("cannot encode the state: {e}")))?;
    let tensor_bytes = tensors.to_safetensors()?;
    let state = write_part(dir, &format!("state-{generation}.bin"), &state_bytes)?;
    let tensors = write_part(dir, &format!("tensors-{generation}.safetensors"), &tensor_bytes)?;
    let manifest = CheckpointManifest {
        format: FORMAT.to_owned(),
        generation,
        label: label.to_owned(),
        state,
        tensors,
    };
    let mut text = serde_json::to_string_pretty(&manifest)
        .map_err(|e| CatmapError::checkpoint(dir, format!("cannot encode the manifest: {e}")))?;
    text.push('\n');
    write_atomic(&dir.join(MANIFEST), text.as_bytes())?;
    sync_dir(dir);
    remove_other_generations(dir, &manifest);
    Ok(manifest)
}

/// Reads and verifies the current generation in `dir`.
pub fn read_checkpoint<T: DeserializeOwned>(dir: &Path) -> Result<LoadedCheckpoint<T>> {
    let manifest = read_manifest(dir)?;
    let state_path = dir.join(&manifest.state.name);
    let state_bytes = read_part(dir, &manifest.state)?;
    let state = postcard::from_bytes(&state_bytes).map_err(|e| CatmapError::checkpoint(&state_path, format!("{e}")))?;
    let tensor_path = dir.join(&manifest.tensors.name);
    let tensors = TensorStore::from_safetensors(&read_part(dir, &manifest.tensors)?, &tensor_path)?;
    Ok(LoadedCheckpoint {
        manifest,
        state,
        tensors,
    })
}

/// Checks that the current generation in `dir` is complete and intact (sizes and CRC-32s)
/// without decoding it; returns its manifest.
pub fn verify_checkpoint(dir: &Path) -> Result<CheckpointManifest> {
    let manifest = read_manifest(dir)?;
    read_part(dir, &manifest.state)?;
    read_part(dir, &manifest.tensors)?;
    Ok(manifest)
}

/// Reads the manifest of `dir` (without verifying the files it names).
pub fn read_manifest(dir: &Path) -> Result<CheckpointManifest> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| CatmapError::io(&path, e))?;
    let manifest: CheckpointManifest =
        serde_json::from_str(&text).map_err(|e| CatmapError::checkpoint(&path, format!("bad manifest: {e}")))?;
    if manifest.format != FORMAT {
        return Err(CatmapError::checkpoint(
            &path,
            format!("format {:?}, this catmap reads {FORMAT:?}", manifest.format),
        ));
    }
    for file in [&manifest.state, &manifest.tensors] {
        if file.name.contains(['/', '\\']) || file.name.starts_with('.') {
            return Err(CatmapError::checkpoint(&path, format!("bad file name {:?}", file.name)));
        }
    }
    Ok(manifest)
}

fn write_part(dir: &Path, name: &str, bytes: &[u8]) -> Result<CheckpointFile> {
    write_atomic(&dir.join(name), bytes)?;
    Ok(CheckpointFile {
        name: name.to_owned(),
        bytes: bytes.len() as u64,
        crc32: crc32fast::hash(bytes),
    })
}

fn read_part(dir: &Path, file: &CheckpointFile) -> Result<Vec<u8>> {
    let path = dir.join(&file.name);
    let bytes = std::fs::read(&path).map_err(|e| CatmapError::io(&path, e))?;
    if bytes.len() as u64 != file.bytes {
        return Err(CatmapError::checkpoint(
            &path,
            format!("{} bytes, the manifest says {} (torn write?)", bytes.len(), file.bytes),
        ));
    }
    let crc = crc32fast::hash(&bytes);
    if crc != file.crc32 {
        return Err(CatmapError::checkpoint(
            &path,
            format!("CRC-32 {crc:08x}, the manifest says {:08x}", file.crc32),
        ));
    }
    Ok(bytes)
}

/// One more than the current manifest's generation, or than any generation file lying around.
fn next_generation(dir: &Path) -> u64 {
    let from_manifest = read_manifest(dir).map(|m| m.generation).unwrap_or(0);
    let from_files = generation_files(dir).into_iter().map(|(g, _)| g).max().unwrap_or(0);
    from_manifest.max(from_files) + 1
}

/// `(generation, path)` of every `state-{g}.bin` / `tensors-{g}.safetensors` (and their temps).
fn generation_files(dir: &Path) -> Vec<(u64, PathBuf)> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter_map(|path| {
            let name = path.file_name()?.to_str()?;
            let name = name.strip_suffix(".tmp").unwrap_or(name);
            let number = name
                .strip_prefix("state-")
                .and_then(|n| n.strip_suffix(".bin"))
                .or_else(|| {
                    name.strip_prefix("tensors-")
                        .and_then(|n| n.strip_suffix(".safetensors"))
                })?;
            Some((number.parse().ok()?, path))
        })
        .collect()
}

fn remove_other_generations(dir: &Path, keep: &CheckpointManifest) {
    for (generation, path) in generation_files(dir) {
        if generation != keep.generation
            && let Err(e) = std::fs::remove_file(&path)
        {
            tracing::warn!(path = %path.display(), error = %e, "cannot remove an old checkpoint file");
        }
    }
}

/// Makes the renames durable across a power cut (a kill alone cannot lose them).
fn sync_dir(dir: &Path) {
    if let Ok(handle) = std::fs::File::open(dir) {
        let _ = handle.sync_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn store(x: f32) -> TensorStore {
        let mut t = TensorStore::new();
        t.insert("w", vec![x, 2.0 * x]);
        t
    }

    #[test]
    fn generations_replace_each_other_and_read_back() {
        let dir = tempfile::tempdir().expect("temp dir");
        let first = write_checkpoint(dir.path(), &("one", 1u64), &store(1.0), "first").expect("writes");
        let second = write_checkpoint(dir.path(), &("two", 2u64), &store(2.0), "second").expect("writes");
        assert_eq!(second.generation, first.generation + 1);
        let loaded: LoadedCheckpoint<(String, u64)> = read_checkpoint(dir.path()).expect("reads");
        assert_eq!(loaded.state, ("two".to_owned(), 2));
        assert_eq!(loaded.tensors, store(2.0));
        assert_eq!(loaded.manifest.label, "second");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .expect("lists")
            .map(|e| e.expect("entry").file_name().into_string().expect("utf-8"))
            .collect();
        assert_eq!(names.len(), 3, "old generation removed: {names:?}");
    }

    #[test]
    fn a_torn_or_altered_file_is_refused_naming_it() {
        let dir = tempfile::tempdir().expect("temp dir");
        let manifest = write_checkpoint(dir.path(), &vec![7u8; 100], &store(1.0), "x").expect("writes");
        let tensors = dir.path().join(&manifest.tensors.name);
        let mut bytes = std::fs::read(&tensors).expect("reads");
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(&tensors, &bytes).expect("alters");
        let err = read_checkpoint::<Vec<u8>>(dir.path()).unwrap_err().to_string();
        assert!(err.contains("CRC-32") && err.contains(&manifest.tensors.name), "{err}");
        let state = dir.path().join(&manifest.state.name);
        let bytes = std::fs::read(&state).expect("reads");
        std::fs::write(&state, &bytes[..bytes.len() / 2]).expect("truncates");
        let err = read_checkpoint::<Vec<u8>>(dir.path()).unwrap_err().to_string();
        assert!(
            err.contains("torn write") && err.contains(&manifest.state.name),
            "{err}"
        );
    }

    #[test]
    fn leftovers_of_a_killed_write_do_not_disturb_the_current_generation() {
        let dir = tempfile::tempdir().expect("temp dir");
        let manifest = write_checkpoint(dir.path(), &5u32, &store(1.0), "x").expect("writes");
        // A kill after writing half of the next generation's state file.
        let next = manifest.generation + 1;
        std::fs::write(dir.path().join(format!("state-{next}.bin.tmp")), [1, 2, 3]).expect("writes");
        std::fs::write(dir.path().join("checkpoint.json.tmp"), "{\"form").expect("writes");
        assert_eq!(verify_checkpoint(dir.path()).expect("intact"), manifest);
        let loaded: LoadedCheckpoint<u32> = read_checkpoint(dir.path()).expect("reads the intact generation");
        assert_eq!(loaded.state, 5);
        let newer = write_checkpoint(dir.path(), &6u32, &store(3.0), "y").expect("writes");
        assert_eq!(
            newer.generation,
            next + 1,
            "skips the generation whose files were left behind"
        );
        let loaded: LoadedCheckpoint<u32> = read_checkpoint(dir.path()).expect("reads");
        assert_eq!(loaded.state, 6);
    }

    #[test]
    fn a_missing_or_foreign_manifest_is_a_clear_error() {
        let dir = tempfile::tempdir().expect("temp dir");
        let err = read_checkpoint::<u32>(dir.path()).unwrap_err().to_string();
        assert!(err.contains(MANIFEST), "{err}");
        std::fs::write(dir.path().join(MANIFEST), "{\"format\": \"other\"}").expect("writes");
        let err = read_checkpoint::<u32>(dir.path()).unwrap_err().to_string();
        assert!(err.contains("bad manifest"), "{err}");
    }
}
