//! Which category field each subcategory gets when the membership changes while streaming: a new
//! subcategory takes over the current field it shares the most members with (its network and
//! the codes of the members it keeps, with their optimiser states); members new to a field get
//! fresh codes; a field no subcategory takes over is dropped (its members keep their per-object
//! fields, which trained all along). Nothing else changes, so no other object loses training.

use crate::ids::ObjectId;

/// One category field of the new membership.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlannedField {
    /// Its members, in code order (the subcategory's members, sorted).
    pub members: Vec<ObjectId>,
    /// The current field it continues, if any.
    pub continues: Option<usize>,
    /// Per member, its code index in the continued field (`None`: a fresh code).
    pub codes: Vec<Option<usize>>,
}

/// Plans the fields for `wanted` subcategories (each a member list) given the `current` fields'
/// members. Pairs are matched greedily by shared members (most first; ties to the lower index).
pub fn plan_category_fields(current: &[Vec<ObjectId>], wanted: &[Vec<ObjectId>]) -> Vec<PlannedField> {
    let mut pairs: Vec<(usize, usize, usize)> = Vec::new();
    for (j, want) in wanted.iter().enumerate() {
        for (i, have) in current.iter().enumerate() {
            let shared = want.iter().filter(|id| have.contains(id)).count();
            if shared > 0 {
                pairs.push((shared, j, i));
            }
        }
    }
    pairs.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut continues: Vec<Option<usize>> = vec![None; wanted.len()];
    let mut taken = vec![false; current.len()];
    for (_, j, i) in pairs {
        if continues[j].is_none() && !taken[i] {
            continues[j] = Some(i);
            taken[i] = true;
        }
    }
    wanted
        .iter()
        .zip(continues)
        .map(|(want, from)| {
            let mut members = want.clone();
            members.sort_unstable();
            members.dedup();
            let codes = members
                .iter()
                .map(|id| from.and_then(|i| current[i].iter().position(|m| m == id)))
                .collect();
            PlannedField {
                members,
                continues: from,
                codes,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ids(v: &[u32]) -> Vec<ObjectId> {
        v.iter().map(|&i| ObjectId(i)).collect()
    }

    #[test]
    fn unchanged_membership_keeps_every_field_and_code() {
        let current = vec![ids(&[1, 2, 3]), ids(&[7, 8])];
        let plan = plan_category_fields(&current, &current);
        assert_eq!(plan[0].continues, Some(0));
        assert_eq!(plan[0].codes, vec![Some(0), Some(1), Some(2)]);
        assert_eq!(plan[1].continues, Some(1));
        assert_eq!(plan[1].codes, vec![Some(0), Some(1)]);
    }

    #[test]
    fn a_split_keeps_the_field_for_the_larger_part_and_starts_one_for_the_rest() {
        let plan = plan_category_fields(&[ids(&[1, 2, 3, 4, 5])], &[ids(&[1, 2]), ids(&[3, 4, 5])]);
        assert_eq!(plan[0].continues, None, "the smaller part starts a new field");
        assert_eq!(plan[0].codes, vec![None, None]);
        assert_eq!(plan[1].continues, Some(0));
        assert_eq!(plan[1].codes, vec![Some(2), Some(3), Some(4)]);
    }

    #[test]
    fn a_join_keeps_codes_where_it_can_and_drops_the_unmatched_field() {
        let current = vec![ids(&[2, 3]), ids(&[1, 9])];
        let plan = plan_category_fields(&current, &[ids(&[3, 1, 2])]);
        assert_eq!(plan.len(), 1);
        assert_eq!(plan[0].members, ids(&[1, 2, 3]));
        assert_eq!(plan[0].continues, Some(0), "two shared members beat one");
        assert_eq!(plan[0].codes, vec![None, Some(0), Some(1)]);
    }

    #[test]
    fn the_first_fields_start_fresh() {
        let plan = plan_category_fields(&[], &[ids(&[4, 5])]);
        assert_eq!(plan[0].continues, None);
        assert_eq!(plan[0].codes, vec![None, None]);
        assert!(plan_category_fields(&[ids(&[1, 2])], &[]).is_empty());
    }
}
