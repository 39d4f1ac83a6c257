//! Subcategories of a class (METHOD.md §4): members are registered to a representative and split
//! off when their shapes differ, recursively.
//!
//! With `cd` = the normalised one-way Chamfer distance of the aligned member to the
//! representative: `cd > new_above` → the member leaves; `cd < same_below` → it stays; otherwise
//! the reverse distance (representative → aligned member, normalised by the representative's
//! scale) decides: above `reverse_split_above` it leaves. Members that leave form a new group
//! with its own representative, which may split again.

use std::collections::BTreeMap;

use nalgebra::Isometry3;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::categories::uncertainty::{RepresentativeChoice, choose_representative};
use crate::error::Result;
use crate::ids::ObjectId;

/// Thresholds of the subcategory rule (the reference code's values).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SubcategoryRule {
    /// Split subcategories at all (off: one subcategory per class, the ablation).
    pub enabled: bool,
    /// Below this one-way distance a member stays.
    pub same_below: f32,
    /// Above this one-way distance a member leaves.
    pub new_above: f32,
    /// In between, the member leaves when the reverse distance is above this.
    pub reverse_split_above: f32,
}

impl Default for SubcategoryRule {
    fn default() -> Self {
        Self {
            enabled: true,
            same_below: 0.06,
            new_above: 0.15,
            reverse_split_above: 0.12,
        }
    }
}

/// A member registered to its representative.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Alignment {
    /// Maps the member's points onto the representative's (identity for the representative).
    pub template_from_object: Isometry3<f32>,
    /// Normalised one-way Chamfer distance member → representative (0 for the representative).
    pub chamfer: f32,
    /// The reverse distance, when the rule needed it.
    pub reverse_chamfer: Option<f32>,
}

/// One subcategory: its representative and every member's alignment to it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Subcategory {
    /// The best-observed member.
    pub representative: ObjectId,
    /// Members (the representative included), by id.
    pub members: BTreeMap<ObjectId, Alignment>,
}

/// What subcategorisation needs from registration.
pub trait PairRegistration {
    /// Registers `source` to `template`: the rigid transform and the normalised one-way distance.
    fn register(&self, source: ObjectId, template: ObjectId) -> Result<(Isometry3<f32>, f32)>;
    /// The normalised distance from `template` to `source` aligned by `template_from_source`.
    fn reverse_chamfer(&self, source: ObjectId, template: ObjectId, template_from_source: &Isometry3<f32>) -> f32;
}

/// Splits `members` of one class into subcategories. `reliable_rays` ranks candidates for
/// representative (see [`choose_representative`]); registration failures make a member its own
/// subcategory (logged).
pub fn subcategorize(
    members: &[ObjectId],
    reliable_rays: &BTreeMap<ObjectId, usize>,
    choice: RepresentativeChoice,
    rule: &SubcategoryRule,
    registration: &(impl PairRegistration + Sync),
    rng: &mut impl Rng,
) -> Vec<Subcategory> {
    let mut groups = Vec::new();
    let mut remaining: Vec<ObjectId> = members.to_vec();
    remaining.sort_unstable();
    remaining.dedup();
    while !remaining.is_empty() {
        let ranked: Vec<(ObjectId, usize)> = remaining
            .iter()
            .map(|id| (*id, reliable_rays.get(id).copied().unwrap_or(0)))
            .collect();
        let Some(representative) = choose_representative(&ranked, choice, rng) else {
            break;
        };
        let identity = Alignment {
            template_from_object: Isometry3::identity(),
            chamfer: 0.0,
            reverse_chamfer: None,
        };
        let mut group = Subcategory {
            representative,
            members: BTreeMap::from([(representative, identity)]),
        };
        let others: Vec<ObjectId> = remaining.iter().copied().filter(|id| *id != representative).collect();
        let decisions: Vec<(ObjectId, Option<Alignment>)> = {
            use rayon::prelude::*;
            others
                .par_iter()
                .map(|&id| (id, decide(id, representative, rule, registration)))
                .collect()
        };
        remaining.clear();
        for (id, decision) in decisions {
            match decision {
                Some(alignment) => {
                    group.members.insert(id, alignment);
                }
                None => remaining.push(id),
            }
        }
        groups.push(group);
    }
    groups
}

/// `Some(alignment)` when `id` stays with `representative`.
fn decide(
    id: ObjectId,
    representative: ObjectId,
    rule: &SubcategoryRule,
    registration: &impl PairRegistration,
) -> Option<Alignment> {
    let (template_from_object, chamfer) = match registration.register(id, representative) {
        Ok(r) => r,
        Err(e) => {
            tracing::warn!(object = %id, representative = %representative, error = %e, "registration failed");
            return None;
        }
    };
    let mut alignment = Alignment {
        template_from_object,
        chamfer,
        reverse_chamfer: None,
    };
    if !rule.enabled || chamfer < rule.same_below {
        return Some(alignment);
    }
    if chamfer > rule.new_above {
        return None;
    }
    let reverse = registration.reverse_chamfer(id, representative, &template_from_object);
    alignment.reverse_chamfer = Some(reverse);
    (reverse <= rule.reverse_split_above).then_some(alignment)
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// Objects whose "shape" is a number: distance = |a − b| / 10, reverse = the same × 2.
    struct Shapes(BTreeMap<ObjectId, f32>);

    impl PairRegistration for Shapes {
        fn register(&self, source: ObjectId, template: ObjectId) -> Result<(Isometry3<f32>, f32)> {
            Ok((
                Isometry3::translation(1.0, 0.0, 0.0),
                (self.0[&source] - self.0[&template]).abs() / 10.0,
            ))
        }
        fn reverse_chamfer(&self, source: ObjectId, template: ObjectId, _: &Isometry3<f32>) -> f32 {
            2.0 * (self.0[&source] - self.0[&template]).abs() / 10.0
        }
    }

    fn shapes(values: &[(u32, f32)]) -> Shapes {
        Shapes(values.iter().map(|&(id, v)| (ObjectId(id), v)).collect())
    }

    #[test]
    fn two_designs_split_and_identical_copies_stay_together() {
        // Design A (shape 0.0), design B (shape 2.0); ids 1–3 A, 4–6 B; object 5 is best observed.
        let reg = shapes(&[(1, 0.0), (2, 0.1), (3, 0.0), (4, 2.0), (5, 2.1), (6, 2.0)]);
        let ids: Vec<ObjectId> = (1..=6).map(ObjectId).collect();
        let rays = BTreeMap::from([(ObjectId(5), 900), (ObjectId(2), 700), (ObjectId(1), 500)]);
        let groups = subcategorize(
            &ids,
            &rays,
            RepresentativeChoice::Uncertainty,
            &SubcategoryRule::default(),
            &reg,
            &mut ChaCha8Rng::seed_from_u64(0),
        );
        assert_eq!(groups.len(), 2);
        assert_eq!(groups[0].representative, ObjectId(5));
        assert_eq!(groups[0].members.keys().map(|i| i.0).collect::<Vec<_>>(), [4, 5, 6]);
        assert_eq!(groups[1].representative, ObjectId(2), "the best observed of the rest");
        assert_eq!(groups[1].members.keys().map(|i| i.0).collect::<Vec<_>>(), [1, 2, 3]);
        assert_eq!(groups[0].members[&ObjectId(5)].chamfer, 0.0);
    }

    #[test]
    fn the_middle_band_asks_the_reverse_distance() {
        // cd = 0.08 (between 0.06 and 0.15): reverse 0.16 > 0.12 → split; cd = 0.065: reverse 0.13 → split;
        // cd = 0.059 → stays without asking.
        let reg = shapes(&[(1, 0.0), (2, 0.8), (3, 0.59)]);
        let ids = [ObjectId(1), ObjectId(2), ObjectId(3)];
        let rays = BTreeMap::from([(ObjectId(1), 10)]);
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let groups = subcategorize(
            &ids,
            &rays,
            RepresentativeChoice::Uncertainty,
            &SubcategoryRule::default(),
            &reg,
            &mut rng,
        );
        assert_eq!(groups[0].members.keys().map(|i| i.0).collect::<Vec<_>>(), [1, 3]);
        assert_eq!(groups[0].members[&ObjectId(3)].reverse_chamfer, None);
        assert_eq!(groups.len(), 2, "object 2 leaves");

        let off = SubcategoryRule {
            enabled: false,
            ..SubcategoryRule::default()
        };
        let groups = subcategorize(&ids, &rays, RepresentativeChoice::Uncertainty, &off, &reg, &mut rng);
        assert_eq!(groups.len(), 1, "no subcategories: one group per class");
    }
}
