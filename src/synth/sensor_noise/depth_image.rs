//! What the depth camera families read off a rendered depth image before they degrade it: depth
//! steps to a neighbour, the angle a surface is seen at, how concave the surface around a pixel
//! is, and which pixels a second viewpoint beside the camera (a projector, a second imager)
//! cannot see.

use crate::sensor::frame::CameraIntrinsics;

/// The 4-neighbours of pixel `i` in a `w` × `h` image.
pub fn neighbours4(i: usize, w: usize, h: usize) -> impl Iterator<Item = usize> {
    let (u, v) = (i % w, i / w);
    [
        (u > 0).then(|| i - 1),
        (u + 1 < w).then(|| i + 1),
        (v > 0).then(|| i - w),
        (v + 1 < h).then(|| i + w),
    ]
    .into_iter()
    .flatten()
}

/// The depth of the 4-neighbour of pixel `i` that differs most from it, when that difference is
/// more than `jump_m` (both depths valid).
pub fn largest_step(depth: &[f32], w: usize, h: usize, i: usize, jump_m: f32) -> Option<f32> {
    let z = depth[i];
    if z <= 0.0 {
        return None;
    }
    neighbours4(i, w, h)
        .map(|j| depth[j])
        .filter(|&d| d > 0.0 && (d - z).abs() > jump_m)
        .max_by(|a, b| (a - z).abs().total_cmp(&(b - z).abs()))
}

/// Cosine of the angle between the surface at pixel `i` and the ray that sees it, from the
/// 3D points of its neighbours (central differences, one-sided at a border or a depth step of
/// more than `jump_m`); `None` without a valid neighbour on both axes.
pub fn incidence_cos(depth: &[f32], k: &CameraIntrinsics, i: usize, jump_m: f32) -> Option<f32> {
    let (w, h) = (k.width as usize, k.height as usize);
    let z = depth[i];
    if z <= 0.0 {
        return None;
    }
    let (u, v) = (i % w, i / w);
    let point = |j: usize| k.point_in_camera((j % w) as f32, (j / w) as f32, depth[j]);
    let usable = |j: usize| depth[j] > 0.0 && (depth[j] - z).abs() <= jump_m;
    let axis = |before: Option<usize>, after: Option<usize>| {
        let before = before.filter(|&j| usable(j)).unwrap_or(i);
        let after = after.filter(|&j| usable(j)).unwrap_or(i);
        (before != after).then(|| point(after) - point(before))
    };
    let du = axis((u > 0).then(|| i - 1), (u + 1 < w).then(|| i + 1))?;
    let dv = axis((v > 0).then(|| i - w), (v + 1 < h).then(|| i + w))?;
    let normal = du.cross(&dv).try_normalize(1e-12)?;
    let ray = point(i).coords.normalize();
    Some(normal.dot(&ray).abs())
}

/// How concave the surface around pixel `i` is: the mean inverse depth of the valid pixels on
/// the square ring at `radius` px, over the pixel's own, less 1. A plane gives 0 (inverse depth
/// is affine in the pixel coordinates on a plane), a concave corner (the pixel farther than its
/// surroundings) a positive value, a convex edge a negative one. 0 with fewer than half the ring
/// valid, or where a ring pixel's depth differs from the pixel's by more than `continuity` × its
/// depth (a depth edge, not one surface bending).
pub fn concavity(depth: &[f32], w: usize, h: usize, i: usize, radius: usize, continuity: f32) -> f32 {
    let z = depth[i];
    if z <= 0.0 || radius == 0 {
        return 0.0;
    }
    let (u, v) = ((i % w) as i64, (i / w) as i64);
    let r = radius as i64;
    let (mut sum, mut valid, mut total) = (0.0f64, 0usize, 0usize);
    for dv in -r..=r {
        for du in -r..=r {
            if du.abs() != r && dv.abs() != r {
                continue;
            }
            total += 1;
            let (x, y) = (u + du, v + dv);
            if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                continue;
            }
            let d = depth[(y as usize) * w + x as usize];
            if d > 0.0 {
                if (d - z).abs() > continuity * z {
                    return 0.0;
                }
                sum += 1.0 / f64::from(d);
                valid += 1;
            }
        }
    }
    if 2 * valid < total {
        return 0.0;
    }
    ((sum / valid as f64) * f64::from(z) - 1.0) as f32
}

/// The pixels that a second viewpoint `baseline_m` to the camera's right (+x) cannot see: a
/// projector's shadows or a second imager's occlusions, and what lies beyond the left edge of its
/// view. Pixel (u, z) is seen from there at u − fx·b/z; along a row a pixel is hidden when a
/// pixel to its right is seen further left (it lies in front of the ray), or when it is seen left
/// of the image (`outside_view`, the second view's field being the camera's).
pub fn hidden_from_baseline(depth: &[f32], k: &CameraIntrinsics, baseline_m: f32, outside_view: bool) -> Vec<bool> {
    let (w, h) = (k.width as usize, k.height as usize);
    let shift = k.fx * baseline_m;
    let mut hidden = vec![false; w * h];
    for v in 0..h {
        let mut least = f32::INFINITY;
        for u in (0..w).rev() {
            let i = v * w + u;
            let z = depth[i];
            if z <= 0.0 {
                continue;
            }
            let seen_at = u as f32 - shift / z;
            hidden[i] = seen_at > least + 0.5 || (outside_view && seen_at < -0.5);
            least = least.min(seen_at);
        }
    }
    hidden
}

/// Luminance of an sRGB pixel in [0, 1] (Rec. 601 weights on the stored values).
pub fn luminance(rgb: [u8; 3]) -> f32 {
    (0.299 * f32::from(rgb[0]) + 0.587 * f32::from(rgb[1]) + 0.114 * f32::from(rgb[2])) / 255.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn k(w: u32, h: u32) -> CameraIntrinsics {
        CameraIntrinsics {
            width: w,
            height: h,
            fx: 100.0,
            fy: 100.0,
            cx: (w as f32 - 1.0) / 2.0,
            cy: (h as f32 - 1.0) / 2.0,
        }
    }

    #[test]
    fn a_wall_facing_the_camera_is_seen_head_on_and_a_tilted_one_at_its_tilt() {
        let k = k(41, 31);
        let flat = vec![2.0f32; 41 * 31];
        let centre = 15 * 41 + 20;
        let cos = incidence_cos(&flat, &k, centre, 0.05).expect("valid");
        assert!((cos - 1.0).abs() < 1e-4, "{cos}");
        // A plane through (0, 0, 2) tilted 60° about the y axis: z = 2 + tan(60°)·x.
        let t = 60f32.to_radians().tan();
        let tilted: Vec<f32> = (0..41 * 31)
            .map(|i| {
                let x = (i % 41) as f32 - k.cx;
                2.0 / (1.0 - t * x / k.fx)
            })
            .collect();
        let cos = incidence_cos(&tilted, &k, centre, 0.5).expect("valid");
        assert!((cos - 0.5).abs() < 0.01, "60° off the ray: cos {cos}");
        assert!(
            concavity(&tilted, 41, 31, centre, 5, 0.5).abs() < 1e-4,
            "a plane is not concave"
        );
    }

    #[test]
    fn a_corner_is_concave_and_an_edge_convex() {
        // A V whose centre column lies farthest from the camera is a concave corner; one whose
        // centre column lies nearest, a convex edge.
        let valley: Vec<f32> = (0..41 * 31)
            .map(|i| 2.0 - 0.02 * ((i % 41) as f32 - 20.0).abs())
            .collect();
        let ridge: Vec<f32> = (0..41 * 31)
            .map(|i| 2.0 + 0.02 * ((i % 41) as f32 - 20.0).abs())
            .collect();
        let centre = 15 * 41 + 20;
        assert!(
            concavity(&valley, 41, 31, centre, 5, 0.5) > 0.02,
            "the centre lies behind its ring"
        );
        assert!(concavity(&ridge, 41, 31, centre, 5, 0.5) < -0.02);
        assert_eq!(
            concavity(&valley, 41, 31, centre, 5, 0.01),
            0.0,
            "a step beyond the continuity"
        );
    }

    #[test]
    fn a_box_before_a_wall_hides_a_strip_to_its_left_as_wide_as_the_baseline_says() {
        let k = k(60, 1);
        // Wall at 3 m, a box at 1 m over columns 30..40; fx·b = 100 × 0.3 = 30 px.
        let depth: Vec<f32> = (0..60).map(|u| if (30..40).contains(&u) { 1.0 } else { 3.0 }).collect();
        let hidden = hidden_from_baseline(&depth, &k, 0.3, false);
        // The box is seen from the right at u − 30; the wall at u − 10: the wall left of the box
        // is hidden where u − 10 > 0 (the box's left edge seen at 30 − 30 = 0), i.e. u in 11..30.
        let strip: Vec<usize> = (0..60).filter(|&u| hidden[u]).collect();
        assert_eq!(strip, (11..30).collect::<Vec<_>>());
        let with_edge = hidden_from_baseline(&depth, &k, 0.3, true);
        assert!((0..10).all(|u| with_edge[u]), "seen left of the second view's image");
        assert!(!with_edge[10]);
    }

    #[test]
    fn the_largest_step_is_the_neighbour_farthest_off() {
        let depth = [1.0, 1.0, 3.0, 1.0, 1.02, 1.0, 1.0, 0.0, 1.0];
        assert_eq!(largest_step(&depth, 3, 3, 1, 0.05), Some(3.0));
        assert_eq!(largest_step(&depth, 3, 3, 3, 0.05), None, "1.02 is within the jump");
        assert_eq!(largest_step(&depth, 3, 3, 7, 0.05), None, "no depth");
    }
}
