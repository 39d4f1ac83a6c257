use super::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn brute_force(tris: &[[Point3<f32>; 3]], ray: &Ray) -> Option<Hit> {
    let (o, d) = (ray.origin.coords, ray.direction);
    tris.iter()
        .enumerate()
        .filter_map(|(i, tri)| {
            PreparedTriangle::new(*tri)
                .intersect(&o, &d, f32::INFINITY)
                .map(|t| (t, i))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(t, i)| Hit { t, triangle: i as u32 })
}

#[test]
fn ray_hits_triangle_at_expected_distance_from_either_side() {
    let tri = PreparedTriangle::new([[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.0]].map(Point3::from));
    let origin = Vector3::new(0.2, 0.2, 0.0);
    // Unnormalised direction: t is in units of the direction (here z = 1, so t = depth).
    assert_eq!(
        tri.intersect(&origin, &Vector3::new(0.0, 0.0, 1.0), f32::INFINITY),
        Some(2.0)
    );
    let behind = Vector3::new(0.2, 0.2, 4.0);
    assert_eq!(
        tri.intersect(&behind, &Vector3::new(0.0, 0.0, -2.0), f32::INFINITY),
        Some(1.0)
    );
    assert_eq!(
        tri.intersect(&Vector3::new(0.8, 0.8, 0.0), &Vector3::z(), f32::INFINITY),
        None,
        "outside"
    );
    assert_eq!(tri.intersect(&origin, &Vector3::z(), 1.5), None, "beyond t_max");
    assert_eq!(tri.intersect(&origin, &Vector3::x(), f32::INFINITY), None, "parallel");
}

#[test]
fn bvh_agrees_with_brute_force_on_random_rays() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut p = |s: f32| {
        Point3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    };
    let tris: Vec<[Point3<f32>; 3]> = (0..500)
        .map(|_| {
            let c = p(2.0);
            [c + p(0.3).coords, c + p(0.3).coords, c + p(0.3).coords]
        })
        .collect();
    let bvh = Bvh::build(&tris);
    assert_eq!(bvh.len(), tris.len());
    let mut hits = 0;
    for _ in 0..2000 {
        let ray = Ray {
            origin: p(3.0),
            direction: p(1.0).coords,
        };
        let (expected, got) = (brute_force(&tris, &ray), bvh.nearest_hit(&ray, f32::INFINITY));
        assert_eq!(got.map(|h| h.triangle), expected.map(|h| h.triangle), "ray {ray:?}");
        hits += usize::from(got.is_some());
    }
    assert!(hits > 200, "the test exercises hits, got {hits}");
}

#[test]
fn empty_and_degenerate_inputs_do_not_panic() {
    let ray = Ray {
        origin: Point3::origin(),
        direction: Vector3::z(),
    };
    assert_eq!(Bvh::build(&[]).nearest_hit(&ray, f32::INFINITY), None);
    let same = [[Point3::new(0.0, 0.0, 1.0); 3]; 40];
    assert_eq!(Bvh::build(&same).nearest_hit(&ray, f32::INFINITY), None);
}
