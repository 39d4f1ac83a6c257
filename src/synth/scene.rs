//! A generated synthetic scene: room, placed furniture with ground-truth meshes, camera path, and
//! on-demand rendering behind [`FrameSource`].
//!
//! Everything follows from `(seed, preset)`: a ChaCha8 generator seeded with `seed` draws the
//! furnishing and the layout; surface samples for [`SyntheticScene::observed_surface_fraction`]
//! use each object's own stream of the seed ([`crate::rng::seeded_rng`]).

use std::collections::BTreeMap;
use std::sync::OnceLock;

use nalgebra::{Isometry3, Point3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::furniture::Design;
use super::geometry::SceneGeometry;
use super::layout::place_furniture;
use super::preset::Preset;
use super::render::{RenderedFrame, render_view};
use super::room::{Room, SurfaceLabel};
use super::sensor_noise::SensorSettings;
use super::trajectory::camera_trajectory;
use crate::dataset::{FrameSource, frame_index};
use crate::error::{CatmapError, Result};
use crate::geometry::mesh::TriangleMesh;
use crate::ids::{ClassId, ObjectId};
use crate::rng::{RngStream, seeded_rng};
use crate::sensor::frame::{CameraIntrinsics, RgbdFrame};

/// Surface samples per object for the observed-surface fraction.
pub const OBSERVATION_SAMPLES: usize = 2000;
/// A sample counts as observed when the rendered depth agrees with its depth within this, metres.
pub const OBSERVATION_TOLERANCE_M: f32 = 0.02;

/// One placed piece of furniture.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneObject {
    /// Instance id in the instance images (1..=N).
    pub id: ObjectId,
    /// The design; identical designs give identical shapes.
    pub design: Design,
    /// Pose: object frame (z up, origin at the footprint centre on the floor) → world.
    pub world_from_object: Isometry3<f32>,
    /// Its parts merged, in world coordinates (what the renderer casts rays against).
    pub mesh_in_world: TriangleMesh,
    /// Ground-truth surface in world coordinates: the parts without what lies inside another
    /// part ([`Design::surface`]).
    pub surface_in_world: TriangleMesh,
}

impl SceneObject {
    /// Semantic class (Replica id).
    pub fn class(&self) -> ClassId {
        self.design.class()
    }

    fn label(&self) -> SurfaceLabel {
        let instance_id = u16::try_from(self.id.0).expect("scenes hold fewer than 100 objects");
        SurfaceLabel {
            instance_id,
            class: self.class(),
        }
    }
}

/// A procedurally generated indoor scene, deterministic in `(seed, preset)`.
#[derive(Debug)]
pub struct SyntheticScene {
    seed: u64,
    preset: Preset,
    intrinsics: CameraIntrinsics,
    room: Room,
    objects: Vec<SceneObject>,
    trajectory: Vec<Isometry3<f32>>,
    geometry: SceneGeometry,
    observed: OnceLock<BTreeMap<ObjectId, f32>>,
    sensor: SensorSettings,
}

impl SyntheticScene {
    /// Generates the scene of `preset` for `seed`: furniture layout, meshes, camera path and
    /// the ray-casting structure. Frames are rendered later, on demand.
    pub fn generate(seed: u64, preset: Preset) -> Result<Self> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let room = preset.room();
        let furnishing = preset.furnishing([rng.random::<f32>(), rng.random::<f32>()]);
        let placements = place_furniture(&furnishing, &room, &mut rng)?;
        let mut design_meshes = BTreeMap::new();
        let objects: Vec<SceneObject> = placements
            .into_iter()
            .zip(1..)
            .map(|(p, id)| {
                let (mesh, surface) = design_meshes
                    .entry(p.design)
                    .or_insert_with(|| (p.design.mesh(), p.design.surface()));
                SceneObject {
                    id: ObjectId(id),
                    design: p.design,
                    world_from_object: p.world_from_object,
                    mesh_in_world: mesh.transformed(&p.world_from_object),
                    surface_in_world: surface.transformed(&p.world_from_object),
                }
            })
            .collect();
        let background = room.surfaces();
        let geometry = SceneGeometry::build(
            background.iter().map(|(label, mesh)| (*label, mesh)),
            objects.iter().map(|o| (o.label(), &o.mesh_in_world)),
        );
        Ok(Self {
            seed,
            preset,
            intrinsics: preset.intrinsics(),
            room,
            trajectory: camera_trajectory(&room, preset.frame_count()),
            objects,
            geometry,
            observed: OnceLock::new(),
            sensor: SensorSettings::default(),
        })
    }

    /// The same scene seen through `sensor`'s depth camera and segmenter.
    pub fn with_sensor(mut self, sensor: SensorSettings) -> Self {
        self.sensor = sensor;
        self
    }

    /// The same scene seen through a camera `width` pixels wide, of the presets' field of view
    /// ([`super::preset::camera_of_width`]).
    pub fn with_image_width(mut self, width: u32) -> Self {
        self.intrinsics = super::preset::camera_of_width(width);
        self
    }

    /// The imperfections its frames have.
    pub fn sensor(&self) -> SensorSettings {
        self.sensor
    }

    /// The seed the scene was generated from.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The preset the scene was generated from.
    pub fn preset(&self) -> Preset {
        self.preset
    }

    /// The room.
    pub fn room(&self) -> &Room {
        &self.room
    }

    /// The objects, in id order.
    pub fn objects(&self) -> &[SceneObject] {
        &self.objects
    }

    /// The object with instance id `id`.
    pub fn object(&self, id: ObjectId) -> Option<&SceneObject> {
        self.objects.iter().find(|o| o.id == id)
    }

    /// Camera poses (`world_from_camera`), one per frame.
    pub fn trajectory(&self) -> &[Isometry3<f32>] {
        &self.trajectory
    }

    /// Renders frame `position` with its raw instance-id and class images, as the scene's
    /// sensor gives them.
    pub fn render(&self, position: usize) -> Result<RenderedFrame> {
        let pose = self.trajectory.get(position).ok_or_else(|| {
            CatmapError::layout(
                self.name(),
                format!("frame {position} out of range ({} frames)", self.trajectory.len()),
            )
        })?;
        let mut frame = render_view(&self.geometry, &self.intrinsics, pose);
        if !self.sensor.is_exact() {
            let mut classes: Vec<ClassId> = self.objects.iter().map(SceneObject::class).collect();
            classes.sort_unstable();
            classes.dedup();
            self.sensor.apply(&mut frame, self.seed, position, &classes);
        }
        Ok(frame)
    }

    /// Per object, the fraction of its surface ([`OBSERVATION_SAMPLES`] area-uniform samples) seen in
    /// at least one frame: it projects inside the image, in front of the camera, and the rendered
    /// depth along its ray agrees with its own depth within [`OBSERVATION_TOLERANCE_M`].
    /// Computed once, then cached.
    pub fn observed_surface_fraction(&self) -> &BTreeMap<ObjectId, f32> {
        self.observed.get_or_init(|| self.compute_observed_fractions())
    }

    fn compute_observed_fractions(&self) -> BTreeMap<ObjectId, f32> {
        let samples: Vec<Vec<Point3<f32>>> = self
            .objects
            .iter()
            .map(|o| {
                let mut rng = seeded_rng(self.seed, RngStream::Object(o.id));
                o.surface_in_world
                    .sample_surface(OBSERVATION_SAMPLES, &mut rng)
                    .unwrap_or_default()
            })
            .collect();
        let flat: Vec<Point3<f32>> = samples.iter().flatten().copied().collect();
        let seen = self
            .trajectory
            .par_iter()
            .map(|pose| flat.iter().map(|p| self.sees(pose, p)).collect::<Vec<bool>>())
            .reduce(
                || vec![false; flat.len()],
                |a, b| a.iter().zip(&b).map(|(x, y)| *x || *y).collect(),
            );
        let mut offset = 0;
        self.objects
            .iter()
            .zip(&samples)
            .map(|(o, s)| {
                let hits = seen[offset..offset + s.len()].iter().filter(|&&v| v).count();
                offset += s.len();
                (
                    o.id,
                    if s.is_empty() {
                        0.0
                    } else {
                        hits as f32 / s.len() as f32
                    },
                )
            })
            .collect()
    }

    /// True when the camera at `world_from_camera` sees the surface point `point_in_world`.
    fn sees(&self, world_from_camera: &Isometry3<f32>, point_in_world: &Point3<f32>) -> bool {
        let p = world_from_camera.inverse_transform_point(point_in_world);
        let k = &self.intrinsics;
        let Some((u, v)) = k.project(&p) else {
            return false;
        };
        let inside = u >= -0.5 && v >= -0.5 && u < k.width as f32 - 0.5 && v < k.height as f32 - 0.5;
        if !inside {
            return false;
        }
        let direction = world_from_camera.rotation * (p.coords / p.z);
        let origin = Point3::from(world_from_camera.translation.vector);
        let t_max = p.z + OBSERVATION_TOLERANCE_M;
        self.geometry
            .cast(origin, direction, t_max)
            .is_none_or(|hit| hit.t >= p.z - OBSERVATION_TOLERANCE_M)
    }
}

impl FrameSource for SyntheticScene {
    fn len(&self) -> usize {
        self.trajectory.len()
    }

    fn intrinsics(&self) -> CameraIntrinsics {
        self.intrinsics
    }

    fn read_frame(&self, position: usize) -> Result<RgbdFrame> {
        Ok(self.render(position)?.into_rgbd_frame(frame_index(position)))
    }

    fn name(&self) -> String {
        format!("synthetic-{}-seed{}", self.preset.name(), self.seed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_scene_renders_every_frame_with_objects_in_view() {
        let scene = SyntheticScene::generate(1, Preset::Small).expect("small scene");
        assert_eq!(scene.len(), 30);
        assert_eq!(scene.objects().len(), 6);
        let frame = scene.read_frame(15).expect("frame in range");
        assert_eq!(frame.validate(), Ok(()));
        assert!(
            (0..frame.instances.len()).any(|i| frame.instances.object_at(i).is_some()),
            "objects in view"
        );
        assert!(scene.read_frame(30).is_err(), "out-of-range frame is an error");
    }

    #[test]
    fn observed_fractions_are_computed_once_and_every_object_is_partly_seen() {
        let scene = SyntheticScene::generate(2, Preset::Small).expect("small scene");
        let first = scene.observed_surface_fraction();
        assert!(
            std::ptr::eq(first, scene.observed_surface_fraction()),
            "a second call returns the stored fractions, not a new computation"
        );
        assert_eq!(first.len(), scene.objects().len());
        // Every object of the small scene is in view, and none is seen all round (its underside
        // stands on the floor).
        assert!(first.values().all(|&f| f > 0.05 && f < 0.95), "fractions {first:?}");
    }

    #[test]
    fn a_wider_camera_sees_the_same_view_in_four_times_the_pixels() {
        let small = SyntheticScene::generate(0, Preset::Small).expect("small scene");
        let wide = SyntheticScene::generate(0, Preset::Small)
            .expect("small scene")
            .with_image_width(320);
        let k = wide.intrinsics();
        assert_eq!((k.width, k.height, k.fx, k.cx), (320, 240, 256.0, 159.5), "{k:?}");
        let (a, b) = (
            small.read_frame(15).expect("frame"),
            wide.read_frame(15).expect("frame"),
        );
        let object_pixels = |f: &crate::sensor::frame::RgbdFrame| {
            (0..f.instances.len())
                .filter(|&i| f.instances.object_at(i).is_some())
                .count() as f32
        };
        let ratio = object_pixels(&b) / object_pixels(&a);
        assert!(
            (3.6..4.4).contains(&ratio),
            "twice the width, four times the object pixels: {ratio}"
        );
    }
}
