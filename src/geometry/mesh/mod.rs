//! Indexed triangle meshes: rigid and similarity transforms, merging, area, area-uniform surface
//! sampling, bounds, vertex clustering (a lighter copy for display), connected pieces (dropping
//! floating fragments), and PLY input/output.
//!
//! Ground-truth object meshes, the synthetic furniture and reconstructed surfaces all use this type.
//! Sampling draws a triangle with probability proportional to its area, then a uniform point in it
//! from barycentric coordinates `(1 − √r₁, √r₁(1 − r₂), √r₁·r₂)`, so the samples are uniform over the
//! surface for any triangulation.
//!
//! PLY: [`TriangleMesh::write_ply`] writes binary little-endian (`float x y z`, optional `uchar red
//! green blue`, `list uchar int vertex_indices`) atomically; [`TriangleMesh::read_ply`] reads ASCII
//! and binary files with any numeric vertex type and fan-triangulates polygons.

use nalgebra::{Isometry3, Point3, Similarity3, Vector3};
use rand::{Rng, RngExt};

use crate::error::{CatmapError, Result};

/// An indexed triangle mesh with optional per-vertex colours.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub vertices: Vec<Point3<f32>>,
    /// Triangles as indices into `vertices`, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// One RGB colour per vertex, when the mesh is coloured.
    pub colors: Option<Vec<[u8; 3]>>,
}

/// An axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest coordinate on each axis.
    pub min: Point3<f32>,
    /// Largest coordinate on each axis.
    pub max: Point3<f32>,
}

impl Aabb {
    /// The smallest box holding all `points`, or `None` when there are none.
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Point3<f32>>) -> Option<Self> {
        let mut points = points.into_iter();
        let first = *points.next()?;
        Some(points.fold(Self { min: first, max: first }, |b, p| Self {
            min: b.min.inf(p),
            max: b.max.sup(p),
        }))
    }

    /// Side lengths along x, y and z.
    pub fn extent(&self) -> Vector3<f32> {
        self.max - self.min
    }

    /// Centre of the box.
    pub fn center(&self) -> Point3<f32> {
        nalgebra::center(&self.min, &self.max)
    }
}

/// Grey given to vertices of uncoloured meshes merged into coloured ones.
const DEFAULT_GREY: [u8; 3] = [128, 128, 128];

impl TriangleMesh {
    /// An uncoloured mesh.
    pub fn new(vertices: Vec<Point3<f32>>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            vertices,
            triangles,
            colors: None,
        }
    }

    /// The same mesh with every vertex painted `rgb`.
    pub fn with_uniform_color(mut self, rgb: [u8; 3]) -> Self {
        self.colors = Some(vec![rgb; self.vertices.len()]);
        self
    }

    /// True when the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Checks that every index is in range and the colours match the vertices.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.vertices.len();
        if let Some(bad) = self.triangles.iter().flatten().find(|&&i| i as usize >= n) {
            return Err(format!("triangle index {bad} out of range ({n} vertices)"));
        }
        match &self.colors {
            Some(c) if c.len() != n => Err(format!("{} colours for {n} vertices", c.len())),
            _ => Ok(()),
        }
    }

    /// Maps every vertex through `world_from_local` in place.
    pub fn transform_isometry(&mut self, world_from_local: &Isometry3<f32>) {
        self.vertices.iter_mut().for_each(|v| *v = world_from_local * *v);
    }

    /// Maps every vertex through a similarity (rotation, translation, uniform scale) in place.
    pub fn transform_similarity(&mut self, world_from_local: &Similarity3<f32>) {
        self.vertices.iter_mut().for_each(|v| *v = world_from_local * *v);
    }

    /// A copy mapped through `world_from_local`.
    pub fn transformed(&self, world_from_local: &Isometry3<f32>) -> Self {
        let mut out = self.clone();
        out.transform_isometry(world_from_local);
        out
    }

    /// Appends `other`'s vertices and triangles. The result is coloured when either mesh is;
    /// the uncoloured side's vertices become grey.
    pub fn append(&mut self, other: &TriangleMesh) {
        let offset = u32::try_from(self.vertices.len()).expect("meshes stay below 2³² vertices");
        let (own_n, other_n) = (self.vertices.len(), other.vertices.len());
        self.colors = match (self.colors.take(), &other.colors) {
            (None, None) => None,
            (own, theirs) => {
                let mut c = own.unwrap_or_else(|| vec![DEFAULT_GREY; own_n]);
                match theirs {
                    Some(t) => c.extend_from_slice(t),
                    None => c.extend(std::iter::repeat_n(DEFAULT_GREY, other_n)),
                }
                Some(c)
            }
        };
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + offset)));
    }

    /// All `meshes` merged into one.
    pub fn merged<'a>(meshes: impl IntoIterator<Item = &'a TriangleMesh>) -> Self {
        let mut out = Self::default();
        meshes.into_iter().for_each(|m| out.append(m));
        out
    }

    /// Corner positions of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [Point3<f32>; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// Area of triangle `t`.
    pub fn triangle_area(&self, t: usize) -> f32 {
        let [a, b, c] = self.corners(t);
        0.5 * (b - a).cross(&(c - a)).norm()
    }

    /// Total surface area.
    pub fn area(&self) -> f32 {
        (0..self.triangles.len())
            .map(|t| f64::from(self.triangle_area(t)))
            .sum::<f64>() as f32
    }

    /// Axis-aligned bounds of the vertices, or `None` for a mesh without vertices.
    pub fn bounds(&self) -> Option<Aabb> {
        Aabb::from_points(&self.vertices)
    }

    /// `count` points drawn uniformly over the surface with `rng`. Errors when the mesh has no area.
    pub fn sample_surface<R: Rng + ?Sized>(&self, count: usize, rng: &mut R) -> Result<Vec<Point3<f32>>> {
        Ok(self
            .sample_surface_oriented(count, rng)?
            .into_iter()
            .map(|(p, _)| p)
            .collect())
    }

    /// Like [`Self::sample_surface`] (the same draws), each point with the unit normal of its
    /// triangle (right-hand rule over the triangle's corner order).
    pub fn sample_surface_oriented<R: Rng + ?Sized>(
        &self,
        count: usize,
        rng: &mut R,
    ) -> Result<Vec<(Point3<f32>, Vector3<f32>)>> {
        let cumulative: Vec<f64> = (0..self.triangles.len())
            .scan(0.0, |acc, t| {
                *acc += f64::from(self.triangle_area(t));
                Some(*acc)
            })
            .collect();
        let total = cumulative.last().copied().unwrap_or(0.0);
        if count > 0 && !(total > 0.0 && total.is_finite()) {
            return Err(CatmapError::bad_value(
                "the area of a mesh to sample",
                total,
                "be positive and finite",
            ));
        }
        let last = self.triangles.len().saturating_sub(1);
        let points = (0..count)
            .map(|_| {
                let target = rng.random::<f64>() * total;
                let t = cumulative.partition_point(|&c| c <= target).min(last);
                let [a, b, c] = self.corners(t);
                let (r1, r2) = (rng.random::<f32>().sqrt(), rng.random::<f32>());
                let p = Point3::from(a.coords * (1.0 - r1) + b.coords * (r1 * (1.0 - r2)) + c.coords * (r1 * r2));
                let normal = (b - a).cross(&(c - a)).try_normalize(0.0).unwrap_or_else(Vector3::z);
                (p, normal)
            })
            .collect();
        Ok(points)
    }
}

/// One PLY element record as the parser fills it: position, colour and face indices.
mod clustering;
mod fragments;
mod ply;

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn unit_square() -> TriangleMesh {
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        TriangleMesh::new(v.map(Point3::from).to_vec(), vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn unit_square_has_unit_area_and_bounds() {
        let mesh = unit_square();
        assert!((mesh.area() - 1.0).abs() < 1e-6);
        let b = mesh.bounds().expect("mesh has vertices");
        assert_eq!((b.min, b.max), (Point3::origin(), Point3::new(1.0, 1.0, 0.0)));
    }

    #[test]
    fn a_point_box_has_its_centre_and_extent_and_no_points_have_none() {
        let cloud = [
            Point3::new(1.0, 0.0, 0.5),
            Point3::new(2.0, -1.0, 0.0),
            Point3::new(1.5, 3.0, 0.25),
        ];
        let b = Aabb::from_points(&cloud).expect("non-empty");
        assert!((b.center() - Point3::new(1.5, 1.0, 0.25)).norm() < 1e-6);
        assert!((b.extent() - Vector3::new(1.0, 4.0, 0.5)).norm() < 1e-6);
        assert!(Aabb::from_points(&[]).is_none());
    }

    #[test]
    fn samples_are_uniform_over_unequal_triangles() {
        // Triangle 0 covers 3/4 of the area of this quad, triangle 1 a quarter.
        let v = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let mesh = TriangleMesh::new(v.map(Point3::from).to_vec(), vec![[0, 1, 2], [0, 2, 3]]);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let points = mesh.sample_surface(20_000, &mut rng).expect("mesh has area");
        let left = points.iter().filter(|p| p.x < 1.5).count() as f32 / points.len() as f32;
        assert!(
            (left - 0.5).abs() < 0.02,
            "half the samples lie left of x = 1.5, got {left}"
        );
        assert!(
            points
                .iter()
                .all(|p| p.x >= 0.0 && p.x <= 3.0 && p.y >= 0.0 && p.y <= 1.0)
        );
    }

    #[test]
    fn sampling_a_mesh_without_area_is_an_error() {
        let mesh = TriangleMesh::new(vec![Point3::origin(); 3], vec![[0, 1, 2]]);
        assert!(mesh.sample_surface(10, &mut ChaCha8Rng::seed_from_u64(0)).is_err());
    }

    #[test]
    fn append_offsets_indices_and_fills_missing_colours() {
        let mut mesh = unit_square().with_uniform_color([255, 0, 0]);
        mesh.append(&unit_square());
        assert_eq!(mesh.triangles[2], [4, 5, 6]);
        let colors = mesh.colors.as_ref().expect("coloured side keeps colours");
        assert_eq!((colors[0], colors[7]), ([255, 0, 0], DEFAULT_GREY));
        assert_eq!(mesh.validate(), Ok(()));
    }

    #[test]
    fn transforms_move_vertices() {
        let rot = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f32::consts::FRAC_PI_2);
        let iso = Isometry3::from_parts(Translation3::new(0.0, 0.0, 2.0), rot);
        let moved = unit_square().transformed(&iso);
        assert!((moved.vertices[1] - Point3::new(0.0, 1.0, 2.0)).norm() < 1e-6);
        let mut scaled = unit_square();
        scaled.transform_similarity(&Similarity3::from_isometry(Isometry3::identity(), 2.0));
        assert!((scaled.area() - 4.0).abs() < 1e-5);
    }

    #[test]
    fn binary_ply_round_trips_with_and_without_colours() {
        let dir = tempfile::tempdir().expect("temp dir");
        for mesh in [unit_square(), unit_square().with_uniform_color([1, 2, 3])] {
            let path = dir.path().join("m.ply");
            mesh.write_ply(&path).expect("write");
            assert_eq!(TriangleMesh::read_ply(&path).expect("read"), mesh);
            assert!(
                !path.with_extension("ply.tmp").exists(),
                "temporary file is renamed away"
            );
        }
    }

    #[test]
    fn ascii_ply_with_doubles_and_a_quad_is_fan_triangulated() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("quad.ply");
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n\
                    property double z\nproperty float nx\nelement face 1\nproperty list uchar uint vertex_index\n\
                    end_header\n0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n4 0 1 2 3\n";
        std::fs::write(&path, text).expect("write");
        let mesh = TriangleMesh::read_ply(&path).expect("valid ascii PLY");
        assert_eq!(mesh, unit_square());
    }

    #[test]
    fn corrupt_ply_files_are_errors_naming_the_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("bad.ply");
        unit_square().write_ply(&path).expect("write");
        let bytes = std::fs::read(&path).expect("read back");
        let cases: [&[u8]; 4] = [
            &bytes[..bytes.len() - 5], // truncated payload
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
              element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
            b"not a ply file at all",
        ];
        for (k, case) in cases.iter().enumerate() {
            std::fs::write(&path, case).expect("write case");
            let err = TriangleMesh::read_ply(&path).expect_err("corrupt file must fail");
            assert!(
                err.to_string().contains("bad.ply"),
                "case {k}: error names the file: {err}"
            );
        }
        let missing = TriangleMesh::read_ply(&dir.path().join("missing.ply")).expect_err("no file");
        assert!(matches!(missing, CatmapError::Io { .. }));
    }
}
