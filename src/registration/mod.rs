//! Registration of a partially observed object cloud (source) to its category representative's
//! cloud (template), as METHOD.md §4 specifies.
//!
//! [`register_to_representative`] composes the pieces, one concept per file:
//! - [`voxel_centroids`]: centroid voxel downsampling;
//! - [`robust_start`]: METHOD's own front end + back end, as one optional start;
//! - front ends: correspondence-free all-to-all pairs ([`consistency::all_to_all_pairs`]) or
//!   FPFH descriptors ([`fpfh`], normals from [`normals`]) matched by mutual nearest neighbours;
//! - the TEASER++ back end without scale ([`teaser`]): pairwise-length [`consistency`] graph,
//!   [`max_clique`], [`gnc_tls`] rotation, [`scalar_tls`] translation;
//! - point-to-point [`icp`] refinement over a kiddo k-d tree ([`crate::geometry::nearest::PointIndex`]);
//! - the 24 [`cube_rotations`] as initial orientations, scored by the scale-normalised one-way
//!   [`chamfer`] distance.
//!
//! Everything is pure and deterministic given the caller's random generator.

pub mod chamfer;
pub mod cloud;
pub mod config;
pub mod consistency;
pub mod cube_rotations;
pub mod fpfh;
pub mod gnc_tls;
pub mod horn;
pub mod icp;
pub mod max_clique;
pub mod normals;
pub mod register;
pub mod robust_start;
pub mod scalar_tls;
mod start_rotations;
pub mod teaser;

pub use chamfer::{normalised_one_way_chamfer, one_way_chamfer};
pub use cloud::{half_max_extent, voxel_centroids};
pub use config::{FrontEnd, RegistrationConfig, Rotations, Tilt};
pub use cube_rotations::cube_rotations;
pub use register::{Registration, RegistrationTrace, refine_registration, register_to_representative};
pub use robust_start::{RobustTrace, front_end_correspondences};
