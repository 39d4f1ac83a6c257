//! Registering one class: representative choice, registration of every member to it,
//! subcategories and each member's NOCS frame (METHOD.md §3–§4), as one pure function.

mod config;
mod pair_cache;
mod pairs;

use std::collections::BTreeMap;

use nalgebra::Point3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

pub use config::{CategoryConfig, RegistrationStart};
pub use pair_cache::{CachedPair, PairCache, PairPoints, PairVersions};
pub use pairs::warm_start_holds;

use crate::categories::nocs::{NocsFrame, aligned_member_frame, representative_frame};
use crate::categories::subcategories::{Alignment, subcategorize};
use crate::error::{CatmapError, Result};
use crate::geometry::oriented_box::OrientedBox;
use crate::ids::ObjectId;
use crate::registration::voxel_centroids;
use pairs::ClassClouds;

/// One member as registration sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct MemberInput {
    /// The object.
    pub id: ObjectId,
    /// Its observed cloud (world).
    pub cloud: Vec<Point3<f32>>,
    /// The version of its observed cloud: changes whenever the cloud does (see [`PairCache`]).
    pub cloud_version: u64,
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

/// A class's registration: its subcategories, and every pair it answered.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ClassRegistration {
    /// Subcategories in the order they were split off.
    pub groups: Vec<RegisteredSubcategory>,
    /// The pairs answered (for the next registration; see [`PairCache`]).
    #[serde(default)]
    pub pairs: PairCache,
}

/// Registers the members of one class; `seed` makes every random draw reproducible. `previous`
/// is the class's last registration (empty the first time): a pair whose two clouds have not
/// changed since is answered as it was then, and a pair registered there starts from its previous
/// alignment (see [`RegistrationStart`]).
pub fn register_class(
    members: &[MemberInput],
    previous: &ClassRegistration,
    cfg: &CategoryConfig,
    seed: u64,
) -> Result<ClassRegistration> {
    if members.is_empty() {
        return Err(CatmapError::Degenerate("a class without members".into()));
    }
    let clouds: BTreeMap<ObjectId, Vec<Point3<f32>>> = members
        .iter()
        .map(|m| Ok((m.id, voxel_centroids(&m.cloud, cfg.cloud_voxel_m)?)))
        .collect::<Result<_>>()?;
    let sizes: BTreeMap<ObjectId, usize> = members.iter().map(|m| (m.id, m.cloud.len())).collect();
    let versions: BTreeMap<ObjectId, u64> = members.iter().map(|m| (m.id, m.cloud_version)).collect();
    let pairs = ClassClouds::new(&clouds, &sizes, &versions, &previous.pairs, cfg, seed);
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
    let groups = groups
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
        .collect::<Result<_>>()?;
    Ok(ClassRegistration {
        groups,
        pairs: pairs.into_answered(),
    })
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

#[cfg(test)]
mod tests {
    use nalgebra::Isometry3;

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

    /// Two copies of one chair design and a table, each a partial, noisy view.
    fn three_members() -> Vec<MemberInput> {
        use crate::geometry::oriented_box::fit_minimum_volume_box;
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
                cloud_version: 1,
                reliable_rays: 10 - id as usize,
            }
        })
        .collect()
    }

    /// The same members after their clouds changed (new versions of the same points), so that no
    /// pair is answered from the cache.
    fn touched(members: &[MemberInput]) -> Vec<MemberInput> {
        members
            .iter()
            .map(|m| MemberInput {
                cloud_version: m.cloud_version + 1,
                ..m.clone()
            })
            .collect()
    }

    fn first_time() -> ClassRegistration {
        ClassRegistration::default()
    }

    fn groups(registered: &ClassRegistration) -> Vec<(ObjectId, Vec<ObjectId>)> {
        registered
            .groups
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
        let first = register_class(&members, &first_time(), &starting(RegistrationStart::Search), 7).unwrap();
        assert_eq!(
            groups(&first),
            vec![
                (ObjectId(1), vec![ObjectId(1), ObjectId(2)]),
                (ObjectId(3), vec![ObjectId(3)])
            ],
            "the chair copies share a subcategory, the table does not"
        );
        let again = register_class(&touched(&members), &first, &starting(RegistrationStart::Warm), 7).unwrap();
        assert_eq!(groups(&again), groups(&first));
        let (cold, warm) = (
            first.groups[0].members[&ObjectId(2)].alignment.chamfer,
            again.groups[0].members[&ObjectId(2)].alignment.chamfer,
        );
        assert!(
            warm_start_holds(warm, cold, CategoryConfig::default().warm_start_tolerance),
            "refining the stored pose on the same clouds: {warm} vs {cold}"
        );
    }

    #[test]
    fn a_warm_start_that_scores_worse_falls_back_to_the_full_search() {
        let members = three_members();
        let first = register_class(&members, &first_time(), &starting(RegistrationStart::Search), 7).unwrap();
        // A stored alignment half a turn off, with the good score: the warm start cannot reach it.
        let mut wrong = first.clone();
        let pair = wrong.pairs.0.get_mut(&(ObjectId(2), ObjectId(1))).unwrap();
        pair.template_from_source =
            Isometry3::rotation(nalgebra::Vector3::new(0.0, 0.0, std::f32::consts::PI)) * pair.template_from_source;
        let again = register_class(&touched(&members), &wrong, &starting(RegistrationStart::Warm), 7).unwrap();
        assert_eq!(groups(&again), groups(&first));
        assert_eq!(
            again.groups[0].members[&ObjectId(2)].alignment.chamfer,
            first.groups[0].members[&ObjectId(2)].alignment.chamfer,
            "the full search's result"
        );
    }

    #[test]
    fn pairs_on_unchanged_clouds_are_answered_as_before_and_only_they() {
        let members = three_members();
        let search = starting(RegistrationStart::Search);
        let first = register_class(&members, &first_time(), &search, 7).expect("registered");
        // Table → chair representative (rejected) and chair → chair (joined): both answered.
        assert_eq!(first.pairs.len(), 2, "{:?}", first.pairs.0.keys());
        // An impossible answer planted in the cache shows whether a pair was searched again.
        let mut planted = first.clone();
        for cached in planted.pairs.0.values_mut() {
            cached.chamfer = 1e-6;
        }
        let again = register_class(&members, &planted, &search, 7).expect("registered");
        assert_eq!(
            again.pairs, planted.pairs,
            "no cloud changed: every pair from the cache"
        );
        assert_eq!(
            groups(&again),
            vec![(ObjectId(1), members.iter().map(|m| m.id).collect())]
        );

        let mut table_moved = members.clone();
        table_moved[2].cloud_version += 1;
        let after = register_class(&table_moved, &planted, &search, 7).expect("registered");
        assert_eq!(groups(&after), groups(&first), "the table's pair searched again");
        let chair_pair = (ObjectId(2), ObjectId(1));
        assert_eq!(
            after.pairs.0[&chair_pair], planted.pairs.0[&chair_pair],
            "the chairs' pair kept"
        );
        assert_eq!(
            after.pairs.0[&(ObjectId(3), ObjectId(1))],
            CachedPair {
                versions: PairVersions { source: 2, template: 1 },
                ..first.pairs.0[&(ObjectId(3), ObjectId(1))]
            },
            "searched anew: exactly the first search's answer"
        );
    }

    #[test]
    fn a_reused_pair_keeps_its_alignment_until_a_cloud_grows() {
        let members = three_members();
        let first = register_class(&members, &first_time(), &starting(RegistrationStart::Search), 7).unwrap();
        let chair = |registered: &ClassRegistration| registered.groups[0].members[&ObjectId(2)];
        let found_at = |registered: &ClassRegistration| registered.pairs.0[&(ObjectId(2), ObjectId(1))].found_at;
        assert_eq!(
            found_at(&first),
            PairPoints {
                source: members[1].cloud.len(),
                template: members[0].cloud.len()
            },
            "a searched pair records its cloud sizes"
        );
        let reuse = starting(RegistrationStart::Reuse);
        let again = register_class(&touched(&members), &first, &reuse, 7).unwrap();
        assert_eq!(groups(&again), groups(&first));
        let (kept, searched) = (chair(&again), chair(&first));
        assert_eq!(
            (kept.alignment.template_from_object, kept.nocs, found_at(&again)),
            (searched.alignment.template_from_object, searched.nocs, found_at(&first)),
            "same clouds: the alignment is kept as it was"
        );
        assert!(
            (kept.alignment.chamfer - searched.alignment.chamfer).abs() < 1e-6,
            "rescored on the same clouds (in f32 rather than the search's f64 pose)"
        );

        // The member's cloud grows by half (its points again, shifted by 1 mm): searched anew.
        let mut grown = members.clone();
        let extra: Vec<Point3<f32>> = grown[1]
            .cloud
            .iter()
            .step_by(2)
            .map(|p| p + nalgebra::Vector3::new(0.001, 0.0, 0.0))
            .collect();
        grown[1].cloud.extend(extra);
        grown[1].cloud_version += 1;
        let after = register_class(&grown, &again, &reuse, 7).unwrap();
        assert_eq!(groups(&after), groups(&first));
        assert_eq!(
            found_at(&after).source,
            grown[1].cloud.len(),
            "searched at the grown size"
        );
        let searched = register_class(&grown, &first_time(), &starting(RegistrationStart::Search), 7).unwrap();
        assert_eq!(chair(&after), chair(&searched), "exactly the full search's result");
    }
}
