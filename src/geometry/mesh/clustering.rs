//! Vertex clustering: a lighter copy of a mesh for display, its vertices merged on a grid.
//!
//! Every vertex falls in one cubic cell of side `cell` (cells are aligned to the origin); the
//! vertices of a cell become one, at their mean position with their mean colour, numbered in
//! the order their cells first appear. A triangle whose corners land in fewer than three cells
//! is dropped. The surface moves by less than one cell; a 5 mm marching-cubes mesh clustered on
//! 1 cm keeps about a fifth of its vertices and triangles.

use std::collections::HashMap;

use nalgebra::{Point3, Vector3};

use super::TriangleMesh;

impl TriangleMesh {
    /// The mesh with its vertices merged on a grid of `cell` metres (see the module doc); a
    /// copy of the mesh when `cell` is not positive and finite.
    pub fn clustered(&self, cell: f32) -> TriangleMesh {
        if !(cell.is_finite() && cell > 0.0) {
            return self.clone();
        }
        let mut cluster_of_cell: HashMap<[i64; 3], u32> = HashMap::new();
        let mut sums: Vec<(Vector3<f64>, [u32; 3], u32)> = Vec::new();
        let mut cluster_of_vertex = Vec::with_capacity(self.vertices.len());
        for (i, v) in self.vertices.iter().enumerate() {
            let key = [v.x, v.y, v.z].map(|c| (f64::from(c) / f64::from(cell)).floor() as i64);
            let next = sums.len() as u32;
            let cluster = *cluster_of_cell.entry(key).or_insert(next);
            if cluster == next {
                sums.push((Vector3::zeros(), [0; 3], 0));
            }
            let (position, colour, count) = &mut sums[cluster as usize];
            *position += v.coords.cast::<f64>();
            if let Some(colours) = &self.colors {
                for (sum, c) in colour.iter_mut().zip(colours[i]) {
                    *sum += u32::from(c);
                }
            }
            *count += 1;
            cluster_of_vertex.push(cluster);
        }
        let vertices = sums
            .iter()
            .map(|(p, _, n)| Point3::from((p / f64::from(*n)).cast::<f32>()))
            .collect();
        let colors = self.colors.as_ref().map(|_| {
            sums.iter()
                .map(|(_, c, n)| c.map(|s| ((s + n / 2) / n) as u8))
                .collect()
        });
        let triangles = self
            .triangles
            .iter()
            .map(|t| t.map(|v| cluster_of_vertex[v as usize]))
            .filter(|[a, b, c]| a != b && b != c && a != c)
            .collect();
        TriangleMesh {
            vertices,
            triangles,
            colors,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat `n × n` grid of squares of side `step`, two triangles each, coloured by row.
    fn grid(n: u32, step: f32) -> TriangleMesh {
        let mut vertices = Vec::new();
        let mut colors = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                vertices.push(Point3::new(x as f32 * step + 0.0003, y as f32 * step + 0.0003, 0.5));
                colors.push([(y * 10) as u8, 100, 200]);
            }
        }
        let at = |x: u32, y: u32| y * (n + 1) + x;
        let mut triangles = Vec::new();
        for y in 0..n {
            for x in 0..n {
                triangles.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                triangles.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
            }
        }
        TriangleMesh {
            vertices,
            triangles,
            colors: Some(colors),
        }
    }

    #[test]
    fn a_fine_grid_clustered_on_a_coarser_cell_keeps_its_extent_with_fewer_triangles() {
        // 20 × 20 squares of 5 mm clustered on 1 cm: 2 × 2 vertices per cell.
        let fine = grid(20, 0.005);
        let coarse = fine.clustered(0.01);
        assert_eq!(coarse.vertices.len(), 11 * 11, "one vertex per occupied cell");
        assert!(
            coarse.triangles.len() < fine.triangles.len() / 3 && !coarse.triangles.is_empty(),
            "{} of {} triangles",
            coarse.triangles.len(),
            fine.triangles.len()
        );
        assert!(
            coarse.triangles.iter().all(|[a, b, c]| a != b && b != c && a != c),
            "no degenerate triangle"
        );
        let (fb, cb) = (fine.bounds().expect("fine"), coarse.bounds().expect("coarse"));
        for axis in 0..3 {
            assert!(
                (fb.min[axis] - cb.min[axis]).abs() <= 0.01,
                "min within a cell on axis {axis}"
            );
            assert!(
                (fb.max[axis] - cb.max[axis]).abs() <= 0.01,
                "max within a cell on axis {axis}"
            );
        }
        let area_ratio = coarse.area() / fine.area();
        assert!(
            (0.8..=1.05).contains(&area_ratio),
            "the surface stays: area ratio {area_ratio}"
        );
        let colors = coarse.colors.as_ref().expect("colours kept");
        assert_eq!(colors.len(), coarse.vertices.len());
        assert_eq!(colors[0], [5, 100, 200], "mean colour of rows 0 and 1 (0 and 10)");
    }

    #[test]
    fn a_cell_finer_than_the_mesh_keeps_it_and_no_cell_copies_it() {
        let fine = grid(4, 0.05);
        let same = fine.clustered(0.001);
        assert_eq!(same.vertices.len(), fine.vertices.len());
        assert_eq!(same.triangles, fine.triangles);
        assert_eq!(fine.clustered(0.0), fine);
        assert_eq!(fine.clustered(f32::NAN), fine);
    }
}
