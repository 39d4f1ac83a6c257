//! The two profiles a run's settings start from. `paper` is the protocol docs/METHOD.md states,
//! every constant as the paper and its code have it; `fast` (the default) is `paper` with
//! catmap's choices, each named in [`MapperConfig::paper`]'s list of what it undoes. A sensor's
//! settings, a config file and the command line's flags are laid over the profile
//! ([`super::layers`]).

use crate::categories::class_registration::AlignmentTemplate;
use crate::categories::grown_box::RepresentativeBox;
use crate::categories::nocs::MemberScale;
use crate::categories::subcategories::SubcategoryAssignment;
use crate::field::RaySamplerConfig;
use crate::field::category::{CategoryRayBudget, ShapeCodes};
use crate::meshing::object_grid::PAPER_SURFACE_OCCUPANCY;
use crate::objects::config::BoxFit;
use crate::registration::Tilt;
use crate::training::SchedulePolicy;

use super::MapperConfig;

impl MapperConfig {
    /// The settings of `profile`: [`Self::paper`] or [`Self::fast`].
    pub fn profile(profile: SchedulePolicy) -> Self {
        match profile {
            SchedulePolicy::Paper => Self::paper(),
            SchedulePolicy::Fast => Self::fast(),
        }
    }

    /// catmap's default settings: the paper's protocol with catmap's choices (the fast
    /// schedule, the object sampler's priors, upright boxes, the surface at occupancy 0.75, one
    /// shape per subcategory, alignments to the whole subcategory, grown representative boxes,
    /// the representative's scale, upright registrations, 120 rays per category member).
    pub fn fast() -> Self {
        Self::default()
    }

    /// The paper's protocol (docs/METHOD.md, "The `paper` profile"): `fast` with each of catmap's
    /// choices undone.
    pub fn paper() -> Self {
        let mut c = Self::default();
        c.schedule.policy = SchedulePolicy::Paper;
        // vMAP's object sampler: no box samples, priors, mirrored rays or own-pixel draws.
        c.fields.object_rays = RaySamplerConfig {
            box_free_samples: RaySamplerConfig::OBJECT.box_free_samples,
            hidden_solid_rays: RaySamplerConfig::OBJECT.hidden_solid_rays,
            seen_free_rays: RaySamplerConfig::OBJECT.seen_free_rays,
            below_support_rays: RaySamplerConfig::OBJECT.below_support_rays,
            mirror_rays: RaySamplerConfig::OBJECT.mirror_rays,
            own_pixel_draws: RaySamplerConfig::OBJECT.own_pixel_draws,
            ..c.fields.object_rays
        };
        c.objects.box_fit = BoxFit::MinimumVolume;
        c.categories.subcategories.assignment = SubcategoryAssignment::First;
        c.categories.alignment_template = AlignmentTemplate::Representative;
        c.categories.frames.representative_box = RepresentativeBox::Own;
        c.categories.frames.member_scale = MemberScale::OwnBox;
        c.categories.registration.tilt = Tilt::Kept;
        c.category_fields.shape_codes = ShapeCodes::PerMember;
        c.category_fields.ray_budget = CategoryRayBudget::PerCategory;
        c.category_fields.hidden_solid_rays = 0;
        c.meshes.object.occupancy_level = PAPER_SURFACE_OCCUPANCY;
        c
    }
}

#[cfg(test)]
#[path = "profile_tests.rs"]
mod tests;
