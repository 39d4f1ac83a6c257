//! The profiles against docs/METHOD.md: its table of the keys where `paper` and `fast` differ
//! names every such key with both values, and `paper`'s constants are the ones its sections state.

use super::*;

/// docs/METHOD.md, the method section by section.
const METHOD_PAGE: &str = include_str!("../../docs/METHOD.md");

/// A TOML literal of the page (`0.5`, `"per_member"`) as a value.
fn literal(text: &str) -> toml::Value {
    let table: toml::Table = toml::from_str(&format!("v = {text}")).expect("a TOML literal");
    table["v"].clone()
}

/// The rows of METHOD.md's profile table: (key, paper's value, fast's value).
fn profile_rows() -> Vec<(String, toml::Value, toml::Value)> {
    let section = METHOD_PAGE
        .split("\n## ")
        .find(|s| s.starts_with("§7"))
        .expect("METHOD.md has a §7, the profiles");
    section
        .lines()
        .filter(|line| line.starts_with("| `"))
        .map(|row| {
            let cells: Vec<&str> = row.split('|').map(str::trim).collect();
            let unquote = |cell: &str| cell.trim_matches('`').to_owned();
            (
                unquote(cells[1]),
                literal(&unquote(cells[2])),
                literal(&unquote(cells[3])),
            )
        })
        .collect()
}

#[test]
fn methods_profile_table_names_every_key_where_paper_and_fast_differ_with_both_values() {
    let paper = crate::config::layers::leaves(&MapperConfig::paper().to_table());
    let fast = crate::config::layers::leaves(&MapperConfig::fast().to_table());
    assert_eq!(paper.len(), fast.len(), "one tree");
    let differing: Vec<(String, toml::Value, toml::Value)> = paper
        .into_iter()
        .zip(fast)
        .filter(|(p, f)| p.1 != f.1)
        .map(|(p, f)| (p.0, p.1, f.1))
        .collect();
    let mut rows = profile_rows();
    rows.sort_by(|a, b| a.0.cmp(&b.0));
    let mut differing = differing;
    differing.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(
        differing.len() >= 15,
        "the profiles differ in catmap's choices: {differing:?}"
    );
    assert_eq!(rows, differing, "METHOD.md §7 against the profiles");
}

#[test]
fn papers_constants_are_the_ones_methods_sections_state() {
    let paper = MapperConfig::paper();
    let fields = &paper.fields;
    let rays = &fields.object_rays;
    // §2: vMAP's sampler, keyframes and optimiser.
    assert_eq!(
        (
            rays.keyframes_per_step,
            rays.pixels_per_keyframe,
            rays.free_samples,
            rays.surface_samples
        ),
        (5, 24, 1, 9)
    );
    assert_eq!((rays.surface_band_m, rays.behind_occluder_m), (0.1, 0.05));
    assert_eq!(
        (
            rays.box_free_samples,
            rays.hidden_solid_rays,
            rays.mirror_rays,
            rays.own_pixel_draws
        ),
        (0, 0, 0, 0),
        "no box samples, priors, mirrored rays or own-pixel draws"
    );
    assert_eq!((fields.learning_rate, fields.weight_decay), (1e-3, 0.013));
    assert_eq!((fields.steps_per_frame, fields.offline_iterations), (20, 15_000));
    let k = &paper.keyframes;
    assert_eq!((k.capacity, k.object_stride, k.background_stride), (20, 25, 50));
    assert_eq!(paper.objects.box_fit, BoxFit::MinimumVolume);
    assert_eq!((paper.objects.cloud_voxel_m, paper.objects.min_extent_m), (0.01, 0.10));
    // §3: the uncertainty sphere.
    let u = &paper.categories.uncertainty;
    assert_eq!((u.angles, u.samples_per_ray, u.radius_factor), (100, 96, 1.2));
    // §4: the subcategory rule, the paper's greedy assignment, its frames.
    let s = &paper.categories.subcategories;
    assert_eq!((s.same_below, s.new_above, s.reverse_split_above), (0.06, 0.15, 0.12));
    assert_eq!(s.assignment, SubcategoryAssignment::First);
    assert_eq!(paper.categories.alignment_template, AlignmentTemplate::Representative);
    assert_eq!(paper.categories.frames.representative_box, RepresentativeBox::Own);
    assert_eq!(paper.categories.frames.member_scale, MemberScale::OwnBox);
    assert_eq!(paper.categories.registration.tilt, Tilt::Kept);
    // §5: one field per subcategory, a shape code per member, the reference's ray budget.
    let c = &paper.category_fields;
    assert_eq!((c.code_dim, c.rays_per_object, c.iterations), (32, 120, 10_000));
    assert_eq!(
        (c.shape_codes, c.ray_budget),
        (ShapeCodes::PerMember, CategoryRayBudget::PerCategory)
    );
    assert_eq!(c.hidden_solid_rays, 0);
    // §6: meshes at occupancy 0.5.
    let m = &paper.meshes.object;
    assert_eq!((m.voxel_size_m, m.max_samples_per_side, m.box_fill), (0.005, 256, 0.9));
    assert_eq!(m.occupancy_level, 0.5);
    assert_eq!(paper.schedule.policy, SchedulePolicy::Paper);
    assert_eq!(paper.training_policy(), SchedulePolicy::Paper);
}

#[test]
fn fast_is_the_default_and_each_profile_reads_back_from_its_printed_tree() {
    assert_eq!(MapperConfig::fast(), MapperConfig::default());
    for policy in [SchedulePolicy::Paper, SchedulePolicy::Fast] {
        let config = MapperConfig::profile(policy);
        assert_eq!(MapperConfig::from_toml(&config.to_toml()).expect("parses"), config);
    }
}
