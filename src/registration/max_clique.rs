//! Maximum clique of the consistency graph, exact within a node budget (the role PMC plays in
//! TEASER++: k-core pruning, a greedy lower bound, then branch and bound with colouring bounds).
//!
//! 1. Core numbers k(v) (Batagelj–Zaversnik): a vertex of a clique of size s has k(v) ≥ s − 1,
//!    so ω ≤ max k + 1, and once a clique of size s is known every vertex with k(v) < s is pruned.
//! 2. Greedy lower bound: from each vertex, in decreasing core order, grow a clique by adding the
//!    candidate of highest core number and intersecting the candidates with its neighbours.
//! 3. Exact search: each vertex v, in degeneracy order, seeds a branch and bound over its later
//!    neighbours (every clique is found from its earliest vertex), bounded by a greedy colouring
//!    of the candidates (Tomita's MCQ): |C| + colours(P) ≤ |best| prunes the branch.
//!
//! The search expands at most `max_nodes` branch-and-bound nodes (a deterministic stand-in for
//! TEASER++'s time limit). When the budget runs out the largest clique found so far is returned
//! (never smaller than the greedy one) and [`Clique::proven_maximum`] is false.

/// An undirected graph as sorted adjacency lists.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Graph {
    adjacency: Vec<Vec<u32>>,
}

impl Graph {
    /// A graph on `vertex_count` vertices with the given edges (self-loops and repeats ignored).
    pub fn from_edges(vertex_count: usize, edges: impl IntoIterator<Item = (u32, u32)>) -> Self {
        let mut adjacency = vec![Vec::new(); vertex_count];
        for (a, b) in edges {
            if a != b {
                adjacency[a as usize].push(b);
                adjacency[b as usize].push(a);
            }
        }
        for list in &mut adjacency {
            list.sort_unstable();
            list.dedup();
        }
        Self { adjacency }
    }

    /// A graph from adjacency lists that are already sorted, duplicate-free and symmetric.
    pub(crate) fn from_sorted_adjacency(adjacency: Vec<Vec<u32>>) -> Self {
        debug_assert!(
            adjacency.iter().all(|l| l.windows(2).all(|w| w[0] < w[1])),
            "lists are sorted"
        );
        Self { adjacency }
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.adjacency.len()
    }

    /// Number of edges.
    pub fn edge_count(&self) -> usize {
        self.adjacency.iter().map(Vec::len).sum::<usize>() / 2
    }

    /// Sorted neighbours of `v`.
    pub fn neighbours(&self, v: u32) -> &[u32] {
        &self.adjacency[v as usize]
    }

    /// Whether `a` and `b` are adjacent.
    pub fn has_edge(&self, a: u32, b: u32) -> bool {
        self.adjacency[a as usize].binary_search(&b).is_ok()
    }
}

/// Core numbers and the degeneracy order they were found in.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cores {
    /// k(v): the largest k such that v belongs to the k-core (every vertex of degree ≥ k).
    pub core: Vec<u32>,
    /// Vertices in the order they were peeled (non-decreasing core number).
    pub order: Vec<u32>,
}

/// Core numbers by repeatedly peeling a vertex of minimum remaining degree, O(V + E).
pub fn core_numbers(graph: &Graph) -> Cores {
    let n = graph.vertex_count();
    let mut degree: Vec<usize> = (0..n).map(|v| graph.adjacency[v].len()).collect();
    let max_degree = degree.iter().copied().max().unwrap_or(0);
    // Bucket sort by degree: `vert` is sorted by degree, `pos[v]` is v's place in it, and
    // `bin[d]` is where the vertices of degree d start.
    let mut bin = vec![0usize; max_degree + 2];
    for &d in &degree {
        bin[d + 1] += 1;
    }
    for d in 1..bin.len() {
        bin[d] += bin[d - 1];
    }
    let mut next = bin.clone();
    let mut vert = vec![0u32; n];
    let mut pos = vec![0usize; n];
    for v in 0..n {
        pos[v] = next[degree[v]];
        vert[pos[v]] = v as u32;
        next[degree[v]] += 1;
    }
    for i in 0..n {
        let v = vert[i] as usize;
        for &u in &graph.adjacency[v] {
            let u = u as usize;
            if degree[u] > degree[v] {
                // Move u to the front of its bucket, then shrink its degree by one.
                let du = degree[u];
                let (pu, pw) = (pos[u], bin[du]);
                let w = vert[pw] as usize;
                vert.swap(pu, pw);
                pos[u] = pw;
                pos[w] = pu;
                bin[du] += 1;
                degree[u] -= 1;
            }
        }
    }
    Cores {
        core: degree.iter().map(|&d| d as u32).collect(),
        order: vert,
    }
}

/// Outcome of [`maximum_clique`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Clique {
    /// The clique's vertices, ascending.
    pub vertices: Vec<u32>,
    /// True when the search finished within its budget, so no larger clique exists.
    pub proven_maximum: bool,
}

/// A maximum clique of `graph`, exact unless the search needs more than `max_nodes` nodes.
///
/// Vertices are relabelled by degeneracy position and the adjacency is held as one bit row per
/// vertex (V²/8 bytes: 12.5 MB for the default 10 000 correspondences).
pub fn maximum_clique(graph: &Graph, max_nodes: u64) -> Clique {
    let n = graph.vertex_count();
    if n == 0 {
        return Clique {
            vertices: Vec::new(),
            proven_maximum: true,
        };
    }
    let cores = core_numbers(graph);
    let bits = BitGraph::new(graph, &cores);
    let mut best = bits.greedy_clique();
    let max_core = bits.core.last().copied().unwrap_or(0) as usize;
    let mut search = BranchAndBound {
        bits: &bits,
        nodes: 0,
        max_nodes,
        aborted: false,
    };
    if best.len() <= max_core {
        for v in 0..n {
            if search.aborted {
                break;
            }
            // Candidates: later vertices adjacent to v whose core admits a larger clique.
            let first = bits.first_with_core(best.len()).max(v + 1);
            let mut candidates = bits.row(v).to_vec();
            clear_below(&mut candidates, first);
            if (bits.core[v] as usize) < best.len() || popcount(&candidates) < best.len() {
                continue;
            }
            let mut clique = vec![v];
            search.expand(&mut clique, candidates, &mut best);
        }
    }
    let mut vertices: Vec<u32> = best.iter().map(|&v| cores.order[v]).collect();
    vertices.sort_unstable();
    Clique {
        vertices,
        proven_maximum: !search.aborted,
    }
}

/// The graph relabelled by degeneracy position (so core numbers are non-decreasing in the
/// label), with bitset adjacency rows.
struct BitGraph {
    words: usize,
    rows: Vec<u64>,
    core: Vec<u32>,
}

impl BitGraph {
    fn new(graph: &Graph, cores: &Cores) -> Self {
        let n = graph.vertex_count();
        let words = n.div_ceil(64);
        let mut position = vec![0usize; n];
        for (i, &v) in cores.order.iter().enumerate() {
            position[v as usize] = i;
        }
        let mut rows = vec![0u64; n * words];
        for (v, list) in graph.adjacency.iter().enumerate() {
            let row = &mut rows[position[v] * words..(position[v] + 1) * words];
            for &u in list {
                let u = position[u as usize];
                row[u / 64] |= 1 << (u % 64);
            }
        }
        let core = cores.order.iter().map(|&v| cores.core[v as usize]).collect();
        Self { words, rows, core }
    }

    fn row(&self, v: usize) -> &[u64] {
        &self.rows[v * self.words..(v + 1) * self.words]
    }

    /// The first label whose core number is at least `k` (labels after it all qualify).
    fn first_with_core(&self, k: usize) -> usize {
        self.core.partition_point(|&c| (c as usize) < k)
    }

    /// Step 2: from each vertex, highest core first, add the candidate of highest core (the
    /// highest label) and keep its neighbours as the next candidates.
    fn greedy_clique(&self) -> Vec<usize> {
        let n = self.core.len();
        let mut best = vec![n - 1];
        for v in (0..n).rev() {
            if (self.core[v] as usize) < best.len() {
                continue;
            }
            let mut candidates = self.row(v).to_vec();
            clear_below(&mut candidates, self.first_with_core(best.len()));
            let mut clique = vec![v];
            while let Some(u) = highest_bit(&candidates) {
                if clique.len() + popcount(&candidates) <= best.len() {
                    break;
                }
                clique.push(u);
                and_assign(&mut candidates, self.row(u));
            }
            if clique.len() > best.len() {
                best = clique;
            }
        }
        best
    }
}

struct BranchAndBound<'a> {
    bits: &'a BitGraph,
    nodes: u64,
    max_nodes: u64,
    aborted: bool,
}

impl BranchAndBound<'_> {
    /// MCQ: colour the candidates greedily, then branch on them from the highest colour down,
    /// pruning when |clique| + colour ≤ |best|.
    fn expand(&mut self, clique: &mut Vec<usize>, candidates: Vec<u64>, best: &mut Vec<usize>) {
        self.nodes += 1;
        if self.nodes > self.max_nodes {
            self.aborted = true;
            return;
        }
        let (order, colours) = self.colour_sort(&candidates);
        let mut remaining = candidates;
        for k in (0..order.len()).rev() {
            if clique.len() + colours[k] <= best.len() || self.aborted {
                return;
            }
            let v = order[k];
            clique.push(v);
            let mut next = remaining.clone();
            and_assign(&mut next, self.bits.row(v));
            if next.iter().all(|&w| w == 0) {
                if clique.len() > best.len() {
                    best.clone_from(clique);
                }
            } else {
                self.expand(clique, next, best);
            }
            clique.pop();
            remaining[v / 64] &= !(1 << (v % 64));
        }
    }

    /// Greedy sequential colouring: the vertices by colour and each one's colour (1-based).
    fn colour_sort(&self, candidates: &[u64]) -> (Vec<usize>, Vec<usize>) {
        let lo = candidates.iter().position(|&w| w != 0).unwrap_or(candidates.len());
        let mut uncoloured = candidates.to_vec();
        let (mut order, mut colours) = (Vec::new(), Vec::new());
        let mut colour = 0;
        while uncoloured[lo..].iter().any(|&w| w != 0) {
            colour += 1;
            let mut open = uncoloured.clone();
            while let Some(word) = open[lo..].iter().position(|&w| w != 0).map(|w| w + lo) {
                let v = word * 64 + open[word].trailing_zeros() as usize;
                open[word] &= !(1 << (v % 64));
                uncoloured[word] &= !(1 << (v % 64));
                for (o, r) in open[lo..].iter_mut().zip(&self.bits.row(v)[lo..]) {
                    *o &= !r;
                }
                order.push(v);
                colours.push(colour);
            }
        }
        (order, colours)
    }
}

fn popcount(set: &[u64]) -> usize {
    set.iter().map(|w| w.count_ones() as usize).sum()
}

fn highest_bit(set: &[u64]) -> Option<usize> {
    set.iter()
        .rposition(|&w| w != 0)
        .map(|i| i * 64 + 63 - set[i].leading_zeros() as usize)
}

fn and_assign(set: &mut [u64], other: &[u64]) {
    for (a, b) in set.iter_mut().zip(other) {
        *a &= b;
    }
}

/// Clears every bit below `first`.
fn clear_below(set: &mut [u64], first: usize) {
    let word = (first / 64).min(set.len());
    set[..word].iter_mut().for_each(|w| *w = 0);
    if word < set.len() && !first.is_multiple_of(64) {
        set[word] &= !0 << (first % 64);
    }
}

#[cfg(test)]
#[path = "max_clique_tests.rs"]
mod tests;
