//! Putative correspondences of the all-to-all front end and their pairwise-length consistency
//! graph (TEASER++'s "TIM" pruning, without scale).
//!
//! A correspondence k = (i, j) claims that source point a_i lands on template point b_j. A rigid
//! motion keeps lengths, so two inlier correspondences k, l satisfy
//! | |b_l − b_k| − |a_l − a_k| | ≤ 2ε when each point is off by at most ε (`noise_bound`). The
//! graph has one vertex per correspondence and an edge for every consistent pair; the inliers
//! form a clique of it.

use nalgebra::Point3;
use rand::Rng;
use rand::seq::index;

use super::max_clique::Graph;

/// A correspondence: (source index, template index).
pub type Correspondence = (u32, u32);

/// All `source_count × template_count` pairs, or `max_pairs` of them drawn uniformly without
/// replacement from `rng`. Sorted by source index, then template index.
pub fn all_to_all_pairs<R: Rng + ?Sized>(
    source_count: usize,
    template_count: usize,
    max_pairs: usize,
    rng: &mut R,
) -> Vec<Correspondence> {
    let total = source_count * template_count;
    let flat: Vec<usize> = if total <= max_pairs {
        (0..total).collect()
    } else {
        let mut drawn = index::sample(rng, total, max_pairs).into_vec();
        drawn.sort_unstable();
        drawn
    };
    flat.into_iter()
        .map(|k| ((k / template_count) as u32, (k % template_count) as u32))
        .collect()
}

/// The consistency graph of `pairs`: an edge between k and l when
/// | |b_l − b_k| − |a_l − a_k| | ≤ 2·`noise_bound`.
pub fn consistency_graph(
    source: &[Point3<f32>],
    template: &[Point3<f32>],
    pairs: &[Correspondence],
    noise_bound: f32,
) -> Graph {
    let source_lengths = pairwise_lengths(source);
    let template_lengths = pairwise_lengths(template);
    let (n_source, n_template) = (source.len(), template.len());
    let tolerance = 2.0 * noise_bound;
    let mut adjacency: Vec<Vec<u32>> = vec![Vec::new(); pairs.len()];
    for k in 0..pairs.len() {
        let (ak, bk) = (pairs[k].0 as usize, pairs[k].1 as usize);
        let source_row = &source_lengths[ak * n_source..(ak + 1) * n_source];
        let template_row = &template_lengths[bk * n_template..(bk + 1) * n_template];
        let mut row = Vec::new();
        for (l, &(al, bl)) in pairs.iter().enumerate().skip(k + 1) {
            if (template_row[bl as usize] - source_row[al as usize]).abs() <= tolerance {
                row.push(l as u32);
            }
        }
        for &l in &row {
            adjacency[l as usize].push(k as u32);
        }
        // Lower neighbours (pushed by earlier rows) come first, so each list stays sorted.
        adjacency[k].extend(row);
    }
    Graph::from_sorted_adjacency(adjacency)
}

/// Row-major |p_j − p_i| for all i, j.
fn pairwise_lengths(points: &[Point3<f32>]) -> Vec<f32> {
    points
        .iter()
        .flat_map(|p| points.iter().map(move |q| (q - p).norm()))
        .collect()
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn small_products_are_kept_whole_and_large_ones_sampled_without_repeats() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        assert_eq!(all_to_all_pairs(2, 2, 10, &mut rng), [(0, 0), (0, 1), (1, 0), (1, 1)]);
        let sampled = all_to_all_pairs(100, 100, 500, &mut rng);
        assert_eq!(sampled.len(), 500);
        assert!(sampled.windows(2).all(|w| w[0] < w[1]), "sorted and distinct");
        let again = all_to_all_pairs(100, 100, 500, &mut ChaCha8Rng::seed_from_u64(1));
        let first = all_to_all_pairs(100, 100, 500, &mut ChaCha8Rng::seed_from_u64(1));
        assert_eq!(again, first, "same seed, same pairs");
    }

    #[test]
    fn rigidly_moved_matches_are_consistent_and_a_wrong_match_is_not() {
        let source = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
        ];
        // The template is the source rotated 90° about z and shifted, plus one stray point.
        let template = [
            Point3::new(5.0, 0.0, 0.0),
            Point3::new(5.0, 1.0, 0.0),
            Point3::new(3.0, 0.0, 0.0),
            Point3::new(9.0, 9.0, 9.0),
        ];
        let pairs = [(0, 0), (1, 1), (2, 2), (2, 3)];
        let graph = consistency_graph(&source, &template, &pairs, 0.01);
        assert!(
            graph.has_edge(0, 1) && graph.has_edge(0, 2) && graph.has_edge(1, 2),
            "true matches agree"
        );
        assert!(graph.neighbours(3).is_empty(), "the stray match agrees with none");
    }
}
