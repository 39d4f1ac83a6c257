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
pub fn maximum_clique(graph: &Graph, max_nodes: u64) -> Clique {
    if graph.vertex_count() == 0 {
        return Clique {
            vertices: Vec::new(),
            proven_maximum: true,
        };
    }
    let cores = core_numbers(graph);
    let mut best = greedy_clique(graph, &cores);
    let max_core = cores.core.iter().copied().max().unwrap_or(0) as usize;
    let mut search = BranchAndBound {
        nodes: 0,
        max_nodes,
        aborted: false,
    };
    if best.len() <= max_core {
        let mut position = vec![0usize; graph.vertex_count()];
        for (i, &v) in cores.order.iter().enumerate() {
            position[v as usize] = i;
        }
        let mut scratch = LocalScratch::new(graph.vertex_count());
        for &v in &cores.order {
            if search.aborted {
                break;
            }
            if (cores.core[v as usize] as usize) < best.len() {
                continue;
            }
            let later: Vec<u32> = graph
                .neighbours(v)
                .iter()
                .copied()
                .filter(|&u| {
                    position[u as usize] > position[v as usize] && cores.core[u as usize] as usize >= best.len()
                })
                .collect();
            if later.len() < best.len() {
                continue;
            }
            let local = scratch.subgraph(graph, &later, best.len());
            search.seed(v, &local, &mut best);
        }
    }
    best.sort_unstable();
    Clique {
        vertices: best,
        proven_maximum: !search.aborted,
    }
}

/// The greedy lower bound of step 2.
fn greedy_clique(graph: &Graph, cores: &Cores) -> Vec<u32> {
    let core = |v: u32| cores.core[v as usize];
    let mut best: Vec<u32> = vec![cores.order[cores.order.len() - 1]];
    let mut in_candidates = vec![false; graph.vertex_count()];
    for &v in cores.order.iter().rev() {
        if core(v) as usize + 1 <= best.len() {
            continue;
        }
        let mut clique = vec![v];
        let mut candidates: Vec<u32> = graph
            .neighbours(v)
            .iter()
            .copied()
            .filter(|&u| core(u) as usize >= best.len())
            .collect();
        while !candidates.is_empty() && clique.len() + candidates.len() > best.len() {
            let &u = candidates
                .iter()
                .max_by_key(|&&u| (core(u), std::cmp::Reverse(u)))
                .expect("candidates are not empty");
            clique.push(u);
            for &w in graph.neighbours(u) {
                in_candidates[w as usize] = true;
            }
            candidates.retain(|&w| in_candidates[w as usize]);
            for &w in graph.neighbours(u) {
                in_candidates[w as usize] = false;
            }
        }
        if clique.len() > best.len() {
            best = clique;
        }
    }
    best
}

/// A small induced subgraph with bitset rows, local ids sorted by decreasing local degree.
struct LocalGraph {
    global: Vec<u32>,
    rows: Vec<Vec<u64>>,
}

/// Reused buffers mapping global vertex ids to local ones.
struct LocalScratch {
    local_of: Vec<u32>,
}

impl LocalScratch {
    fn new(vertex_count: usize) -> Self {
        Self {
            local_of: vec![u32::MAX; vertex_count],
        }
    }

    /// The subgraph induced by `vertices`, without vertices of local degree < `min_size` − 1.
    fn subgraph(&mut self, graph: &Graph, vertices: &[u32], min_size: usize) -> LocalGraph {
        for (i, &v) in vertices.iter().enumerate() {
            self.local_of[v as usize] = i as u32;
        }
        let lists: Vec<Vec<u32>> = vertices
            .iter()
            .map(|&v| {
                graph
                    .neighbours(v)
                    .iter()
                    .map(|&u| self.local_of[u as usize])
                    .filter(|&l| l != u32::MAX)
                    .collect()
            })
            .collect();
        for &v in vertices {
            self.local_of[v as usize] = u32::MAX;
        }
        let mut kept: Vec<usize> = (0..vertices.len()).filter(|&i| lists[i].len() + 2 > min_size).collect();
        kept.sort_by_key(|&i| (std::cmp::Reverse(lists[i].len()), i));
        let mut new_of = vec![u32::MAX; vertices.len()];
        for (new, &old) in kept.iter().enumerate() {
            new_of[old] = new as u32;
        }
        let words = kept.len().div_ceil(64);
        let rows = kept
            .iter()
            .map(|&old| {
                let mut row = vec![0u64; words];
                for &l in &lists[old] {
                    let new = new_of[l as usize];
                    if new != u32::MAX {
                        row[new as usize / 64] |= 1 << (new % 64);
                    }
                }
                row
            })
            .collect();
        LocalGraph {
            global: kept.iter().map(|&old| vertices[old]).collect(),
            rows,
        }
    }
}

struct BranchAndBound {
    nodes: u64,
    max_nodes: u64,
    aborted: bool,
}

impl BranchAndBound {
    /// Searches cliques {v} ∪ C with C ⊆ `local`, improving `best` (global ids).
    fn seed(&mut self, v: u32, local: &LocalGraph, best: &mut Vec<u32>) {
        let n = local.global.len();
        let mut candidates = vec![0u64; n.div_ceil(64)];
        for i in 0..n {
            candidates[i / 64] |= 1 << (i % 64);
        }
        let mut clique = Vec::new();
        let mut found: Option<Vec<usize>> = None;
        let mut best_len = best.len();
        self.expand(local, &mut clique, candidates, &mut best_len, &mut found);
        if let Some(members) = found {
            *best = std::iter::once(v)
                .chain(members.iter().map(|&i| local.global[i]))
                .collect();
        }
    }

    /// MCQ: colour the candidates greedily, then branch on them from the highest colour down.
    /// `best_len` counts the seed vertex, `clique` does not.
    fn expand(
        &mut self,
        local: &LocalGraph,
        clique: &mut Vec<usize>,
        candidates: Vec<u64>,
        best_len: &mut usize,
        found: &mut Option<Vec<usize>>,
    ) {
        self.nodes += 1;
        if self.nodes > self.max_nodes {
            self.aborted = true;
            return;
        }
        let (order, colours) = colour_sort(local, &candidates);
        let mut remaining = candidates;
        for k in (0..order.len()).rev() {
            if 1 + clique.len() + colours[k] <= *best_len || self.aborted {
                return;
            }
            let v = order[k];
            clique.push(v);
            let next: Vec<u64> = remaining.iter().zip(&local.rows[v]).map(|(a, b)| a & b).collect();
            if next.iter().all(|&w| w == 0) {
                if 1 + clique.len() > *best_len {
                    *best_len = 1 + clique.len();
                    *found = Some(clique.clone());
                }
            } else {
                self.expand(local, clique, next, best_len, found);
            }
            clique.pop();
            remaining[v / 64] &= !(1 << (v % 64));
        }
    }
}

/// Greedy sequential colouring: returns the vertices by colour and each one's colour (1-based).
fn colour_sort(local: &LocalGraph, candidates: &[u64]) -> (Vec<usize>, Vec<usize>) {
    let mut uncoloured = candidates.to_vec();
    let (mut order, mut colours) = (Vec::new(), Vec::new());
    let mut colour = 0;
    while uncoloured.iter().any(|&w| w != 0) {
        colour += 1;
        let mut open = uncoloured.clone();
        while let Some(word) = open.iter().position(|&w| w != 0) {
            let v = word * 64 + open[word].trailing_zeros() as usize;
            open[word] &= !(1 << (v % 64));
            uncoloured[word] &= !(1 << (v % 64));
            for (o, r) in open.iter_mut().zip(&local.rows[v]) {
                *o &= !r;
            }
            order.push(v);
            colours.push(colour);
        }
    }
    (order, colours)
}

#[cfg(test)]
#[path = "max_clique_tests.rs"]
mod tests;
