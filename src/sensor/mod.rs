//! Sensor data: one posed RGB-D frame with its instance masks, image-space boxes, the
//! depth smoothing applied before use, and the small image operations used for display.

pub mod depth_noise;
pub mod depth_smoothing;
pub mod frame;
pub mod image_ops;
pub mod instance_ids;
pub mod mask_borders;
pub mod pixel_box;
