//! Oriented bounding boxes, and the minimum-volume box of a point cloud.
//!
//! The minimum-volume box is searched over box "up" axes: for a candidate axis `a`, the points
//! are projected onto the plane orthogonal to `a`, where the smallest enclosing rectangle has a
//! side on the 2D convex hull (rotating calipers); the box volume is that area times the extent
//! along `a`. Candidates are the principal axes, the world z axis and a Fibonacci hemisphere of
//! directions; the best one is then refined on shrinking cones. The result is deterministic.

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector2, Vector3};
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

use crate::error::{CatmapError, Result};

/// A box with its own frame: centre and axes given by `world_from_box`, size by `half_extents`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OrientedBox {
    /// Maps box coordinates (origin at the centre, axes along the edges) to world coordinates.
    pub world_from_box: Isometry3<f32>,
    /// Half of the edge lengths along the box's x, y, z axes, metres.
    pub half_extents: Vector3<f32>,
}

impl OrientedBox {
    /// Edge lengths, metres.
    pub fn extents(&self) -> Vector3<f32> {
        self.half_extents * 2.0
    }

    /// Volume, cubic metres.
    pub fn volume(&self) -> f32 {
        let e = self.extents();
        e.x * e.y * e.z
    }

    /// Centre in world coordinates.
    pub fn center(&self) -> Point3<f32> {
        Point3::from(self.world_from_box.translation.vector)
    }

    /// The eight corners in world coordinates.
    pub fn corners(&self) -> [Point3<f32>; 8] {
        let h = self.half_extents;
        std::array::from_fn(|i| {
            let s = |bit: usize| if i & (1 << bit) == 0 { -1.0 } else { 1.0 };
            self.world_from_box * Point3::new(s(0) * h.x, s(1) * h.y, s(2) * h.z)
        })
    }

    /// The angle about world z of the box's x axis, radians from world x (of its y axis when x
    /// stands upright): the turn of its [`OrientedBox::upright`] box.
    pub fn yaw(&self) -> f32 {
        let axes = self.world_from_box.rotation.to_rotation_matrix().into_inner();
        let (x, y) = (axes.column(0), axes.column(1));
        let along = if x.x.hypot(x.y) >= 1e-3 { x } else { y };
        along.y.atan2(along.x)
    }

    /// The smallest box standing upright (its z along world z) that encloses this one, turned
    /// about world z as this box's x axis is (its y axis when x stands upright). A box fitted to
    /// a partly seen object may lean; space "beside" or "under" the object is upright space.
    pub fn upright(&self) -> OrientedBox {
        let yaw = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.yaw());
        let frame = Isometry3::from_parts(self.world_from_box.translation, yaw);
        let corners = self.corners().map(|c| frame.inverse_transform_point(&c).coords);
        let (lo, hi) = corners.iter().fold(
            (Vector3::repeat(f32::INFINITY), Vector3::repeat(f32::NEG_INFINITY)),
            |(lo, hi), c| (lo.inf(c), hi.sup(c)),
        );
        let centre = frame * Point3::from((lo + hi) / 2.0);
        OrientedBox {
            world_from_box: Isometry3::from_parts(Translation3::from(centre.coords), yaw),
            half_extents: (hi - lo) / 2.0,
        }
    }

    /// Whether `p` lies inside (within `margin_m`).
    pub fn contains(&self, p: &Point3<f32>, margin_m: f32) -> bool {
        let local = self.world_from_box.inverse_transform_point(p);
        (0..3).all(|k| local[k].abs() <= self.half_extents[k] + margin_m)
    }

    /// The same box with every edge at least `min_extent_m` long (grown about the centre).
    pub fn with_min_extent(mut self, min_extent_m: f32) -> Self {
        self.half_extents = self.half_extents.map(|h| h.max(0.5 * min_extent_m));
        self
    }
}

/// The minimum-volume oriented box of `points` (see the module doc).
///
/// Axes are canonical: box z is the axis closest to world z (pointing up), box x the longer of
/// the two others with a non-negative world-x component. Errors on an empty or non-finite cloud.
pub fn fit_minimum_volume_box(points: &[Point3<f32>]) -> Result<OrientedBox> {
    let (mean, centred) = centred_cloud(points)?;

    // The box only depends on the convex hull: search on the points that are extreme in some
    // direction (nearly all hull vertices), then measure the chosen box on every point.
    let support = support_points(&centred, &fibonacci_sphere(SUPPORT_DIRECTIONS));
    let mut best = candidate_axes(&centred)
        .into_iter()
        .map(|axis| fit_around_axis(&support, axis))
        .min_by(|a, b| a.volume.total_cmp(&b.volume))
        .expect("there is always at least one candidate axis");
    for cone_deg in [4.0_f64, 2.0, 1.0, 0.5, 0.25] {
        for axis in cone_around(best.axes[2], cone_deg.to_radians(), 16) {
            let fit = fit_around_axis(&support, axis);
            if fit.volume < best.volume {
                best = fit;
            }
        }
    }
    best.measure(&centred);
    Ok(best.into_box(mean))
}

/// The mean of `points` and the points about it; errors on an empty or non-finite cloud.
pub(super) fn centred_cloud(points: &[Point3<f32>]) -> Result<(Vector3<f64>, Vec<Vector3<f64>>)> {
    if points.is_empty() {
        return Err(CatmapError::too_few("points to fit a box to", 1, 0));
    }
    if points.iter().any(|p| !p.coords.iter().all(|x| x.is_finite())) {
        return Err(CatmapError::NonFinitePoint {
            what: "a cloud to fit a box to".into(),
        });
    }
    let mean = points
        .iter()
        .fold(Vector3::zeros(), |acc, p| acc + p.coords.cast::<f64>())
        / points.len() as f64;
    Ok((mean, points.iter().map(|p| p.coords.cast::<f64>() - mean).collect()))
}

/// One candidate box: its axes (x, y, z = the candidate axis), extents and centre offset.
pub(super) struct AxisFit {
    pub(super) axes: [Vector3<f64>; 3],
    min: Vector3<f64>,
    max: Vector3<f64>,
    volume: f64,
}

impl AxisFit {
    /// Recomputes the extents of an upright fit: its sides over `footprint`, its height over
    /// `points`.
    pub(super) fn measure_upright(&mut self, footprint: &[Vector3<f64>], points: &[Vector3<f64>]) {
        self.measure(points);
        let (z_min, z_max) = (self.min.z, self.max.z);
        self.measure(footprint);
        (self.min.z, self.max.z) = (z_min, z_max);
    }

    /// Recomputes the extents along the fitted axes over `points`.
    pub(super) fn measure(&mut self, points: &[Vector3<f64>]) {
        self.min = Vector3::repeat(f64::INFINITY);
        self.max = Vector3::repeat(f64::NEG_INFINITY);
        for p in points {
            let local = Vector3::new(p.dot(&self.axes[0]), p.dot(&self.axes[1]), p.dot(&self.axes[2]));
            self.min = self.min.inf(&local);
            self.max = self.max.sup(&local);
        }
    }

    pub(super) fn into_box(self, mean: Vector3<f64>) -> OrientedBox {
        let local_centre = (self.min + self.max) * 0.5;
        let half = (self.max - self.min) * 0.5;
        let centre =
            mean + self.axes[0] * local_centre.x + self.axes[1] * local_centre.y + self.axes[2] * local_centre.z;
        let (axes, half) = canonical_axes(self.axes, half);
        let rotation = Rotation3::from_basis_unchecked(&axes.map(|a| a.cast::<f32>()));
        OrientedBox {
            world_from_box: Isometry3::from_parts(
                Translation3::from(centre.cast::<f32>()),
                UnitQuaternion::from_rotation_matrix(&rotation),
            ),
            half_extents: half.cast::<f32>(),
        }
    }
}

/// Reorders and flips box axes: z closest to world up, x the longer remaining one, right-handed.
fn canonical_axes(axes: [Vector3<f64>; 3], half: Vector3<f64>) -> ([Vector3<f64>; 3], Vector3<f64>) {
    let up = (0..3)
        .max_by(|&a, &b| axes[a].z.abs().total_cmp(&axes[b].z.abs()))
        .expect("three axes");
    let (i, j) = match up {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let (xi, yi) = if half[i] >= half[j] { (i, j) } else { (j, i) };
    let z = if axes[up].z < 0.0 { -axes[up] } else { axes[up] };
    let mut x = axes[xi];
    if x.x < -1e-9 || (x.x.abs() <= 1e-9 && x.y < 0.0) {
        x = -x;
    }
    let y = z.cross(&x);
    ([x, y, z], Vector3::new(half[xi], half[yi], half[up]))
}

pub(super) fn fit_around_axis(points: &[Vector3<f64>], axis: Vector3<f64>) -> AxisFit {
    let axis = axis.normalize();
    let helper = if axis.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let e1 = axis.cross(&helper).normalize();
    let e2 = axis.cross(&e1);
    let (mut h_min, mut h_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut planar: Vec<Vector2<f64>> = Vec::with_capacity(points.len());
    for p in points {
        let h = p.dot(&axis);
        h_min = h_min.min(h);
        h_max = h_max.max(h);
        planar.push(Vector2::new(p.dot(&e1), p.dot(&e2)));
    }
    let hull = convex_hull_2d(planar);
    let (dir, min2, max2) = min_area_rectangle(&hull);
    let x = e1 * dir.x + e2 * dir.y;
    let y = axis.cross(&x);
    let area = (max2.x - min2.x) * (max2.y - min2.y);
    AxisFit {
        axes: [x, y, axis],
        min: Vector3::new(min2.x, min2.y, h_min),
        max: Vector3::new(max2.x, max2.y, h_max),
        volume: area.max(0.0) * (h_max - h_min) + 1e-12 * (area + h_max - h_min),
    }
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without collinear points.
pub fn convex_hull_2d(mut points: Vec<Vector2<f64>>) -> Vec<Vector2<f64>> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let cross = |o: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>| (a - o).perp(&(b - o));
    let mut hull: Vec<Vector2<f64>> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let (mut forward, mut backward) = (points.iter(), points.iter().rev());
        let ordered: &mut dyn Iterator<Item = &Vector2<f64>> = if pass == 0 { &mut forward } else { &mut backward };
        for p in ordered {
            while hull.len() >= start + 2 && cross(&hull[hull.len() - 2], &hull[hull.len() - 1], p) <= 0.0 {
                hull.pop();
            }
            hull.push(*p);
        }
        hull.pop();
    }
    hull
}

/// Smallest-area enclosing rectangle of a convex polygon: one side lies on a hull edge.
/// Returns the rectangle's first axis (unit) and its min/max corner in (axis, perpendicular) coordinates.
fn min_area_rectangle(hull: &[Vector2<f64>]) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
    let mut best = (f64::INFINITY, Vector2::x(), Vector2::zeros(), Vector2::zeros());
    let n = hull.len();
    for k in 0..n.max(1) {
        let edge = if n >= 2 {
            hull[(k + 1) % n] - hull[k]
        } else {
            Vector2::x()
        };
        let Some(d) = edge.try_normalize(1e-12) else { continue };
        let perp = Vector2::new(-d.y, d.x);
        let (mut lo, mut hi) = (Vector2::repeat(f64::INFINITY), Vector2::repeat(f64::NEG_INFINITY));
        for p in hull {
            let q = Vector2::new(p.dot(&d), p.dot(&perp));
            lo = lo.inf(&q);
            hi = hi.sup(&q);
        }
        let area = (hi.x - lo.x) * (hi.y - lo.y);
        if area < best.0 {
            best = (area, d, lo, hi);
        }
    }
    if !best.0.is_finite() {
        let p = hull.first().copied().unwrap_or_else(Vector2::zeros);
        return (Vector2::x(), p, p);
    }
    (best.1, best.2, best.3)
}

/// Directions whose extreme points stand in for the convex hull.
const SUPPORT_DIRECTIONS: usize = 1000;
/// Candidate box axes on the upper hemisphere.
const CANDIDATE_AXES: usize = 256;

/// Lanes of the blocked argmax in [`support_points`] (independent lanes vectorise).
const LANES: usize = 8;

/// Points per block of [`support_points`]: their coordinates (24 KiB) stay in L1 while every
/// direction passes over them.
const SUPPORT_BLOCK: usize = 2048;

/// The points that are extreme (maximal) along at least one of `directions` (the last one on
/// ties), deduplicated. Projections are compared in `f32` on `LANES`-padded coordinate arrays
/// (the support set only stands in for the hull; the chosen box is measured on every point in
/// `f64`). The points are visited block by block, every direction over a block before the next
/// block, so that a large cloud (a ground-truth mesh: millions of vertices) is read from memory
/// once rather than once per direction; each lane still sees its points in order.
fn support_points(points: &[Vector3<f64>], directions: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    // Only the last copy of a repeated point can be the last maximum, so the others are left out
    // (a mesh whose triangles do not share vertices repeats each point about six times).
    let kept = last_copies(points);
    let padded = kept.len().div_ceil(LANES) * LANES;
    let mut xyz = [0, 1, 2].map(|k| kept.iter().map(|&i| points[i][k] as f32).collect::<Vec<f32>>());
    // Padding repeats the last point, so a padding slot can only win where the last point does.
    xyz.iter_mut()
        .for_each(|c| c.resize(padded, c.last().copied().unwrap_or(0.0)));
    let [xs, ys, zs] = &xyz;
    let directions: Vec<Vector3<f32>> = directions.iter().map(|d| d.cast::<f32>()).collect();
    let mut best = vec![([f32::NEG_INFINITY; LANES], [0u32; LANES]); directions.len()];
    for start in (0..padded).step_by(SUPPORT_BLOCK) {
        let end = (start + SUPPORT_BLOCK).min(padded);
        let blocks = xs[start..end]
            .chunks_exact(LANES)
            .zip(ys[start..end].chunks_exact(LANES))
            .zip(zs[start..end].chunks_exact(LANES));
        for (d, (best, best_at)) in directions.iter().zip(&mut best) {
            for (b, ((x, y), z)) in blocks.clone().enumerate() {
                let first = (start + b * LANES) as u32;
                for l in 0..LANES {
                    let dot = x[l] * d.x + y[l] * d.y + z[l] * d.z;
                    let better = dot >= best[l];
                    best[l] = if better { dot } else { best[l] };
                    best_at[l] = if better { first + l as u32 } else { best_at[l] };
                }
            }
        }
    }
    let last = kept.len() - 1;
    let mut chosen: Vec<usize> = best
        .iter()
        .map(|(best, best_at)| {
            let winner = (0..LANES).max_by(|&a, &b| best[a].total_cmp(&best[b]).then(best_at[a].cmp(&best_at[b])));
            kept[(best_at[winner.expect("LANES > 0")] as usize).min(last)]
        })
        .collect();
    chosen.sort_unstable();
    chosen.dedup();
    chosen.into_iter().map(|i| points[i]).collect()
}

/// Indices of the last copy of every distinct point, ascending (an unkeyed hash, several times
/// faster than the default on a ground-truth mesh's millions of vertices; the keys are our own).
fn last_copies(points: &[Vector3<f64>]) -> Vec<usize> {
    let mut last: FxHashMap<[u64; 3], usize> = FxHashMap::default();
    last.reserve(points.len());
    for (i, p) in points.iter().enumerate() {
        last.insert([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()], i);
    }
    let mut kept: Vec<usize> = last.into_values().collect();
    kept.sort_unstable();
    kept
}

/// `n` nearly uniform unit vectors on the whole sphere.
fn fibonacci_sphere(n: usize) -> Vec<Vector3<f64>> {
    let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            Vector3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// Principal axes, world z, and the upper half of a Fibonacci sphere.
fn candidate_axes(points: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let covariance = points
        .iter()
        .fold(nalgebra::Matrix3::zeros(), |acc, p| acc + p * p.transpose());
    let eigen = covariance.symmetric_eigen();
    let mut axes: Vec<Vector3<f64>> = eigen.eigenvectors.column_iter().map(|c| c.into_owned()).collect();
    axes.push(Vector3::z());
    axes.extend(fibonacci_sphere(2 * CANDIDATE_AXES).into_iter().filter(|a| a.z >= 0.0));
    axes.retain(|a| a.norm() > 1e-9);
    axes
}

/// `count` unit vectors at angle `angle` around `axis`.
fn cone_around(axis: Vector3<f64>, angle: f64, count: usize) -> Vec<Vector3<f64>> {
    let helper = if axis.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let e1 = axis.cross(&helper).normalize();
    let e2 = axis.cross(&e1);
    (0..count)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / count as f64;
            (axis * angle.cos() + (e1 * t.cos() + e2 * t.sin()) * angle.sin()).normalize()
        })
        .collect()
}

#[cfg(test)]
#[path = "oriented_box_tests.rs"]
pub(super) mod tests;
