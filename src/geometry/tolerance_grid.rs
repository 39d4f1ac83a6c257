//! Points in a dense grid of cells as large as a tolerance: "is there a point within the
//! tolerance of this one?" in a few cell lookups (the mirror search asks it of every reflected
//! point of every candidate plane).

use nalgebra::{Point3, Vector3};

/// The points of a cloud in a dense grid of cells as large as the tolerance (cell lists stored
/// back to back), answering "is there a point within the tolerance?".
pub(crate) struct ToleranceGrid {
    corner: Point3<f32>,
    cell: f32,
    dims: [usize; 3],
    tolerance_sq: f32,
    /// Where each cell's points start in `points` (one more entry than cells).
    starts: Vec<u32>,
    points: Vec<Point3<f32>>,
}

impl ToleranceGrid {
    pub(crate) fn new(points: &[Point3<f32>], tolerance: f32) -> Self {
        let lo = points
            .iter()
            .fold(Point3::from(Vector3::repeat(f32::INFINITY)), |a, p| a.inf(p));
        let hi = points
            .iter()
            .fold(Point3::from(Vector3::repeat(f32::NEG_INFINITY)), |a, p| a.sup(p));
        let corner = lo - Vector3::repeat(tolerance);
        let dims = [0, 1, 2].map(|a| ((hi[a] - corner[a]) / tolerance).floor() as usize + 2);
        let mut set = Self {
            corner,
            cell: tolerance,
            dims,
            tolerance_sq: tolerance * tolerance,
            starts: vec![0; dims[0] * dims[1] * dims[2] + 1],
            points: vec![Point3::origin(); points.len()],
        };
        let index: Vec<usize> = points.iter().map(|p| set.index(set.key(p).expect("inside"))).collect();
        for &i in &index {
            set.starts[i + 1] += 1;
        }
        for i in 1..set.starts.len() {
            set.starts[i] += set.starts[i - 1];
        }
        let mut fill = set.starts.clone();
        for (p, &i) in points.iter().zip(&index) {
            set.points[fill[i] as usize] = *p;
            fill[i] += 1;
        }
        set
    }

    /// The cell of `p`, if inside the grid.
    fn key(&self, p: &Point3<f32>) -> Option<[usize; 3]> {
        let mut key = [0; 3];
        for a in 0..3 {
            let k = ((p[a] - self.corner[a]) / self.cell).floor();
            if !(0.0..self.dims[a] as f32).contains(&k) {
                return None;
            }
            key[a] = k as usize;
        }
        Some(key)
    }

    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// Whether a point lies within the tolerance of `p`.
    pub(crate) fn any_near(&self, p: &Point3<f32>) -> bool {
        let Some([x, y, z]) = self.key(p) else {
            return false;
        };
        let range = |k: usize, dim: usize| k.saturating_sub(1)..=(k + 1).min(dim - 1);
        range(z, self.dims[2]).any(|k| {
            range(y, self.dims[1]).any(|j| {
                range(x, self.dims[0]).any(|i| {
                    let c = self.index([i, j, k]);
                    self.points[self.starts[c] as usize..self.starts[c + 1] as usize]
                        .iter()
                        .any(|q| (q - p).norm_squared() <= self.tolerance_sq)
                })
            })
        })
    }

    /// The squared distance from `p` to its nearest point, if within the tolerance.
    pub(crate) fn nearest_sq(&self, p: &Point3<f32>) -> Option<f32> {
        // A point within the tolerance of one inside the grid lies in the grid (its margin is
        // the tolerance).
        let [x, y, z] = self.key(p)?;
        let range = |k: usize, dim: usize| k.saturating_sub(1)..=(k + 1).min(dim - 1);
        let mut nearest = f32::INFINITY;
        for k in range(z, self.dims[2]) {
            for j in range(y, self.dims[1]) {
                for i in range(x, self.dims[0]) {
                    let c = self.index([i, j, k]);
                    for q in &self.points[self.starts[c] as usize..self.starts[c + 1] as usize] {
                        nearest = nearest.min((q - p).norm_squared());
                    }
                }
            }
        }
        (nearest <= self.tolerance_sq).then_some(nearest)
    }
}
