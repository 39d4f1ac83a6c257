//! [`CategoryFieldConfig`]: the category-level fields of METHOD.md §5 (`catmap run --mode category`).

use serde::{Deserialize, Serialize};

/// Settings of the category-level fields. A config file lists only what it changes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CategoryFieldConfig {
    /// Train one shared field per subcategory with more than one member (category mode). Needs
    /// `categories.enabled`; single-member subcategories keep their per-object fields. `catmap run`
    /// sets it from `--mode` (category, the default: on; instance: off).
    pub enabled: bool,
    /// Steps of the category fields once the classes are registered (the paper's 10⁴).
    pub iterations: usize,
    /// Dimension of each member's shape code and of its texture code.
    pub code_dim: usize,
    /// Rays per member per step (the paper's 120·objects/categories per category averages to
    /// 120 per member when every object is in a category).
    pub rays_per_member: usize,
}

impl Default for CategoryFieldConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            iterations: 10_000,
            code_dim: 32,
            rays_per_member: 120,
        }
    }
}
