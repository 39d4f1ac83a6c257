//! Registering one class: representative choice, registration of every member to it,
//! subcategories and each member's NOCS frame (METHOD.md §3–§4), as one pure function.

mod config;
mod pair_cache;
mod pairs;
mod subcategory_template;

use std::collections::BTreeMap;

use nalgebra::Point3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

pub use config::{CategoryConfig, RegistrationStart, SecondSearch};
pub use pair_cache::{CachedPair, PairCache, PairPoints, PairSearches, PairVersions};
pub use pairs::warm_start_holds;
pub use subcategory_template::AlignmentTemplate;

use crate::categories::grown_box::{RepresentativeBox, grown_box};
use crate::categories::held_frames::{RepresentativeFrame, hold_frame};
use crate::categories::nocs::{NocsFrame, aligned_member_frame, representative_frame};
use crate::categories::subcategories::{Alignment, Subcategory, subcategorize};
use crate::error::{CatmapError, Result};
use crate::geometry::oriented_box::OrientedBox;
use crate::ids::ObjectId;
use crate::objects::observed_space::ObservedSpace;
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

/// Where a member's views looked, by member, computed when first asked (the reverse distance of
/// [`crate::categories::subcategories::ReversePoints::LookedAt`]); `None` where its views are
/// not known.
pub type LookedAt<'a> = &'a (dyn Fn(ObjectId) -> Option<ObservedSpace> + Sync);

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

impl RegisteredSubcategory {
    /// Its members' frames, by id.
    pub fn frames(&self) -> impl Iterator<Item = (ObjectId, NocsFrame)> + '_ {
        self.members.iter().map(|(id, m)| (*id, m.nocs))
    }
}

impl ClassRegistration {
    /// Every member's frame, by id.
    pub fn frames(&self) -> BTreeMap<ObjectId, NocsFrame> {
        self.groups.iter().flat_map(RegisteredSubcategory::frames).collect()
    }
}

/// Registers the members of one class; `seed` makes every random draw reproducible. `previous`
/// is the class's last registration (empty the first time): a pair whose two clouds have not
/// changed since is answered as it was then, and a pair registered there starts from its previous
/// alignment (see [`RegistrationStart`]). A representative keeps the frame it had there unless
/// its box moved beyond `cfg.frames`' tolerance (`categories::held_frames`); the other members'
/// frames follow their alignments to it. No member's views are known: the reverse distance reads
/// every point ([`register_class_seeing`]).
pub fn register_class(
    members: &[MemberInput],
    previous: &ClassRegistration,
    cfg: &CategoryConfig,
    seed: u64,
) -> Result<ClassRegistration> {
    register_class_seeing(members, previous, cfg, seed, &|_| None)
}

/// [`register_class`] with `looked`: where each member's views looked, asked only of members that
/// no subcategory candidate accepts otherwise.
pub fn register_class_seeing(
    members: &[MemberInput],
    previous: &ClassRegistration,
    cfg: &CategoryConfig,
    seed: u64,
    looked: LookedAt<'_>,
) -> Result<ClassRegistration> {
    if members.is_empty() {
        return Err(CatmapError::too_few("members of a class", 1, 0));
    }
    let clouds: BTreeMap<ObjectId, Vec<Point3<f32>>> = members
        .iter()
        .map(|m| Ok((m.id, voxel_centroids(&m.cloud, cfg.cloud_voxel_m)?)))
        .collect::<Result<_>>()?;
    let sizes: BTreeMap<ObjectId, usize> = members.iter().map(|m| (m.id, m.cloud.len())).collect();
    let versions: BTreeMap<ObjectId, u64> = members.iter().map(|m| (m.id, m.cloud_version)).collect();
    let pairs = ClassClouds::new(&clouds, &sizes, &versions, looked, &previous.pairs, cfg, seed);
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
    let held = previous.frames();
    let groups = groups
        .into_iter()
        .map(|group| searched_again(group, &pairs, &cfg.second_search))
        .map(|group| subcategory_template::refined_against(group?, &clouds, cfg, seed))
        .collect::<Result<Vec<_>>>()?;
    let groups = groups
        .into_iter()
        .map(|group| {
            let rep = group.representative;
            let rep_box = match cfg.frames.representative_box {
                RepresentativeBox::Grown => {
                    let aligned: Vec<Vec<Point3<f32>>> = group
                        .members
                        .iter()
                        .filter(|(id, _)| **id != rep)
                        .map(|(id, a)| by_id[id].cloud.iter().map(|p| a.template_from_object * p).collect())
                        .collect();
                    grown_box(&by_id[&rep].bounds, &aligned)
                }
                RepresentativeBox::Own => by_id[&rep].bounds,
            };
            let rep_frame = hold_frame(
                held.get(&rep),
                representative_frame(&rep_box),
                &by_id[&rep].cloud,
                &cfg.frames,
                cfg.min_extent_m,
            )?;
            if let RepresentativeFrame::Replaced(_) = rep_frame {
                tracing::debug!(representative = %rep, "subcategory frame replaced");
            }
            let rep_frame = rep_frame.frame();
            let members = group
                .members
                .into_iter()
                .map(|(id, alignment)| {
                    let nocs = if id == rep {
                        rep_frame
                    } else {
                        let cloud = &by_id[&id].cloud;
                        aligned_member_frame(
                            cloud,
                            &alignment.template_from_object,
                            &rep_frame,
                            (cfg.min_extent_m, cfg.frames.member_scale),
                        )?
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

/// `group` with every member that fits its representative worse than `second.above` searched
/// again ([`SecondSearch`]), each keeping the better alignment.
fn searched_again(mut group: Subcategory, pairs: &ClassClouds<'_>, second: &SecondSearch) -> Result<Subcategory> {
    let representative = group.representative;
    for (id, alignment) in group.members.iter_mut().filter(|(id, _)| **id != representative) {
        if alignment.chamfer <= second.above {
            continue;
        }
        if let Some((pose, chamfer)) = pairs.search_again(*id, representative, second.keep_fraction)? {
            alignment.template_from_object = pose;
            alignment.chamfer = chamfer;
        }
    }
    Ok(group)
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
mod tests;
