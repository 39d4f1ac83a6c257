//! Nearest-timestamp association of TUM RGB-D's streams, as TUM's `associate.py` does it: every
//! colour image takes the depth image and the ground-truth pose whose timestamps are nearest to
//! its own, when they are at most `max_difference_s` away (associate.py's default: 0.02 s).
//!
//! Poses are not interpolated: the ground truth runs at 100 Hz or more, so the nearest pose is at
//! most 5 ms off. Unlike associate.py, which pairs greedily one to one, a depth image may serve
//! two colour images; on TUM's 30 Hz streams the two agree.

/// associate.py's default largest time difference, seconds.
pub const MAX_TIME_DIFFERENCE_S: f64 = 0.02;

/// Index of the entry of `timestamps_s` (increasing) nearest to `t_s`, if it is at most
/// `max_difference_s` away; of two equally near, the earlier.
pub fn nearest(timestamps_s: &[f64], t_s: f64, max_difference_s: f64) -> Option<usize> {
    let after = timestamps_s.partition_point(|&t| t < t_s);
    let candidates = [after.checked_sub(1), Some(after)];
    candidates
        .into_iter()
        .flatten()
        .filter_map(|i| timestamps_s.get(i).map(|&t| (i, (t - t_s).abs())))
        .filter(|&(_, difference)| difference <= max_difference_s)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// What a colour image was matched with: indices into the depth and pose lists.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Matched {
    /// Index of its depth image.
    pub depth: usize,
    /// Index of its pose.
    pub pose: usize,
}

/// Why a colour image has no frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Unmatched {
    /// No depth image is near enough in time.
    NoDepth,
    /// No ground-truth pose is near enough in time.
    NoPose,
}

/// For each colour timestamp, its depth image and pose, or why it has none (a missing depth image
/// is reported before a missing pose). All three lists are increasing.
pub fn associate(
    rgb_s: &[f64],
    depth_s: &[f64],
    poses_s: &[f64],
    max_difference_s: f64,
) -> Vec<Result<Matched, Unmatched>> {
    rgb_s
        .iter()
        .map(|&t| {
            let depth = nearest(depth_s, t, max_difference_s).ok_or(Unmatched::NoDepth)?;
            let pose = nearest(poses_s, t, max_difference_s).ok_or(Unmatched::NoPose)?;
            Ok(Matched { depth, pose })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_timestamp_within_the_tolerance_is_taken() {
        let depth = [1.00, 1.033, 1.066, 1.2];
        assert_eq!(nearest(&depth, 1.03, 0.02), Some(1), "3 ms after beats 30 ms before");
        assert_eq!(
            nearest(&[1.0, 1.25, 1.5], 1.375, 0.2),
            Some(1),
            "a tie goes to the earlier"
        );
        assert_eq!(nearest(&depth, 0.99, 0.02), Some(0), "before the first");
        assert_eq!(nearest(&depth, 1.21, 0.02), Some(3), "after the last");
        assert_eq!(nearest(&depth, 1.13, 0.02), None, "64 ms and 70 ms are too far");
        assert_eq!(nearest(&depth, 1.15, 0.06), Some(3), "a wider tolerance reaches it");
        assert_eq!(nearest(&[], 1.0, 0.02), None, "an empty list");
        assert_eq!(nearest(&depth, 1.2, 0.0), Some(3), "an exact match at tolerance 0");
    }

    #[test]
    fn each_colour_image_takes_its_own_nearest_depth_and_pose_or_says_what_it_lacks() {
        let rgb = [0.0, 0.033, 0.066, 0.1, 0.5];
        let depth = [0.004, 0.037, 0.104, 0.5];
        let poses = [0.0, 0.01, 0.02, 0.03, 0.04, 0.1, 0.11];
        let matches = associate(&rgb, &depth, &poses, MAX_TIME_DIFFERENCE_S);
        assert_eq!(
            matches,
            [
                Ok(Matched { depth: 0, pose: 0 }),
                Ok(Matched { depth: 1, pose: 3 }),
                Err(Unmatched::NoDepth),
                Ok(Matched { depth: 2, pose: 5 }),
                Err(Unmatched::NoPose),
            ],
            "0.066 is 29 ms from depth 0.037; 0.5 is 390 ms after the last pose"
        );
    }
}
