//! Ray-based uncertainty on a fixture field (the category-registration issue's acceptance): a
//! per-object field trained on a ball seen only from the −x side. Rays through the trained
//! surface are certain hits (high u, high g), rays through empty space certain misses (low u,
//! high g). Rays into the never-seen +x half should be uncertain (medium u, low g) but read as
//! certain hits: a known gap, asserted as it is so that its fix (the issue "Beyond the paper on
//! what no camera saw", point 5) shows here and turns the assertion round.

use catmap::categories::uncertainty::{UncertaintyConfig, ray_uncertainty, reliability};
use catmap::field::{AdamWConfig, FieldBatch, OBJECT_HIDDEN, OccupancyField, RaySamples};
use catmap::objects::object_view::PixelState;
use catmap::rng::{RngStream, seeded_rng, standard_normal_f32};
use nalgebra::{Point3, Vector3};
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

/// u and g of the ray from `origin` along `dir` over 2.4 m, evaluated like the uncertainty sphere.
fn ray_u_g(field: &OccupancyField, origin: Point3<f32>, dir: Vector3<f32>, cfg: &UncertaintyConfig) -> (f32, f32) {
    let s = cfg.samples_per_ray;
    let points: Vec<[f32; 3]> = (0..s)
        .map(|k| {
            let p = origin + dir * (2.4 * (k as f32 + 0.5) / s as f32);
            [p.x, p.y, p.z]
        })
        .collect();
    let u = ray_uncertainty(&field.eval_alpha(&points), cfg);
    (u, reliability(u, cfg))
}

#[test]
fn trained_surface_and_empty_space_are_certain_and_the_unseen_half_reads_certain_too_a_known_gap() {
    let mut rng = seeded_rng(3, RngStream::Mapper);
    let mut batch = FieldBatch::new(AdamWConfig::default());
    batch.push(OccupancyField::new(OBJECT_HIDDEN, 1.0, &mut rng));
    for _ in 0..750 {
        let rays = half_seen_rays(&mut rng, 240);
        batch.train_step(&[rays]).expect("valid rays");
    }
    let field = batch.field(0).expect("one field");
    let cfg = UncertaintyConfig::default();
    let mean = |rays: &[(Point3<f32>, Vector3<f32>)]| -> (f32, f32) {
        let v: Vec<(f32, f32)> = rays.iter().map(|(o, d)| ray_u_g(field, *o, *d, &cfg)).collect();
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
    let (u_seen, g_seen) = mean(&seen);
    let (u_empty, g_empty) = mean(&empty);
    let (u_unseen, g_unseen) = mean(&unseen);
    let report = format!(
        "seen u {u_seen:.3} g {g_seen:.3}; empty u {u_empty:.3} g {g_empty:.3}; unseen u {u_unseen:.3} g {g_unseen:.3}"
    );
    println!("{report}");
    assert!(u_seen > cfg.high.1 && g_seen > 0.5, "{report}");
    assert!(u_empty < cfg.low.0 && g_empty > 0.5, "{report}");
    // The known gap: the never-seen half should give medium u and low g, but the field
    // extrapolates the ball's interior into a confident solid, so rays into the unseen half look
    // like certain hits, as certain as the seen surface.
    assert!(
        u_unseen > cfg.high.1 && g_unseen > 0.5,
        "the known gap (the unseen half reads certain) has changed — if it is fixed, assert medium u and low g here: {report}"
    );
}
