//! All meshes of a map and how they are written: `obj_{id}.ply` per object (dataset instance
//! ids), `background.ply`, and `scene.ply` (everything merged). Each file is written atomically.

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{CatmapError, Result};
use crate::geometry::mesh::TriangleMesh;
use crate::ids::ObjectId;
use crate::metrics::mesh_file_name;

/// The meshes of one map.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MapMeshes {
    /// Object meshes by dataset instance id (world coordinates).
    pub objects: BTreeMap<ObjectId, TriangleMesh>,
    /// The background's mesh, when it has a field.
    pub background: Option<TriangleMesh>,
}

impl MapMeshes {
    /// Writes every mesh into `dir` (created if needed); returns the number of files written.
    /// Empty object meshes are skipped with a warning (nothing was occupied).
    pub fn write_dir(&self, dir: &Path) -> Result<usize> {
        std::fs::create_dir_all(dir).map_err(|e| CatmapError::io(dir, e))?;
        let mut written = 0;
        for (id, mesh) in &self.objects {
            if mesh.is_empty() {
                tracing::warn!(object = %id, "empty mesh (no occupied sample), not written");
                continue;
            }
            mesh.write_ply(&dir.join(mesh_file_name(*id)))?;
            written += 1;
        }
        if let Some(background) = self.background.as_ref().filter(|m| !m.is_empty()) {
            background.write_ply(&dir.join("background.ply"))?;
            written += 1;
        }
        let scene = TriangleMesh::merged(self.objects.values().chain(self.background.iter()));
        if !scene.is_empty() {
            scene.write_ply(&dir.join("scene.ply"))?;
            written += 1;
        }
        Ok(written)
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;

    #[test]
    fn writes_objects_background_and_scene_and_skips_empty_meshes() {
        let tri = TriangleMesh::new(
            vec![Point3::origin(), Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.0)],
            vec![[0, 1, 2]],
        );
        let mut meshes = MapMeshes::default();
        meshes.objects.insert(ObjectId(3), tri.clone());
        meshes.objects.insert(ObjectId(4), TriangleMesh::default());
        meshes.background = Some(tri);
        let dir = tempfile::tempdir().expect("temp dir");
        assert_eq!(meshes.write_dir(dir.path()).expect("write"), 3);
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["background.ply", "obj_3.ply", "scene.ply"]);
        let scene = TriangleMesh::read_ply(&dir.path().join("scene.ply")).expect("read back");
        assert_eq!(scene.triangles.len(), 2);
    }
}
