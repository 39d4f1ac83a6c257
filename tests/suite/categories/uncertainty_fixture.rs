//! Ray-based uncertainty on a fixture field (the category-registration issue's acceptance): a
//! per-object field trained on a ball seen only from the −x side. Rays through the trained
//! surface are certain hits (high u, high g), rays through empty space certain misses (low u,
//! high g). Rays into the never-seen +x half should be uncertain (medium u, low g).
//!
//! Read as the paper reads it (the field's occupancy everywhere) they are certain hits: nothing
//! trains the field behind the seen surface, and it extends the ball's interior into the unseen
//! half as a confident solid — σ(10·α) with α = 10·raw turns any extrapolated raw value of a
//! few tenths into occupancy 0 or 1 — so the never-seen half looks as certain as the seen
//! surface. Read with [`UnobservedSpace::Unknown`], space that the views saw only behind the
//! ball's surface has occupancy ½, and those rays read as uncertain.

use catmap::FrameIndex;
use catmap::categories::uncertainty::{UncertaintyConfig, UnobservedSpace, ray_uncertainty, reliability};
use catmap::field::{AdamWConfig, FieldBatch, OBJECT_HIDDEN, OccupancyField, RaySamples};
use catmap::objects::object_view::{ObjectView, PixelState};
use catmap::objects::observed_space::ObservedSpace;
use catmap::rng::{RngStream, seeded_rng, standard_normal_f32};
use catmap::sensor::frame::CameraIntrinsics;
use catmap::sensor::pixel_box::PixelBox;
use catmap::synth::trajectory::look_rotation;
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

const RADIUS: f32 = 0.3;
const SAMPLES: usize = 10;

/// `count` training rays from origins 1.2 m from the ball's centre on the −x side only: 2 free
/// samples before the hit and 8 around it; rays that miss get 10 free samples.
fn half_seen_rays(rng: &mut ChaCha8Rng, count: usize) -> RaySamples {
    let mut out = RaySamples {
        samples_per_ray: SAMPLES,
        ..RaySamples::default()
    };
    for _ in 0..count {
        let origin = loop {
            let v = Vector3::from_fn(|_, _| rng.random_range(-1.0f32..1.0));
            if v.norm() > 0.1 && v.norm() <= 1.0 && v.x < -0.3 * v.norm() {
                break v.normalize() * 1.2;
            }
        };
        let target = Vector3::from_fn(|_, _| rng.random_range(-0.5f32..0.5));
        let dir = (target - origin).normalize();
        let (near, far) = (0.3, 2.2);
        let od = origin.dot(&dir);
        let disc = od * od - (origin.norm_squared() - RADIUS * RADIUS);
        let mut z: Vec<f32> = if disc > 0.0 {
            let hit = -od - disc.sqrt();
            out.depth_m.push(hit);
            out.states.push(PixelState::ThisObject);
            let mut z: Vec<f32> = (0..2).map(|_| rng.random_range(near..hit - 0.1)).collect();
            z.extend((0..8).map(|_| hit + (standard_normal_f32(rng) * 0.1 / 3.0).clamp(-0.1, 0.1)));
            z
        } else {
            out.depth_m.push(far);
            out.states.push(PixelState::OtherObject);
            (0..SAMPLES)
                .map(|i| near + (far - near) * (i as f32 + rng.random::<f32>()) / SAMPLES as f32)
                .collect()
        };
        z.sort_by(f32::total_cmp);
        for zi in z {
            let p = origin + dir * zi;
            out.points.push([p.x, p.y, p.z]);
            out.z.push(zi);
        }
        out.rgb.push([0.8, 0.3, 0.2]);
    }
    out
}

/// Views of the ball like the training rays': 64×64 crops from 1.2 m on the −x side, looking at
/// its centre from straight on and 0.6 rad to each side, above and below; pixels that miss it
/// see the background 2.2 m away.
fn half_seen_views() -> Vec<ObjectView> {
    let k = CameraIntrinsics {
        width: 64,
        height: 64,
        fx: 50.0,
        fy: 50.0,
        cx: 31.5,
        cy: 31.5,
    };
    let half_pi = std::f32::consts::FRAC_PI_2;
    [(0.0, 0.0), (0.6, 0.0), (-0.6, 0.0), (0.0, 0.6), (0.0, -0.6)]
        .iter()
        .enumerate()
        .map(|(i, &(yaw, pitch))| {
            let rotation = look_rotation(half_pi + yaw, pitch);
            let eye = -(rotation * Vector3::z()) * 1.2;
            let (mut depth_m, mut states) = (Vec::new(), Vec::new());
            for v in 0..k.height {
                for u in 0..k.width {
                    let d = rotation * k.ray_in_camera(u as f32, v as f32);
                    // |eye + t·d| = R: the nearer root, in units of camera depth.
                    let (a, b, c) = (d.norm_squared(), eye.dot(&d), eye.norm_squared() - RADIUS * RADIUS);
                    let disc = b * b - a * c;
                    if disc > 0.0 {
                        depth_m.push((-b - disc.sqrt()) / a);
                        states.push(PixelState::ThisObject);
                    } else {
                        depth_m.push(2.2);
                        states.push(PixelState::OtherObject);
                    }
                }
            }
            ObjectView {
                frame: FrameIndex(i as u64),
                world_from_camera: Isometry3::from_parts(Translation3::from(eye), rotation),
                intrinsics: k,
                region: PixelBox::whole_image(k.width, k.height),
                rgb: vec![[200, 80, 50]; depth_m.len()],
                depth_m,
                states,
                depth_noise_per_m2: 0.0,
                deepest_return_m: 2.2,
            }
        })
        .collect()
}

/// u and g of the ray from `origin` along `dir` over 2.4 m, evaluated like the uncertainty sphere
/// (with the unobserved space read as unknown when `observed` is given).
fn ray_u_g(
    field: &OccupancyField,
    observed: Option<&ObservedSpace>,
    origin: Point3<f32>,
    dir: Vector3<f32>,
    cfg: &UncertaintyConfig,
) -> (f32, f32) {
    let s = cfg.samples_per_ray;
    let points: Vec<Point3<f32>> = (0..s)
        .map(|k| origin + dir * (2.4 * (k as f32 + 0.5) / s as f32))
        .collect();
    let raw: Vec<[f32; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    let alpha = field.eval_alpha(&raw);
    let alpha = match observed {
        Some(space) => space.unknown_where_unobserved(&points, alpha),
        None => alpha,
    };
    let u = ray_uncertainty(&alpha, cfg);
    (u, reliability(u, cfg))
}

#[test]
fn the_unseen_half_reads_certain_from_the_field_and_uncertain_once_unobserved_space_is_unknown() {
    let mut rng = seeded_rng(3, RngStream::Mapper);
    let mut batch = FieldBatch::new(AdamWConfig::default());
    batch.push(OccupancyField::new(OBJECT_HIDDEN, 1.0, &mut rng));
    for _ in 0..750 {
        let rays = half_seen_rays(&mut rng, 240);
        batch.train_step(&[rays]).expect("valid rays");
    }
    let field = batch.field(0).expect("one field");
    let cfg = UncertaintyConfig::default();
    assert_eq!(cfg.unobserved, UnobservedSpace::Field, "the paper's reading by default");
    let views = half_seen_views();
    let view_refs: Vec<&ObjectView> = views.iter().collect();
    let space = ObservedSpace::of_views(&view_refs, &Point3::origin(), 1.2);
    let mean_in = |observed: Option<&ObservedSpace>, rays: &[(Point3<f32>, Vector3<f32>)]| -> (f32, f32) {
        let v: Vec<(f32, f32)> = rays
            .iter()
            .map(|(o, d)| ray_u_g(field, observed, *o, *d, &cfg))
            .collect();
        let n = v.len() as f32;
        (
            v.iter().map(|x| x.0).sum::<f32>() / n,
            v.iter().map(|x| x.1).sum::<f32>() / n,
        )
    };
    let offsets = [(0.0, 0.0), (0.1, 0.0), (0.0, 0.1), (-0.1, -0.05), (0.05, -0.1)];
    let seen: Vec<_> = offsets
        .iter()
        .map(|&(y, z)| (Point3::new(-1.2, y, z), Vector3::x()))
        .collect();
    let empty: Vec<_> = [(0.45, 0.0), (-0.45, 0.1), (0.0, 0.45), (0.3, -0.4)]
        .iter()
        .map(|&(y, z)| (Point3::new(-1.2, y, z), Vector3::x()))
        .collect();
    let unseen: Vec<_> = offsets
        .iter()
        .map(|&(y, z)| (Point3::new(1.2, y, z), -Vector3::x()))
        .collect();
    let mut report = String::new();
    let mut read = |name: &str, observed: Option<&ObservedSpace>| {
        let [seen, empty, unseen] = [&seen, &empty, &unseen].map(|rays| mean_in(observed, rays));
        report += &format!(
            "{name}: seen u {:.3} g {:.3}; empty u {:.3} g {:.3}; unseen u {:.3} g {:.3}\n",
            seen.0, seen.1, empty.0, empty.1, unseen.0, unseen.1
        );
        [seen, empty, unseen]
    };
    let [field_seen, field_empty, field_unseen] = read("field", None);
    let [seen, empty, unseen] = read("unobserved unknown", Some(&space));
    println!("{report}unobserved share of the cube {:.3}", space.unobserved_share());
    for (u, g) in [field_seen, seen] {
        assert!(
            u > cfg.high.1 && g > 0.5,
            "the seen surface is a certain hit:\n{report}"
        );
    }
    for (u, g) in [field_empty, empty] {
        assert!(u < cfg.low.0 && g > 0.5, "empty space is a certain miss:\n{report}");
    }
    // The field alone: the unseen half reads as certain as the seen surface.
    assert!(field_unseen.0 > cfg.high.1 && field_unseen.1 > 0.5, "{report}");
    // Unobserved space read as unknown: medium u, low g.
    let (u, g) = unseen;
    assert!(
        u > cfg.low.1 && u < cfg.high.0 && g < 0.5,
        "the unseen half reads uncertain:\n{report}"
    );
}
