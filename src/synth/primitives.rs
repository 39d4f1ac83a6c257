//! Closed mesh primitives the furniture is built from: boxes, beams, frusta (cylinders, cones) and
//! curved panels (sections of a thick cylindrical shell). All are closed and wound
//! counter-clockwise seen from outside, so their signed volume is positive.

use std::f32::consts::TAU;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use crate::geometry::mesh::TriangleMesh;

/// Appends the two triangles of quad `a b c d` (counter-clockwise seen from outside).
fn push_quad(triangles: &mut Vec<[u32; 3]>, [a, b, c, d]: [u32; 4]) {
    triangles.push([a, b, c]);
    triangles.push([a, c, d]);
}

/// An axis-aligned box between corners `min` and `max`.
pub fn cuboid(min: [f32; 3], max: [f32; 3]) -> TriangleMesh {
    // Corner k has x from bit 0, y from bit 1, z from bit 2.
    let vertices = (0..8)
        .map(|k| {
            let pick = |bit: usize, axis: usize| if k >> bit & 1 == 1 { max[axis] } else { min[axis] };
            Point3::new(pick(0, 0), pick(1, 1), pick(2, 2))
        })
        .collect();
    let faces = [
        [1, 3, 7, 5],
        [0, 4, 6, 2],
        [2, 6, 7, 3],
        [0, 1, 5, 4],
        [4, 5, 7, 6],
        [0, 2, 3, 1],
    ];
    let mut triangles = Vec::with_capacity(12);
    faces.into_iter().for_each(|f| push_quad(&mut triangles, f));
    TriangleMesh::new(vertices, triangles)
}

/// A box centred at `(cx, cy)` on the floor plane, `size` = (x, y, z) extents, from height `z0`.
pub fn block(cx: f32, cy: f32, z0: f32, size: [f32; 3]) -> TriangleMesh {
    let [sx, sy, sz] = size;
    cuboid(
        [cx - sx / 2.0, cy - sy / 2.0, z0],
        [cx + sx / 2.0, cy + sy / 2.0, z0 + sz],
    )
}

/// A beam of square cross-section `width` from `from` to `to`.
pub fn beam(from: Point3<f32>, to: Point3<f32>, width: f32) -> TriangleMesh {
    let axis = to - from;
    let h = width / 2.0;
    let mut mesh = cuboid([-h, -h, 0.0], [h, h, axis.norm()]);
    let rotation = UnitQuaternion::rotation_between(&Vector3::z(), &axis)
        .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f32::consts::PI));
    mesh.transform_isometry(&Isometry3::from_parts(Translation3::from(from.coords), rotation));
    mesh
}

/// A closed frustum around the vertical axis through `base`: radius `r_bottom` at `base.z`,
/// `r_top` at `base.z + height`, `segments` sides. A cylinder when the radii agree.
pub fn frustum(base: Point3<f32>, r_bottom: f32, r_top: f32, height: f32, segments: u32) -> TriangleMesh {
    let n = segments.max(3);
    let ring = |r: f32, z: f32| {
        (0..n).map(move |i| {
            let a = TAU * i as f32 / n as f32;
            base + Vector3::new(r * a.cos(), r * a.sin(), z)
        })
    };
    let mut vertices: Vec<Point3<f32>> = ring(r_bottom, 0.0).chain(ring(r_top, height)).collect();
    vertices.push(base);
    vertices.push(base + Vector3::new(0.0, 0.0, height));
    let (bottom_centre, top_centre) = (2 * n, 2 * n + 1);
    let mut triangles = Vec::with_capacity(4 * n as usize);
    for i in 0..n {
        let j = (i + 1) % n;
        push_quad(&mut triangles, [i, j, n + j, n + i]);
        triangles.push([bottom_centre, j, i]);
        triangles.push([top_centre, n + i, n + j]);
    }
    TriangleMesh::new(vertices, triangles)
}

/// A closed vertical cylinder standing on `base`.
pub fn cylinder(base: Point3<f32>, radius: f32, height: f32, segments: u32) -> TriangleMesh {
    frustum(base, radius, radius, height, segments)
}

/// A section of a thick vertical cylindrical shell around the z axis: radii `r_inner..r_outer`,
/// angles `angle_from..angle_to` (radians, counter-clockwise from +x), heights `z_from..z_to`.
pub fn curved_panel(radii: (f32, f32), angles: (f32, f32), heights: (f32, f32), segments: u32) -> TriangleMesh {
    let n = segments.max(1);
    let (r_inner, r_outer) = radii;
    let mut vertices = Vec::with_capacity(4 * (n as usize + 1));
    for i in 0..=n {
        let a = angles.0 + (angles.1 - angles.0) * i as f32 / n as f32;
        let (s, c) = a.sin_cos();
        for (r, z) in [
            (r_inner, heights.0),
            (r_inner, heights.1),
            (r_outer, heights.0),
            (r_outer, heights.1),
        ] {
            vertices.push(Point3::new(r * c, r * s, z));
        }
    }
    // Vertex 4i + {0: inner bottom, 1: inner top, 2: outer bottom, 3: outer top} at step i.
    let v = |i: u32, k: u32| 4 * i + k;
    let mut triangles = Vec::with_capacity(8 * n as usize + 4);
    for i in 0..n {
        let j = i + 1;
        push_quad(&mut triangles, [v(i, 2), v(j, 2), v(j, 3), v(i, 3)]); // outer
        push_quad(&mut triangles, [v(i, 0), v(i, 1), v(j, 1), v(j, 0)]); // inner
        push_quad(&mut triangles, [v(i, 1), v(i, 3), v(j, 3), v(j, 1)]); // top
        push_quad(&mut triangles, [v(i, 0), v(j, 0), v(j, 2), v(i, 2)]); // bottom
    }
    push_quad(&mut triangles, [v(0, 0), v(0, 2), v(0, 3), v(0, 1)]);
    push_quad(&mut triangles, [v(n, 0), v(n, 1), v(n, 3), v(n, 2)]);
    TriangleMesh::new(vertices, triangles)
}

/// Signed volume enclosed by a closed mesh (positive when wound outward).
pub fn signed_volume(mesh: &TriangleMesh) -> f32 {
    (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            a.coords.dot(&b.coords.cross(&c.coords)) / 6.0
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    fn assert_close(got: f32, expected: f32, tol: f32, what: &str) {
        assert!((got - expected).abs() <= tol, "{what}: got {got}, expected {expected}");
    }

    #[test]
    fn primitives_enclose_their_analytic_volumes_with_outward_winding() {
        assert_close(
            signed_volume(&cuboid([0.0, 0.0, 0.0], [1.0, 2.0, 3.0])),
            6.0,
            1e-5,
            "cuboid",
        );
        let b = beam(Point3::new(1.0, 1.0, 1.0), Point3::new(1.0, 3.0, 1.0), 0.1);
        assert_close(signed_volume(&b), 0.02, 1e-6, "beam");
        let down = beam(Point3::new(0.0, 0.0, 1.0), Point3::new(0.0, 0.0, 0.0), 0.1);
        assert_close(signed_volume(&down), 0.01, 1e-6, "beam pointing down");
        // A 64-gon prism has area (n/2)·r²·sin(2π/n).
        let prism = 32.0 * (TAU / 64.0).sin();
        assert_close(
            signed_volume(&cylinder(Point3::new(2.0, 0.0, 0.0), 1.0, 2.0, 64)),
            2.0 * prism,
            1e-4,
            "cylinder",
        );
        let cone = frustum(Point3::origin(), 1.0, 0.0, 3.0, 64);
        assert_close(signed_volume(&cone), prism, 1e-4, "cone");
        // Half of a shell with radii 1..2, height 1: π(4 − 1)/2.
        let panel = curved_panel((1.0, 2.0), (0.0, PI), (0.0, 1.0), 128);
        assert_close(signed_volume(&panel), 1.5 * PI, 2e-3, "curved panel");
    }

    #[test]
    fn block_is_centred_on_its_footprint() {
        let b = block(1.0, 2.0, 0.5, [0.2, 0.4, 1.0])
            .bounds()
            .expect("box has vertices");
        assert_eq!(b.min, Point3::new(0.9, 1.8, 0.5));
        assert_eq!(b.max, Point3::new(1.1, 2.2, 1.5));
    }
}
