//! Masks that bleed past their object: a 2D segmenter's mask often covers a pixel or two of what
//! lies behind the object (a wall, the floor a few metres back). Back-projected, those pixels put
//! wall points into the object's cloud, and its box grows by metres.
//!
//! [`trim_bleeding_masks`] labels such pixels [`InstanceLabel::Unsure`]: an object pixel whose
//! depth lies more than `bleed_depth_m` beyond the nearest pixel of the same object within
//! `bleed_radius_px` (a square window), plus `bleed_depth_per_m` per metre of its depth. A pixel
//! on the object itself has a neighbour of its object at about its own depth; a pixel past the
//! object's silhouette has the silhouette much nearer. Where an object hides part of itself (a chair's back leg beside its front leg), the
//! hidden part's edge pixels are trimmed too; with exact masks nothing else changes.
//!
//! [`mark_unsure_borders`] does not look at depth: every pixel within a few pixels of a mask's
//! border becomes unsure, on both sides, since a segmenter's border may be off either way (a mask
//! too large teaches a field the wall behind; one too small carves the object's rim).
//!
//! [`spare_pixels_in_front`] gives some of the band back: a mask pixel that lies in front of
//! everything across its border — every pixel of another label within reach that has a depth is
//! farther by more than `bleed_depth_m` + `in_front_depth_per_m` × its depth — is its object's.
//! Had the mask grown there, its grown pixels would show what lies behind, at about the depth of
//! the pixels across their border, and would not be in front of them; so only where the object
//! meets a surface at its own depth (the floor under a leg, the wall it stands against, a
//! neighbour) does its border stay unsure. A lamp's pole 4–5 px wide in front of a wall keeps its
//! inner pixels instead of losing every one to the band, and an armchair's side stretcher 0.3 m
//! before the floor behind it keeps its rows.

use serde::{Deserialize, Serialize};

use crate::objects::config::ObjectConfig;
use crate::sensor::frame::{InstanceLabel, RgbdFrame};

/// `frame` with its bleeding mask pixels unknown (module doc), or `None` when none bleeds or
/// `bleed_radius_px` is 0.
pub fn trim_bleeding_masks(frame: &RgbdFrame, cfg: &ObjectConfig) -> Option<RgbdFrame> {
    let r = cfg.bleed_radius_px as i64;
    if r == 0 {
        return None;
    }
    let (w, h) = (frame.intrinsics.width as i64, frame.intrinsics.height as i64);
    let at = |u: i64, v: i64| (v * w + u) as usize;
    let trimmed: Vec<usize> = (0..frame.instances.len())
        .filter(|&i| {
            let Some(id) = frame.instances.object_at(i) else {
                return false;
            };
            let z = frame.depth_m[i];
            if z <= 0.0 {
                return false;
            }
            let (u, v) = ((i as i64) % w, (i as i64) / w);
            let mut nearest = f32::INFINITY;
            for y in (v - r).max(0)..=(v + r).min(h - 1) {
                for x in (u - r).max(0)..=(u + r).min(w - 1) {
                    let j = at(x, y);
                    let d = frame.depth_m[j];
                    if d > 0.0 && d < nearest && frame.instances.object_at(j) == Some(id) {
                        nearest = d;
                    }
                }
            }
            z - nearest > cfg.bleed_depth_m + cfg.bleed_depth_per_m * z
        })
        .collect();
    if trimmed.is_empty() {
        return None;
    }
    let mut out = frame.clone();
    for i in trimmed {
        out.instances.set(i, InstanceLabel::Unsure);
    }
    Some(out)
}

/// What becomes of a mask's band pixels that lie in front of everything across its border
/// (`objects.band_in_front`; module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BandInFront {
    /// They keep their object's label ([`spare_pixels_in_front`]).
    #[default]
    Kept,
    /// They are unsure like the rest of the band.
    Unsure,
}

/// Takes out of `band` (of `radius_px`) the mask pixels of `frame` in front of everything across
/// their border (module doc): every pixel of another label within `radius_px` + 1 (a square
/// window) that has a depth lies more than `bleed_depth_m` + `in_front_depth_per_m` · z beyond
/// the pixel's depth z, and at least one does.
pub fn spare_pixels_in_front(frame: &RgbdFrame, band: &mut [bool], radius_px: u32, cfg: &ObjectConfig) {
    let r = i64::from(radius_px) + 1;
    let (w, h) = (frame.intrinsics.width as i64, frame.intrinsics.height as i64);
    let spared: Vec<usize> = (0..band.len())
        .filter(|&i| band[i])
        .filter(|&i| {
            let Some(id) = frame.instances.object_at(i) else {
                return false;
            };
            let z = frame.depth_m[i];
            if z.is_nan() || z <= 0.0 {
                return false;
            }
            let beyond = z + cfg.bleed_depth_m + cfg.in_front_depth_per_m * z;
            let (u, v) = ((i as i64) % w, (i as i64) / w);
            let mut across = false;
            for y in (v - r).max(0)..=(v + r).min(h - 1) {
                for x in (u - r).max(0)..=(u + r).min(w - 1) {
                    let j = (y * w + x) as usize;
                    let d = frame.depth_m[j];
                    if d > 0.0 && frame.instances.object_at(j) != Some(id) {
                        if d <= beyond {
                            return false;
                        }
                        across = true;
                    }
                }
            }
            across
        })
        .collect();
    for i in spared {
        band[i] = false;
    }
}

/// `frame` with every pixel of its [`border_band`] of `radius_px` [`InstanceLabel::Unsure`];
/// `None` when the band is empty.
#[cfg(test)]
pub fn mark_unsure_borders(frame: &RgbdFrame, radius_px: u32) -> Option<RgbdFrame> {
    border_band(frame, radius_px).map(|band| with_band_unsure(frame, &band))
}

/// `frame` with the pixels of `band` [`InstanceLabel::Unsure`].
pub fn with_band_unsure(frame: &RgbdFrame, band: &[bool]) -> RgbdFrame {
    let mut out = frame.clone();
    for (i, _) in band.iter().enumerate().filter(|&(_, &b)| b) {
        out.instances.set(i, InstanceLabel::Unsure);
    }
    out
}

/// The pixels within `radius_px` pixels (a square window) of a border between two labels, one of
/// them an object's; `None` when `radius_px` is 0 or the frame has no such border. A border pixel
/// is one whose right or lower neighbour has another label, and that neighbour; the band grows
/// from them by `radius_px − 1` pixels, so a mask that is `radius_px` pixels too large or too
/// small has all its wrong pixels in it.
pub fn border_band(frame: &RgbdFrame, radius_px: u32) -> Option<Vec<bool>> {
    if radius_px == 0 {
        return None;
    }
    let (w, h) = (frame.intrinsics.width as usize, frame.intrinsics.height as usize);
    let labels = &frame.instances;
    let differ = |a: usize, b: usize| {
        let (la, lb) = (labels.label(a), labels.label(b));
        la != lb && (matches!(la, InstanceLabel::Object(_)) || matches!(lb, InstanceLabel::Object(_)))
    };
    let mut border = vec![false; w * h];
    for v in 0..h {
        for u in 0..w {
            let i = v * w + u;
            for j in [(u + 1 < w).then_some(i + 1), (v + 1 < h).then_some(i + w)]
                .into_iter()
                .flatten()
            {
                if differ(i, j) {
                    border[i] = true;
                    border[j] = true;
                }
            }
        }
    }
    if !border.contains(&true) {
        return None;
    }
    let grow = radius_px as usize - 1;
    let mut rows = vec![false; w * h];
    for v in 0..h {
        let row = &border[v * w..(v + 1) * w];
        for u in 0..w {
            rows[v * w + u] = row[u.saturating_sub(grow)..(u + grow + 1).min(w)].contains(&true);
        }
    }
    let mut band = vec![false; w * h];
    for u in 0..w {
        for v in 0..h {
            band[v * w + u] = (v.saturating_sub(grow)..(v + grow + 1).min(h)).any(|y| rows[y * w + u]);
        }
    }
    Some(band)
}

#[cfg(test)]
mod tests {
    use nalgebra::Isometry3;

    use super::*;
    use crate::ids::{ClassId, FrameIndex, ObjectId};
    use crate::sensor::frame::{CameraIntrinsics, InstanceMask};

    /// A 20×10 frame: a wall at 3 m, object 4 at 1.5 m in columns 5..12; the mask covers columns
    /// `mask_from..mask_to`.
    fn frame(mask_from: u32, mask_to: u32) -> RgbdFrame {
        let (w, h) = (20u32, 10u32);
        let n = (w * h) as usize;
        let column = |i: usize| i as u32 % w;
        RgbdFrame {
            index: FrameIndex(0),
            world_from_camera: Isometry3::identity(),
            intrinsics: CameraIntrinsics {
                width: w,
                height: h,
                fx: 10.0,
                fy: 10.0,
                cx: 9.5,
                cy: 4.5,
            },
            rgb: vec![[0; 3]; n],
            depth_m: (0..n)
                .map(|i| if (5..12).contains(&column(i)) { 1.5 } else { 3.0 })
                .collect(),
            instances: InstanceMask::from_labels((0..n).map(|i| {
                if (mask_from..mask_to).contains(&column(i)) {
                    InstanceLabel::Object(ObjectId(4))
                } else {
                    InstanceLabel::Background
                }
            })),
            classes: vec![ClassId(20); n],
        }
    }

    fn labels_of_row(f: &RgbdFrame) -> Vec<InstanceLabel> {
        (0..20).map(|i| f.instances.label(i)).collect()
    }

    #[test]
    fn the_wall_pixels_a_mask_bled_onto_become_unsure_and_the_object_stays() {
        let cfg = ObjectConfig {
            bleed_radius_px: 2,
            ..ObjectConfig::default()
        };
        let trimmed = trim_bleeding_masks(&frame(3, 14), &cfg).expect("the mask bleeds two columns each side");
        let row = labels_of_row(&trimmed);
        for u in [3, 4, 12, 13] {
            assert_eq!(row[u], InstanceLabel::Unsure, "column {u} shows the wall");
        }
        for (u, label) in row.iter().enumerate().take(12).skip(5) {
            assert_eq!(
                *label,
                InstanceLabel::Object(ObjectId(4)),
                "column {u} shows the object"
            );
        }
        assert_eq!(row[2], InstanceLabel::Background);
    }

    #[test]
    fn an_exact_mask_is_left_alone_and_a_radius_of_zero_trims_nothing() {
        let cfg = ObjectConfig {
            bleed_radius_px: 2,
            ..ObjectConfig::default()
        };
        assert!(trim_bleeding_masks(&frame(5, 12), &cfg).is_none());
        let off = ObjectConfig::default();
        assert!(trim_bleeding_masks(&frame(3, 14), &off).is_none());
    }

    #[test]
    fn a_border_band_of_radius_r_covers_r_pixels_on_each_side_of_a_masks_border() {
        let unsure = |row: &[InstanceLabel]| -> Vec<usize> {
            (0..row.len()).filter(|&u| row[u] == InstanceLabel::Unsure).collect()
        };
        let one = mark_unsure_borders(&frame(5, 12), 1).expect("the mask has borders");
        assert_eq!(unsure(&labels_of_row(&one)), vec![4, 5, 11, 12]);
        let two = mark_unsure_borders(&frame(5, 12), 2).expect("the mask has borders");
        let row = labels_of_row(&two);
        assert_eq!(unsure(&row), vec![3, 4, 5, 6, 10, 11, 12, 13]);
        assert!((7..10).all(|u| row[u] == InstanceLabel::Object(ObjectId(4))), "{row:?}");
        assert_eq!(row[2], InstanceLabel::Background);
        // A mask two pixels too large on each side has every wrong pixel unsure.
        let grown = labels_of_row(&mark_unsure_borders(&frame(3, 14), 2).expect("borders"));
        assert!(
            [3, 4, 12, 13].iter().all(|&u| grown[u] == InstanceLabel::Unsure),
            "{grown:?}"
        );
    }

    /// The columns of `f`'s first row left in its 2 px band once the pixels in front are spared.
    fn banded(f: &RgbdFrame, cfg: &ObjectConfig) -> Vec<usize> {
        let mut band = border_band(f, 2).expect("the mask has borders");
        spare_pixels_in_front(f, &mut band, 2, cfg);
        (0..20).filter(|&u| band[u]).collect()
    }

    #[test]
    fn mask_pixels_in_front_of_everything_across_their_border_leave_the_band() {
        let cfg = ObjectConfig::default();
        let banded = |f: &RgbdFrame| banded(f, &cfg);
        // The object 1.5 m in front of the wall: its own pixels in the band are spared, the
        // wall's stay unsure (the mask may have shrunk there).
        assert_eq!(banded(&frame(5, 12)), vec![3, 4, 12, 13]);
        // The object against a surface at its own depth (5 cm behind): nothing is spared.
        let mut against = frame(5, 12);
        for (i, z) in against.depth_m.iter_mut().enumerate() {
            if !(5..12).contains(&(i % 20)) {
                *z = 1.55;
            }
        }
        assert_eq!(banded(&against), vec![3, 4, 5, 6, 10, 11, 12, 13]);
        // A mask grown onto the wall: the grown pixels show the wall, near the wall's other
        // pixels, and stay unsure; the object's pixels in front of them are spared.
        let row = banded(&frame(3, 14));
        assert_eq!(
            row,
            vec![1, 2, 3, 4, 12, 13, 14, 15],
            "the grown pixels 3, 4, 12, 13 stay unsure"
        );
        assert!((5..12).all(|u| !row.contains(&u)), "{row:?}");
    }

    #[test]
    fn a_thin_part_a_few_decimetres_before_the_surface_behind_leaves_the_band_with_the_in_front_allowance() {
        // The object at 2.7 m, 0.3 m before the wall: in front by more than 0.1 + 0.03 × 2.7 m,
        // not by the bleed trim's 0.1 + 0.1 × 2.7 m.
        let mut rod = frame(5, 12);
        for (i, z) in rod.depth_m.iter_mut().enumerate() {
            *z = if (5..12).contains(&(i % 20)) { 2.7 } else { 3.0 };
        }
        assert_eq!(banded(&rod, &ObjectConfig::default()), vec![3, 4, 12, 13]);
        let bleed_allowance = ObjectConfig {
            in_front_depth_per_m: 0.1,
            ..ObjectConfig::default()
        };
        assert_eq!(banded(&rod, &bleed_allowance), vec![3, 4, 5, 6, 10, 11, 12, 13]);
    }

    #[test]
    fn no_border_band_without_a_radius_or_without_a_mask() {
        assert!(mark_unsure_borders(&frame(5, 12), 0).is_none());
        assert!(
            mark_unsure_borders(&frame(0, 0), 2).is_none(),
            "no object pixel, no border"
        );
    }

    #[test]
    fn a_surface_falling_away_at_a_grazing_angle_is_kept_with_a_depth_allowance() {
        // The object's surface falls away by 6 cm per column at 3 m; the mask bleeds onto the wall.
        let mut grazing = frame(3, 14);
        for (i, z) in grazing.depth_m.iter_mut().enumerate() {
            let u = i as u32 % 20;
            if (5..12).contains(&u) {
                *z = 3.0 + 0.06 * (u - 5) as f32;
            } else {
                *z = 5.0;
            }
        }
        let strict = ObjectConfig {
            bleed_radius_px: 2,
            ..ObjectConfig::default()
        };
        let row = labels_of_row(&trim_bleeding_masks(&grazing, &strict).expect("trims"));
        assert_eq!(
            row[9],
            InstanceLabel::Unsure,
            "0.12 m beyond column 7 at 3 m: trimmed without allowance"
        );
        let allowing = ObjectConfig {
            bleed_depth_per_m: 0.1,
            ..strict
        };
        let row = labels_of_row(&trim_bleeding_masks(&grazing, &allowing).expect("the wall still bleeds"));
        assert!((5..12).all(|u| row[u] == InstanceLabel::Object(ObjectId(4))), "{row:?}");
        assert!(
            [3, 4, 12, 13].iter().all(|&u| row[u] == InstanceLabel::Unsure),
            "{row:?}"
        );
    }
}
