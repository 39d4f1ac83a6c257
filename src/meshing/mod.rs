//! Surfaces from fields: marching cubes on dense grids, and the per-object meshing grid.
//!
//! - [`marching_cubes`] / [`IsoSurfaceExtractor`]: the iso-surface of a scalar grid as a closed,
//!   welded, outward-oriented [`TriangleMesh`](crate::geometry::mesh::TriangleMesh) (inside = value > iso).
//! - [`extract_object_mesh`]: METHOD.md §6 — sample an object's occupancy on a 5 mm grid over its
//!   enlarged box, one z-layer at a time, and mesh it at its surface level (occupancy 0.75, see
//!   [`object_grid`]) in world coordinates;
//!   [`paint_vertices`] adds colours from the field. By default the grid is sampled coarse to fine
//!   ([`coarse_to_fine`]): the field is evaluated densely only in blocks the surface may cross.
//!
//! ```
//! use catmap::meshing::{SampleGrid, marching_cubes};
//! use nalgebra::Point3;
//! let grid = SampleGrid::cubic(Point3::new(-1.0, -1.0, -1.0), 0.1, [21; 3]);
//! let mut values = Vec::new();
//! let mut layer = Vec::new();
//! for k in 0..21 {
//!     grid.layer_positions(k, &mut layer);
//!     values.extend(layer.iter().map(|p| 0.8 - p.coords.norm())); // a ball of radius 0.8
//! }
//! let ball = marching_cubes(&values, &grid, 0.0)?;
//! assert!((ball.area() - 4.0 * std::f32::consts::PI * 0.64).abs() < 0.2);
//! # Ok::<(), catmap::CatmapError>(())
//! ```

pub mod case_table;
pub mod coarse_to_fine;
mod config;
mod field_mesh;
mod map_meshes;
mod marching_cubes;
pub mod object_grid;
pub mod sample_grid;

pub use config::MeshConfig;
pub use field_mesh::{mesh_category_member, mesh_occupancy_field};
pub use map_meshes::MapMeshes;
pub use marching_cubes::{IsoSurfaceExtractor, marching_cubes};
pub use object_grid::{ObjectFrame, ObjectGrid, ObjectMeshConfig, extract_object_mesh, paint_vertices};
pub use sample_grid::SampleGrid;
