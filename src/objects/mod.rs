//! What the map keeps of one object (METHOD.md §1): what each frame says about it, its keyframes
//! and the crops it keeps of them, its observed point cloud and its oriented box.

pub mod association_config;
pub mod border_votes;
pub mod cell_evidence;
pub mod cell_rules;
pub mod config;
pub mod frame_observation;
pub mod hidden_space;
pub mod instance_association;
pub mod keyframes;
pub mod mask_footprint;
pub mod mask_trim;
pub mod object_bounds;
pub mod object_merge;
pub mod object_view;
pub mod observed_cloud;
pub mod observed_space;
pub mod pair_evidence;
pub mod segment;
#[cfg(test)]
pub(crate) mod view_fixtures;
