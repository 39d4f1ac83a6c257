//! A frame source whose frames' depth is smoothed as `dataset.depth_smoothing` says
//! ([`crate::sensor::depth_smoothing`]), in the reader thread, before the mapper sees it.

use std::sync::Arc;

use super::FrameSource;
use super::class_names::ClassNames;
use crate::error::Result;
use crate::sensor::depth_smoothing::{BilateralDepth, DepthSmoothing};
use crate::sensor::frame::{CameraIntrinsics, RgbdFrame};

/// `inner` with every frame's depth smoothed.
pub struct SmoothedDepth {
    inner: Arc<dyn FrameSource>,
    bilateral: BilateralDepth,
}

/// `source` as it is under [`DepthSmoothing::None`], else wrapped in a [`SmoothedDepth`].
pub fn with_depth_smoothing(
    source: Arc<dyn FrameSource>,
    smoothing: DepthSmoothing,
    bilateral: &BilateralDepth,
) -> Arc<dyn FrameSource> {
    match smoothing {
        DepthSmoothing::None => source,
        DepthSmoothing::Bilateral => Arc::new(SmoothedDepth {
            inner: source,
            bilateral: *bilateral,
        }),
    }
}

impl FrameSource for SmoothedDepth {
    fn len(&self) -> usize {
        self.inner.len()
    }
    fn intrinsics(&self) -> CameraIntrinsics {
        self.inner.intrinsics()
    }
    fn read_frame(&self, position: usize) -> Result<RgbdFrame> {
        let mut frame = self.inner.read_frame(position)?;
        let (w, h) = (frame.intrinsics.width as usize, frame.intrinsics.height as usize);
        frame.depth_m = self.bilateral.smooth(&frame.depth_m, w, h);
        Ok(frame)
    }
    fn name(&self) -> String {
        self.inner.name()
    }
    fn class_names(&self) -> ClassNames {
        self.inner.class_names()
    }
}
