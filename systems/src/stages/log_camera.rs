//! Rerun logging of the camera: its pose, the pinhole of the logged images, and the colour
//! (JPEG), instance and depth (u16 mm) images, downscaled by `rerun.image_downscale`:
//! `world/camera`, `world/camera/image`, `…/image/rgb`, `…/image/instances`, `…/image/depth`.

use bevy_ecs::prelude::*;
use catmap::sensor::image_ops::{downscale_nearest, downscale_rgb};
use catmap::{InstanceLabel, ObjectId, RgbdFrame};
use image::ImageEncoder;

use crate::components::CameraFrame;
use crate::recording::{Rerun, warn_on_error};
use crate::rerun_paths as paths;
use crate::resources::Settings;

/// Logs each new frame's pose, pinhole and (every `image_every` frames) its colour and instance
/// images, and its depth every `depth_every` frames.
pub fn log_camera_frames(rerun: Res<Rerun>, settings: Res<Settings>, frames: Query<&CameraFrame, Added<CameraFrame>>) {
    let cfg = &settings.0.rerun;
    for frame in &frames {
        let frame = &frame.0;
        rerun.at_frame(frame.index.0);
        log_camera_pose(&rerun.0, frame);
        if frame.index.0.is_multiple_of(u64::from(cfg.image_every)) {
            log_images(&rerun.0, frame, cfg.image_downscale, cfg.jpeg_quality);
        }
        if frame.index.0.is_multiple_of(u64::from(cfg.depth_every)) {
            log_depth(&rerun.0, frame, cfg.image_downscale);
        }
    }
}

fn log_camera_pose(rec: &rerun::RecordingStream, frame: &RgbdFrame) {
    let t = frame.world_from_camera.translation.vector;
    let r = frame.world_from_camera.rotation.to_rotation_matrix();
    let m = r.matrix();
    let columns = [
        [m[(0, 0)], m[(1, 0)], m[(2, 0)]],
        [m[(0, 1)], m[(1, 1)], m[(2, 1)]],
        [m[(0, 2)], m[(1, 2)], m[(2, 2)]],
    ];
    let transform =
        rerun::Transform3D::from_translation_mat3x3([t.x, t.y, t.z], rerun::datatypes::Mat3x3::from(columns));
    warn_on_error(rec.log(paths::CAMERA, &transform), paths::CAMERA);
}

fn log_images(rec: &rerun::RecordingStream, frame: &RgbdFrame, downscale: u32, jpeg_quality: u8) {
    let k = frame.intrinsics;
    let (rgb, w, h) = downscale_rgb(&frame.rgb, k.width, k.height, downscale);
    let small = k.scaled(w as f32 / k.width as f32);
    let pinhole = rerun::Pinhole::from_focal_length_and_resolution([small.fx, small.fy], [w as f32, h as f32])
        .with_principal_point([small.cx + 0.5, small.cy + 0.5]);
    warn_on_error(rec.log(paths::IMAGE, &pinhole), paths::IMAGE);

    let mut jpeg = Vec::new();
    let encoded = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, jpeg_quality.clamp(1, 100))
        .write_image(&rgb, w, h, image::ExtendedColorType::Rgb8);
    match encoded {
        Ok(()) => warn_on_error(
            rec.log(
                paths::RGB,
                &rerun::EncodedImage::from_file_contents(jpeg).with_media_type(rerun::MediaType::JPEG),
            ),
            paths::RGB,
        ),
        Err(e) => tracing::warn!(error = %e, "cannot encode the colour image for Rerun"),
    }

    let labels: Vec<u16> = (0..frame.instances.len())
        .map(|i| match frame.instances.label(i) {
            InstanceLabel::Object(ObjectId(id)) => u16::try_from(id).unwrap_or(u16::MAX),
            InstanceLabel::Background | InstanceLabel::Unknown | InstanceLabel::Unsure => 0,
        })
        .collect();
    let (labels, _, _) = downscale_nearest(&labels, k.width, k.height, downscale);
    let format = rerun::components::ImageFormat::segmentation([w, h], rerun::ChannelDatatype::U16);
    let segmentation = rerun::SegmentationImage::new(to_le_bytes(&labels), format);
    warn_on_error(rec.log(paths::INSTANCES, &segmentation), paths::INSTANCES);
}

/// Logs the depth image (u16 millimetres, at the colour image's size).
fn log_depth(rec: &rerun::RecordingStream, frame: &RgbdFrame, downscale: u32) {
    let k = frame.intrinsics;
    let depth_mm: Vec<u16> = frame
        .depth_m
        .iter()
        .map(|d| (d * 1000.0).round().clamp(0.0, 65535.0) as u16)
        .collect();
    let (depth_mm, w, h) = downscale_nearest(&depth_mm, k.width, k.height, downscale);
    let depth = rerun::DepthImage::from_gray16(to_le_bytes(&depth_mm), [w, h]).with_meter(1000.0);
    warn_on_error(rec.log(paths::DEPTH, &depth), paths::DEPTH);
}

fn to_le_bytes(values: &[u16]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}
