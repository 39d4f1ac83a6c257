//! The fused category-field kernel against candle autograd (f64): losses, the gradient of every
//! network tensor and of every member's codes, for several category, member and ray counts;
//! bit-identical results across thread counts; and a short training run on two spheres.

use candle_core::DType;
use catmap::field::category::ShapeCodes;
use catmap::field::category::reference::category_reference;
use catmap::field::reference::worst_tensor_error;
use catmap::field::{AdamWConfig, Backend, CHUNK_SAMPLES, CategoryBatch, CategoryField, CategorySamples, RaySamples};
use catmap::ids::ObjectId;
use catmap::objects::object_view::PixelState;
use catmap::rng::{RngStream, seeded_rng};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// ‖a − b‖ / max(‖b‖, 1e-2·‖b_all‖): norm-relative error with a floor for near-cancelling tensors
/// (as `worst_tensor_error` measures a tensor; here for the members' codes).
fn relative_error(got: &[f32], want: &[f64], all_norm: f64) -> f64 {
    let diff = got
        .iter()
        .zip(want)
        .map(|(g, w)| (f64::from(*g) - w).powi(2))
        .sum::<f64>()
        .sqrt();
    let norm = want.iter().map(|w| w * w).sum::<f64>().sqrt();
    diff / norm.max(1e-2 * all_norm)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The field with its α head scaled down by 10 (see [`super::scale_tensors`]).
fn well_conditioned(mut field: CategoryField) -> CategoryField {
    let layout = field.layout();
    super::scale_tensors(field.params_mut(), &layout, &["sigma.weight", "sigma.bias"], 0.1);
    field
}

/// Categories with `members[c]` members each, code dimension `code_dim`, and random rays of
/// random members.
fn setup(
    seed: u64,
    members: &[usize],
    code_dim: usize,
    rays: usize,
    samples_per_ray: usize,
    backend: Backend,
) -> (CategoryBatch, Vec<CategorySamples>) {
    let mut batch = CategoryBatch::with_backend(AdamWConfig::default(), backend);
    let mut samples = Vec::new();
    for (c, &m) in members.iter().enumerate() {
        let mut rng = seeded_rng(seed, RngStream::Object(ObjectId(c as u32)));
        batch.push(well_conditioned(CategoryField::new(32, code_dim, 1.0, m, &mut rng)));
        let rays = RaySamples::random(&mut rng, rays, samples_per_ray, 0.8, 0.15);
        let members = (0..rays.num_rays()).map(|_| rng.random_range(0..m)).collect();
        samples.push(CategorySamples { rays, members });
    }
    (batch, samples)
}

fn check_against_candle(seed: u64, members: &[usize], code_dim: usize, rays: usize, spr: usize, backend: Backend) {
    let (mut batch, samples) = setup(seed, members, code_dim, rays, spr, backend);
    check_samples_against_candle(&mut batch, &samples, backend);
}

/// The fused step's losses and gradients (weights and codes) on `samples` against candle's.
fn check_samples_against_candle(batch: &mut CategoryBatch, samples: &[CategorySamples], backend: Backend) {
    let (losses, grads) = batch.loss_and_gradients(samples).expect("shapes agree");
    for (c, field) in batch.fields().iter().enumerate() {
        let reference = category_reference(field, &samples[c], DType::F64).expect("candle runs");
        let l = losses[c];
        let close = |a: f32, b: f64| (f64::from(a) - b).abs() <= 1e-4 * b.abs().max(1e-2);
        assert!(
            close(l.total, reference.total) && close(l.code_reg, reference.code_reg),
            "category {c}: total {} (reg {}) vs candle {} (reg {})",
            l.total,
            l.code_reg,
            reference.total,
            reference.code_reg
        );
        let f = l.field;
        assert!(
            close(f.depth, reference.depth) && close(f.colour, reference.colour) && close(f.opacity, reference.opacity),
            "category {c}: loss terms {f:?} vs {reference:?}"
        );
        let (worst, tensor) = worst_tensor_error(&field.layout(), &grads[c].weights, &reference.grad);
        assert!(
            worst <= 1e-4,
            "{backend:?} category {c}: gradient of {tensor} off by {worst:.2e}"
        );
        let all_codes: Vec<f64> = reference.code_grads.concat();
        for (m, want) in reference.code_grads.iter().enumerate() {
            let rel = relative_error(&grads[c].codes[m], want, norm(&all_codes));
            if std::env::var("FIELD_DEBUG").is_ok() {
                eprintln!("{} category {c} member {m:>2} codes: rel {rel:.2e}", backend.name());
            }
            assert!(
                rel <= 1e-4,
                "{backend:?} category {c}: gradient of member {m}'s codes off by {rel:.2e}"
            );
        }
    }
}

#[test]
fn rays_of_other_objects_last_skip_the_colour_branch_and_keep_the_gradients() {
    // Each member's rays as the sampler orders them (its own first), members one after the
    // other: chunks end in rays whose colour branch the step skips.
    for backend in [Backend::detect(), Backend::Scalar] {
        let (mut batch, samples) = setup(7, &[3, 2], 8, 40, 10, backend);
        let ordered: Vec<CategorySamples> = samples
            .into_iter()
            .map(|s| {
                let mut members = s.members.clone();
                let rays = s.rays.with_colour_rays_first();
                members.sort_unstable();
                CategorySamples { rays, members }
            })
            .collect();
        for (c, s) in ordered.iter().enumerate() {
            assert!(s.members.is_sorted(), "category {c}: members one after the other");
            let reads: Vec<bool> = s.rays.states.iter().map(|p| p.reads_colour()).collect();
            assert!(reads.is_sorted_by_key(|r| !r), "category {c}: colour rays first");
            // The step's chunks (`CHUNK_SAMPLES` samples each): one runs the colour branch on a
            // prefix and skips it on the rest, one skips it throughout.
            let chunks: Vec<(usize, usize)> = reads
                .chunks(CHUNK_SAMPLES / s.rays.samples_per_ray)
                .map(|chunk| (chunk.iter().filter(|r| **r).count(), chunk.len()))
                .collect();
            assert!(
                chunks.iter().any(|&(colour, len)| colour > 0 && colour < len),
                "category {c}: a chunk ends in rays whose colour branch is skipped: {chunks:?}"
            );
            assert!(
                chunks.iter().any(|&(colour, _)| colour == 0),
                "category {c}: a chunk skips the colour branch throughout: {chunks:?}"
            );
        }
        check_samples_against_candle(&mut batch, &ordered, backend);
    }
}

#[test]
fn one_category_of_two_members_matches_candle_autograd() {
    check_against_candle(1, &[2], 32, 24, 10, Backend::detect());
}

#[test]
fn several_categories_and_member_counts_match_candle_autograd() {
    // 1, 3 and 4 members; 37 rays of 7 samples (chunks not filled), small codes.
    check_against_candle(2, &[1, 3, 4], 8, 37, 7, Backend::detect());
}

#[test]
fn many_rays_split_into_several_tasks_match_candle_autograd() {
    // 300 rays × 10 samples × 18k parameters: four tasks, reduced in order.
    check_against_candle(3, &[3, 2], 32, 300, 10, Backend::detect());
}

#[test]
fn every_simd_backend_matches_candle_autograd() {
    let backends = Backend::all_available();
    println!("SIMD paths run: {}", Backend::describe_all(&backends));
    for backend in backends {
        check_against_candle(4, &[2, 3], 16, 13, 10, backend);
    }
}

#[test]
fn results_are_bit_identical_for_any_thread_count() {
    let run = |threads: usize| {
        super::on_threads(threads, || {
            let (mut batch, samples) = setup(5, &[3, 2, 4], 32, 200, 10, Backend::detect());
            let losses: Vec<f32> = (0..3)
                .flat_map(|_| batch.train_step(&samples).expect("shapes agree"))
                .map(|l| l.total)
                .collect();
            let state: Vec<(Vec<f32>, Vec<Vec<f32>>)> = batch
                .fields()
                .iter()
                .map(|f| {
                    let codes = (0..f.num_members())
                        .map(|m| f.code(m).expect("member").to_vec())
                        .collect();
                    (f.params().to_vec(), codes)
                })
                .collect();
            (losses, state)
        })
    };
    assert_eq!(
        run(1),
        run(2),
        "1 and 2 threads give the same losses, weights and codes"
    );
}

#[test]
fn one_adamw_step_moves_weights_and_codes_by_the_hand_computed_update() {
    let (mut batch, samples) = setup(9, &[3], 16, 30, 10, Backend::detect());
    let (_, grads) = batch.loss_and_gradients(&samples).expect("shapes agree");
    let field = &batch.fields()[0];
    let before: Vec<f32> = (0..3).flat_map(|m| field.code(m).expect("member").to_vec()).collect();
    let before_weights = field.params().to_vec();
    batch.train_step(&samples).expect("shapes agree");
    let field = &batch.fields()[0];
    let after: Vec<f32> = (0..3).flat_map(|m| field.code(m).expect("member").to_vec()).collect();
    let cfg = AdamWConfig::default();
    let check = |p0: &[f32], p1: &[f32], g: &[f32], what: &str| {
        for ((p0, p1), g) in p0.iter().zip(p1).zip(g) {
            // First AdamW step: p ← p·(1 − lr·wd) − lr·g / (|g| + ε).
            let (p0, g) = (f64::from(*p0), f64::from(*g));
            let want = p0 * (1.0 - f64::from(cfg.lr * cfg.weight_decay))
                - f64::from(cfg.lr) * g / (g.abs() + f64::from(cfg.eps));
            assert!(
                (f64::from(*p1) - want).abs() < 2e-7 * (1.0 + p0.abs()),
                "{what}: {p1} vs {want}"
            );
        }
    };
    check(&before_weights, field.params(), &grads[0].weights, "weights");
    check(&before, &after, &grads[0].codes.concat(), "codes");
}

#[test]
fn adding_a_member_keeps_the_other_members_optimiser_states() {
    let (mut batch, mut samples) = setup(6, &[2], 16, 20, 10, Backend::detect());
    batch.train_step(&samples).expect("shapes agree");
    let before = batch.fields()[0].code_optimiser_state(1).expect("member 1").clone();
    let mut rng = seeded_rng(6, RngStream::Mapper);
    let new = batch.field_mut(0).expect("category 0").add_member(&mut rng);
    assert_eq!(new, 2);
    assert_eq!(
        batch.fields()[0].code_optimiser_state(1),
        Some(&before),
        "member 1 untouched"
    );
    samples[0].members[0] = new;
    batch.train_step(&samples).expect("shapes agree");
    let field = &batch.fields()[0];
    assert_eq!(field.code_optimiser_state(1).map(|s| s.step), Some(2));
    assert_eq!(field.code_optimiser_state(2).map(|s| s.step), Some(1));
    assert_eq!(field.optimiser_state().step, 2);
}

/// Rays from a sphere of radius 2.5 at a sphere of radius `radius` around the origin (NOCS):
/// hits get 2 free-space samples and 8 around the surface (vMAP-style, σ = 0.1/3), misses 10
/// stratified samples through the unit cube; colour `rgb`.
fn sphere_rays(rng: &mut ChaCha8Rng, radius: f32, rgb: [f32; 3], rays: usize, out: &mut RaySamples) {
    out.samples_per_ray = 10;
    for _ in 0..rays {
        let unit = |rng: &mut ChaCha8Rng| loop {
            let v: [f32; 3] = std::array::from_fn(|_| rng.random_range(-1.0f32..1.0));
            let n = v.iter().map(|x| x * x).sum::<f32>().sqrt();
            if n > 0.1 && n <= 1.0 {
                break v.map(|x| x / n);
            }
        };
        let origin = unit(rng).map(|x| 2.5 * x);
        let target: [f32; 3] = std::array::from_fn(|_| rng.random_range(-0.75f32..0.75));
        let len = (0..3).map(|c| (target[c] - origin[c]).powi(2)).sum::<f32>().sqrt();
        let dir: [f32; 3] = std::array::from_fn(|c| (target[c] - origin[c]) / len);
        // |o + t d|² = r²  →  t² + 2 (o·d) t + |o|² − r² = 0.
        let od: f32 = (0..3).map(|c| origin[c] * dir[c]).sum();
        let disc = od * od - (6.25 - radius * radius);
        let (near, far) = (2.5 - 1.75, 2.5 + 1.75);
        let mut z: Vec<f32> = if disc > 0.0 {
            let hit = -od - disc.sqrt();
            out.depth_m.push(hit);
            out.states.push(PixelState::ThisObject);
            let mut z: Vec<f32> = (0..2).map(|_| rng.random_range(near..hit - 0.1)).collect();
            z.extend((0..8).map(|_| {
                let g = (-2.0 * (1.0 - rng.random::<f32>()).ln()).sqrt()
                    * (std::f32::consts::TAU * rng.random::<f32>()).cos();
                hit + (g * 0.1 / 3.0).clamp(-0.1, 0.1)
            }));
            z
        } else {
            out.depth_m.push(far);
            out.states.push(PixelState::OtherObject);
            (0..10)
                .map(|i| near + (far - near) * (i as f32 + rng.random::<f32>()) / 10.0)
                .collect()
        };
        z.sort_by(f32::total_cmp);
        for zi in z {
            out.points.push(std::array::from_fn(|c| origin[c] + zi * dir[c]));
            out.z.push(zi);
        }
        out.rgb.push(rgb);
    }
}

#[test]
fn two_spheres_train_into_two_shapes_of_one_category() {
    let (small, large) = (0.45f32, 0.6f32);
    let mut rng = seeded_rng(7, RngStream::Mapper);
    let mut batch = CategoryBatch::new(AdamWConfig::default());
    batch.push(CategoryField::new(32, 32, 1.0, 2, &mut rng));
    let mut totals = Vec::new();
    for _ in 0..400 {
        let mut s = CategorySamples::default();
        sphere_rays(&mut rng, small, [0.9, 0.1, 0.1], 120, &mut s.rays);
        s.members.extend([0; 120]);
        sphere_rays(&mut rng, large, [0.1, 0.9, 0.1], 120, &mut s.rays);
        s.members.extend([1; 120]);
        totals.push(batch.train_step(&[s]).expect("valid samples")[0].total);
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    let (first, last) = (mean(&totals[..20]), mean(&totals[totals.len() - 20..]));
    assert!(last < 0.5 * first, "loss falls: first 20 steps {first}, last 20 {last}");

    let field = &batch.fields()[0];
    let shell = |r: f32| -> Vec<[f32; 3]> {
        let mut dirs = seeded_rng(8, RngStream::Mapper);
        (0..200)
            .map(|_| {
                let v: [f32; 3] = std::array::from_fn(|_| dirs.random_range(-1.0f32..1.0));
                let n = v.iter().map(|x| x * x).sum::<f32>().sqrt().max(1e-3);
                v.map(|x| r * x / n)
            })
            .collect()
    };
    let occ = |member: usize, r: f32| mean(&field.eval_occupancy(member, &shell(r)).expect("member exists"));
    let between = (small + large) / 2.0;
    let (o_small, o_large) = (occ(0, between), occ(1, between));
    assert!(
        o_large > 0.5 && o_small < 0.5 && o_large - o_small > 0.3,
        "at r = {between} the larger sphere is occupied ({o_large}) and the smaller is not ({o_small})"
    );
    // Only the first surface along each ray is observed, so the interior may stay empty (a shell).
    for (member, r) in [small, large].into_iter().enumerate() {
        assert!(
            occ(member, r - 0.05) > 0.5,
            "member {member} is occupied just inside its surface"
        );
        assert!(occ(member, 0.8) < 0.5, "member {member} is empty outside r = 0.8");
    }
    let colour = field.eval(1, &shell(0.6)).expect("member exists").colour;
    let green = mean(&colour.iter().map(|c| c[1] - c[0]).collect::<Vec<_>>());
    assert!(green > 0.2, "the larger sphere is green at its surface ({green})");
}

#[test]
fn members_of_a_field_with_one_shape_draw_one_shape_in_their_own_colours() {
    let mut rng = seeded_rng(7, RngStream::Mapper);
    let mut batch = CategoryBatch::new(AdamWConfig::default());
    batch.push(CategoryField::new(32, 32, 1.0, 2, &mut rng).with_shape_codes(ShapeCodes::Shared));
    for _ in 0..300 {
        let mut s = CategorySamples::default();
        sphere_rays(&mut rng, 0.5, [0.9, 0.1, 0.1], 120, &mut s.rays);
        s.members.extend([0; 120]);
        sphere_rays(&mut rng, 0.5, [0.1, 0.9, 0.1], 120, &mut s.rays);
        s.members.extend([1; 120]);
        batch.train_step(&[s]).expect("valid samples");
    }
    let field = &batch.fields()[0];
    for member in 0..2 {
        let code = field.shape_code(member).expect("member exists");
        assert!(
            code.iter().all(|&z| z == 0.0),
            "member {member}'s shape code stays zero"
        );
    }
    let mut dirs = seeded_rng(8, RngStream::Mapper);
    let points: Vec<[f32; 3]> = (0..300)
        .map(|i| {
            let v: [f32; 3] = std::array::from_fn(|_| dirs.random_range(-1.0f32..1.0));
            let n = v.iter().map(|x| x * x).sum::<f32>().sqrt().max(1e-3);
            let r = 0.3 + 0.5 * (i % 3) as f32 / 2.0;
            v.map(|x| r * x / n)
        })
        .collect();
    let (first, second) = (
        field.eval_occupancy(0, &points).expect("member 0"),
        field.eval_occupancy(1, &points).expect("member 1"),
    );
    assert_eq!(first, second, "one shape for both members");
    assert!(
        first.iter().any(|&o| o > 0.5) && first.iter().any(|&o| o < 0.5),
        "a surface between"
    );
    let surface: Vec<[f32; 3]> = points.iter().step_by(3).map(|p| p.map(|x| x * 0.5 / 0.3)).collect();
    let green = |member: usize| {
        let colour = field.eval(member, &surface).expect("member exists").colour;
        colour.iter().map(|c| c[1] - c[0]).sum::<f32>() / colour.len() as f32
    };
    assert!(
        green(1) > 0.2 && green(0) < -0.2,
        "each member keeps its colour: green − red {} and {}",
        green(0),
        green(1)
    );
}

#[test]
fn a_scaled_category_step_trains_each_category_at_its_own_learning_rate() {
    let backend = Backend::detect();
    let (mut scaled, samples) = setup(5, &[2, 3], 8, 24, 6, backend);
    let (base, _) = setup(5, &[2, 3], 8, 24, 6, backend);
    scaled
        .train_step_scaled(&[0, 1], &[0.3, 1.0], &samples)
        .expect("valid step");
    let mut slowed = CategoryBatch::with_backend(
        AdamWConfig {
            lr: AdamWConfig::default().lr * 0.3,
            ..AdamWConfig::default()
        },
        backend,
    );
    let mut full = CategoryBatch::with_backend(AdamWConfig::default(), backend);
    for field in base.fields() {
        slowed.push(field.clone());
        full.push(field.clone());
    }
    slowed.train_step(&samples).expect("valid step");
    full.train_step(&samples).expect("valid step");
    assert_eq!(
        scaled.fields()[0],
        slowed.fields()[0],
        "category 0 (weights and codes) at 0.3 × the rate"
    );
    assert_eq!(scaled.fields()[1], full.fields()[1], "category 1 at the full rate");
    assert_ne!(scaled.fields()[0], full.fields()[0]);
    let err = scaled
        .train_step_scaled(&[0, 1], &[1.0], &samples)
        .expect_err("one scale for two categories");
    assert!(err.to_string().contains("scale"), "{err}");
}
