//! [`CategoryConfig`]: how classes are registered while mapping.

use serde::{Deserialize, Serialize};

use super::AlignmentTemplate;
use crate::categories::held_frames::FrameHoldConfig;
use crate::categories::subcategories::SubcategoryRule;
use crate::categories::uncertainty::{RepresentativeChoice, UncertaintyConfig};
use crate::registration::RegistrationConfig;

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
    /// [`crate::MapperConfig::field_steps_before_registration`]).
    pub min_field_steps: u64,
    /// Members' clouds are thinned to this voxel before registration and Chamfer scores, metres.
    pub cloud_voxel_m: f32,
    /// Smallest edge of an aligned member's box, metres.
    pub min_extent_m: f32,
    /// A member's alignment to its representative, searched again with less trimming when it
    /// fits worse than its twins'.
    pub second_search: SecondSearch,
    /// What a member's final alignment fits: its representative's cloud, or its whole
    /// subcategory's ([`AlignmentTemplate`]).
    pub alignment_template: AlignmentTemplate,
    /// Where a re-registration starts each pair registered before.
    pub registration_start: RegistrationStart,
    /// A warm start is kept when its score is at most the stored one × (1 + this); otherwise the
    /// full search runs and the better of the two is kept.
    pub warm_start_tolerance: f32,
    /// A member's uncertainty sphere is evaluated again only when its cloud or its field's steps
    /// have grown by more than this fraction since it was last evaluated (0.25 = 25 %).
    pub uncertainty_refresh_growth: f32,
    /// Whether members keep their normalised frames across re-registrations, and how far a
    /// registration may move one before it is replaced (`categories::held_frames`).
    pub frames: FrameHoldConfig,
}

/// The second search of a member's alignment to its representative, once its subcategory is
/// decided.
///
/// The search trims the worst `registration.keep_fraction` (0.8) of its pairs at every ICP step,
/// for a member's outliers; a member seen from one side then slides along the representative
/// into a wrong basin where its remaining points fit: the chair seen at 20 % under the default
/// scene's table was registered 5–9° and 3–8 cm off in every run, its twins within 0.5° and
/// 0.5 cm, and the category field drew it from that frame (clean seed 0: completion 3.19 cm). Its
/// points all have a counterpart on its representative, so a search keeping 95 % of the pairs
/// finds the true pose (1.4° off; completion 1.05 cm). A member whose normalised distance to
/// its representative is above `above` (its twins': 0.014–0.02 on the clean default scene) is
/// searched again so, and keeps the better alignment; the subcategory decision stays the first
/// search's. Measured in docs/ROBUSTNESS.md.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SecondSearch {
    /// Members above this normalised one-way distance are searched again (1 or more: none is; a
    /// member above `subcategories.new_above` never joins).
    pub above: f32,
    /// The share of pairs the second search's ICP keeps.
    pub keep_fraction: f32,
}

impl Default for SecondSearch {
    fn default() -> Self {
        Self {
            above: 0.025,
            keep_fraction: 0.95,
        }
    }
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
    /// The pair's previous alignment, kept as it is (its score recomputed on today's clouds) while
    /// neither cloud has grown by more than `reregister_growth` since the alignment was found —
    /// on nearly the same clouds the search finds nearly the same alignment; otherwise the full
    /// search.
    Reuse,
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
            second_search: SecondSearch::default(),
            alignment_template: AlignmentTemplate::default(),
            registration_start: RegistrationStart::Search,
            warm_start_tolerance: 0.1,
            uncertainty_refresh_growth: 0.25,
            frames: FrameHoldConfig::default(),
        }
    }
}
