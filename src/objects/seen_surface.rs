//! Where an object was seen: the points of its own pixels in its keyframe crops, thinned to one
//! per centimetre, and how near a point lies to them in 3D.
//!
//! The seen-free prior ([`super::hidden_space`]) asks points around cells seen free to be empty.
//! A lamp's 2.6 cm pole stands among such cells: views see past it on both sides, and a draw a
//! few millimetres beside it is free in every view and at the object's surface in none (no ray
//! passes through both). Asked empty that close, the field drops the pole (living seed 1: the
//! lamp's completion 1.0 → 4.5 cm). The prior keeps its draws [`SURFACE_CLEARANCE_M`] from every
//! point the object was seen at; the keyframe rays' surface samples teach the surface.

use std::collections::HashMap;

use nalgebra::Point3;

use super::object_view::{ObjectView, PixelState};

/// How near (3D) to a point the object was seen at no free draw may lie, metres.
pub const SURFACE_CLEARANCE_M: f32 = 0.03;

/// Spacing of the seen points kept (one per voxel of this edge), metres.
const THINNING_M: f32 = 0.01;

/// The points an object was seen at, thinned and hashed for neighbourhood queries.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SeenSurface {
    /// Thinned points by hash cell (edge [`SURFACE_CLEARANCE_M`]).
    cells: HashMap<[i32; 3], Vec<Point3<f32>>>,
}

impl SeenSurface {
    /// The points of the object's own pixels with valid depth in `views` (every `stride`-th pixel
    /// along rows and columns), one per centimetre voxel.
    pub fn of_views(views: &[&ObjectView], stride: u32) -> Self {
        let stride = stride.max(1);
        let mut thinned: HashMap<[i32; 3], Point3<f32>> = HashMap::new();
        for view in views {
            let region = view.region;
            for v in (region.v_min..=region.v_max).step_by(stride as usize) {
                for u in (region.u_min..=region.u_max).step_by(stride as usize) {
                    let Some(i) = view.index_of(u, v) else { continue };
                    let d = view.depth_m[i];
                    if view.states[i] != PixelState::ThisObject || !(d.is_finite() && d > 0.0) {
                        continue;
                    }
                    let p = view.world_from_camera * view.intrinsics.point_in_camera(u as f32, v as f32, d);
                    thinned.entry(key(&p, THINNING_M)).or_insert(p);
                }
            }
        }
        let mut cells: HashMap<[i32; 3], Vec<Point3<f32>>> = HashMap::new();
        let mut points: Vec<Point3<f32>> = thinned.into_values().collect();
        // Hash-map order is not deterministic; the order of points within a cell does not change
        // any answer, but keep it stable anyway.
        points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)).then(a.z.total_cmp(&b.z)));
        for p in points {
            cells.entry(key(&p, SURFACE_CLEARANCE_M)).or_default().push(p);
        }
        Self { cells }
    }

    /// Whether no point was seen.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Whether `p` lies within [`SURFACE_CLEARANCE_M`] of a seen point.
    pub fn is_near(&self, p: &Point3<f32>) -> bool {
        let [x, y, z] = key(p, SURFACE_CLEARANCE_M);
        let r2 = SURFACE_CLEARANCE_M * SURFACE_CLEARANCE_M;
        (-1..=1).any(|dz| {
            (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    self.cells
                        .get(&[x + dx, y + dy, z + dz])
                        .is_some_and(|points| points.iter().any(|q| (q - p).norm_squared() <= r2))
                })
            })
        })
    }
}

/// The voxel of edge `edge` holding `p`.
fn key(p: &Point3<f32>, edge: f32) -> [i32; 3] {
    [0, 1, 2].map(|k| (p[k] / edge).floor() as i32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::view_fixtures::{Solid, aabb, render};

    #[test]
    fn a_thin_pole_seen_from_two_sides_is_near_within_the_clearance_and_not_beyond() {
        // A 2.6 cm pole from the floor up to 1.2 m at (0, 2), seen from the front and the side.
        let pole = [Solid {
            aabb: aabb([-0.013, 1.987, 0.0], [0.013, 2.013, 1.2]),
            is_object: true,
        }];
        let views = [
            render([0.0, 1.2, 0.6], 0.0, &pole),
            render([0.8, 2.0, 0.6], -std::f32::consts::FRAC_PI_2, &pole),
        ];
        let views: Vec<&ObjectView> = views.iter().collect();
        let seen = SeenSurface::of_views(&views, 1);
        assert!(!seen.is_empty());
        for z in [0.1, 0.6, 1.1] {
            // Beside the pole, on the sides no view saw: within 3 cm of the seen faces.
            assert!(seen.is_near(&Point3::new(-0.02, 2.0, z)), "1 cm beside at {z}");
            assert!(seen.is_near(&Point3::new(0.0, 2.025, z)), "1.2 cm behind at {z}");
            assert!(!seen.is_near(&Point3::new(0.06, 2.0, z)), "4.7 cm off at {z}");
        }
        assert!(!seen.is_near(&Point3::new(0.0, 2.0, 1.26)), "above the top");
        assert!(SeenSurface::of_views(&[], 1).is_empty());
    }
}
