//! Geometry shared by every layer: oriented boxes, nearest-neighbour queries, triangle meshes and
//! their PLY files.

pub mod connected_parts;
pub mod face_normals_turn;
pub mod local_plane;
pub mod local_surfaces;
pub mod mesh;
pub mod mirror_symmetry;
pub mod nearest;
pub mod oriented_box;
pub mod round_axis;
pub mod tolerance_grid;
pub mod tracked_nearest;
pub mod upright_box;
