use nalgebra::{Point3, Rotation3, Vector3};

use super::*;

/// Points on the faces of the box centred at `centre` with half extents `half`, about every
/// `step` metres.
fn box_surface(centre: [f32; 3], half: [f32; 3], step: f32) -> Vec<Point3<f32>> {
    let c = Point3::from(centre);
    let h = Vector3::from(half);
    let mut out = Vec::new();
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let (nu, nv) = ((2.0 * h[u] / step).ceil() as i32, (2.0 * h[v] / step).ceil() as i32);
        for side in [-1.0, 1.0] {
            for a in 0..=nu {
                for b in 0..=nv {
                    let mut p = Vector3::zeros();
                    p[axis] = side * h[axis];
                    p[u] = -h[u] + 2.0 * h[u] * a as f32 / nu.max(1) as f32;
                    p[v] = -h[v] + 2.0 * h[v] * b as f32 / nv.max(1) as f32;
                    out.push(c + p);
                }
            }
        }
    }
    out
}

/// A sofa in its own frame (symmetric about x = 0): a seat, a back at +y and two arms.
fn sofa() -> Vec<Point3<f32>> {
    let step = 0.03;
    let mut points = box_surface([0.0, 0.0, 0.2], [0.8, 0.4, 0.2], step);
    points.extend(box_surface([0.0, 0.32, 0.55], [0.8, 0.08, 0.3], step));
    points.extend(box_surface([-0.85, 0.0, 0.3], [0.07, 0.4, 0.3], step));
    points.extend(box_surface([0.85, 0.0, 0.3], [0.07, 0.4, 0.3], step));
    points
}

/// `points` turned by `yaw` about z and moved by `shift`.
fn placed(points: &[Point3<f32>], yaw: f32, shift: [f32; 3]) -> Vec<Point3<f32>> {
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
    points.iter().map(|p| r * p + Vector3::from(shift)).collect()
}

fn assert_finds(found: Option<SymmetryFit>, truth: &MirrorPlane) {
    assert_finds_within(found, truth, 2f32.to_radians(), 0.015);
}

fn assert_finds_within(found: Option<SymmetryFit>, truth: &MirrorPlane, angle: f32, offset: f32) {
    let fit = found.expect("a plane");
    let p = fit.plane;
    let offset_error = if p.normal.dot(&truth.normal) >= 0.0 {
        (p.offset - truth.offset).abs()
    } else {
        (p.offset + truth.offset).abs()
    };
    assert!(
        p.angle_to(truth) < angle && offset_error < offset,
        "found {p:?} (matched {:.2}), truth {truth:?}",
        fit.matched
    );
}

#[test]
fn a_reflection_is_its_own_inverse_and_keeps_distances() {
    let plane = MirrorPlane::vertical(0.7, 0.3);
    let (a, b) = (Point3::new(0.4, -1.0, 0.2), Point3::new(-0.3, 0.5, 1.1));
    assert!((plane.reflect(&plane.reflect(&a)) - a).norm() < 1e-5);
    assert!(((plane.reflect(&a) - plane.reflect(&b)).norm() - (a - b).norm()).abs() < 1e-5);
    assert!((plane.distance(&plane.reflect(&a)) + plane.distance(&a)).abs() < 1e-5);
    let v = Vector3::new(0.2, 0.9, -0.4);
    assert!((plane.reflect_vector(&v) - (plane.reflect(&(a + v)) - plane.reflect(&a))).norm() < 1e-5);
}

#[test]
fn the_plane_of_a_mirrored_cloud_is_found() {
    let yaw = 0.5;
    let points = placed(&sofa(), yaw, [1.2, -0.7, 0.0]);
    // The sofa's plane is its frame's x = 0, turned by the yaw: normal (cos yaw, sin yaw).
    let truth = MirrorPlane::vertical(
        yaw,
        Vector3::new(yaw.cos(), yaw.sin(), 0.0).dot(&Vector3::new(1.2, -0.7, 0.0)),
    );
    let found = find_vertical_mirror(&points, &SymmetryConfig::default());
    assert_finds_within(found, &truth, 0.4f32.to_radians(), 0.003);
    assert!(found.is_some_and(|f| f.residual_m < 0.005), "{found:?}");
}

#[test]
fn the_plane_of_a_sofa_seen_from_its_front_and_one_end_is_found() {
    // Only what a camera in front of it and to its right sees: faces towards −y or +x, and the
    // tops; the back's rear face, the left end and everything under the seat are missing.
    let seen: Vec<Point3<f32>> = sofa()
        .into_iter()
        .filter(|p| p.y < 0.39 && p.x > -0.9 && p.z > 0.01)
        .collect();
    let truth = MirrorPlane::vertical(0.0, 0.0);
    assert_finds_within(
        find_vertical_mirror(&seen, &SymmetryConfig::default()),
        &truth,
        0.5f32.to_radians(),
        0.005,
    );
}

#[test]
fn an_asymmetric_cloud_has_no_plane() {
    // An L of unequal arms with a post at the end of the long one and a low block under the short
    // one: no vertical plane maps it onto itself.
    let step = 0.03;
    let mut points = box_surface([0.5, 0.0, 0.05], [0.5, 0.06, 0.05], step);
    points.extend(box_surface([0.0, 0.25, 0.05], [0.06, 0.25, 0.05], step));
    points.extend(box_surface([0.95, 0.0, 0.6], [0.05, 0.05, 0.6], step));
    points.extend(box_surface([0.15, 0.35, 0.25], [0.1, 0.15, 0.25], step));
    let points = placed(&points, 0.3, [0.2, 0.1, 0.0]);
    let any = SymmetryConfig {
        min_matched: 0.0,
        ..SymmetryConfig::default()
    };
    let best = find_vertical_mirror(&points, &any).expect("a best plane");
    assert!(best.matched > 0.2 && best.matched < 0.45, "best {best:?}");
    let found = find_vertical_mirror(&points, &SymmetryConfig::default());
    assert!(found.is_none(), "found {found:?}");
}

#[test]
fn a_flat_panel_is_not_symmetric_about_its_own_plane() {
    // A vertical panel in the plane y = 0.2: every point lies on that plane, so it is never
    // scored; the plane found is the one across its width.
    let panel: Vec<Point3<f32>> = (0..40)
        .flat_map(|i| (0..30).map(move |k| Point3::new(i as f32 * 0.02, 0.2, k as f32 * 0.02)))
        .collect();
    assert_finds(
        find_vertical_mirror(&panel, &SymmetryConfig::default()),
        &MirrorPlane::vertical(0.0, 0.39),
    );
}

/// A dining table in its own frame (symmetric about x = 0 and y = 0): a 1.6 × 0.9 m top at
/// 0.72–0.75 m, four legs and an apron under the top's edges.
fn table() -> Vec<Point3<f32>> {
    let step = 0.03;
    let mut points = box_surface([0.0, 0.0, 0.735], [0.8, 0.45, 0.015], step);
    for (x, y) in [(-0.73, -0.38), (-0.73, 0.38), (0.73, -0.38), (0.73, 0.38)] {
        points.extend(box_surface([x, y, 0.36], [0.03, 0.03, 0.36], step));
    }
    points.extend(box_surface([0.0, -0.38, 0.67], [0.7, 0.01, 0.05], step));
    points.extend(box_surface([0.0, 0.38, 0.67], [0.7, 0.01, 0.05], step));
    points.extend(box_surface([-0.73, 0.0, 0.67], [0.01, 0.35, 0.05], step));
    points.extend(box_surface([0.73, 0.0, 0.67], [0.01, 0.35, 0.05], step));
    points
}

#[test]
fn a_table_with_one_end_hidden_has_a_second_plane_at_right_angles_and_a_sofa_none() {
    // A chair tucked under the table's −x end hides the apron there; the +x end's apron mirrors
    // onto nothing, the rest onto the table.
    let seen: Vec<Point3<f32>> = table()
        .into_iter()
        .filter(|p| !(p.x < -0.7 && p.y.abs() < 0.35 && p.z > 0.6 && p.z < 0.72))
        .collect();
    let (yaw, shift) = (0.5f32, [1.2, -0.7, 0.0]);
    let points = placed(&seen, yaw, shift);
    let (first, second) = find_vertical_mirrors(&points, &SymmetryConfig::default(), MirrorDirections::Any);
    let at = |theta: f32| {
        let n = Vector3::new(theta.cos(), theta.sin(), 0.0);
        MirrorPlane::vertical(theta, n.dot(&Vector3::from(shift)))
    };
    let (ends, sides) = (at(yaw), at(yaw + std::f32::consts::FRAC_PI_2));
    let (first, second) = (first.expect("a first plane"), second.expect("a second plane"));
    let (long, short) = if first.plane.angle_to(&sides) < first.plane.angle_to(&ends) {
        ((first, sides), (second, ends))
    } else {
        ((first, ends), (second, sides))
    };
    // Within the matching tolerance: the end plane may shift until the seen end's apron lands
    // on the hidden end's legs.
    assert_finds_within(Some(long.0), &long.1, 1f32.to_radians(), 0.025);
    assert_finds_within(Some(short.0), &short.1, 1f32.to_radians(), 0.025);

    // A sofa seen from the front is symmetric end to end, not front to back: its back's front
    // face mirrors onto the seat's empty front.
    let seen: Vec<Point3<f32>> = sofa().into_iter().filter(|p| p.y < 0.39 && p.z > 0.01).collect();
    let sofa = placed(&seen, yaw, shift);
    let (first, second) = find_vertical_mirrors(&sofa, &SymmetryConfig::default(), MirrorDirections::Any);
    assert_finds(first, &at(yaw));
    assert!(second.is_none(), "a sofa's back is not its front: {second:?}");
}

#[test]
fn a_cabinet_seen_from_its_front_and_one_side_is_mirrored_across_its_box_axes_not_its_diagonal() {
    // Its doors (y = −0.23) and its right side (x = +0.4), 1.2 m high, the top unseen: the L's
    // bisector maps the side onto the doors' right part (about 0.73 of the points match), the
    // true plane x = 0 the doors onto themselves (about 0.63).
    let seen: Vec<Point3<f32>> = box_surface([0.0, 0.0, 0.6], [0.4, 0.23, 0.6], 0.02)
        .into_iter()
        .filter(|p| (p.y < -0.229 || p.x > 0.399) && p.z > 0.001 && p.z < 1.199)
        .collect();
    let (yaw, shift) = (0.5f32, [1.2, -0.7, 0.0]);
    let points = placed(&seen, yaw, shift);
    let truth = MirrorPlane::vertical(yaw, Vector3::new(yaw.cos(), yaw.sin(), 0.0).dot(&Vector3::from(shift)));
    let cfg = SymmetryConfig::default();

    let (any, _) = find_vertical_mirrors(&points, &cfg, MirrorDirections::Any);
    let any = any.expect("a plane in some direction");
    assert!(
        any.plane.angle_to(&truth) > 30f32.to_radians(),
        "the bisector wins in any direction: {any:?}"
    );

    // A box fitted to a noisy cloud, a degree and a half off; and the same box named by its
    // other horizontal axis.
    for box_yaw in [yaw + 0.025, yaw + 0.025 + std::f32::consts::FRAC_PI_2] {
        let (first, _) = find_vertical_mirrors(&points, &cfg, MirrorDirections::BoxAxesFirst { yaw: box_yaw });
        assert_finds(first, &truth);
    }
}

#[test]
fn a_box_turned_away_from_the_objects_axes_leaves_the_search_to_every_direction() {
    // A sofa whose box is 30° off its axes: neither plane parallel to the box's faces matches
    // 0.6 of its points, and the search in every direction finds its plane.
    let (yaw, shift) = (0.5f32, [1.2, -0.7, 0.0]);
    let points = placed(&sofa(), yaw, shift);
    let truth = MirrorPlane::vertical(yaw, Vector3::new(yaw.cos(), yaw.sin(), 0.0).dot(&Vector3::from(shift)));
    let box_yaw = yaw + 30f32.to_radians();
    let (first, _) = find_vertical_mirrors(
        &points,
        &SymmetryConfig::default(),
        MirrorDirections::BoxAxesFirst { yaw: box_yaw },
    );
    assert_finds(first, &truth);
}
