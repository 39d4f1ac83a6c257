//! Floating fragments: the connected pieces of a mesh and the mesh without the small ones.
//!
//! Two triangles belong to one piece when they share a vertex (marching cubes shares the vertices
//! of neighbouring triangles, so a piece is a connected patch of surface). A field that is
//! slightly occupied somewhere away from the object leaves a small closed blob there: a piece of a
//! few square centimetres that no camera saw and that counts against accuracy. A piece is kept
//! when its area is at least `min_share` of the whole mesh's area, so a lamp's shade stays even
//! where its thin pole broke off at the meshing resolution, and a blob of 0.1 % goes.

use super::TriangleMesh;

impl TriangleMesh {
    /// Connected piece of every triangle (pieces numbered from 0 in the order of their first
    /// triangle) and the number of pieces.
    pub fn pieces(&self) -> (Vec<u32>, usize) {
        let mut parent: Vec<u32> = (0..self.vertices.len() as u32).collect();
        for t in &self.triangles {
            let a = root(&mut parent, t[0]);
            for &v in &t[1..] {
                let b = root(&mut parent, v);
                parent[b as usize] = a;
            }
        }
        let mut piece_of_root = vec![u32::MAX; self.vertices.len()];
        let mut count = 0;
        let pieces = self
            .triangles
            .iter()
            .map(|t| {
                let r = root(&mut parent, t[0]) as usize;
                if piece_of_root[r] == u32::MAX {
                    piece_of_root[r] = count;
                    count += 1;
                }
                piece_of_root[r]
            })
            .collect();
        (pieces, count as usize)
    }

    /// The mesh without the connected pieces whose area is below `min_share` of the mesh's
    /// area (see the module doc), and without the vertices only they used; colours follow
    /// their vertices. A `min_share` of 0 or less keeps every piece (the mesh is returned as it
    /// is, without a copy).
    pub fn without_fragments(self, min_share: f32) -> TriangleMesh {
        if min_share <= 0.0 || self.triangles.is_empty() {
            return self;
        }
        let (pieces, count) = self.pieces();
        let mut areas = vec![0.0f64; count];
        for (t, &p) in pieces.iter().enumerate() {
            areas[p as usize] += f64::from(self.triangle_area(t));
        }
        let total: f64 = areas.iter().sum();
        let keep: Vec<bool> = areas.iter().map(|&a| a >= f64::from(min_share) * total).collect();
        if keep.iter().all(|&k| k) {
            return self;
        }
        let mut new_index = vec![u32::MAX; self.vertices.len()];
        let mut out = TriangleMesh {
            colors: self.colors.as_ref().map(|_| Vec::new()),
            ..TriangleMesh::default()
        };
        for (t, &p) in self.triangles.iter().zip(&pieces) {
            if !keep[p as usize] {
                continue;
            }
            let mapped = t.map(|v| {
                let slot = &mut new_index[v as usize];
                if *slot == u32::MAX {
                    *slot = out.vertices.len() as u32;
                    out.vertices.push(self.vertices[v as usize]);
                    if let (Some(into), Some(from)) = (&mut out.colors, &self.colors) {
                        into.push(from[v as usize]);
                    }
                }
                *slot
            });
            out.triangles.push(mapped);
        }
        out
    }
}

/// The root of `v` in the union-find forest `parent`, halving the path on the way.
fn root(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        let grand = parent[parent[v as usize] as usize];
        parent[v as usize] = grand;
        v = grand;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::primitives::block;

    /// A 1 m cube (6 m²) with a 5 cm cube (0.015 m², 0.25 %) floating beside it, each its own
    /// colour.
    fn cube_and_blob() -> TriangleMesh {
        let big = block(0.0, 0.0, 0.0, [1.0, 1.0, 1.0]).with_uniform_color([200, 10, 10]);
        let blob = block(2.0, 0.0, 0.0, [0.05, 0.05, 0.05]).with_uniform_color([10, 10, 200]);
        TriangleMesh::merged([&blob, &big])
    }

    #[test]
    fn pieces_are_the_connected_patches() {
        let (pieces, count) = cube_and_blob().pieces();
        assert_eq!(count, 2);
        assert_eq!(pieces.len(), 24);
        assert!(pieces[..12].iter().all(|&p| p == 0) && pieces[12..].iter().all(|&p| p == 1));
    }

    #[test]
    fn a_small_floating_piece_goes_with_its_vertices_and_the_rest_stays_whole() {
        let mesh = cube_and_blob();
        let kept = mesh.without_fragments(0.01);
        assert_eq!(kept.validate(), Ok(()));
        assert_eq!(kept.triangles.len(), 12, "the blob's 12 triangles went");
        assert_eq!(kept.vertices.len(), 8, "and its 8 vertices");
        assert!((kept.area() - 6.0).abs() < 1e-4, "the cube is whole: {}", kept.area());
        let colors = kept.colors.as_ref().expect("coloured");
        assert!(
            colors.iter().all(|&c| c == [200, 10, 10]),
            "colours follow their vertices"
        );
        assert!(kept.vertices.iter().all(|v| v.x < 1.0), "nothing of the blob remains");
    }

    #[test]
    fn pieces_above_the_share_stay_and_a_share_of_zero_keeps_everything() {
        let mesh = cube_and_blob();
        assert_eq!(
            mesh.clone().without_fragments(0.002),
            mesh,
            "the blob is 0.25 % of the area"
        );
        assert_eq!(mesh.clone().without_fragments(0.0), mesh);
        let two = TriangleMesh::merged([
            &block(0.0, 0.0, 0.0, [1.0, 1.0, 1.0]),
            &block(3.0, 0.0, 0.0, [0.6, 0.6, 0.6]),
        ]);
        assert_eq!(
            two.clone().without_fragments(0.05),
            two,
            "a piece of a quarter of the area stays"
        );
        assert!(TriangleMesh::default().without_fragments(0.5).is_empty());
    }
}
