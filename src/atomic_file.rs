//! Writing files so that a reader never sees half of one: write a temporary sibling, then rename.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{CatmapError, Result};

/// The temporary sibling `path` is written through (`name.tmp` in the same folder).
pub fn temp_path_for(path: &Path) -> PathBuf {
    let mut name = path.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(".tmp");
    path.with_file_name(name)
}

/// Writes `bytes` to `path` atomically, creating parent folders as needed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |file| file.write_all(bytes))
}

/// Writes `path` atomically through `fill`, which receives a buffered writer on the temporary file.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<()> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| CatmapError::io(parent, e))?;
    }
    let temp = temp_path_for(path);
    let result = (|| {
        let file = std::fs::File::create(&temp)?;
        let mut writer = std::io::BufWriter::new(file);
        fill(&mut writer)?;
        let file = writer.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&temp);
        return Err(CatmapError::io(path, e));
    }
    std::fs::rename(&temp, path).map_err(|e| CatmapError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_neither_the_file_nor_the_temporary() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("out.json");
        let err = write_atomic_with(&path, |_| Err(std::io::Error::other("disk full"))).expect_err("must fail");
        assert!(
            err.to_string().contains("out.json") && err.to_string().contains("disk full"),
            "{err}"
        );
        assert!(!path.exists() && !temp_path_for(&path).exists());
    }

    #[test]
    fn a_write_creates_parents_and_replaces_old_content() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("a/b/out.txt");
        write_atomic(&path, b"one").expect("write");
        write_atomic(&path, b"two").expect("rewrite");
        assert_eq!(std::fs::read(&path).expect("read"), b"two");
    }
}
