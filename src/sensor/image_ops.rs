//! Small image operations for display: downscaling RGB, depth and label images.

/// Box-filter downscale of a row-major RGB image by an integer `factor`; returns the new size too.
pub fn downscale_rgb(rgb: &[[u8; 3]], width: u32, height: u32, factor: u32) -> (Vec<u8>, u32, u32) {
    let f = factor.max(1);
    let (w, h) = ((width / f).max(1), (height / f).max(1));
    let mut out = Vec::with_capacity((w * h * 3) as usize);
    for v in 0..h {
        for u in 0..w {
            let mut sum = [0u32; 3];
            let mut n = 0u32;
            for dv in 0..f {
                for du in 0..f {
                    let (x, y) = (u * f + du, v * f + dv);
                    if x < width && y < height {
                        let p = rgb[(y * width + x) as usize];
                        for c in 0..3 {
                            sum[c] += u32::from(p[c]);
                        }
                        n += 1;
                    }
                }
            }
            out.extend(sum.map(|s| (s / n.max(1)) as u8));
        }
    }
    (out, w, h)
}

/// Nearest-sample downscale (top-left pixel of each block) of any per-pixel values, so labels
/// and invalid depths are never blended.
pub fn downscale_nearest<T: Copy>(values: &[T], width: u32, height: u32, factor: u32) -> (Vec<T>, u32, u32) {
    let f = factor.max(1);
    let (w, h) = ((width / f).max(1), (height / f).max(1));
    let mut out = Vec::with_capacity((w * h) as usize);
    for v in 0..h {
        for u in 0..w {
            out.push(values[((v * f).min(height - 1) * width + (u * f).min(width - 1)) as usize]);
        }
    }
    (out, w, h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb_downscale_averages_blocks() {
        let rgb = [[0, 0, 0], [10, 20, 30], [20, 40, 60], [30, 60, 90]];
        let (out, w, h) = downscale_rgb(&rgb, 2, 2, 2);
        assert_eq!((w, h), (1, 1));
        assert_eq!(out, [15, 30, 45]);
    }

    #[test]
    fn nearest_downscale_keeps_labels_unblended() {
        let labels = [1u16, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16];
        let (out, w, h) = downscale_nearest(&labels, 4, 4, 2);
        assert_eq!((w, h, out), (2, 2, vec![1, 3, 9, 11]));
    }
}
