//! [`CategoryFieldConfig`]: the category-level fields of METHOD.md §5 (`catmap run --mode category`).

use serde::{Deserialize, Serialize};

use super::member_codes::{MemberCodes, ShapeCodes};
use crate::objects::cell_rules::UnseenCells;

/// How many rays a category field draws per step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CategoryRayBudget {
    /// The reference's: `rays_per_object · objects / categories` rays per category field, where
    /// every object is in one category (a category field, or on its own), shared by its members.
    PerCategory,
    /// `rays_per_object` rays for every member (a field's cost grows with its members).
    PerMember,
}

/// Settings of the category-level fields. A config file lists only what it changes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CategoryFieldConfig {
    /// Train one shared field per subcategory with more than one member (category mode, the
    /// paper's method: on by default). Needs `categories.enabled`; single-member subcategories
    /// keep their per-object fields. `catmap run --mode instance` turns it off (the vMAP*
    /// baseline: one field per object).
    pub enabled: bool,
    /// Steps of the category fields once the classes are registered (the paper's 10⁴; the paper
    /// schedule, and the offline protocol's cap).
    pub iterations: usize,
    /// Dimension of each member's shape code and of its texture code.
    pub code_dim: usize,
    /// Whose shape a field draws for each member: its own shape code (METHOD.md §5) or one shape
    /// for the subcategory ([`ShapeCodes`]).
    pub shape_codes: ShapeCodes,
    /// Rays per object and step (vMAP's 120), the unit of the ray budget.
    pub rays_per_object: usize,
    /// How the rays of a step are shared out among the category fields.
    pub ray_budget: CategoryRayBudget,
    /// Solid-prior rays per member and step in the cells of its box that no member of its field
    /// saw into (`catmap::categories::member_hidden`; the object sampler's `hidden_cells` pick
    /// them, its `hidden_solid_weight` weighs them). 0: none (`paper`).
    pub hidden_solid_rays: usize,
    /// The share of a member's box those cells must make up for it to take them: a side of the
    /// design no member's camera faced (the drawer fronts of two nightstands seen from behind:
    /// 75–82 % of their boxes), not a layer under a chair's seat (at most 6 %).
    pub min_hidden_share: f64,
    /// Whether a member's cells no view saw under it count as hidden (as the object sampler's
    /// `unseen_cells` for an object alone in its class). Unknown by default: on living seed 0
    /// the rule moved a nightstand's completion 1.30 → 1.45 cm.
    pub unseen_cells: UnseenCells,
}

impl Default for CategoryFieldConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            iterations: 10_000,
            code_dim: 32,
            shape_codes: ShapeCodes::Shared,
            rays_per_object: 120,
            ray_budget: CategoryRayBudget::PerMember,
            hidden_solid_rays: 8,
            min_hidden_share: 0.25,
            unseen_cells: UnseenCells::Unknown,
        }
    }
}

impl CategoryFieldConfig {
    /// The codes every member gets.
    pub fn member_codes(&self) -> MemberCodes {
        MemberCodes {
            dim: self.code_dim,
            shape: self.shape_codes,
        }
    }

    /// Rays per member and step of a category field with `members` members, in a map of
    /// `objects` objects forming `categories` categories (category fields plus objects on their
    /// own); at least one ray per member.
    pub fn rays_per_member(&self, members: usize, objects: usize, categories: usize) -> usize {
        match self.ray_budget {
            CategoryRayBudget::PerMember => self.rays_per_object,
            CategoryRayBudget::PerCategory => {
                let per_category = self.rays_per_object * objects / categories.max(1);
                per_category.div_ceil(members.max(1)).max(1)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_budget_shares_the_average_category_rays_among_members() {
        let cfg = CategoryFieldConfig {
            ray_budget: CategoryRayBudget::PerCategory,
            ..CategoryFieldConfig::default()
        };
        // 14 objects: two 4-member category fields and 6 objects on their own = 8 categories;
        // 120 · 14 / 8 = 210 rays per category, 53 per member of a 4-member field.
        assert_eq!(cfg.rays_per_member(4, 14, 8), 53);
        assert_eq!(cfg.rays_per_member(2, 2, 1), 120, "every object in one field: 120 each");
        let per_member = CategoryFieldConfig {
            ray_budget: CategoryRayBudget::PerMember,
            ..cfg
        };
        assert_eq!(per_member.rays_per_member(4, 14, 8), 120);
        assert_eq!(cfg.rays_per_member(500, 1, 1), 1, "at least one ray per member");
    }
}
