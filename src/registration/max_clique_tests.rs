use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

fn random_graph(n: usize, density: f64, rng: &mut ChaCha8Rng) -> Graph {
    let mut edges = Vec::new();
    for a in 0..n as u32 {
        for b in a + 1..n as u32 {
            if rng.random::<f64>() < density {
                edges.push((a, b));
            }
        }
    }
    Graph::from_edges(n, edges)
}

fn is_clique(graph: &Graph, vertices: &[u32]) -> bool {
    vertices
        .iter()
        .enumerate()
        .all(|(i, &a)| vertices[i + 1..].iter().all(|&b| graph.has_edge(a, b)))
}

/// ω(G) by enumerating every vertex subset.
fn brute_force_clique_number(graph: &Graph) -> usize {
    let n = graph.vertex_count();
    (0u32..1 << n)
        .filter(|mask| {
            let members: Vec<u32> = (0..n as u32).filter(|v| mask & (1 << v) != 0).collect();
            is_clique(graph, &members)
        })
        .map(|mask| mask.count_ones() as usize)
        .max()
        .unwrap_or(0)
}

#[test]
fn the_maximum_clique_matches_brute_force_on_small_random_graphs() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for trial in 0..60 {
        let n = 4 + trial % 13;
        let density = [0.2, 0.5, 0.8][trial % 3];
        let graph = random_graph(n, density, &mut rng);
        let clique = maximum_clique(&graph, u64::MAX);
        assert!(clique.proven_maximum, "trial {trial}: unlimited search finishes");
        assert!(is_clique(&graph, &clique.vertices), "trial {trial}: result is a clique");
        assert_eq!(
            clique.vertices.len(),
            brute_force_clique_number(&graph),
            "trial {trial}: size is ω(G)"
        );
    }
}

#[test]
fn a_planted_clique_is_found_in_a_large_sparse_graph() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let n = 2000;
    let mut edges: Vec<(u32, u32)> = (0..20_000)
        .map(|_| (rng.random_range(0..n), rng.random_range(0..n)))
        .collect();
    let planted: Vec<u32> = (0..25).map(|i| i * 79 + 3).collect();
    for (i, &a) in planted.iter().enumerate() {
        for &b in &planted[i + 1..] {
            edges.push((a, b));
        }
    }
    let clique = maximum_clique(&Graph::from_edges(n as usize, edges), 1_000_000);
    assert_eq!(clique.vertices, planted, "the planted clique is the unique maximum");
    assert!(clique.proven_maximum);
}

#[test]
fn core_numbers_of_a_triangle_with_a_tail() {
    // Triangle 0-1-2 and a path 2-3-4: the triangle is the 2-core.
    let graph = Graph::from_edges(5, [(0, 1), (1, 2), (0, 2), (2, 3), (3, 4)]);
    assert_eq!(core_numbers(&graph).core, [2, 2, 2, 1, 1]);
}

#[test]
fn a_spent_budget_falls_back_to_a_valid_clique() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let graph = random_graph(120, 0.5, &mut rng);
    let clique = maximum_clique(&graph, 1);
    assert!(!clique.proven_maximum, "one node is not enough for this graph");
    assert!(is_clique(&graph, &clique.vertices), "the fallback is still a clique");
    assert!(
        clique.vertices.len() >= 3,
        "the greedy clique of a dense graph is not trivial"
    );
}
