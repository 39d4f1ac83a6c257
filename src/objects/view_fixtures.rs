//! Constructed scenes of axis-aligned boxes rendered into object views, for the tests of the
//! hidden space and of the priors that draw from it.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use crate::field::free_space::ray_box_interval;
use crate::geometry::oriented_box::OrientedBox;
use crate::ids::FrameIndex;
use crate::objects::object_view::{ObjectView, PixelState};
use crate::sensor::frame::CameraIntrinsics;
use crate::sensor::pixel_box::PixelBox;
use crate::synth::trajectory::look_rotation;

/// An axis-aligned box of the constructed scene, and whether it is the object.
pub(crate) struct Solid {
    pub(crate) aabb: OrientedBox,
    pub(crate) is_object: bool,
}

pub(crate) fn aabb(min: [f32; 3], max: [f32; 3]) -> OrientedBox {
    let (min, max) = (Vector3::from(min), Vector3::from(max));
    OrientedBox {
        world_from_box: Isometry3::from_parts(Translation3::from((min + max) / 2.0), UnitQuaternion::identity()),
        half_extents: (max - min) / 2.0,
    }
}

/// A 96×96 view from `eye` looking along yaw `yaw` (level) of `scene` inside a room whose
/// walls are 5 m away (background): every pixel gets the depth of the nearest hit.
pub(crate) fn render(eye: [f32; 3], yaw: f32, scene: &[Solid]) -> ObjectView {
    render_pitched(eye, yaw, 0.0, scene)
}

/// [`render`] looking up by `pitch` (down when negative).
pub(crate) fn render_pitched(eye: [f32; 3], yaw: f32, pitch: f32, scene: &[Solid]) -> ObjectView {
    let k = CameraIntrinsics {
        width: 96,
        height: 96,
        fx: 60.0,
        fy: 60.0,
        cx: 47.5,
        cy: 47.5,
    };
    let pose = Isometry3::from_parts(Translation3::from(Vector3::from(eye)), look_rotation(yaw, pitch));
    let (mut depth_m, mut states) = (Vec::new(), Vec::new());
    for v in 0..k.height {
        for u in 0..k.width {
            let dir = pose.rotation * k.ray_in_camera(u as f32, v as f32);
            let origin = Point3::from(Vector3::from(eye));
            let hit = scene
                .iter()
                .filter_map(|s| ray_box_interval(&s.aabb, &origin, &dir).map(|(t, _)| (t, s.is_object)))
                .filter(|(t, _)| *t > 0.0)
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let (d, state) = match hit {
                Some((t, true)) => (t, PixelState::ThisObject),
                Some((t, false)) => (t, PixelState::OtherObject),
                None => (5.0, PixelState::OtherObject),
            };
            depth_m.push(d);
            states.push(state);
        }
    }
    let deepest_return_m = crate::objects::object_view::deepest_return(&depth_m);
    ObjectView {
        frame: FrameIndex(0),
        world_from_camera: pose,
        intrinsics: k,
        region: PixelBox::whole_image(k.width, k.height),
        rgb: vec![[0; 3]; depth_m.len()],
        depth_m,
        states,
        depth_noise_per_m2: 0.0,
        deepest_return_m,
    }
}

/// A bed (the object): a frame 12–50 cm high over [−0.75, 0.75] × [1, 3] on four legs, a
/// headboard at its back up to 1 m; the floor (another object) under it.
pub(crate) fn bed_on_the_floor() -> (Vec<Solid>, OrientedBox) {
    let object = |min, max| Solid {
        aabb: aabb(min, max),
        is_object: true,
    };
    let mut scene = vec![
        object([-0.75, 1.0, 0.12], [0.75, 2.94, 0.5]),
        object([-0.75, 2.94, 0.0], [0.75, 3.0, 1.0]),
        Solid {
            aabb: aabb([-5.0, -5.0, -0.1], [5.0, 5.0, 0.0]),
            is_object: false,
        },
    ];
    for (x, y) in [(-0.75, 1.0), (0.69, 1.0)] {
        scene.push(object([x, y, 0.0], [x + 0.06, y + 0.06, 0.12]));
    }
    (scene, aabb([-0.75, 1.0, 0.0], [0.75, 3.0, 1.0]))
}

/// Views of the bed from the front and both sides, 1.4 m high, looking down.
pub(crate) fn bed_views(scene: &[Solid]) -> [ObjectView; 3] {
    let half_pi = std::f32::consts::FRAC_PI_2;
    [
        render_pitched([0.0, -0.6, 1.4], 0.0, -0.5, scene),
        render_pitched([2.6, 2.0, 1.4], -half_pi, -0.5, scene),
        render_pitched([-2.6, 2.0, 1.4], half_pi, -0.5, scene),
    ]
}

/// The object: a slab 5 cm thick facing −y at y = 1 (its front), in a box 40 cm deep behind it.
pub(crate) fn slab_and_box() -> (Vec<Solid>, OrientedBox) {
    let slab = Solid {
        aabb: aabb([-0.2, 1.0, 0.0], [0.2, 1.05, 0.4]),
        is_object: true,
    };
    (vec![slab], aabb([-0.2, 1.0, 0.0], [0.2, 1.4, 0.4]))
}
