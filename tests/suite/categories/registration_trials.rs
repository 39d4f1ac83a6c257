//! Registration of partial, noisy, outlier-laden views of the synthetic designs to their full
//! surface: a trial passes when the rotation error is < 5° and the centre's translation error
//! < 3 cm, or — for symmetric designs — the aligned clean surface lies within 1 cm (mean) of the
//! true surface. The trials are deterministic, so each test names the trials that fail: the
//! free search passes 48 of 50, the search about up 49, the free search with its tilt removed
//! all 50 upright trials.

use catmap::registration::{RegistrationConfig, Rotations, Tilt, refine_registration, register_to_representative};
use catmap::synth::{Design, RegistrationTrial, RegistrationTrialSpec};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The designs of the category-registration issue's acceptance. The sofa, the bed and the
/// bookcase (issue 33's scenes) stand alone in their class in every preset, so no member is
/// registered to them; the bed, a large box seen from one side, fails 4 of 5 such trials.
const TRIAL_DESIGNS: [Design; 8] = [
    Design::LadderBackChair,
    Design::Armchair,
    Design::DiningTable,
    Design::Cabinet,
    Design::StorageBox,
    Design::FloorLamp,
    Design::Stool,
    Design::Nightstand,
];

#[test]
fn fifty_seeded_trials_register_within_five_degrees_and_three_centimetres() {
    let failures = failed_trials(
        &RegistrationTrialSpec::default(),
        &RegistrationConfig::default(),
        |_, _| {},
    );
    // Measured: a ladder-back chair 7.5° / 3.2 cm off, a stool 90.6° off (its aligned clouds
    // 1.65 and 1.45 cm apart).
    assert_eq!(seeds_of(&failures), [0, 38], "the failing trials: {failures:#?}");
}

#[test]
fn upright_trials_register_upright_within_five_degrees_and_three_centimetres() {
    // Furniture on a floor, turned about up only, registered over turns about up
    // (`categories.registration.rotations = "about_up"`): every estimate is upright, and the
    // trials pass as the free search's do.
    let spec = RegistrationTrialSpec {
        rotations: Rotations::AboutUp,
        ..RegistrationTrialSpec::default()
    };
    let cfg = RegistrationConfig {
        rotations: Rotations::AboutUp,
        ..RegistrationConfig::default()
    };
    let failures = failed_trials(&spec, &cfg, |seed, estimate| {
        let up = estimate.rotation * nalgebra::Vector3::z();
        assert!((up.z - 1.0).abs() < 1e-5, "seed {seed}: the estimate tilts ({up:?})");
    });
    // Measured: the dining table half a turn off (180°, its aligned cloud 1.31 cm apart).
    assert_eq!(seeds_of(&failures), [42], "the failing trials: {failures:#?}");
}

#[test]
fn a_free_search_with_its_tilt_removed_registers_upright_trials_upright() {
    // The default: rotations searched freely, a found tilt of 1–15° removed
    // (`categories.registration.tilt = "removed"`). Upright trials come out within 1° of upright
    // and pass as the others do; searched alone, some tilt by more.
    let spec = RegistrationTrialSpec {
        rotations: Rotations::AboutUp,
        ..RegistrationTrialSpec::default()
    };
    let removed = RegistrationConfig::default();
    assert_eq!((removed.rotations, removed.tilt), (Rotations::Any, Tilt::Removed));
    let tilt_deg = |estimate: &nalgebra::Isometry3<f32>| {
        (estimate.rotation * nalgebra::Vector3::z())
            .z
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    };
    let most_tilt = std::cell::Cell::new(0.0f32);
    let failures = failed_trials(&spec, &removed, |seed, estimate| {
        assert!(
            tilt_deg(estimate) < 1.0,
            "seed {seed}: the estimate tilts {}°",
            tilt_deg(estimate)
        );
    });
    assert!(failures.is_empty(), "every trial passes: {failures:#?}");
    let kept = RegistrationConfig {
        tilt: Tilt::Kept,
        ..RegistrationConfig::default()
    };
    failed_trials(&spec, &kept, |_, estimate| {
        most_tilt.set(most_tilt.get().max(tilt_deg(estimate)))
    });
    assert!(most_tilt.get() >= 1.0, "kept, the largest tilt is {}°", most_tilt.get());
}

/// The seeds of `failures` (each "seed N …").
fn seeds_of(failures: &[String]) -> Vec<u64> {
    failures
        .iter()
        .filter_map(|f| f.strip_prefix("seed ")?.split(' ').next()?.parse().ok())
        .collect()
}

/// The 50 seeded trials of `spec` (the designs in turn) registered with `cfg`, each estimate
/// shown to `check`: the trials whose rotation is 5° or more off or whose centre is 3 cm or
/// more off, unless the aligned clean surface lies within 1 cm of the template (a symmetric
/// design).
#[allow(clippy::print_stdout, reason = "the measured failures, shown with --nocapture")]
fn failed_trials(
    spec: &RegistrationTrialSpec,
    cfg: &RegistrationConfig,
    check: impl Fn(u64, &nalgebra::Isometry3<f32>),
) -> Vec<String> {
    let mut failures = Vec::new();
    for seed in 0..50u64 {
        let design = TRIAL_DESIGNS[seed as usize % TRIAL_DESIGNS.len()];
        let trial = RegistrationTrial::draw(design, spec, seed).expect("trial");
        let fit = register_to_representative(
            &trial.source,
            &trial.template,
            cfg,
            &mut ChaCha8Rng::seed_from_u64(seed),
        )
        .expect("registration");
        let estimate = fit.template_from_source();
        check(seed, &estimate);
        let (rotation_deg, translation_m) = trial.pose_error(&estimate);
        let cloud_m = trial.aligned_cloud_distance(&estimate).expect("distance");
        if !((rotation_deg < 5.0 && translation_m < 0.03) || cloud_m < 0.01) {
            failures.push(format!(
                "seed {seed} {}: {rotation_deg:.1}°, {:.1} cm, aligned cloud {:.2} cm",
                design.name(),
                translation_m * 100.0,
                cloud_m * 100.0
            ));
        }
    }
    println!("{} of 50 trials failed: {failures:#?}", failures.len());
    failures
}

#[test]
fn the_same_seed_gives_the_same_registration() {
    let trial = RegistrationTrial::draw(Design::Armchair, &RegistrationTrialSpec::default(), 7).unwrap();
    let cfg = RegistrationConfig::default();
    let run =
        || register_to_representative(&trial.source, &trial.template, &cfg, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
    let (a, b) = (run(), run());
    assert_eq!(a.rotation, b.rotation);
    assert_eq!(a.translation, b.translation);
    assert_eq!(a.score, b.score);
}

#[test]
fn degenerate_clouds_are_errors_not_panics() {
    let cfg = RegistrationConfig::default();
    let template = Design::Stool
        .mesh()
        .sample_surface(500, &mut ChaCha8Rng::seed_from_u64(0))
        .unwrap();
    let two = template[..2].to_vec();
    let err = register_to_representative(&two, &template, &cfg, &mut ChaCha8Rng::seed_from_u64(0)).unwrap_err();
    assert!(err.to_string().contains("source"), "{err}");
    let mut nan = template.clone();
    nan[3].x = f32::NAN;
    assert!(register_to_representative(&template, &nan, &cfg, &mut ChaCha8Rng::seed_from_u64(0)).is_err());
}

#[test]
fn a_warm_start_near_the_answer_refines_back_to_the_full_search() {
    let cfg = RegistrationConfig::default();
    for (seed, design) in [(3u64, Design::Armchair), (4, Design::Stool), (5, Design::DiningTable)] {
        let trial = RegistrationTrial::draw(design, &RegistrationTrialSpec::default(), seed).unwrap();
        let full = register_to_representative(
            &trial.source,
            &trial.template,
            &cfg,
            &mut ChaCha8Rng::seed_from_u64(seed),
        )
        .unwrap();
        // The previous registration of a smaller cloud: a few degrees and centimetres off.
        let nudge = nalgebra::Isometry3::new(
            nalgebra::Vector3::new(0.02, -0.01, 0.015),
            nalgebra::Vector3::new(0.0, 0.0, 4f32.to_radians()),
        );
        let warm = refine_registration(
            &trial.source,
            &trial.template,
            &(nudge * full.template_from_source()),
            &cfg,
        )
        .unwrap();
        assert!(
            warm.score <= full.score * 1.02 + 1e-4,
            "{}: warm {} vs full {}",
            design.name(),
            warm.score,
            full.score
        );
        let (rotation_deg, translation_m) = trial.pose_error(&warm.template_from_source());
        let cloud_m = trial.aligned_cloud_distance(&warm.template_from_source()).unwrap();
        assert!(
            (rotation_deg < 5.0 && translation_m < 0.03) || cloud_m < 0.01,
            "{}: {rotation_deg:.1}°, {translation_m:.3} m",
            design.name()
        );
    }
}

#[test]
fn a_warm_start_far_from_the_answer_scores_worse_than_the_search() {
    let cfg = RegistrationConfig::default();
    let trial = RegistrationTrial::draw(Design::Armchair, &RegistrationTrialSpec::default(), 11).unwrap();
    let full =
        register_to_representative(&trial.source, &trial.template, &cfg, &mut ChaCha8Rng::seed_from_u64(11)).unwrap();
    let turned = nalgebra::Isometry3::rotation(nalgebra::Vector3::new(0.0, 0.0, std::f32::consts::PI));
    let warm = refine_registration(
        &trial.source,
        &trial.template,
        &(turned * full.template_from_source()),
        &cfg,
    )
    .unwrap();
    assert!(
        warm.score > full.score * 1.1,
        "a half-turned start stays in its basin: warm {} vs full {}",
        warm.score,
        full.score
    );
}
