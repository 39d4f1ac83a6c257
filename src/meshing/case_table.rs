//! The marching-cubes case table: for each of the 256 inside/outside patterns of a cube's corners,
//! the surface loops to emit and how to triangulate them.
//!
//! Instead of a hand-typed table, the 256 cases are derived once from one rule, so the table is
//! provably crack-free:
//!
//! 1. On each of the six faces, the corners' signs give 0, 1 or 2 contour segments between the
//!    face's crossing edges. On an *ambiguous* face (diagonal corners inside) the inside corners
//!    are joined, i.e. the segments cut off the two outside corners. The rule depends only on
//!    the face's four corners, so the two cubes sharing a face draw the same segments there.
//! 2. Each segment is oriented with the inside on its left as seen from outside the cube. Every
//!    crossing edge lies on two faces and starts one segment and ends the other, so the
//!    segments chain into closed loops: the boundaries of the inside patches of the cube surface.
//! 3. Each loop is reversed (so the surface normal points from inside to outside) and filled by
//!    a fan from a vertex that shares no face with a non-neighbouring loop vertex, or, when no
//!    such vertex exists, by a fan around the loop's centroid. Fan diagonals therefore never lie
//!    on a cube face, and every mesh edge on a face is a contour segment shared by exactly the
//!    two cubes beside it: the mesh is closed and manifold along cube faces.
//!
//! Corner `c` of a cube sits at offset `(c & 1, c >> 1 & 1, c >> 2 & 1)`; edges are numbered by
//! axis (`0..4` along x, `4..8` along y, `8..12` along z), see [`EDGE_CORNERS`].

use std::sync::LazyLock;

/// The two corners of each of the 12 cube edges, lower corner first.
#[rustfmt::skip]
pub const EDGE_CORNERS: [[u8; 2]; 12] = [
    [0, 1], [2, 3], [4, 5], [6, 7], // along x
    [0, 2], [1, 3], [4, 6], [5, 7], // along y
    [0, 4], [1, 5], [2, 6], [3, 7], // along z
];

/// The four corners of each face in cyclic order, and the face's outward axis and side.
const FACES: [([u8; 4], usize, u8); 6] = [
    ([0, 2, 6, 4], 0, 0),
    ([1, 3, 7, 5], 0, 1),
    ([0, 1, 5, 4], 1, 0),
    ([2, 3, 7, 6], 1, 1),
    ([0, 1, 3, 2], 2, 0),
    ([4, 5, 7, 6], 2, 1),
];

/// How a loop is filled with triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fill {
    /// Triangles `(e₀, eᵢ, eᵢ₊₁)`: a fan from the loop's first vertex.
    Fan,
    /// Triangles `(eᵢ, eᵢ₊₁, centroid)` around one extra vertex at the loop vertices' mean.
    Centroid,
}

/// One surface loop of a case: crossing edges in output order (normals point outward).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SurfaceLoop {
    /// Cube edge ids, in the order the triangles use them.
    pub edges: Vec<u8>,
    /// How the loop is triangulated.
    pub fill: Fill,
}

/// The loops of every case, indexed by the case byte (bit `c` set = corner `c` inside).
pub static CASES: LazyLock<Vec<Vec<SurfaceLoop>>> = LazyLock::new(|| (0..=255).map(case_loops).collect());

/// Index of the edge joining corners `a` and `b` (which must be cube neighbours).
fn edge_between(a: u8, b: u8) -> u8 {
    let pair = [a.min(b), a.max(b)];
    let index = EDGE_CORNERS
        .iter()
        .position(|e| *e == pair)
        .expect("face corners are cube neighbours");
    index as u8
}

/// Position of corner `c` in the unit cube.
fn corner_position(c: u8) -> [f32; 3] {
    [f32::from(c & 1), f32::from(c >> 1 & 1), f32::from(c >> 2 & 1)]
}

/// Midpoint of edge `e`.
fn edge_midpoint(e: u8) -> [f32; 3] {
    let [a, b] = EDGE_CORNERS[usize::from(e)].map(corner_position);
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])]
}

/// The faces (index into [`FACES`]) that edge `e` lies on.
fn faces_of_edge(e: u8) -> impl Iterator<Item = usize> {
    let [a, b] = EDGE_CORNERS[usize::from(e)];
    (0..6).filter(move |&f| FACES[f].0.contains(&a) && FACES[f].0.contains(&b))
}

/// The directed contour segments `(from_edge, to_edge)` of `case` on one face, inside on the left
/// seen from outside the cube.
fn face_segments(case: u8, face: usize) -> Vec<(u8, u8)> {
    let (corners, axis, side) = FACES[face];
    let inside = |c: u8| case >> c & 1 == 1;
    let face_edge = |k: usize| edge_between(corners[k], corners[(k + 1) % 4]);
    let crossing: Vec<usize> = (0..4)
        .filter(|&k| inside(corners[k]) != inside(corners[(k + 1) % 4]))
        .collect();
    // Each segment with a reference corner whose side of the segment has that corner's status.
    let undirected: Vec<(u8, u8, u8)> = match crossing.as_slice() {
        [k1, k2] => {
            let reference = if k2 - k1 == 1 {
                corners[*k2] // adjacent edges: they share corner k2
            } else if (*k1, *k2) == (0, 3) {
                corners[0]
            } else {
                corners[k1 + 1] // opposite edges: the face is cut in two halves
            };
            vec![(face_edge(*k1), face_edge(*k2), reference)]
        }
        [_, _, _, _] => (0..4)
            .filter(|&k| !inside(corners[k]))
            .map(|k| (face_edge((k + 3) % 4), face_edge(k), corners[k]))
            .collect(),
        _ => Vec::new(),
    };
    let normal_sign = if side == 0 { -1.0 } else { 1.0 };
    undirected
        .into_iter()
        .map(|(a, b, reference)| {
            let (pa, pb, pc) = (edge_midpoint(a), edge_midpoint(b), corner_position(reference));
            let (u, v) = (sub(pb, pa), sub(pc, pa));
            let cross_along_normal =
                normal_sign * (u[(axis + 1) % 3] * v[(axis + 2) % 3] - u[(axis + 2) % 3] * v[(axis + 1) % 3]);
            // Reference inside → it must lie on the left (positive), outside → on the right.
            if (cross_along_normal > 0.0) == inside(reference) {
                (a, b)
            } else {
                (b, a)
            }
        })
        .collect()
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The loops of one case, reversed for output and with their fill chosen.
fn case_loops(case: u8) -> Vec<SurfaceLoop> {
    let mut next: [Option<u8>; 12] = [None; 12];
    for face in 0..6 {
        for (from, to) in face_segments(case, face) {
            debug_assert!(
                next[usize::from(from)].is_none(),
                "case {case}: edge {from} starts two segments"
            );
            next[usize::from(from)] = Some(to);
        }
    }
    let mut visited = [false; 12];
    let mut loops = Vec::new();
    for start in 0..12u8 {
        if visited[usize::from(start)] || next[usize::from(start)].is_none() {
            continue;
        }
        let mut edges = Vec::new();
        let mut e = start;
        while !visited[usize::from(e)] {
            visited[usize::from(e)] = true;
            edges.push(e);
            e = next[usize::from(e)].expect("every crossing edge ends one segment and starts another");
        }
        debug_assert_eq!(e, start, "case {case}: segments chain into closed loops");
        edges.reverse();
        loops.push(with_fill(edges));
    }
    loops
}

/// Chooses the fill of a loop: a fan from the first vertex whose diagonals avoid the cube faces,
/// rotated to the front, or a centroid fan.
fn with_fill(edges: Vec<u8>) -> SurfaceLoop {
    let n = edges.len();
    let shares_face = |a: u8, b: u8| faces_of_edge(a).any(|f| faces_of_edge(b).any(|g| g == f));
    let good_start = (0..n).find(|&s| (2..n.saturating_sub(1)).all(|d| !shares_face(edges[s], edges[(s + d) % n])));
    match good_start {
        Some(s) => SurfaceLoop {
            edges: edges[s..].iter().chain(&edges[..s]).copied().collect(),
            fill: Fill::Fan,
        },
        None => SurfaceLoop {
            edges,
            fill: Fill::Centroid,
        },
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;

    #[test]
    fn empty_and_full_cubes_have_no_surface() {
        assert!(CASES[0].is_empty(), "all outside");
        assert!(CASES[255].is_empty(), "all inside");
    }

    #[test]
    fn a_single_inside_corner_is_cut_off_by_one_outward_triangle() {
        let loops = &CASES[1];
        assert_eq!(loops.len(), 1, "one loop around corner 0");
        let [a, b, c] = [0, 1, 2].map(|i| edge_midpoint(loops[0].edges[i]));
        let (u, v) = (sub(b, a), sub(c, a));
        let normal = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        assert!(
            normal.iter().all(|&x| x > 0.0),
            "normal points away from the inside corner: {normal:?}"
        );
    }

    #[test]
    fn every_case_uses_each_crossing_edge_in_exactly_one_loop() {
        for case in 0..=255u8 {
            let crossing: Vec<u8> = (0..12u8)
                .filter(|&e| {
                    let [a, b] = EDGE_CORNERS[usize::from(e)];
                    (case >> a & 1) != (case >> b & 1)
                })
                .collect();
            let mut used: Vec<u8> = CASES[usize::from(case)].iter().flat_map(|l| l.edges.clone()).collect();
            used.sort_unstable();
            assert_eq!(used, crossing, "case {case} visits each crossing edge once");
        }
    }

    #[test]
    fn complementary_cases_differ_only_on_ambiguous_faces() {
        // A case and its complement have the same crossing edges; with no ambiguous face they
        // draw the same segments with opposite orientation.
        let segments =
            |case: u8| -> BTreeMap<usize, Vec<(u8, u8)>> { (0..6).map(|f| (f, face_segments(case, f))).collect() };
        let (case, complement) = (0b0000_0011u8, !0b0000_0011u8);
        for (face, forward) in segments(case) {
            let mut backward: Vec<(u8, u8)> = segments(complement)[&face].iter().map(|&(a, b)| (b, a)).collect();
            let mut forward = forward;
            forward.sort_unstable();
            backward.sort_unstable();
            assert_eq!(forward, backward, "face {face} of case {case}");
        }
    }

    #[test]
    fn fan_diagonals_never_join_two_vertices_of_one_face() {
        for (case, loops) in CASES.iter().enumerate() {
            for l in loops.iter().filter(|l| l.fill == Fill::Fan) {
                let n = l.edges.len();
                for d in 2..n.saturating_sub(1) {
                    let shared = faces_of_edge(l.edges[0]).any(|f| faces_of_edge(l.edges[d]).any(|g| g == f));
                    assert!(
                        !shared,
                        "case {case}: diagonal {}–{} lies on a face",
                        l.edges[0], l.edges[d]
                    );
                }
            }
        }
    }
}
