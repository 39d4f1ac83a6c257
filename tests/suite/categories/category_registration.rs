//! Category registration on the default synthetic scene (the category-registration issue's
//! acceptance): every 4th frame, the offline protocol with a short training (500 steps) and
//! categories on; then the subcategories and every object's aligned box (single members'
//! too; of the floor lamp, a solid of revolution, only the tilt) are checked against the
//! scene's truth, and the representatives' observed surface fractions are printed.

use std::collections::{BTreeMap, BTreeSet};

use catmap::categories::subcategories::SubcategoryAssignment;
use catmap::config::FieldConfig;
use catmap::dataset::FrameSource;
use catmap::registration::cube_rotations;
use catmap::synth::{Design, Preset, SyntheticScene};
use catmap::{MapperConfig, ObjectId};
use catmap_systems::categories_report::ClassRecord;
use nalgebra::{Matrix3, Matrix4, Point3};

fn map_default_scene() -> (SyntheticScene, Vec<ClassRecord>, BTreeMap<String, f64>) {
    let scene = SyntheticScene::generate(0, Preset::Default).expect("default scene");
    let mut config = MapperConfig {
        seed: 0,
        fields: FieldConfig {
            offline: true,
            offline_iterations: 500,
            ..FieldConfig::default()
        },
        ..MapperConfig::paper()
    };
    // Members join the representative that explains them best (the fast schedule's rule): on
    // this scene the paper's first acceptance leaves ladder-back chair 2, seen at 20 % and
    // ranked first, alone and makes a second group of its design.
    config.categories.subcategories.assignment = SubcategoryAssignment::Best;
    config.categories.enabled = true;
    config.category_fields.enabled = false; // registration only
    let mut mapper = crate::common::mapping::map_scene(&scene, (0..scene.len()).step_by(4), config);
    let records = mapper.category_records();
    let stages = mapper.stage_seconds();
    (scene, records, stages)
}

/// Smallest rotation angle (degrees) between two box orientations, modulo the box's 24 axis
/// relabellings.
fn box_rotation_error_deg(a: &Matrix3<f32>, b: &Matrix3<f32>) -> f32 {
    cube_rotations()
        .iter()
        .map(|c| {
            let d = a.transpose() * b * c.matrix();
            ((d.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
        })
        .fold(f32::INFINITY, f32::min)
}

/// Angle (degrees) between the box axis closest to the truth's vertical and that vertical.
fn tilt_error_deg(a: &Matrix3<f32>, truth: &Matrix3<f32>) -> f32 {
    let up = truth.column(2);
    (0..3)
        .map(|k| a.column(k).dot(&up).abs().clamp(0.0, 1.0).acos().to_degrees())
        .fold(f32::INFINITY, f32::min)
}

#[test]
fn the_default_scene_splits_the_chair_designs_and_aligns_every_box() {
    let (scene, records, stages) = map_default_scene();
    // The uncertainty spheres and the registration proper are timed as separate stages.
    for stage in ["uncertainty", "register"] {
        assert!(
            stages.get(stage).is_some_and(|s| *s > 0.0),
            "stage {stage} timed: {stages:?}"
        );
    }
    let observed = scene.observed_surface_fraction().clone();
    let chair = records
        .iter()
        .find(|r| r.name.as_deref() == Some("chair"))
        .expect("a chair class");
    assert!(!chair.subcategories.is_empty(), "the chair class was registered");
    let design_of = |id: ObjectId| scene.object(id).expect("scene object").design;
    let mut subcategory_of_design: BTreeMap<_, BTreeSet<usize>> = BTreeMap::new();
    for (k, sub) in chair.subcategories.iter().enumerate() {
        for m in &sub.members {
            subcategory_of_design.entry(design_of(m.id)).or_default().insert(k);
        }
    }
    assert_eq!(subcategory_of_design.len(), 2, "two chair designs in the scene");
    for (design, subs) in &subcategory_of_design {
        assert_eq!(
            subs.len(),
            1,
            "identical {design:?} chairs share one subcategory: {chair:#?}"
        );
    }
    let firsts: BTreeSet<_> = subcategory_of_design.values().map(|s| s.first().copied()).collect();
    assert_eq!(
        firsts.len(),
        2,
        "the two designs are in different subcategories: {chair:#?}"
    );

    let mut report = Vec::new();
    let mut failures = Vec::new();
    for class in &records {
        for sub in &class.subcategories {
            let fractions: Vec<f32> = sub.members.iter().map(|m| observed[&m.id]).collect();
            let mut sorted = fractions.clone();
            sorted.sort_by(f32::total_cmp);
            let n = sorted.len();
            let median = 0.5 * (sorted[(n - 1) / 2] + sorted[n / 2]);
            // Measured, not asserted: the uncertainty ranking does not track the observed surface
            // fraction on this scene, not even after the full 15 000-step training (see the
            // category-registration issue's notes).
            println!(
                "representative {} observed {:.3}, subcategory median {median:.3} of {fractions:?}",
                sub.representative, observed[&sub.representative]
            );
            for m in &sub.members {
                let object = scene.object(m.id).expect("scene object");
                let local = object.design.mesh().bounds().expect("design bounds");
                let truth_centre = object.world_from_object * local.center();
                let h = Matrix4::from_fn(|r, c| m.world_from_nocs[r][c]);
                let linear = h.fixed_view::<3, 3>(0, 0).into_owned();
                let scale = linear.column(0).norm();
                let centre = Point3::new(h[(0, 3)], h[(1, 3)], h[(2, 3)]);
                let truth = object.world_from_object.rotation.to_rotation_matrix();
                let rotation_deg = match object.design {
                    // A solid of revolution about the vertical: its box's yaw is arbitrary.
                    Design::FloorLamp => tilt_error_deg(&(linear / scale), truth.matrix()),
                    _ => box_rotation_error_deg(&(linear / scale), truth.matrix()),
                };
                let centre_m = (centre - truth_centre).norm();
                report.push(format!(
                    "{} {:?}: {rotation_deg:.1}°, {:.1} cm",
                    m.id,
                    object.design,
                    centre_m * 100.0
                ));
                // Measured: the stool 3.4° / 0.6 cm and the lamp's tilt 2.6° / 3.7 cm (small,
                // round, thin); every other box within 1.0° / 1.2 cm. Bounds: those plus about
                // 0.5° / 0.5–0.8 cm.
                let (max_deg, max_m) = match object.design {
                    Design::Stool | Design::FloorLamp => (4.0, 0.045),
                    _ => (1.5, 0.015),
                };
                if centre_m >= max_m || rotation_deg >= max_deg {
                    failures.push(m.id);
                }
            }
        }
    }
    println!("{report:#?}");
    assert!(failures.is_empty(), "boxes off for {failures:?}: {report:#?}");
}
