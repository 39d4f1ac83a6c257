//! Subcategories of a class (METHOD.md §4): members are registered to a representative and split
//! off when their shapes differ, recursively.
//!
//! With `cd` = the normalised one-way Chamfer distance of the aligned member to the
//! representative: `cd > new_above` → the member leaves; `cd < same_below` → it stays; otherwise
//! the reverse distance (representative → aligned member, normalised by the representative's
//! scale) decides: above `reverse_split_above` it leaves. Members that leave form a new group
//! with its own representative, which may split again.
//!
//! That greedy pass (the paper's) keeps a member with the first representative that accepts it,
//! and a poorly observed representative (a chair seen at 20 %, under a table) accepts few: its
//! own design's chairs leave it and form a second group of that design. With
//! [`SubcategoryAssignment::Best`] a second pass follows: the representatives of the groups the
//! greedy pass left with two or more members are the candidates, and every other object — the
//! members, and the representatives left alone — joins the candidate that explains it best, by
//! the two-way distance (one-way + reverse, both normalised by scale) among the candidates whose
//! rule accepts it. A member is too partial to decide when its two best candidates' two-way
//! distances lie within `undecided_margin` of each other (a chair seen only by its seat fits
//! both designs): it keeps a subcategory of its own rather than join a wrong design. A member no
//! candidate accepts is asked again with the reverse distance over the representative's points
//! its views looked at ([`ReversePoints::LookedAt`]: a chair seen from above lacks the legs its
//! cameras never faced, not its design's); one still unaccepted is its own subcategory too. A
//! candidate whose greedy group all joins other candidates is placed like a member. The pairs only the second pass asks may keep an
//! alignment found on nearly the same clouds ([`PairRegistration::register_again`]): a class
//! registers again whenever one member's cloud grew, and most of those pairs did not change.

use std::collections::BTreeMap;

use nalgebra::Isometry3;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::categories::uncertainty::{RepresentativeChoice, choose_representative};
use crate::error::Result;
use crate::ids::ObjectId;

/// Thresholds of the subcategory rule (the reference code's values) and how members are
/// assigned.
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
    /// Which representative a member joins (see the module doc; `paper`: first).
    pub assignment: SubcategoryAssignment,
    /// Under [`SubcategoryAssignment::Best`], a member whose two best candidates' two-way
    /// distances differ by less than this share of the better one keeps its own subcategory.
    pub undecided_margin: f32,
    /// Under [`SubcategoryAssignment::Best`], the reverse distance a member that no candidate
    /// accepts is asked again with ([`ReversePoints::All`]: it is not asked again).
    pub unplaced_reverse: ReversePoints,
}

/// Which of the representative's points the reverse distance (representative → aligned member)
/// reads.
///
/// The reverse distance tells a member that lacks a part of its representative (a stool under
/// an armchair: the seat fits, the arms and back are not there). A member seen from one side
/// lacks every part its cameras never faced too, and reads far from the representative of its
/// own design: a chair seen at 20 % under a table (default seed 0, a segmenter's masks), its
/// one-way distance in the rule's grey zone, had a reverse distance of 0.29–0.33 to either
/// design (0.12 splits) and kept a field of its own, which filled the space under its seat.
/// Over the points its views looked at, its own design's representative read 0.10, the other
/// 0.13. Read that way for every member, though, the reverse tells designs apart less well (a
/// ladder-back chair seen at 75 % left its design on default seed 1), so it is asked only of a
/// member no candidate accepts otherwise ([`SubcategoryRule::unplaced_reverse`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReversePoints {
    /// Every point (the paper's).
    All,
    /// The points that land, in the member, where its views looked: seen free, at its surface, or
    /// glimpsed through ([`crate::objects::observed_space::ObservedSpace::looked_at`]). A part
    /// that lands in space the member's views saw free is one it lacks; a part that lands behind
    /// its surface or outside its views is one its cameras never faced. When fewer than
    /// [`MIN_LOOKED_AT_SHARE`] of the points qualify, or the member's views are unknown, every
    /// point is read.
    LookedAt,
}

/// Under [`ReversePoints::LookedAt`], the least share of the representative's points that must
/// land where the member's views looked for the reverse distance to read only those.
pub const MIN_LOOKED_AT_SHARE: f32 = 0.1;

impl Default for SubcategoryRule {
    fn default() -> Self {
        Self {
            enabled: true,
            same_below: 0.06,
            new_above: 0.15,
            reverse_split_above: 0.12,
            assignment: SubcategoryAssignment::Best,
            undecided_margin: 0.1,
            unplaced_reverse: ReversePoints::LookedAt,
        }
    }
}

impl SubcategoryRule {
    /// The assignment that applies.
    pub fn assignment(&self) -> SubcategoryAssignment {
        self.assignment
    }
}

/// Which representative a member joins.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SubcategoryAssignment {
    /// The paper's: the first representative whose rule accepts it (greedy).
    First,
    /// The candidate representative that explains it best, two-way (see the module doc).
    Best,
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
    /// The normalised distance from `template` to `source` aligned by `template_from_source`,
    /// over the template's `points`.
    fn reverse_chamfer(
        &self,
        source: ObjectId,
        template: ObjectId,
        template_from_source: &Isometry3<f32>,
        points: ReversePoints,
    ) -> f32;
    /// Registers `source` to `template` for the best-explanation pass (a candidate the greedy
    /// pass did not ask about this member): as [`PairRegistration::register`], except that an
    /// implementation may keep an alignment it found on nearly the same clouds.
    fn register_again(&self, source: ObjectId, template: ObjectId) -> Result<(Isometry3<f32>, f32)> {
        self.register(source, template)
    }
}

/// Which pass asks a pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pass {
    /// The paper's greedy pass.
    Greedy,
    /// The best-explanation pass.
    Best,
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
                .map(|&id| {
                    let decision = decide(id, representative, rule, registration, Pass::Greedy, ReversePoints::All);
                    (id, decision)
                })
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
    match rule.assignment() {
        SubcategoryAssignment::Best if rule.enabled => assign_best(groups, rule, registration),
        _ => groups,
    }
}

/// The second pass of [`SubcategoryAssignment::Best`] over the greedy pass's `groups` (see the
/// module doc): groups in the greedy order, the candidates' first, then one per member that
/// joined none, in id order. A candidate that every member of its greedy group leaves is a
/// member to place like the others: the pass runs again without it.
fn assign_best(
    groups: Vec<Subcategory>,
    rule: &SubcategoryRule,
    registration: &(impl PairRegistration + Sync),
) -> Vec<Subcategory> {
    let mut candidates: Vec<ObjectId> = groups
        .iter()
        .filter(|g| g.members.len() > 1)
        .map(|g| g.representative)
        .collect();
    if candidates.is_empty() {
        return groups;
    }
    loop {
        let out = assign_to(&groups, &candidates, rule, registration);
        let emptied: Vec<ObjectId> = out
            .iter()
            .filter(|g| g.members.len() == 1 && candidates.contains(&g.representative))
            .map(|g| g.representative)
            .collect();
        if emptied.is_empty() || emptied.len() == candidates.len() {
            return out;
        }
        candidates.retain(|c| !emptied.contains(c));
    }
}

/// Every member of `groups` that is not one of `candidates` joins the candidate that explains it
/// best (asked again over what its views looked at when none accepts it, as
/// `rule.unplaced_reverse` says), or a subcategory of its own.
fn assign_to(
    groups: &[Subcategory],
    candidates: &[ObjectId],
    rule: &SubcategoryRule,
    registration: &(impl PairRegistration + Sync),
) -> Vec<Subcategory> {
    use rayon::prelude::*;
    let others: Vec<ObjectId> = groups
        .iter()
        .flat_map(|g| g.members.keys().copied())
        .filter(|id| !candidates.contains(id))
        .collect();
    let explained: Vec<(ObjectId, Vec<Explanation>)> = others
        .par_iter()
        .map(|&id| {
            let fits_over = |points| -> Vec<Explanation> {
                candidates
                    .iter()
                    .filter_map(|&rep| explain(id, rep, rule, registration, points))
                    .collect()
            };
            let fits = fits_over(ReversePoints::All);
            let fits = match rule.unplaced_reverse {
                ReversePoints::LookedAt if fits.is_empty() => fits_over(ReversePoints::LookedAt),
                _ => fits,
            };
            (id, fits)
        })
        .collect();
    let mut out: Vec<Subcategory> = groups
        .iter()
        .filter(|g| candidates.contains(&g.representative))
        .map(|g| Subcategory {
            representative: g.representative,
            members: BTreeMap::from([(g.representative, g.members[&g.representative])]),
        })
        .collect();
    let mut alone = Vec::new();
    for (id, fits) in explained {
        match best_explanation(&fits, rule.undecided_margin) {
            Some(best) => {
                let group = out
                    .iter_mut()
                    .find(|g| g.representative == best.representative)
                    .expect("a candidate heads a group");
                group.members.insert(id, best.alignment);
            }
            None => alone.push(id),
        }
    }
    alone.sort_unstable();
    out.extend(alone.into_iter().map(|id| Subcategory {
        representative: id,
        members: BTreeMap::from([(
            id,
            Alignment {
                template_from_object: Isometry3::identity(),
                chamfer: 0.0,
                reverse_chamfer: None,
            },
        )]),
    }));
    out
}

/// A candidate representative that accepts a member, and how well it explains it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Explanation {
    /// The candidate.
    pub representative: ObjectId,
    /// The member's alignment to it, with both distances.
    pub alignment: Alignment,
}

impl Explanation {
    /// One-way plus reverse distance.
    pub fn two_way(&self) -> f32 {
        self.alignment.chamfer + self.alignment.reverse_chamfer.unwrap_or(0.0)
    }
}

/// How `representative` explains `id`, when the rule accepts it with the reverse distance over
/// `points`: the alignment with the reverse distance always measured.
fn explain(
    id: ObjectId,
    representative: ObjectId,
    rule: &SubcategoryRule,
    registration: &impl PairRegistration,
    points: ReversePoints,
) -> Option<Explanation> {
    let mut alignment = decide(id, representative, rule, registration, Pass::Best, points)?;
    if alignment.reverse_chamfer.is_none() {
        alignment.reverse_chamfer =
            Some(registration.reverse_chamfer(id, representative, &alignment.template_from_object, points));
    }
    Some(Explanation {
        representative,
        alignment,
    })
}

/// The explanation a member takes among those of the candidates that accept it: the smallest
/// two-way distance, unless the second smallest lies within `undecided_margin` of it (too
/// partial to decide: `None`, as when no candidate accepts it).
pub fn best_explanation(fits: &[Explanation], undecided_margin: f32) -> Option<Explanation> {
    let mut sorted: Vec<&Explanation> = fits.iter().collect();
    sorted.sort_by(|a, b| a.two_way().total_cmp(&b.two_way()));
    match sorted.as_slice() {
        [] => None,
        [only] => Some(**only),
        [best, second, ..] => (second.two_way() > best.two_way() * (1.0 + undecided_margin)).then_some(**best),
    }
}

/// `Some(alignment)` when `id` stays with `representative`, the reverse distance read over
/// `points`.
fn decide(
    id: ObjectId,
    representative: ObjectId,
    rule: &SubcategoryRule,
    registration: &impl PairRegistration,
    pass: Pass,
    points: ReversePoints,
) -> Option<Alignment> {
    let registered = match pass {
        Pass::Greedy => registration.register(id, representative),
        Pass::Best => registration.register_again(id, representative),
    };
    let (template_from_object, chamfer) = match registered {
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
    let reverse = registration.reverse_chamfer(id, representative, &template_from_object, points);
    alignment.reverse_chamfer = Some(reverse);
    (reverse <= rule.reverse_split_above).then_some(alignment)
}

#[cfg(test)]
#[path = "subcategories_tests.rs"]
mod tests;
