//! The fused field kernels against candle autograd (f64) on random batches: forward (renders,
//! losses), every parameter's gradient (the trainable encoding matrix B included), one AdamW
//! step against a hand-computed update, and bit-identical results across thread counts.

use candle_core::DType;
use catmap::field::reference::{occupancy_reference, worst_tensor_error};
use catmap::field::{AdamWConfig, Backend, FieldBatch, OccupancyField, RaySamples};
use catmap::ids::ObjectId;
use catmap::objects::object_view::PixelState;
use catmap::rng::{RngStream, seeded_rng};

/// The field with its α head scaled down by 10 (see [`super::scale_tensors`]).
fn well_conditioned(mut field: OccupancyField) -> OccupancyField {
    let layout = field.layout();
    super::scale_tensors(
        field.params_mut(),
        &layout,
        &["out_alpha.weight", "out_alpha.bias"],
        0.1,
    );
    field
}

/// Builds a batch of fields with the given hidden widths and random rays.
fn setup(
    seed: u64,
    hidden: &[usize],
    rays: usize,
    samples_per_ray: usize,
    backend: Backend,
) -> (FieldBatch, Vec<RaySamples>) {
    let mut batch = FieldBatch::with_backend(AdamWConfig::default(), backend);
    let mut samples = Vec::<RaySamples>::new();
    for (i, &h) in hidden.iter().enumerate() {
        let mut rng = seeded_rng(seed, RngStream::Object(ObjectId(i as u32)));
        let scale = if h >= 128 { 5.0 } else { 2.0 };
        batch.push(well_conditioned(OccupancyField::new(h, scale, &mut rng)));
        samples.push(RaySamples::random(&mut rng, rays, samples_per_ray, 1.5, 0.15));
    }
    (batch, samples)
}

fn check_against_candle(seed: u64, hidden: &[usize], rays: usize, samples_per_ray: usize, backend: Backend) {
    let (mut batch, samples) = setup(seed, hidden, rays, samples_per_ray, backend);
    check_samples_against_candle(&mut batch, &samples, backend);
}

/// The fused step's losses and gradients on `samples` against candle's.
fn check_samples_against_candle(batch: &mut FieldBatch, samples: &[RaySamples], backend: Backend) {
    let (losses, grads) = batch.loss_and_gradients(samples).expect("shapes agree");
    for (f, field) in batch.fields().iter().enumerate() {
        let reference = occupancy_reference(field.hidden(), field.scale(), field.params(), &samples[f], DType::F64)
            .expect("candle runs");
        let l = losses[f];
        let close = |a: f32, b: f64| (f64::from(a) - b).abs() <= 1e-4 * b.abs().max(1e-2);
        assert!(
            close(l.total, reference.total),
            "field {f}: total loss {} vs candle {}",
            l.total,
            reference.total
        );
        assert!(
            close(l.depth, reference.depth)
                && close(l.colour, reference.colour)
                && close(l.opacity, reference.opacity)
                && close(l.solid, reference.solid),
            "field {f}: loss terms {l:?} vs {reference:?}"
        );
        let (rel, name) = worst_tensor_error(&field.layout(), &grads[f], &reference.grad);
        assert!(
            rel <= 1e-4,
            "{backend:?} H = {}: gradient of {name} off by {rel:.2e} (norm-relative)",
            field.hidden()
        );
    }
}

#[test]
fn object_field_gradients_match_candle_autograd() {
    check_against_candle(1, &[32, 32, 32], 24, 10, Backend::detect());
}

#[test]
fn rays_of_other_objects_last_skip_the_colour_branch_and_keep_the_gradients() {
    // As the sampler orders them: chunks end in (or are all) rays whose colour is not read,
    // whose colour branch the step skips.
    for backend in [Backend::detect(), Backend::Scalar] {
        let (mut batch, samples) = setup(6, &[32, 32], 40, 10, backend);
        let ordered: Vec<RaySamples> = samples.into_iter().map(RaySamples::with_colour_rays_first).collect();
        let others = |s: &RaySamples| {
            s.states
                .iter()
                .rev()
                .take_while(|s| **s == PixelState::OtherObject)
                .count()
        };
        assert!(
            ordered.iter().all(|s| others(s) >= 12),
            "a whole chunk of other rays at the end"
        );
        check_samples_against_candle(&mut batch, &ordered, backend);
    }
}

#[test]
fn prior_rays_of_the_solid_support_and_seen_free_priors_match_candle_autograd() {
    // The step's rays as the sampler returns them with priors: pixel rays, then rays whose
    // samples are asked to be solid (hidden cells) or empty (under the box, around cells seen
    // free), weighted 0.7.
    for backend in [Backend::detect(), Backend::Scalar] {
        let (mut batch, samples) = setup(7, &[32, 32], 30, 10, backend);
        let with_priors: Vec<RaySamples> = samples
            .into_iter()
            .map(|mut s| {
                let n = s.num_rays();
                for (r, state) in s.states.iter_mut().enumerate().skip(n - 12) {
                    *state = match r % 3 {
                        0 => PixelState::BelowSupport,
                        1 => PixelState::SeenFree,
                        _ => PixelState::HiddenSolid,
                    };
                }
                s.depth_m[n - 12..].fill(0.0);
                s.solid_weight = 0.7;
                s.with_colour_rays_first()
            })
            .collect();
        check_samples_against_candle(&mut batch, &with_priors, backend);
        let (losses, _) = batch.loss_and_gradients(&with_priors).expect("shapes agree");
        assert!(
            losses.iter().all(|l| l.solid > 0.0),
            "the prior's term counts: {losses:?}"
        );
    }
}

#[test]
fn background_field_gradients_match_candle_autograd() {
    check_against_candle(2, &[128], 18, 14, Backend::detect());
}

#[test]
fn mixed_widths_and_odd_sizes_match_candle_autograd() {
    // H = 16 and 48 (not multiples of 32), 7 samples per ray, rays not filling whole chunks.
    check_against_candle(3, &[16, 48, 32], 37, 7, Backend::detect());
}

#[test]
fn every_simd_backend_matches_candle_autograd() {
    let backends = Backend::all_available();
    println!("SIMD paths run: {}", Backend::describe_all(&backends));
    for backend in backends {
        check_against_candle(4, &[32, 128], 13, 10, backend);
    }
}

#[test]
fn forward_renders_match_candle() {
    let (batch, samples) = setup(5, &[32], 40, 10, Backend::detect());
    let field = &batch.fields()[0];
    let renders = field.render_rays(&samples[0]).expect("valid rays");
    let reference = occupancy_reference(32, 2.0, field.params(), &samples[0], DType::F64).expect("candle runs");
    for (r, got) in renders.iter().enumerate() {
        let close = |a: f32, b: f64| (f64::from(a) - b).abs() < 1e-5 * b.abs().max(1.0);
        assert!(
            close(got.depth, reference.rendered_depth[r]),
            "ray {r} depth {} vs {}",
            got.depth,
            reference.rendered_depth[r]
        );
        assert!(close(got.opacity, reference.rendered_opacity[r]), "ray {r} opacity");
        for c in 0..3 {
            assert!(
                close(got.colour[c], reference.rendered_colour[r][c]),
                "ray {r} colour {c}"
            );
        }
    }
}

#[test]
fn one_adamw_step_matches_the_hand_computed_update() {
    let (mut batch, samples) = setup(6, &[32, 128], 12, 10, Backend::detect());
    let (_, grads) = batch.loss_and_gradients(&samples).expect("shapes agree");
    let before: Vec<Vec<f32>> = batch.fields().iter().map(|f| f.params().to_vec()).collect();
    batch.train_step(&samples).expect("shapes agree");
    let cfg = AdamWConfig::default();
    for (f, field) in batch.fields().iter().enumerate() {
        for ((p1, p0), g) in field.params().iter().zip(&before[f]).zip(&grads[f]) {
            // First AdamW step: m̂ = g, v̂ = g², so p ← p·(1 − lr·wd) − lr·g / (|g| + ε).
            let (p0, g) = (f64::from(*p0), f64::from(*g));
            let want = p0 * (1.0 - f64::from(cfg.lr * cfg.weight_decay))
                - f64::from(cfg.lr) * g / (g.abs() + f64::from(cfg.eps));
            assert!(
                (f64::from(*p1) - want).abs() < 2e-7 * (1.0 + p0.abs()),
                "field {f}: {p1} vs {want}"
            );
        }
        assert_eq!(field.optimiser_state().step, 1, "each field counts its own steps");
    }
}

#[test]
fn adding_a_field_keeps_the_others_optimiser_state() {
    let (mut batch, mut samples) = setup(7, &[32], 8, 10, Backend::detect());
    batch.train_step(&samples).expect("shapes agree");
    let moments = batch.fields()[0].optimiser_state().clone();
    let mut rng = seeded_rng(7, RngStream::Object(ObjectId(99)));
    batch.push(OccupancyField::new(32, 2.0, &mut rng));
    samples.push(RaySamples::random(&mut rng, 8, 10, 1.5, 0.15));
    assert_eq!(
        batch.fields()[0].optimiser_state(),
        &moments,
        "pushing a field leaves field 0 untouched"
    );
    batch.train_step(&samples).expect("shapes agree");
    assert_eq!(batch.fields()[0].optimiser_state().step, 2);
    assert_eq!(batch.fields()[1].optimiser_state().step, 1);
}

#[test]
fn results_are_bit_identical_for_any_thread_count() {
    let run = |threads: usize| {
        super::on_threads(threads, || {
            let (mut batch, samples) = setup(8, &[32, 32, 128], 30, 10, Backend::detect());
            for _ in 0..3 {
                batch.train_step(&samples).expect("shapes agree");
            }
            batch.fields().iter().map(|f| f.params().to_vec()).collect::<Vec<_>>()
        })
    };
    assert_eq!(run(1), run(2), "1 and 2 threads give the same parameters");
    assert_eq!(run(2), run(3), "2 and 3 threads give the same parameters");
}
