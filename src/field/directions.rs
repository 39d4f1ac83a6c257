//! The 21 fixed unit directions that initialise the encoding matrix `B` (21 × 3).
//!
//! They are the 42 vertices of the once-subdivided icosahedron (the frequency-2 geodesic
//! sphere), taken once per antipodal pair: the 12 icosahedron vertices give 6 directions and the
//! 30 edge midpoints (pushed out to the sphere) give 15. A direction and its opposite give the
//! same features up to sign (sin is odd), so only one of each pair is kept.
//!
//! Construction (no table): the icosahedron vertices are the cyclic permutations of
//! (0, ±1, ±φ), φ = (1 + √5)/2; two vertices share an edge when they are 2 apart. Each point is
//! normalised, the representative of a pair is the one whose first non-zero coordinate (x, then
//! y, then z) is positive, and the 21 representatives are sorted by descending (x, y, z).
//!
//! vMAP's `UniDirsEmbed` uses the same 21 lines (same set up to sign, other order); the order
//! and signs do not matter for training, since the first layer's weights are random.

/// Number of encoding directions (rows of `B`).
pub const NUM_DIRECTIONS: usize = 21;

/// The 21 fixed unit directions (rows of the initial `B`), in f64.
pub fn icosphere_directions() -> [[f64; 3]; NUM_DIRECTIONS] {
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices = Vec::with_capacity(12);
    for a in [-1.0, 1.0] {
        for b in [-phi, phi] {
            vertices.push([0.0, a, b]);
            vertices.push([a, b, 0.0]);
            vertices.push([b, 0.0, a]);
        }
    }
    let mut points: Vec<[f64; 3]> = vertices.clone();
    for (i, p) in vertices.iter().enumerate() {
        for q in &vertices[i + 1..] {
            let d2: f64 = (0..3).map(|c| (p[c] - q[c]).powi(2)).sum();
            if (d2 - 4.0).abs() < 1e-9 {
                points.push([(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, (p[2] + q[2]) / 2.0]);
            }
        }
    }
    let mut reps: Vec<[f64; 3]> = points
        .into_iter()
        .map(normalised)
        .filter(|p| p.iter().find(|c| c.abs() > 1e-12).is_some_and(|c| *c > 0.0))
        .collect();
    reps.sort_by(|a, b| b.partial_cmp(a).unwrap_or(std::cmp::Ordering::Equal));
    let mut out = [[0.0; 3]; NUM_DIRECTIONS];
    debug_assert_eq!(reps.len(), NUM_DIRECTIONS, "42 geodesic points form 21 antipodal pairs");
    for (o, r) in out.iter_mut().zip(reps) {
        *o = r;
    }
    out
}

fn normalised(p: [f64; 3]) -> [f64; 3] {
    let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    [p[0] / n, p[1] / n, p[2] / n]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    #[test]
    fn there_are_21_distinct_unit_lines() {
        let dirs = icosphere_directions();
        for (i, a) in dirs.iter().enumerate() {
            assert!((dot(*a, *a) - 1.0).abs() < 1e-12, "direction {i} is a unit vector");
            for b in &dirs[i + 1..] {
                assert!(dot(*a, *b).abs() < 0.95, "no two directions are (anti)parallel");
            }
        }
    }

    #[test]
    fn the_set_contains_the_axes_and_icosahedron_vertices() {
        let dirs = icosphere_directions();
        let phi = (1.0 + 5f64.sqrt()) / 2.0;
        let has = |p: [f64; 3]| dirs.iter().any(|d| (dot(*d, normalised(p)).abs() - 1.0).abs() < 1e-12);
        // Edge midpoints of the icosahedron include the coordinate axes.
        assert!(has([1.0, 0.0, 0.0]) && has([0.0, 1.0, 0.0]) && has([0.0, 0.0, 1.0]));
        assert!(has([0.0, 1.0, phi]) && has([phi, 0.0, 1.0]) && has([1.0, phi, 0.0]));
        // vMAP's list starts with (0.8506508, 0, 0.5257311) = normalised (φ, 0, 1).
        assert!(has([0.8506508, 0.0, 0.5257311].map(|c: f64| c * 1.0)));
    }

    #[test]
    fn neighbouring_lines_are_evenly_spread() {
        // The closest pair of lines on the frequency-2 geodesic sphere is 31.7° apart
        // (vertex to adjacent edge midpoint: half the 63.4° edge angle).
        let dirs = icosphere_directions();
        let max_cos = dirs
            .iter()
            .enumerate()
            .flat_map(|(i, a)| dirs[i + 1..].iter().map(move |b| dot(*a, *b).abs()))
            .fold(0.0, f64::max);
        let angle = max_cos.acos().to_degrees();
        assert!((angle - 31.717).abs() < 0.01, "closest lines are {angle}° apart");
    }
}
