//! Marching cubes: the iso-surface `value = iso` of a dense scalar grid as a closed, welded,
//! outward-oriented triangle mesh.
//!
//! "Inside" means `value > iso` (occupancy convention; pass `−sdf` for a signed distance whose
//! inside is negative). NaN counts as outside. The grid is padded with one layer of outside
//! samples on every side, so a surface touching the border is closed by a cap at the border
//! samples. Each cube looks its corner pattern up in [`CASES`], whose loops are crack-free
//! between neighbours; vertices are created once per grid edge (welded by edge id), placed by
//! linear interpolation clamped to `[ε, 1 − ε]` of the edge so that no triangle collapses.
//!
//! [`IsoSurfaceExtractor`] consumes the grid one z-layer at a time and keeps only two layers
//! (and the vertex ids on their edges) in memory; [`marching_cubes`] runs it on a full grid.

use nalgebra::Point3;

use super::case_table::{CASES, EDGE_CORNERS, Fill};
use super::sample_grid::SampleGrid;
use crate::error::{CatmapError, Result};
use crate::geometry::mesh::TriangleMesh;

/// Smallest fraction of an edge between a vertex and the edge's end samples.
const EDGE_EPSILON: f64 = 1e-3;
/// Marks an edge without a vertex yet.
const NO_VERTEX: u32 = u32::MAX;
/// Value of the padding samples around the grid: outside for any iso level.
const PAD: f32 = f32::NEG_INFINITY;
/// Spreads the 4 flags of a cube's x = 0 corners (bit k = corner 2k: y from bit 0, z from bit 1
/// of k) onto their corner bits of the case byte; shifted left by one for the x = 1 corners.
const SPREAD: [u8; 16] = {
    let mut table = [0u8; 16];
    let mut m = 0;
    while m < 16 {
        table[m] = ((m & 1) | (m & 2) << 1 | (m & 4) << 2 | (m & 8) << 3) as u8;
        m += 1;
    }
    table
};

/// The iso-surface of a full grid (`values` x fastest, see [`SampleGrid`]), in the grid's frame.
/// Errors when the grid is invalid or `values` has the wrong length.
pub fn marching_cubes(values: &[f32], grid: &SampleGrid, iso: f32) -> Result<TriangleMesh> {
    if values.len() != grid.len() {
        return Err(CatmapError::mismatch(
            format!("values of a {:?} grid", grid.dims),
            grid.len(),
            values.len(),
        ));
    }
    let mut extractor = IsoSurfaceExtractor::new(*grid, iso)?;
    for layer in values.chunks_exact(grid.layer_len()) {
        extractor.push_layer(layer)?;
    }
    extractor.finish()
}

/// Streaming marching cubes: push the grid's z-layers in order, then [`finish`](Self::finish).
#[derive(Debug)]
pub struct IsoSurfaceExtractor {
    grid: SampleGrid,
    iso: f32,
    /// Padded layer width and height (`nx + 2`, `ny + 2`).
    padded: [usize; 2],
    /// Padded z index of `below` (0 = the padding layer under the grid).
    below_z: usize,
    below: Layer,
    above: Layer,
    /// Scratch: per x, the inside flags of the 4 samples of a cube row's vertical edge.
    columns: Vec<u8>,
    /// Vertex ids of the x-, y- and z-edges at `below`, at `above`, and between them.
    edges: EdgeVertices,
    vertices: Vec<Point3<f32>>,
    triangles: Vec<[u32; 3]>,
}

/// One padded z-layer of samples and their inside flags.
#[derive(Debug, Clone)]
struct Layer {
    values: Vec<f32>,
    inside: Vec<u8>,
    any_inside: bool,
}

impl Layer {
    fn padding(len: usize) -> Self {
        Self {
            values: vec![PAD; len],
            inside: vec![0; len],
            any_inside: false,
        }
    }
}

/// Vertex ids per grid edge around the current cube layer, indexed by the edge's lower corner.
#[derive(Debug)]
struct EdgeVertices {
    x_below: Vec<u32>,
    y_below: Vec<u32>,
    x_above: Vec<u32>,
    y_above: Vec<u32>,
    z_between: Vec<u32>,
}

impl IsoSurfaceExtractor {
    /// An extractor for `grid` at level `iso`. Errors on an invalid grid or a non-finite level.
    pub fn new(grid: SampleGrid, iso: f32) -> Result<Self> {
        grid.validate()?;
        if !iso.is_finite() {
            return Err(CatmapError::bad_value("the iso level", iso, "be finite"));
        }
        let padded = [grid.dims[0] + 2, grid.dims[1] + 2];
        let len = padded[0] * padded[1];
        let none = vec![NO_VERTEX; len];
        Ok(Self {
            grid,
            iso,
            padded,
            below_z: 0,
            below: Layer::padding(len),
            above: Layer::padding(len),
            columns: Vec::with_capacity(padded[0]),
            edges: EdgeVertices {
                x_below: none.clone(),
                y_below: none.clone(),
                x_above: none.clone(),
                y_above: none.clone(),
                z_between: none,
            },
            vertices: Vec::new(),
            triangles: Vec::new(),
        })
    }

    /// Number of z-layers pushed so far.
    pub fn layers_pushed(&self) -> usize {
        self.below_z
    }

    /// Adds the next z-layer (`nx·ny` values, x fastest) and meshes the cubes below it.
    pub fn push_layer(&mut self, values: &[f32]) -> Result<()> {
        if self.below_z >= self.grid.dims[2] {
            return Err(CatmapError::mismatch(
                "z-layers pushed to the extractor",
                format!("at most {}", self.grid.dims[2]),
                self.below_z + 1,
            ));
        }
        if values.len() != self.grid.layer_len() {
            return Err(CatmapError::mismatch(
                format!("values of a z-layer of a {:?} grid", self.grid.dims),
                self.grid.layer_len(),
                values.len(),
            ));
        }
        let (nx, px) = (self.grid.dims[0], self.padded[0]);
        let above = &mut self.above;
        above.any_inside = false;
        for (j, row) in values.chunks_exact(nx).enumerate() {
            let start = (j + 1) * px + 1;
            above.values[start..start + nx].copy_from_slice(row);
        }
        for (flag, &v) in above.inside.iter_mut().zip(&above.values) {
            *flag = u8::from(v > self.iso);
            above.any_inside |= *flag == 1;
        }
        self.march_cube_layer();
        Ok(())
    }

    /// Meshes the last cube layer (against the padding) and returns the mesh in the grid's frame.
    /// Errors when fewer than `nz` layers were pushed.
    pub fn finish(mut self) -> Result<TriangleMesh> {
        if self.below_z != self.grid.dims[2] {
            return Err(CatmapError::mismatch(
                "z-layers pushed to the extractor",
                self.grid.dims[2],
                self.below_z,
            ));
        }
        self.above = Layer::padding(self.padded[0] * self.padded[1]);
        self.march_cube_layer();
        Ok(TriangleMesh::new(self.vertices, self.triangles))
    }

    /// Meshes the cubes between `below` and `above`, then moves up one layer.
    fn march_cube_layer(&mut self) {
        if self.below.any_inside || self.above.any_inside {
            let [px, py] = self.padded;
            let mut columns = std::mem::take(&mut self.columns);
            for j in 0..py - 1 {
                // The 4 inside flags of each vertical cube edge (x fixed) of this row of cubes.
                let (row0, row1) = (j * px, (j + 1) * px);
                columns.clear();
                columns.extend((0..px).map(|i| {
                    let (b, a) = (&self.below.inside, &self.above.inside);
                    b[row0 + i] | b[row1 + i] << 1 | a[row0 + i] << 2 | a[row1 + i] << 3
                }));
                for i in 0..px - 1 {
                    let (left, right) = (columns[i], columns[i + 1]);
                    if left == right && (left == 0 || left == 15) {
                        continue; // all outside or all inside
                    }
                    self.emit_cube(i, j, SPREAD[usize::from(left)] | SPREAD[usize::from(right)] << 1);
                }
            }
            self.columns = columns;
        }
        std::mem::swap(&mut self.below, &mut self.above);
        let e = &mut self.edges;
        std::mem::swap(&mut e.x_below, &mut e.x_above);
        std::mem::swap(&mut e.y_below, &mut e.y_above);
        for ids in [&mut e.x_above, &mut e.y_above, &mut e.z_between] {
            ids.fill(NO_VERTEX);
        }
        self.below_z += 1;
    }

    /// Padded layer index of corner `c` of cube `(i, j)`, and whether it lies in `above`.
    fn corner_slot(&self, i: usize, j: usize, c: u8) -> (usize, bool) {
        let slot = (j + usize::from(c >> 1 & 1)) * self.padded[0] + i + usize::from(c & 1);
        (slot, c >> 2 & 1 == 1)
    }

    fn corner_value(&self, i: usize, j: usize, c: u8) -> f32 {
        let (slot, up) = self.corner_slot(i, j, c);
        if up {
            self.above.values[slot]
        } else {
            self.below.values[slot]
        }
    }

    /// Emits the triangles of cube `(i, j)` in the current layer.
    fn emit_cube(&mut self, i: usize, j: usize, case: u8) {
        for surface_loop in &CASES[usize::from(case)] {
            let n = surface_loop.edges.len();
            let mut ids = [0u32; 12];
            for (id, &e) in ids.iter_mut().zip(&surface_loop.edges) {
                *id = self.edge_vertex(i, j, e);
            }
            match surface_loop.fill {
                Fill::Fan => self.triangles.extend((1..n - 1).map(|k| [ids[0], ids[k], ids[k + 1]])),
                Fill::Centroid => {
                    let sum = ids[..n].iter().fold(nalgebra::Vector3::zeros(), |acc, &v| {
                        acc + self.vertices[v as usize].coords
                    });
                    let centre = self.push_vertex(Point3::from(sum / n as f32));
                    self.triangles
                        .extend((0..n).map(|k| [ids[k], ids[(k + 1) % n], centre]));
                }
            }
        }
    }

    fn push_vertex(&mut self, p: Point3<f32>) -> u32 {
        let id =
            u32::try_from(self.vertices.len()).expect("grid size was checked to fit u32 and each edge has one vertex");
        self.vertices.push(p);
        id
    }

    /// The vertex on cube edge `e` of cube `(i, j)`, created on first use.
    fn edge_vertex(&mut self, i: usize, j: usize, e: u8) -> u32 {
        let [a, b] = EDGE_CORNERS[usize::from(e)];
        let (ci, cj) = (i + usize::from(a & 1), j + usize::from(a >> 1 & 1));
        let slot = cj * self.padded[0] + ci;
        let existing = self.edge_slot(e)[slot];
        if existing != NO_VERTEX {
            return existing;
        }
        let t = crossing(self.corner_value(i, j, a), self.corner_value(i, j, b), self.iso);
        let axis = usize::from(e / 4);
        let mut at = [
            ci as f64 - 1.0,
            cj as f64 - 1.0,
            (self.below_z + usize::from(a >> 2 & 1)) as f64 - 1.0,
        ];
        at[axis] += t;
        let id = self.push_vertex(self.grid.position(at[0], at[1], at[2]));
        self.edge_slot(e)[slot] = id;
        id
    }

    fn edge_slot(&mut self, e: u8) -> &mut Vec<u32> {
        let up = EDGE_CORNERS[usize::from(e)][0] >> 2 & 1 == 1;
        match (e / 4, up) {
            (0, false) => &mut self.edges.x_below,
            (0, true) => &mut self.edges.x_above,
            (1, false) => &mut self.edges.y_below,
            (1, true) => &mut self.edges.y_above,
            _ => &mut self.edges.z_between,
        }
    }
}

/// Where along an edge from value `a` to value `b` the level `iso` is crossed, in `[ε, 1 − ε]`.
/// Infinite ends pull the crossing to the finite end; NaN gives the midpoint.
fn crossing(a: f32, b: f32, iso: f32) -> f64 {
    let (da, db) = (f64::from(a) - f64::from(iso), f64::from(b) - f64::from(iso));
    let t = match (da.is_finite(), db.is_finite()) {
        (true, true) => da / (da - db),
        (false, true) => 1.0,
        (true, false) => 0.0,
        (false, false) => 0.5,
    };
    if t.is_nan() {
        0.5
    } else {
        t.clamp(EDGE_EPSILON, 1.0 - EDGE_EPSILON)
    }
}

#[cfg(test)]
#[path = "marching_cubes_tests.rs"]
mod tests;
