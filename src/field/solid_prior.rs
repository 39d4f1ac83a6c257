//! Prior rays: samples drawn in the cells of an object's box that no view saw into (asked to be
//! solid), under the box, below the lowest point the object was seen at, and around the centres
//! of the cells a view saw free (both asked to be empty), [`crate::objects::hidden_space`]; the
//! loss is [`super::loss`]'s `L_solid`. They are appended to a step's rays, in that order, as
//! rays of `PixelState::HiddenSolid` / `BelowSupport` / `SeenFree` (no depth, no colour; their
//! sample depths only keep the order).

use nalgebra::Point3;
use rand::Rng;

use super::samples::RaySamples;
use crate::objects::hidden_space::HiddenSpace;
use crate::objects::object_view::{ObjectView, PixelState};

/// How many prior rays a step draws, and the prior's weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PriorRays {
    /// Rays in the hidden cells (none when no cell is hidden).
    pub hidden_solid: usize,
    /// Rays under the box.
    pub below_support: usize,
    /// Rays around the centres of the cells seen free (none when no cell is).
    pub seen_free: usize,
    /// Weight of the prior's loss.
    pub weight: f32,
}

/// Appends the prior rays of `counts`, `rays.samples_per_ray` samples each, drawn from `hidden`
/// (relative to `field_origin`); `views` (the keyframe crops the space was computed from) check
/// the draws around seen-free cells ([`HiddenSpace::draw_free`]).
pub fn append_prior_rays(
    rays: &mut RaySamples,
    hidden: &HiddenSpace,
    views: &[&ObjectView],
    counts: PriorRays,
    field_origin: &Point3<f32>,
    rng: &mut impl Rng,
) {
    let solid = if hidden.centres.is_empty() {
        0
    } else {
        counts.hidden_solid
    };
    let free = if !hidden.has_free_cells() { 0 } else { counts.seen_free };
    if solid + counts.below_support + free == 0 {
        return;
    }
    rays.solid_weight = counts.weight;
    let kinds = std::iter::repeat_n(PixelState::HiddenSolid, solid)
        .chain(std::iter::repeat_n(PixelState::BelowSupport, counts.below_support))
        .chain(std::iter::repeat_n(PixelState::SeenFree, free));
    let centre = hidden.world_from_box * Point3::origin();
    for state in kinds {
        for k in 0..rays.samples_per_ray {
            let p = match state {
                PixelState::HiddenSolid => hidden.draw(rng).unwrap_or(centre),
                PixelState::SeenFree => hidden.draw_free(views, rng).unwrap_or(centre),
                _ => hidden.draw_below_support(rng),
            };
            let p = p - field_origin.coords;
            rays.points.push([p.x, p.y, p.z]);
            rays.z.push(k as f32);
        }
        rays.depth_m.push(0.0);
        rays.rgb.push([0.0; 3]);
        rays.states.push(state);
    }
}

#[cfg(test)]
#[path = "solid_prior_field_tests.rs"]
mod field_tests;

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Vector3};

    use super::*;
    use crate::objects::hidden_space::{BELOW_SUPPORT_M, SUPPORT_GAP_M};
    use crate::rng::{RngStream, seeded_rng};

    #[test]
    fn prior_rays_lie_in_hidden_cells_under_the_box_and_around_seen_free_centres() {
        // A box of 16 cells of 1 cm per edge at (1, 2, 0.5) (its bottom at z = 0.42), one cell
        // hidden, one seen free.
        let hidden = HiddenSpace {
            world_from_box: Isometry3::translation(1.0, 2.0, 0.5),
            cell_size: Vector3::new(0.01, 0.01, 0.01),
            centres: vec![Point3::new(0.005, 0.005, 0.005)],
            free_centres: vec![Point3::new(-0.035, 0.025, -0.005)],
            open_centres: Vec::new(),
            beyond_centres: Vec::new(),
        };
        let mut rays = RaySamples {
            samples_per_ray: 4,
            ..RaySamples::default()
        };
        let origin = Point3::new(1.0, 2.0, 0.0);
        let counts = PriorRays {
            hidden_solid: 3,
            below_support: 2,
            seen_free: 2,
            weight: 0.5,
        };
        append_prior_rays(
            &mut rays,
            &hidden,
            &[],
            counts,
            &origin,
            &mut seeded_rng(1, RngStream::Mapper),
        );
        rays.validate().expect("consistent arrays");
        assert_eq!((rays.num_rays(), rays.solid_weight), (7, 0.5));
        for (ray, state) in rays.states.iter().enumerate() {
            for p in &rays.points[ray * 4..(ray + 1) * 4] {
                // World = origin + p; box frame = world − (1, 2, 0.5).
                let local = [p[0], p[1], p[2] - 0.5];
                match state {
                    PixelState::HiddenSolid => assert!(local.iter().all(|c| (0.0..=0.01).contains(c)), "{p:?}"),
                    PixelState::BelowSupport => {
                        let top = -0.08 - SUPPORT_GAP_M;
                        assert!((top - BELOW_SUPPORT_M..=top).contains(&local[2]), "{p:?}");
                        assert!(local[0].abs() <= 0.09 && local[1].abs() <= 0.09, "{p:?}");
                    }
                    PixelState::SeenFree => {
                        // Within a quarter cell (2.5 mm) of the free cell's centre.
                        let centre = [-0.035, 0.025, -0.005];
                        assert!((0..3).all(|a| (local[a] - centre[a]).abs() <= 0.0025 + 1e-6), "{p:?}");
                    }
                    other => panic!("{other:?} among prior rays"),
                }
            }
        }
        let order: Vec<PixelState> = rays.states.clone();
        assert_eq!(
            order,
            [
                [PixelState::HiddenSolid; 3].as_slice(),
                &[PixelState::BelowSupport; 2],
                &[PixelState::SeenFree; 2]
            ]
            .concat()
        );
        // No hidden cell and no cell seen free: only the rays under the box.
        let empty = HiddenSpace {
            centres: Vec::new(),
            free_centres: Vec::new(),
            ..hidden
        };
        let mut few = RaySamples {
            samples_per_ray: 4,
            ..RaySamples::default()
        };
        append_prior_rays(
            &mut few,
            &empty,
            &[],
            counts,
            &origin,
            &mut seeded_rng(1, RngStream::Mapper),
        );
        assert!(few.states.iter().all(|s| *s == PixelState::BelowSupport) && few.num_rays() == 2);
    }
}
