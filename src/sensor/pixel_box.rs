//! Axis-aligned boxes in image space (an object's 2D box in one frame).

use serde::{Deserialize, Serialize};

/// A box of pixels, inclusive on both ends: columns `u_min..=u_max`, rows `v_min..=v_max`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PixelBox {
    /// First column.
    pub u_min: u32,
    /// First row.
    pub v_min: u32,
    /// Last column.
    pub u_max: u32,
    /// Last row.
    pub v_max: u32,
}

impl PixelBox {
    /// The box of a whole `width` × `height` image.
    pub fn whole_image(width: u32, height: u32) -> Self {
        Self {
            u_min: 0,
            v_min: 0,
            u_max: width.saturating_sub(1),
            v_max: height.saturating_sub(1),
        }
    }

    /// The box of one pixel.
    pub fn at(u: u32, v: u32) -> Self {
        Self {
            u_min: u,
            v_min: v,
            u_max: u,
            v_max: v,
        }
    }

    /// Grows the box to contain pixel `(u, v)`.
    #[inline]
    pub fn include(&mut self, u: u32, v: u32) {
        self.u_min = self.u_min.min(u);
        self.u_max = self.u_max.max(u);
        self.v_min = self.v_min.min(v);
        self.v_max = self.v_max.max(v);
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.u_max - self.u_min + 1
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.v_max - self.v_min + 1
    }

    /// The box grown by `fraction` of its size (half on each side), clamped to a `width × height` image.
    pub fn enlarged(&self, fraction: f32, width: u32, height: u32) -> Self {
        let margin_u = (0.5 * fraction * self.width() as f32).round() as u32;
        let margin_v = (0.5 * fraction * self.height() as f32).round() as u32;
        Self {
            u_min: self.u_min.saturating_sub(margin_u),
            v_min: self.v_min.saturating_sub(margin_v),
            u_max: (self.u_max + margin_u).min(width.saturating_sub(1)),
            v_max: (self.v_max + margin_v).min(height.saturating_sub(1)),
        }
    }

    /// Whether pixel `(u, v)` lies inside.
    pub fn contains(&self, u: u32, v: u32) -> bool {
        (self.u_min..=self.u_max).contains(&u) && (self.v_min..=self.v_max).contains(&v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enlarging_by_twenty_percent_adds_a_tenth_on_each_side() {
        let b = PixelBox {
            u_min: 50,
            v_min: 20,
            u_max: 149,
            v_max: 69,
        };
        let e = b.enlarged(0.2, 640, 480);
        assert_eq!(
            e,
            PixelBox {
                u_min: 40,
                v_min: 15,
                u_max: 159,
                v_max: 74
            }
        );
    }

    #[test]
    fn enlarging_is_clamped_to_the_image() {
        let b = PixelBox {
            u_min: 0,
            v_min: 0,
            u_max: 99,
            v_max: 99,
        };
        let e = b.enlarged(0.2, 105, 100);
        assert_eq!(
            e,
            PixelBox {
                u_min: 0,
                v_min: 0,
                u_max: 104,
                v_max: 99
            }
        );
    }
}
