//! Resizing of decoded images with OpenCV's conventions (as vMAP resizes ScanNet's colour and label
//! images to the depth size).

use rayon::prelude::*;

use super::images::Image;

/// Nearest-neighbour resize (OpenCV `INTER_NEAREST`: source pixel `floor(x · src / dst)`), for labels.
pub fn resize_nearest<T: Copy + Default>(src: Image<T>, width: u32, height: u32) -> Image<T> {
    if src.size() == (width, height) || src.pixels.is_empty() {
        return src;
    }
    let (sw, sh) = (src.width as usize, src.height as usize);
    let columns: Vec<usize> = (0..width as usize)
        .map(|x| (x * sw / width as usize).min(sw - 1))
        .collect();
    let mut pixels = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height as usize {
        let sy = (y * sh / height as usize).min(sh - 1);
        let row = src.pixels.get(sy * sw..(sy + 1) * sw).unwrap_or_default();
        pixels.extend(columns.iter().map(|&sx| row.get(sx).copied().unwrap_or_default()));
    }
    Image { width, height, pixels }
}

/// Fixed-point precision of bilinear weights (OpenCV's `INTER_RESIZE_COEF_BITS`).
const WEIGHT_BITS: u32 = 11;
const WEIGHT_ONE: u32 = 1 << WEIGHT_BITS;

/// Source taps of bilinear resampling along one axis (OpenCV `INTER_LINEAR` convention:
/// `s = (d + 0.5) · src / dst − 0.5`, clamped at the edges): `(i0, i1, weight of i1)`, with the
/// weight in units of `1 / WEIGHT_ONE`.
fn bilinear_taps(src_len: usize, dst_len: usize) -> Vec<(usize, usize, u32)> {
    let scale = src_len as f64 / dst_len as f64;
    (0..dst_len)
        .map(|d| {
            let s = ((d as f64 + 0.5) * scale - 0.5).max(0.0);
            let i = s.floor() as usize;
            if i + 1 >= src_len {
                (src_len - 1, src_len - 1, 0)
            } else {
                (i, i + 1, ((s - i as f64) * f64::from(WEIGHT_ONE)).round() as u32)
            }
        })
        .collect()
}

/// Bilinear resize of an RGB image (OpenCV `INTER_LINEAR`, 11-bit fixed-point weights), as vMAP
/// resizes ScanNet colour. Rows are computed in parallel.
pub fn resize_bilinear_rgb(src: Image<[u8; 3]>, width: u32, height: u32) -> Image<[u8; 3]> {
    if src.size() == (width, height) || src.pixels.is_empty() || width == 0 || height == 0 {
        return src;
    }
    let sw = src.width as usize;
    let columns = bilinear_taps(sw, width as usize);
    let rows = bilinear_taps(src.height as usize, height as usize);
    let mut pixels = vec![[0u8; 3]; width as usize * height as usize];
    pixels
        .par_chunks_mut(width as usize)
        .zip(&rows)
        .for_each(|(out, &(y0, y1, wy))| {
            let (Some(top), Some(bottom)) = (
                src.pixels.get(y0 * sw..(y0 + 1) * sw),
                src.pixels.get(y1 * sw..(y1 + 1) * sw),
            ) else {
                return;
            };
            for (o, &(x0, x1, wx)) in out.iter_mut().zip(&columns) {
                // The taps are < `sw` by construction, and `top`/`bottom` hold `sw` pixels.
                let (a, b, c, d) = (top[x0], top[x1], bottom[x0], bottom[x1]);
                *o = std::array::from_fn(|k| {
                    let upper = u32::from(a[k]) * (WEIGHT_ONE - wx) + u32::from(b[k]) * wx;
                    let lower = u32::from(c[k]) * (WEIGHT_ONE - wx) + u32::from(d[k]) * wx;
                    let sum = upper * (WEIGHT_ONE - wy) + lower * wy;
                    ((sum + (1 << (2 * WEIGHT_BITS - 1))) >> (2 * WEIGHT_BITS)) as u8
                });
            }
        });
    Image { width, height, pixels }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(width: u32, height: u32) -> Image<u32> {
        Image {
            width,
            height,
            pixels: (0..width * height).collect(),
        }
    }

    #[test]
    fn nearest_resize_picks_floor_of_scaled_coordinate() {
        let half = resize_nearest(ramp(4, 2), 2, 1);
        assert_eq!(half.pixels, [0, 2]);
    }

    #[test]
    fn bilinear_resize_by_two_averages_pixel_pairs() {
        let src = Image {
            width: 4,
            height: 1,
            pixels: vec![[0; 3], [100; 3], [200; 3], [250; 3]],
        };
        let half = resize_bilinear_rgb(src, 2, 1);
        assert_eq!(half.pixels, [[50; 3], [225; 3]], "OpenCV samples at x = 0.5 and 2.5");
    }
}
