//! PLY input and output of [`TriangleMesh`].

use std::fs::File;
use std::io::{BufReader, Write};
use std::path::Path;

use nalgebra::Point3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};

use super::TriangleMesh;
use crate::atomic_file::write_atomic_with;
use crate::error::{CatmapError, Result};

impl TriangleMesh {
    /// Writes binary little-endian PLY to `path` atomically (via `path.ply.tmp` and a rename).
    pub fn write_ply(&self, path: &Path) -> Result<()> {
        self.validate().map_err(|reason| CatmapError::layout(path, reason))?;
        if self.vertices.len() > i32::MAX as usize {
            return Err(CatmapError::layout(path, "too many vertices for PLY int indices"));
        }
        write_atomic_with(path, |out| {
            out.write_all(self.ply_header().as_bytes())?;
            for (i, v) in self.vertices.iter().enumerate() {
                for x in v.coords.iter() {
                    out.write_all(&x.to_le_bytes())?;
                }
                if let Some(colors) = &self.colors {
                    out.write_all(&colors[i])?;
                }
            }
            for t in &self.triangles {
                out.write_all(&[3])?;
                for i in t {
                    out.write_all(&i.to_le_bytes())?; // < i32::MAX, so the same bytes as an int
                }
            }
            Ok(())
        })
    }

    fn ply_header(&self) -> String {
        let color = if self.colors.is_some() {
            "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        } else {
            ""
        };
        format!(
            "ply\nformat binary_little_endian 1.0\ncomment written by catmap\nelement vertex {}\n\
             property float x\nproperty float y\nproperty float z\n{color}element face {}\n\
             property list uchar int vertex_indices\nend_header\n",
            self.vertices.len(),
            self.triangles.len()
        )
    }

    /// Reads an ASCII or binary PLY mesh. Polygons are fan-triangulated; other elements and
    /// properties are ignored. Errors name `path` and what is wrong.
    pub fn read_ply(path: &Path) -> Result<Self> {
        let file = File::open(path).map_err(|e| CatmapError::io(path, e))?;
        let ply = Parser::<PlyRecord>::new()
            .read_ply(&mut BufReader::new(file))
            .map_err(|e| CatmapError::Parse {
                path: path.to_owned(),
                line: e.line().unwrap_or(0),
                reason: e.to_string(),
            })?;
        let bad = |reason: String| CatmapError::Parse {
            path: path.to_owned(),
            line: 0,
            reason,
        };
        let vertex_def = ply
            .header
            .elements
            .get("vertex")
            .ok_or_else(|| bad("no vertex element".into()))?;
        let has = |name: &str| vertex_def.properties.contains_key(name);
        if !(has("x") && has("y") && has("z")) {
            return Err(bad("vertex element lacks x, y or z".into()));
        }
        let empty = Vec::new();
        let vertex_records = ply.payload.get("vertex").unwrap_or(&empty);
        let vertices: Vec<_> = vertex_records.iter().map(|r| Point3::from(r.xyz)).collect();
        let colors =
            (has("red") && has("green") && has("blue")).then(|| vertex_records.iter().map(|r| r.rgb).collect());
        let mut triangles = Vec::new();
        for (f, face) in ply.payload.get("face").unwrap_or(&empty).iter().enumerate() {
            if face.indices.len() < 3 {
                return Err(bad(format!("face {f} has {} vertices", face.indices.len())));
            }
            if let Some(i) = face.indices.iter().find(|&&i| i as usize >= vertices.len()) {
                return Err(bad(format!("face {f} uses vertex {i} of {}", vertices.len())));
            }
            let i0 = face.indices[0];
            triangles.extend(face.indices[1..].windows(2).map(|w| [i0, w[0], w[1]]));
        }
        Ok(Self {
            vertices,
            triangles,
            colors,
        })
    }
}

#[derive(Debug, Default)]
struct PlyRecord {
    xyz: [f32; 3],
    rgb: [u8; 3],
    indices: Vec<u32>,
}

impl PropertyAccess for PlyRecord {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let stored = match name {
            "x" => store(&mut self.xyz[0], property.to_f32_lossy()),
            "y" => store(&mut self.xyz[1], property.to_f32_lossy()),
            "z" => store(&mut self.xyz[2], property.to_f32_lossy()),
            "red" => store(&mut self.rgb[0], property.to_u8_color_lossy()),
            "green" => store(&mut self.rgb[1], property.to_u8_color_lossy()),
            "blue" => store(&mut self.rgb[2], property.to_u8_color_lossy()),
            "vertex_indices" | "vertex_index" => store(&mut self.indices, property.to_u32_list()),
            _ => return PropertyAccessResult::Ignored,
        };
        if stored {
            PropertyAccessResult::Set
        } else {
            PropertyAccessResult::UnsupportedType
        }
    }
}

/// Writes `value` into `slot` when the conversion succeeded.
fn store<T>(slot: &mut T, value: Option<T>) -> bool {
    value.map(|v| *slot = v).is_some()
}
