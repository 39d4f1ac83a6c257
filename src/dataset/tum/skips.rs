//! Colour images of a TUM sequence that make no frame: why, how many, and the one warning per
//! reason.

use super::lists::TimedFile;
use super::mask_paths;

/// How many colour images [`TumSequence::open`](super::TumSequence::open) skipped, by reason.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SkippedImages {
    /// No depth image within the time tolerance.
    pub no_depth: usize,
    /// No ground-truth pose within the time tolerance.
    pub no_pose: usize,
    /// No `instance/<stem>.png` or no `class/<stem>.png`.
    pub no_mask: usize,
}

/// What a colour image that makes no frame lacks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Missing {
    /// A depth image near enough in time.
    Depth,
    /// A pose near enough in time.
    Pose,
    /// One of its masks.
    Mask,
}

impl SkippedImages {
    /// The counts of `skips`.
    pub(super) fn of(skips: &[(Missing, &TimedFile)]) -> Self {
        let count = |reason: Missing| skips.iter().filter(|(r, _)| *r == reason).count();
        Self {
            no_depth: count(Missing::Depth),
            no_pose: count(Missing::Pose),
            no_mask: count(Missing::Mask),
        }
    }
}

/// Logs each reason colour images were skipped for once, with their count and the first of them.
pub(super) fn warn_skips(skips: &[(Missing, &TimedFile)], max_difference_s: f64) {
    for reason in [Missing::Depth, Missing::Pose, Missing::Mask] {
        let mut skipped = skips.iter().filter(|(r, _)| *r == reason).map(|(_, image)| image);
        let Some(first) = skipped.next() else {
            continue;
        };
        let why = match reason {
            Missing::Depth => format!("no depth image within {max_difference_s} s in depth.txt"),
            Missing::Pose => format!("no pose within {max_difference_s} s in groundtruth.txt"),
            Missing::Mask => {
                let [instance, class] = mask_paths(&first.path);
                format!("no {instance} or no {class}")
            }
        };
        tracing::warn!(
            count = 1 + skipped.count(),
            first = %first.path,
            line = first.line,
            "skipping colour images of rgb.txt: {why}"
        );
    }
}
