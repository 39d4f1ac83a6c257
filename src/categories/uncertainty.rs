//! Ray-based uncertainty of an object's field and the representative of a class (METHOD.md §3).
//!
//! Rays start on a sphere around the object — centre = the centre of the observed cloud's
//! axis-aligned box ([`crate::geometry::mesh::Aabb`]), radius `r` = 1.2 × that box's half-diagonal (every
//! half-extent at least 5 cm) — at φ ∈ linspace(0, π, n) ×
//! θ ∈ linspace(0, 2π, n), and cross to the antipodal point with 96 stratified samples in [0, 2r].
//! Along a ray, with the reference code's sharper occupancy o_i = σ(10·α_i):
//!
//! ```text
//! w_i = o_i · ∏_{j<i} (1 − o_j + 1e-10)        H = −Σ w_i log(w_i + 1e-10)
//! u   = (Σ w_i) · exp(−0.5 · H)
//! g(u) = σ(−α_m (u − β_m)) + σ(α_M (u − β_M)),  α = 2 ln(κ/(1−κ)) / (b − a),  β = (a + b)/2
//! ```
//!
//! with κ = 0.9, m = (0.1, 0.15), M = (0.57, 0.65). A ray is reliable when 1 − g(u) < 0.5. The
//! representative of a class is the member with the most reliable rays.

use nalgebra::{Point3, Vector3};
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::ids::ObjectId;

/// Settings of the uncertainty sphere and the reliability function.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UncertaintyConfig {
    /// Samples of φ and of θ (n × n rays).
    pub angles: usize,
    /// Stratified samples per ray.
    pub samples_per_ray: usize,
    /// Sphere radius as a multiple of the box's half-diagonal.
    pub radius_factor: f32,
    /// Smallest half-extent used for the radius, metres.
    pub min_half_extent_m: f32,
    /// Occupancy is σ(sharpness · α) (the reference code: 10, on top of α = 10·raw).
    pub sharpness: f32,
    /// Weight of the entropy in u = (Σ w) · exp(−weight · H) (the paper's α).
    pub entropy_weight: f32,
    /// κ of the reliability sigmoids.
    pub kappa: f32,
    /// (a, b) of the low-uncertainty sigmoid.
    pub low: (f32, f32),
    /// (a, b) of the high-uncertainty sigmoid.
    pub high: (f32, f32),
    /// A ray is reliable when 1 − g(u) is below this.
    pub reliable_below: f32,
    /// What the sphere reads in space no view of the object observed
    /// ([`crate::objects::observed_space`]).
    pub unobserved: UnobservedSpace,
}

/// What the uncertainty sphere reads in space no view of the object observed (behind its
/// surface or another's in every view that says anything of it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum UnobservedSpace {
    /// The field's occupancy, as everywhere (the paper): a field extrapolates an object's
    /// interior into its never-seen side as a confident solid, which reads as certain.
    #[default]
    Field,
    /// Occupancy ½: rays into the never-seen side read as uncertain.
    Unknown,
}

impl Default for UncertaintyConfig {
    fn default() -> Self {
        Self {
            angles: 100,
            samples_per_ray: 96,
            radius_factor: 1.2,
            min_half_extent_m: 0.05,
            sharpness: 10.0,
            entropy_weight: 0.5,
            kappa: 0.9,
            low: (0.1, 0.15),
            high: (0.57, 0.65),
            reliable_below: 0.5,
            unobserved: UnobservedSpace::Field,
        }
    }
}

/// How a class's representative is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum RepresentativeChoice {
    /// The member with the most reliable rays (the paper).
    #[default]
    Uncertainty,
    /// A member drawn at random (the ablation; seeded).
    Random,
}

/// The rays of the uncertainty sphere: start points on the sphere and unit directions through
/// the centre; each ray spans `[0, 2·radius]`.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereRays {
    /// Ray start points (on the sphere).
    pub origins: Vec<Point3<f32>>,
    /// Unit directions (towards the centre).
    pub directions: Vec<Vector3<f32>>,
    /// Sphere radius, metres.
    pub radius: f32,
}

/// The rays around a box with `center` and `half_extents` (see the module doc).
pub fn sphere_rays(center: &Point3<f32>, half_extents: &Vector3<f32>, cfg: &UncertaintyConfig) -> SphereRays {
    let half = half_extents.map(|h| h.max(cfg.min_half_extent_m));
    let radius = cfg.radius_factor * half.norm();
    let n = cfg.angles.max(2);
    let (mut origins, mut directions) = (Vec::with_capacity(n * n), Vec::with_capacity(n * n));
    for i in 0..n {
        let phi = std::f32::consts::PI * i as f32 / (n - 1) as f32;
        for j in 0..n {
            let theta = std::f32::consts::TAU * j as f32 / (n - 1) as f32;
            let outward = Vector3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), phi.cos());
            origins.push(center + outward * radius);
            directions.push(-outward);
        }
    }
    SphereRays {
        origins,
        directions,
        radius,
    }
}

/// u of one ray from its samples' α (= 10·raw), nearest sample first.
pub fn ray_uncertainty(alpha: &[f32], cfg: &UncertaintyConfig) -> f32 {
    let (mut transmittance, mut weight_sum, mut entropy) = (1.0f32, 0.0f32, 0.0f32);
    for &a in alpha {
        let o = 1.0 / (1.0 + (-cfg.sharpness * a).exp());
        let w = o * transmittance;
        transmittance *= 1.0 - o + 1e-10;
        weight_sum += w;
        entropy -= w * (w + 1e-10).ln();
    }
    weight_sum * (-cfg.entropy_weight * entropy).exp()
}

/// g(u): high for confidently empty (u ≈ 0) and confidently hit (u ≈ 1) rays.
pub fn reliability(u: f32, cfg: &UncertaintyConfig) -> f32 {
    let slope = |(a, b): (f32, f32)| 2.0 * (cfg.kappa / (1.0 - cfg.kappa)).ln() / (b - a);
    let mid = |(a, b): (f32, f32)| 0.5 * (a + b);
    let sigmoid = |x: f32| 1.0 / (1.0 + (-x).exp());
    sigmoid(-slope(cfg.low) * (u - mid(cfg.low))) + sigmoid(slope(cfg.high) * (u - mid(cfg.high)))
}

/// An object's uncertainty sphere, evaluated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectReliability {
    /// The rays' start points (for display).
    pub sphere_points: Vec<Point3<f32>>,
    /// u per ray.
    pub uncertainty: Vec<f32>,
    /// g(u) per ray.
    pub reliability: Vec<f32>,
    /// Rays with 1 − g(u) below the threshold.
    pub reliable_rays: usize,
}

/// Evaluates the sphere around a box: `alpha_at` receives world points (one batch of rays at a
/// time) and returns α = 10·raw per point; depths are stratified with `rng`.
pub fn object_reliability(
    center: &Point3<f32>,
    half_extents: &Vector3<f32>,
    cfg: &UncertaintyConfig,
    rng: &mut impl Rng,
    mut alpha_at: impl FnMut(&[Point3<f32>]) -> Vec<f32>,
) -> ObjectReliability {
    let rays = sphere_rays(center, half_extents, cfg);
    let s = cfg.samples_per_ray.max(1);
    let step = 2.0 * rays.radius / s as f32;
    const RAYS_PER_BATCH: usize = 500;
    let mut uncertainty = Vec::with_capacity(rays.origins.len());
    let mut points = Vec::with_capacity(RAYS_PER_BATCH * s);
    for start in (0..rays.origins.len()).step_by(RAYS_PER_BATCH) {
        let end = (start + RAYS_PER_BATCH).min(rays.origins.len());
        points.clear();
        for r in start..end {
            for k in 0..s {
                let t = (k as f32 + rng.random::<f32>()) * step;
                points.push(rays.origins[r] + rays.directions[r] * t);
            }
        }
        let alpha = alpha_at(&points);
        uncertainty.extend(alpha.chunks(s).take(end - start).map(|a| ray_uncertainty(a, cfg)));
    }
    let reliability: Vec<f32> = uncertainty.iter().map(|&u| reliability(u, cfg)).collect();
    let reliable_rays = reliability.iter().filter(|&&g| 1.0 - g < cfg.reliable_below).count();
    ObjectReliability {
        sphere_points: rays.origins,
        uncertainty,
        reliability,
        reliable_rays,
    }
}

/// What an object's uncertainty sphere was evaluated on: its cloud's size (the sphere's box) and
/// its field's training steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct UncertaintyStamp {
    /// Points of the observed cloud.
    pub cloud_points: usize,
    /// Steps the object's field had taken.
    pub field_steps: u64,
}

impl UncertaintyStamp {
    /// Whether a sphere evaluated at `self` still describes the object at `now`: neither its
    /// cloud nor its field's steps grew by more than `growth` (a fraction) since.
    pub fn still_describes(&self, now: &UncertaintyStamp, growth: f32) -> bool {
        let within = |then: f64, now: f64| now <= then * (1.0 + f64::from(growth));
        within(self.cloud_points as f64, now.cloud_points as f64)
            && within(self.field_steps as f64, now.field_steps as f64)
            && now.cloud_points >= self.cloud_points
            && now.field_steps >= self.field_steps
    }
}

/// The representative among `(object, reliable rays)`: the most reliable rays (ties: the smaller
/// id), or a seeded random member for the ablation.
pub fn choose_representative(
    members: &[(ObjectId, usize)],
    choice: RepresentativeChoice,
    rng: &mut impl Rng,
) -> Option<ObjectId> {
    match choice {
        RepresentativeChoice::Uncertainty => members
            .iter()
            .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))
            .map(|m| m.0),
        RepresentativeChoice::Random => {
            let mut ids: Vec<ObjectId> = members.iter().map(|m| m.0).collect();
            ids.sort_unstable();
            (!ids.is_empty()).then(|| ids[rng.random_range(0..ids.len())])
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn a_sphere_is_evaluated_again_only_after_material_growth() {
        let then = UncertaintyStamp {
            cloud_points: 1_000,
            field_steps: 400,
        };
        let grown = |cloud_points, field_steps| UncertaintyStamp {
            cloud_points,
            field_steps,
        };
        assert!(then.still_describes(&then, 0.25));
        assert!(
            then.still_describes(&grown(1_250, 500), 0.25),
            "25 % is not more than 25 %"
        );
        assert!(!then.still_describes(&grown(1_251, 400), 0.25), "the cloud grew");
        assert!(!then.still_describes(&grown(1_000, 501), 0.25), "the field trained on");
        assert!(
            !then.still_describes(&grown(900, 400), 0.25),
            "a shrunk cloud is a change too"
        );
        assert!(then.still_describes(&then, 0.0), "nothing changed");
    }

    #[test]
    fn sphere_rays_start_on_the_sphere_and_aim_at_the_centre() {
        let cfg = UncertaintyConfig::default();
        let center = Point3::new(1.0, 2.0, 0.5);
        let rays = sphere_rays(&center, &Vector3::new(0.3, 0.4, 0.01), &cfg);
        assert_eq!(rays.origins.len(), 10_000);
        let want_radius = 1.2 * Vector3::new(0.3f32, 0.4, 0.05).norm();
        assert!(
            (rays.radius - want_radius).abs() < 1e-6,
            "half-extents are at least 5 cm"
        );
        for (o, d) in rays.origins.iter().zip(&rays.directions) {
            assert!(((o - center).norm() - rays.radius).abs() < 1e-4);
            assert!(
                (o + d * rays.radius - center).norm() < 1e-4,
                "the ray passes the centre"
            );
        }
    }

    #[test]
    fn empty_rays_and_sharp_hits_are_certain_and_a_soft_haze_is_not() {
        let cfg = UncertaintyConfig::default();
        let empty = vec![-5.0; 96];
        let mut hit = vec![-5.0; 96];
        hit[40..].fill(5.0);
        let haze = vec![-0.15; 96]; // o = σ(−1.5) ≈ 0.18 per sample: weight spread over several samples
        let (u_empty, u_hit, u_haze) = (
            ray_uncertainty(&empty, &cfg),
            ray_uncertainty(&hit, &cfg),
            ray_uncertainty(&haze, &cfg),
        );
        assert!(u_empty < 1e-3, "{u_empty}");
        assert!(u_hit > 0.99, "one sharp surface: Σw ≈ 1, H ≈ 0 → u ≈ 1, got {u_hit}");
        assert!((0.15..0.57).contains(&u_haze), "a diffuse ray is in between: {u_haze}");
        assert!(1.0 - reliability(u_empty, &cfg) < 0.5);
        assert!(1.0 - reliability(u_hit, &cfg) < 0.5);
        assert!(1.0 - reliability(u_haze, &cfg) >= 0.5);
        // g's sigmoids pass 0.9 and 0.1 at their interval ends (κ = 0.9).
        let slope = 2.0 * 9f32.ln() / 0.05;
        let low_at_a = 1.0 / (1.0 + (slope * (0.1 - 0.125)).exp());
        assert!((low_at_a - 0.9).abs() < 1e-4);
    }

    #[test]
    fn a_solid_ball_has_more_reliable_rays_than_a_hazy_one() {
        let cfg = UncertaintyConfig {
            angles: 20,
            ..UncertaintyConfig::default()
        };
        let center = Point3::new(0.0, 0.0, 1.0);
        let half = Vector3::new(0.2, 0.2, 0.2);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let solid = object_reliability(&center, &half, &cfg, &mut rng, |p| {
            p.iter()
                .map(|q| if (q - center).norm() < 0.2 { 5.0 } else { -5.0 })
                .collect()
        });
        let hazy = object_reliability(&center, &half, &cfg, &mut rng, |p| {
            p.iter()
                .map(|q| if (q - center).norm() < 0.2 { -0.15 } else { -5.0 })
                .collect()
        });
        assert_eq!(solid.reliable_rays, 400, "every ray is surely empty or surely hits");
        assert!(
            hazy.reliable_rays < solid.reliable_rays / 2,
            "{} reliable",
            hazy.reliable_rays
        );
    }

    #[test]
    fn the_representative_has_the_most_reliable_rays_or_is_drawn_at_random() {
        let members = [(ObjectId(4), 10), (ObjectId(2), 30), (ObjectId(9), 30)];
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        assert_eq!(
            choose_representative(&members, RepresentativeChoice::Uncertainty, &mut rng),
            Some(ObjectId(2)),
            "ties go to the smaller id"
        );
        let drawn: std::collections::BTreeSet<_> = (0..50)
            .filter_map(|_| choose_representative(&members, RepresentativeChoice::Random, &mut rng))
            .collect();
        assert_eq!(drawn.len(), 3, "random mode reaches every member");
        assert_eq!(
            choose_representative(&[], RepresentativeChoice::Uncertainty, &mut rng),
            None
        );
    }
}
