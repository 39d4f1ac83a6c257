//! Registering one class: representative choice, registration of every member to it,
//! subcategories and each member's NOCS frame (METHOD.md §3–§4), as one pure function.

use std::collections::BTreeMap;

use nalgebra::{Isometry3, Point3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::category::{Alignment, PairRegistration, SubcategoryRule, subcategorize};
use crate::config::FieldConfig;
use crate::error::{CatmapError, Result};
use crate::ids::ObjectId;
use crate::nocs::{NocsFrame, aligned_member_frame, representative_frame};
use crate::oriented_box::OrientedBox;
use crate::registration::{
    RegistrationConfig, normalised_one_way_chamfer, refine_registration, register_to_representative, voxel_centroids,
};
use crate::uncertainty::{RepresentativeChoice, UncertaintyConfig};

/// Settings of category-level registration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CategoryConfig {
    /// Register classes while mapping (needs the per-object fields: uncertainty ranks the
    /// representative). `--mode category` needs it.
    pub enabled: bool,
    /// How a (sub)category's representative is chosen.
    pub representative: RepresentativeChoice,
    /// The subcategory rule.
    pub subcategories: SubcategoryRule,
    /// The uncertainty sphere.
    pub uncertainty: UncertaintyConfig,
    /// Pairwise registration.
    pub registration: RegistrationConfig,
    /// A class is registered again when one of its members' clouds has grown by more than this
    /// fraction since the class was last registered (0.2 = 20 %), or when it gains a member.
    pub reregister_growth: f32,
    /// Members' fields must have taken this many steps before their uncertainty is trusted
    /// (online; offline, the whole per-object training: see
    /// [`CategoryConfig::field_steps_before_registration`]).
    pub min_field_steps: u64,
    /// Members' clouds are thinned to this voxel before registration and Chamfer scores, metres.
    pub cloud_voxel_m: f32,
    /// Smallest edge of an aligned member's box, metres.
    pub min_extent_m: f32,
    /// Where a re-registration starts each pair registered before.
    pub registration_start: RegistrationStart,
    /// A warm start is kept when its score is at most the stored one × (1 + this); otherwise the
    /// full search runs and the better of the two is kept.
    pub warm_start_tolerance: f32,
    /// A member's uncertainty sphere is evaluated again only when its cloud or its field's steps
    /// have grown by more than this fraction since it was last evaluated (0.25 = 25 %).
    pub uncertainty_refresh_growth: f32,
}

/// Where a re-registration of a class starts a pair (member, representative) it registered before.
///
/// Measured on the default scene (seed 0, fast schedule): `warm` cut the registration stage from
/// 65 s to 43–46 s but left the chairs' accuracy at 3.5–3.8 cm against 3.0 cm with `search` — an
/// alignment found on an early, partial cloud stays in its basin as the cloud grows — so `search`
/// is the default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum RegistrationStart {
    /// From the pair's previous alignment (ICP refinement only), falling back to the full search
    /// when that scores worse than the stored alignment.
    Warm,
    /// The full multi-start search every time.
    #[default]
    Search,
}

impl Default for CategoryConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            representative: RepresentativeChoice::Uncertainty,
            subcategories: SubcategoryRule::default(),
            uncertainty: UncertaintyConfig::default(),
            registration: RegistrationConfig::default(),
            reregister_growth: 0.2,
            min_field_steps: 200,
            cloud_voxel_m: 0.02,
            min_extent_m: 0.10,
            registration_start: RegistrationStart::Search,
            warm_start_tolerance: 0.1,
            uncertainty_refresh_growth: 0.25,
        }
    }
}

impl CategoryConfig {
    /// Steps every member's field must have taken before its class is registered: online,
    /// `min_field_steps`; offline, all of the per-object training (as the reference code, which
    /// ranks uncertainty on the finished vMAP fields — early fields are confidently wrong in
    /// space no camera saw, which hides how well each member was observed).
    pub fn field_steps_before_registration(&self, fields: &FieldConfig) -> u64 {
        if fields.offline {
            self.min_field_steps.max(fields.offline_iterations as u64)
        } else {
            self.min_field_steps
        }
    }
}

/// One member as registration sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct MemberInput {
    /// The object.
    pub id: ObjectId,
    /// Its observed cloud (world).
    pub cloud: Vec<Point3<f32>>,
    /// Its minimum-volume oriented box.
    pub bounds: OrientedBox,
    /// Reliable rays of its uncertainty sphere.
    pub reliable_rays: usize,
}

/// A registered member.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RegisteredMember {
    /// Its alignment to the subcategory's representative.
    pub alignment: Alignment,
    /// Its box and normalised frame.
    pub nocs: NocsFrame,
}

/// A registered subcategory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegisteredSubcategory {
    /// The representative.
    pub representative: ObjectId,
    /// Members by id (the representative included).
    pub members: BTreeMap<ObjectId, RegisteredMember>,
}

/// Registers the members of one class; `seed` makes every random draw reproducible. `previous`
/// is the class's last registration (empty the first time): a pair registered there starts from
/// its previous alignment (see [`RegistrationStart`]).
pub fn register_class(
    members: &[MemberInput],
    previous: &[RegisteredSubcategory],
    cfg: &CategoryConfig,
    seed: u64,
) -> Result<Vec<RegisteredSubcategory>> {
    if members.is_empty() {
        return Err(CatmapError::Degenerate("a class without members".into()));
    }
    let clouds: BTreeMap<ObjectId, Vec<Point3<f32>>> = members
        .iter()
        .map(|m| Ok((m.id, voxel_centroids(&m.cloud, cfg.cloud_voxel_m)?)))
        .collect::<Result<_>>()?;
    let warm = match cfg.registration_start {
        RegistrationStart::Warm => previous_alignments(previous),
        RegistrationStart::Search => BTreeMap::new(),
    };
    let pairs = ClassClouds {
        clouds: &clouds,
        cfg: &cfg.registration,
        seed,
        warm,
        warm_tolerance: cfg.warm_start_tolerance,
    };
    let reliable: BTreeMap<ObjectId, usize> = members.iter().map(|m| (m.id, m.reliable_rays)).collect();
    let ids: Vec<ObjectId> = members.iter().map(|m| m.id).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let groups = subcategorize(
        &ids,
        &reliable,
        cfg.representative,
        &cfg.subcategories,
        &pairs,
        &mut rng,
    );
    let by_id: BTreeMap<ObjectId, &MemberInput> = members.iter().map(|m| (m.id, m)).collect();
    groups
        .into_iter()
        .map(|group| {
            let rep_frame = representative_frame(&by_id[&group.representative].bounds);
            let members = group
                .members
                .into_iter()
                .map(|(id, alignment)| {
                    let nocs = if id == group.representative {
                        rep_frame
                    } else {
                        let cloud = &by_id[&id].cloud;
                        aligned_member_frame(cloud, &alignment.template_from_object, &rep_frame, cfg.min_extent_m)?
                    };
                    Ok((id, RegisteredMember { alignment, nocs }))
                })
                .collect::<Result<_>>()?;
            Ok(RegisteredSubcategory {
                representative: group.representative,
                members,
            })
        })
        .collect()
}

/// The stored alignment of every (member, representative) pair of a registration.
fn previous_alignments(groups: &[RegisteredSubcategory]) -> BTreeMap<(ObjectId, ObjectId), Alignment> {
    groups
        .iter()
        .flat_map(|g| {
            g.members
                .iter()
                .filter(|(id, _)| **id != g.representative)
                .map(|(id, m)| ((*id, g.representative), m.alignment))
        })
        .collect()
}

/// Pairwise registration over a class's thinned clouds.
struct ClassClouds<'a> {
    clouds: &'a BTreeMap<ObjectId, Vec<Point3<f32>>>,
    cfg: &'a RegistrationConfig,
    seed: u64,
    /// Previous alignments of (source, template) pairs: warm starts.
    warm: BTreeMap<(ObjectId, ObjectId), Alignment>,
    warm_tolerance: f32,
}

impl ClassClouds<'_> {
    fn cloud(&self, id: ObjectId) -> Result<&[Point3<f32>]> {
        self.clouds
            .get(&id)
            .map(Vec::as_slice)
            .ok_or_else(|| CatmapError::Degenerate(format!("no cloud for object {id}")))
    }
}

impl PairRegistration for ClassClouds<'_> {
    fn register(&self, source: ObjectId, template: ObjectId) -> Result<(Isometry3<f32>, f32)> {
        let (s, t) = (self.cloud(source)?, self.cloud(template)?);
        let warm = match self.warm.get(&(source, template)) {
            Some(stored) => {
                let warm = refine_registration(s, t, &stored.template_from_object, self.cfg)?;
                if warm_start_holds(warm.score, stored.chamfer, self.warm_tolerance) {
                    return Ok((warm.template_from_source(), warm.score));
                }
                Some(warm)
            }
            None => None,
        };
        // One stream per ordered pair, so results do not depend on the order pairs are tried.
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream((u64::from(source.0) << 32) | u64::from(template.0));
        let full = register_to_representative(s, t, self.cfg, &mut rng)?;
        let best = match warm {
            Some(warm) if warm.score < full.score => warm,
            _ => full,
        };
        Ok((best.template_from_source(), best.score))
    }

    fn reverse_chamfer(&self, source: ObjectId, template: ObjectId, template_from_source: &Isometry3<f32>) -> f32 {
        let (Ok(s), Ok(t)) = (self.cloud(source), self.cloud(template)) else {
            return f32::INFINITY;
        };
        let aligned: Vec<Point3<f32>> = s.iter().map(|p| template_from_source * p).collect();
        normalised_one_way_chamfer(t, &aligned).unwrap_or(f32::INFINITY)
    }
}

/// Whether a class must be registered (again): it never was (`registered_points` is `None`), a
/// member joined or left, or a member's cloud (`(id, points)` now) grew by more than `growth` (a
/// fraction) since the cloud sizes `registered_points` of its last registration.
pub fn class_is_due(
    registered_points: Option<&BTreeMap<ObjectId, usize>>,
    members: &[(ObjectId, usize)],
    growth: f32,
) -> bool {
    let Some(then) = registered_points else {
        return true;
    };
    then.len() != members.len()
        || members.iter().any(|(id, now)| {
            then.get(id)
                .is_none_or(|&n| *now as f64 > n as f64 * (1.0 + f64::from(growth)))
        })
}

/// Whether a warm-started registration scoring `warm` may stand in for the full search, given the
/// pair's stored score.
pub fn warm_start_holds(warm: f32, stored: f32, tolerance: f32) -> bool {
    warm.is_finite() && warm <= stored * (1.0 + tolerance)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_class_is_due_when_new_when_its_members_change_or_a_cloud_grows() {
        let (a, b, c) = (ObjectId(1), ObjectId(2), ObjectId(3));
        let then = BTreeMap::from([(a, 1_000), (b, 500)]);
        assert!(class_is_due(None, &[(a, 10)], 0.2), "never registered");
        assert!(
            !class_is_due(Some(&then), &[(a, 1_200), (b, 500)], 0.2),
            "20 % is not more than 20 %"
        );
        assert!(class_is_due(Some(&then), &[(a, 1_000), (b, 601)], 0.2), "a cloud grew");
        assert!(
            class_is_due(Some(&then), &[(a, 1_000), (b, 500), (c, 10)], 0.2),
            "a member joined"
        );
        assert!(
            class_is_due(Some(&then), &[(a, 1_000), (c, 500)], 0.2),
            "a member was replaced"
        );
    }

    #[test]
    fn a_warm_start_holds_only_when_it_scores_no_worse_than_stored_within_tolerance() {
        assert!(warm_start_holds(0.05, 0.05, 0.1));
        assert!(warm_start_holds(0.055, 0.05, 0.1));
        assert!(!warm_start_holds(0.056, 0.05, 0.1));
        assert!(!warm_start_holds(f32::NAN, 0.05, 0.1));
        assert!(!warm_start_holds(f32::INFINITY, f32::INFINITY, 0.1));
    }

    /// Two copies of one chair design and a table, each a partial, noisy view.
    fn three_members() -> Vec<MemberInput> {
        use crate::oriented_box::fit_minimum_volume_box;
        use crate::synth::{Design, RegistrationTrial, RegistrationTrialSpec};
        let spec = RegistrationTrialSpec {
            outlier_fraction: 0.0,
            visible: (0.7, 0.8),
            ..RegistrationTrialSpec::default()
        };
        [
            (1, Design::LadderBackChair, 1),
            (2, Design::LadderBackChair, 2),
            (3, Design::DiningTable, 3),
        ]
        .into_iter()
        .map(|(id, design, seed)| {
            let trial = RegistrationTrial::draw(design, &spec, seed).unwrap();
            MemberInput {
                id: ObjectId(id),
                bounds: fit_minimum_volume_box(&trial.source).unwrap(),
                cloud: trial.source,
                reliable_rays: 10 - id as usize,
            }
        })
        .collect()
    }

    fn groups(registered: &[RegisteredSubcategory]) -> Vec<(ObjectId, Vec<ObjectId>)> {
        registered
            .iter()
            .map(|g| (g.representative, g.members.keys().copied().collect()))
            .collect()
    }

    fn starting(registration_start: RegistrationStart) -> CategoryConfig {
        CategoryConfig {
            registration_start,
            ..CategoryConfig::default()
        }
    }

    #[test]
    fn a_warm_re_registration_keeps_the_full_searchs_groups_and_scores() {
        let members = three_members();
        let first = register_class(&members, &[], &starting(RegistrationStart::Search), 7).unwrap();
        assert_eq!(
            groups(&first),
            vec![
                (ObjectId(1), vec![ObjectId(1), ObjectId(2)]),
                (ObjectId(3), vec![ObjectId(3)])
            ],
            "the chair copies share a subcategory, the table does not"
        );
        let again = register_class(&members, &first, &starting(RegistrationStart::Warm), 7).unwrap();
        assert_eq!(groups(&again), groups(&first));
        let (cold, warm) = (
            first[0].members[&ObjectId(2)].alignment.chamfer,
            again[0].members[&ObjectId(2)].alignment.chamfer,
        );
        assert!(
            warm_start_holds(warm, cold, CategoryConfig::default().warm_start_tolerance),
            "refining the stored pose on the same clouds: {warm} vs {cold}"
        );
    }

    #[test]
    fn a_warm_start_that_scores_worse_falls_back_to_the_full_search() {
        let members = three_members();
        let first = register_class(&members, &[], &starting(RegistrationStart::Search), 7).unwrap();
        // A stored alignment half a turn off, with the good score: the warm start cannot reach it.
        let mut wrong = first.clone();
        let member = wrong[0].members.get_mut(&ObjectId(2)).unwrap();
        member.alignment.template_from_object =
            Isometry3::rotation(nalgebra::Vector3::new(0.0, 0.0, std::f32::consts::PI))
                * member.alignment.template_from_object;
        let again = register_class(&members, &wrong, &starting(RegistrationStart::Warm), 7).unwrap();
        assert_eq!(groups(&again), groups(&first));
        assert_eq!(
            again[0].members[&ObjectId(2)].alignment.chamfer,
            first[0].members[&ObjectId(2)].alignment.chamfer,
            "the full search's result"
        );
    }

    #[test]
    fn offline_classes_wait_for_the_whole_per_object_training() {
        let cfg = CategoryConfig::default();
        let online = FieldConfig::default();
        assert_eq!(cfg.field_steps_before_registration(&online), cfg.min_field_steps);
        let offline = FieldConfig {
            offline: true,
            offline_iterations: 1_500,
            ..FieldConfig::default()
        };
        assert_eq!(cfg.field_steps_before_registration(&offline), 1_500);
        let short = FieldConfig {
            offline_iterations: 50,
            ..offline
        };
        assert_eq!(
            cfg.field_steps_before_registration(&short),
            cfg.min_field_steps,
            "never before the fields are trusted at all"
        );
    }
}
