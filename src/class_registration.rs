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
    RegistrationConfig, normalised_one_way_chamfer, register_to_representative, voxel_centroids,
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

/// Registers the members of one class; `seed` makes every random draw reproducible.
pub fn register_class(members: &[MemberInput], cfg: &CategoryConfig, seed: u64) -> Result<Vec<RegisteredSubcategory>> {
    if members.is_empty() {
        return Err(CatmapError::Degenerate("a class without members".into()));
    }
    let clouds: BTreeMap<ObjectId, Vec<Point3<f32>>> = members
        .iter()
        .map(|m| Ok((m.id, voxel_centroids(&m.cloud, cfg.cloud_voxel_m)?)))
        .collect::<Result<_>>()?;
    let pairs = ClassClouds {
        clouds: &clouds,
        cfg: &cfg.registration,
        seed,
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

/// Pairwise registration over a class's thinned clouds.
struct ClassClouds<'a> {
    clouds: &'a BTreeMap<ObjectId, Vec<Point3<f32>>>,
    cfg: &'a RegistrationConfig,
    seed: u64,
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
        // One stream per ordered pair, so results do not depend on the order pairs are tried.
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream((u64::from(source.0) << 32) | u64::from(template.0));
        let r = register_to_representative(self.cloud(source)?, self.cloud(template)?, self.cfg, &mut rng)?;
        Ok((r.template_from_source(), r.score))
    }

    fn reverse_chamfer(&self, source: ObjectId, template: ObjectId, template_from_source: &Isometry3<f32>) -> f32 {
        let (Ok(s), Ok(t)) = (self.cloud(source), self.cloud(template)) else {
            return f32::INFINITY;
        };
        let aligned: Vec<Point3<f32>> = s.iter().map(|p| template_from_source * p).collect();
        normalised_one_way_chamfer(t, &aligned).unwrap_or(f32::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
