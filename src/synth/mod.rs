//! Procedural synthetic indoor scenes with exact ground truth, deterministic from a seed.
//!
//! A scene is a room (floor and walls, Replica background classes) furnished with primitive-built
//! [`Design`]s — two clearly different chair designs in several identical copies each, a table with
//! chairs tucked under it, a cabinet, a box, a lamp, a stool, a nightstand — and a camera walking
//! along one side of the room so that every object is only partly observed. Frames are ray cast
//! through a BVH on demand ([`SyntheticScene`] is a [`FrameSource`](crate::dataset::FrameSource)),
//! and [`write_replica_layout`] writes them in the Replica vMAP layout with ground-truth meshes
//! ([`write_tum_layout`]: in TUM RGB-D's layout with masks; [`write_scannet_layout`]: in ScanNet's).
//!
//! ```no_run
//! use catmap::synth::{Preset, SyntheticScene, write_replica_layout};
//! let scene = SyntheticScene::generate(7, Preset::Small)?;
//! write_replica_layout(&scene, std::path::Path::new("/tmp/synthetic"), |_, _| {})?;
//! # Ok::<(), catmap::CatmapError>(())
//! ```

pub mod bvh;
pub mod description;
pub mod exterior;
pub mod furniture;
pub mod geometry;
pub mod layout;
pub mod preset;
pub mod primitives;
pub mod reachable_space;
pub mod registration_trial;
pub mod render;
pub mod replica_writer;
pub mod room;
pub mod scannet_writer;
pub mod scene;
pub mod sensor_noise;
pub mod trajectory;
pub mod tum_writer;

pub use description::{ObjectDescription, SceneDescription};
pub use furniture::Design;
pub use preset::Preset;
pub use registration_trial::{RegistrationTrial, RegistrationTrialSpec};
pub use render::RenderedFrame;
pub use replica_writer::write_replica_layout;
pub use room::{Room, SurfaceLabel};
pub use scannet_writer::write_scannet_layout;
pub use scene::{SceneObject, SyntheticScene};
pub use sensor_noise::{InstanceIds, SensorModel, SensorSettings};
pub use tum_writer::write_tum_layout;
