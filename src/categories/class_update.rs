//! Bringing one class's registration up to date while frames stream in (METHOD.md §3–§4).
//!
//! A class waits until every member's field has trained enough to be trusted
//! ([`crate::MapperConfig::field_steps_before_registration`]); it is registered the first time
//! it is ready and again when a member joins or leaves or a member's cloud grows by more than
//! `categories.reregister_growth` ([`class_is_due`]). Registering it evaluates the members'
//! uncertainty spheres — only to rank several members, and only where a member's cloud or field
//! changed materially since its stored sphere — and then [`register_class`].

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use nalgebra::Point3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::class_registration::{CategoryConfig, ClassRegistration, MemberInput, class_is_due, register_class_seeing};
use super::uncertainty::{ObjectReliability, UncertaintyStamp, UnobservedSpace, object_reliability, sphere_rays};
use crate::error::Result;
use crate::field::FieldBatch;
use crate::geometry::mesh::Aabb;
use crate::geometry::oriented_box::OrientedBox;
use crate::ids::{ClassId, ObjectId};
use crate::objects::keyframes::KeyframeWindow;
use crate::objects::object_bounds::{ShapeRule, shape_points};
use crate::objects::object_view::ObjectView;
use crate::objects::observed_cloud::ObservedCloud;
use crate::objects::observed_space::ObservedSpace;
use crate::rng::{RngStream, class_registration_seed, seeded_rng};

/// An object's uncertainty sphere as its class's latest registration used it, and what it was
/// evaluated on (it is evaluated again only after material growth).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MemberReliability {
    /// The evaluated sphere.
    pub sphere: ObjectReliability,
    /// The cloud and field it was evaluated on.
    pub stamp: UncertaintyStamp,
}

/// A member's per-object field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemberField {
    /// Its index in the object batch.
    pub index: usize,
    /// Field coordinates are world coordinates minus this point.
    pub origin: Point3<f32>,
    /// Steps it has taken.
    pub steps: u64,
}

/// One member of a class as the map holds it.
#[derive(Debug, Clone, Copy)]
pub struct ClassMember<'a> {
    /// The object.
    pub id: ObjectId,
    /// Its observed cloud.
    pub cloud: &'a ObservedCloud,
    /// Which of its cloud's voxels make its shape, as they make its box
    /// (`objects.box_min_voxel_points`, `objects.shape_voxels`; [`shape_points`]).
    pub shape: ShapeRule,
    /// Its minimum-volume oriented box.
    pub bounds: OrientedBox,
    /// Its per-object field.
    pub field: MemberField,
    /// Its sphere from an earlier registration, if one was evaluated.
    pub stored: Option<&'a MemberReliability>,
    /// Its keyframe crops (what its views observed), if known.
    pub keyframes: Option<&'a KeyframeWindow<ObjectView>>,
}

impl ClassMember<'_> {
    /// The points its registration reads: its box's ([`shape_points`]).
    fn shape_points(&self) -> Vec<Point3<f32>> {
        shape_points(self.cloud, self.shape)
    }

    /// What its sphere would be evaluated on now.
    fn stamp(&self) -> UncertaintyStamp {
        UncertaintyStamp {
            cloud_points: self.cloud.len(),
            field_steps: self.field.steps,
        }
    }
}

/// Whether a class is registered now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClassReadiness {
    /// A member has no trained field, box or cloud yet.
    Waiting,
    /// Its registration still holds.
    Current,
    /// It must be registered (again).
    Due,
}

/// Whether the class of `members` (`None` where a member lacks a field or a box) is due, given
/// the cloud sizes `registered_points` of its last registration (`None`: never registered).
pub fn class_readiness(
    members: &[Option<ClassMember<'_>>],
    registered_points: Option<&BTreeMap<ObjectId, usize>>,
    field_steps_needed: u64,
    reregister_growth: f32,
) -> ClassReadiness {
    let ready: Option<Vec<(ObjectId, usize)>> = members
        .iter()
        .map(|m| {
            m.filter(|m| m.field.steps >= field_steps_needed)
                .map(|m| (m.id, m.cloud.len()))
        })
        .collect();
    match ready {
        None => ClassReadiness::Waiting,
        Some(sizes) if class_is_due(registered_points, &sizes, reregister_growth) => ClassReadiness::Due,
        Some(_) => ClassReadiness::Current,
    }
}

/// A class registered anew.
#[derive(Debug, Clone)]
pub struct ClassUpdate {
    /// Its subcategories and answered pairs.
    pub registration: ClassRegistration,
    /// Each member's cloud size now (the next [`class_readiness`] compares against them).
    pub registered_points: BTreeMap<ObjectId, usize>,
    /// The spheres evaluated anew, by member (a stored sphere that still holds is not listed).
    pub new_reliabilities: Vec<(ObjectId, MemberReliability)>,
    /// Time spent on uncertainty spheres.
    pub uncertainty_time: Duration,
    /// Time spent on registration.
    pub register_time: Duration,
}

/// Registers `class` (members in the class's order): evaluates the uncertainty spheres that rank
/// several members (in parallel; each from its object's seeded stream), then [`register_class`]
/// from `previous` with the class's seed.
pub fn update_class(
    class: ClassId,
    members: &[ClassMember<'_>],
    previous: &ClassRegistration,
    fields: &FieldBatch,
    cfg: &CategoryConfig,
    seed: u64,
) -> Result<ClassUpdate> {
    let started = Instant::now();
    let clouds: Vec<Vec<Point3<f32>>> = members.iter().map(ClassMember::shape_points).collect();
    let reliabilities: Vec<Option<MemberReliability>> = if members.len() > 1 {
        members
            .par_iter()
            .zip(&clouds)
            .map(|(member, cloud)| member_reliability(member, cloud, fields, cfg, seed))
            .collect()
    } else {
        vec![None]
    };
    let uncertainty_time = started.elapsed();
    let started = Instant::now();
    let inputs: Vec<MemberInput> = members
        .iter()
        .zip(clouds)
        .zip(&reliabilities)
        .map(|((m, cloud), rel)| MemberInput {
            id: m.id,
            cloud,
            cloud_version: m.cloud.points_added(),
            bounds: m.bounds,
            reliable_rays: rel.as_ref().map_or(0, |r| r.sphere.reliable_rays),
        })
        .collect();
    let looked = |id: ObjectId| {
        let (member, input) = members.iter().zip(&inputs).find(|(m, _)| m.id == id)?;
        observed_space(member, &input.cloud, cfg)
    };
    let registration = register_class_seeing(&inputs, previous, cfg, class_registration_seed(seed, class), &looked)?;
    let register_time = started.elapsed();
    let new_reliabilities = members
        .iter()
        .zip(reliabilities)
        .filter_map(|(m, rel)| rel.filter(|r| m.stored != Some(r)).map(|r| (m.id, r)))
        .collect();
    Ok(ClassUpdate {
        registration,
        registered_points: members.iter().map(|m| (m.id, m.cloud.len())).collect(),
        new_reliabilities,
        uncertainty_time,
        register_time,
    })
}

/// What `member`'s views observed of the cube of its uncertainty sphere (around its observed
/// `cloud`'s world-axis box), when its views are known: what the sphere reads under
/// [`UnobservedSpace::Unknown`], and where a member no subcategory candidate accepts looked.
fn observed_space(member: &ClassMember<'_>, cloud: &[Point3<f32>], cfg: &CategoryConfig) -> Option<ObservedSpace> {
    let keyframes = member.keyframes?;
    let aabb = Aabb::from_points(cloud)?;
    let (centre, half_extents) = (aabb.center(), aabb.extent() * 0.5);
    let views: Vec<&ObjectView> = keyframes.slots().iter().map(|s| &s.data).collect();
    let radius = sphere_rays(&centre, &half_extents, &cfg.uncertainty).radius;
    Some(ObservedSpace::of_views(&views, &centre, radius))
}

/// A member's sphere: the stored one while it still describes the member, else evaluated on its
/// field around its observed cloud's world-axis box (METHOD.md §3). `None` without a field.
fn member_reliability(
    member: &ClassMember<'_>,
    cloud: &[Point3<f32>],
    fields: &FieldBatch,
    cfg: &CategoryConfig,
    seed: u64,
) -> Option<MemberReliability> {
    let stamp = member.stamp();
    if let Some(stored) = member
        .stored
        .filter(|s| s.stamp.still_describes(&stamp, cfg.uncertainty_refresh_growth))
    {
        return Some(stored.clone());
    }
    let field = fields.field(member.field.index)?;
    let aabb = Aabb::from_points(cloud)?;
    // A fresh generator of the object's field stream (the draws the field's initial weights
    // started from; the two uses are independent of each other).
    let mut rng = seeded_rng(seed, RngStream::ObjectField(member.id));
    let (centre, half_extents) = (aabb.center(), aabb.extent() * 0.5);
    let observed = match cfg.uncertainty.unobserved {
        UnobservedSpace::Unknown => observed_space(member, cloud, cfg),
        _ => None,
    };
    let sphere = object_reliability(&centre, &half_extents, &cfg.uncertainty, &mut rng, |points| {
        let alpha = field.eval_alpha_world(&member.field.origin, points);
        match &observed {
            Some(space) => space.unknown_where_unobserved(points, alpha),
            None => alpha,
        }
    });
    Some(MemberReliability { sphere, stamp })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::config::ShapeVoxels;

    fn cloud(points: usize) -> ObservedCloud {
        let mut cloud = ObservedCloud::new(0.01);
        for i in 0..points {
            cloud.add_point(&Point3::new(i as f32 * 0.02, 0.0, 0.0));
        }
        cloud
    }

    fn member(id: u32, cloud: &ObservedCloud, steps: u64) -> Option<ClassMember<'_>> {
        Some(ClassMember {
            id: ObjectId(id),
            cloud,
            bounds: OrientedBox {
                world_from_box: nalgebra::Isometry3::identity(),
                half_extents: nalgebra::Vector3::repeat(0.1),
            },
            field: MemberField {
                index: 0,
                origin: Point3::origin(),
                steps,
            },
            shape: ShapeRule {
                min_voxel_points: 1,
                voxels: ShapeVoxels::Uncontested,
            },
            stored: None,
            keyframes: None,
        })
    }

    /// A partial, noisy view of a ladder-back chair, every point seen three times, and — with
    /// `strays` — three points seen once 80 cm off its side (a depth camera's stray pixels).
    fn chair_seen(seed: u64, strays: bool) -> (ObservedCloud, OrientedBox) {
        use crate::geometry::oriented_box::fit_minimum_volume_box;
        use crate::synth::{Design, RegistrationTrial, RegistrationTrialSpec};
        let spec = RegistrationTrialSpec {
            outlier_fraction: 0.0,
            visible: (0.7, 0.8),
            ..RegistrationTrialSpec::default()
        };
        let trial = RegistrationTrial::draw(Design::LadderBackChair, &spec, seed).expect("a trial");
        let mut cloud = ObservedCloud::new(0.01);
        for p in trial.source.iter().flat_map(|p| [p; 3]) {
            cloud.add_point(p);
        }
        if strays {
            let far = trial.source.iter().map(|p| p.x).fold(f32::MIN, f32::max) + 0.8;
            for k in 0..3 {
                cloud.add_point(&Point3::new(far, k as f32 * 0.05, 0.4));
            }
        }
        let bounds = fit_minimum_volume_box(&shape_points(&cloud, uncontested(3))).expect("a box");
        (cloud, bounds)
    }

    /// The shape rule of exact masks, with voxels of at least `min_voxel_points` points.
    fn uncontested(min_voxel_points: u32) -> ShapeRule {
        ShapeRule {
            min_voxel_points,
            voxels: ShapeVoxels::Uncontested,
        }
    }

    /// The largest ratio of a registered frame's extents to the box of a chair seen without
    /// strays, for a chair with strays (1, the member) and one without (2, the representative).
    fn widest_member_frame(min_voxel_points: u32) -> f32 {
        use crate::field::{AdamWConfig, OBJECT_HIDDEN, OccupancyField};
        let chairs = [chair_seen(1, true), chair_seen(2, false)];
        let mut fields = FieldBatch::new(AdamWConfig::default());
        let mut rng = seeded_rng(7, RngStream::ObjectField(ObjectId(1)));
        let members: Vec<ClassMember<'_>> = chairs
            .iter()
            .enumerate()
            .map(|(i, (cloud, bounds))| {
                fields.push(OccupancyField::new(OBJECT_HIDDEN, 2.0, &mut rng));
                ClassMember {
                    id: ObjectId(i as u32 + 1),
                    cloud,
                    shape: uncontested(min_voxel_points),
                    bounds: *bounds,
                    field: MemberField {
                        index: i,
                        origin: bounds.center(),
                        steps: 300,
                    },
                    stored: None,
                    keyframes: None,
                }
            })
            .collect();
        let update = update_class(
            ClassId(20),
            &members,
            &ClassRegistration::default(),
            &fields,
            &CategoryConfig::default(),
            7,
        )
        .expect("registered");
        let group = &update.registration.groups[0];
        let chair = chairs[1].1.extents();
        group
            .members
            .values()
            .map(|m| m.nocs.extents.component_div(&chair).max())
            .fold(0.0, f32::max)
    }

    #[test]
    fn a_members_stray_voxels_leave_its_registered_frame_alone() {
        let widest = widest_member_frame(3);
        assert!(widest < 1.2, "the strays are left out: {widest}");
        let stretched = widest_member_frame(1);
        assert!(stretched > 1.5, "counted, they stretch the frame: {stretched}");
    }

    #[test]
    fn a_class_waits_for_every_members_field_then_is_due_until_registered() {
        let (a, b) = (cloud(10), cloud(20));
        let trained = [member(1, &a, 300), member(2, &b, 300)];
        assert_eq!(
            class_readiness(&[member(1, &a, 300), None], None, 200, 0.2),
            ClassReadiness::Waiting,
            "a member without a field holds the class back"
        );
        assert_eq!(
            class_readiness(&[member(1, &a, 300), member(2, &b, 199)], None, 200, 0.2),
            ClassReadiness::Waiting,
            "a member whose field has not trained enough holds the class back"
        );
        assert_eq!(class_readiness(&trained, None, 200, 0.2), ClassReadiness::Due);
        let then = BTreeMap::from([(ObjectId(1), 10), (ObjectId(2), 20)]);
        assert_eq!(
            class_readiness(&trained, Some(&then), 200, 0.2),
            ClassReadiness::Current
        );
        let smaller = BTreeMap::from([(ObjectId(1), 10), (ObjectId(2), 10)]);
        assert_eq!(
            class_readiness(&trained, Some(&smaller), 200, 0.2),
            ClassReadiness::Due,
            "a cloud doubled since"
        );
    }
}
