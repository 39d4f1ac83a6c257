//! A bounding volume hierarchy over triangles for nearest-hit ray casting.
//!
//! Built top-down with the binned surface-area heuristic (12 bins per axis, all three axes): a node
//! with bounds `B` is split into `L`, `R` minimising `area(L)·|L| + area(R)·|R|`, and stays a leaf
//! when no split beats `area(B)·|B|` (or it holds ≤ 2 triangles). Nodes are stored depth-first, so a
//! node's left child follows it and only the right child's index is kept.
//!
//! Rays are `origin + t·direction` with an unnormalised direction; `t` is in units of `direction`,
//! so a camera ray with direction z = 1 in the camera frame reports camera depth directly.
//! Triangles are intersected with Möller–Trumbore, two-sided.

use nalgebra::{Point3, Vector3};

/// Smallest accepted hit distance, in units of the ray direction (avoids self-hits).
pub const T_MIN: f32 = 1e-5;
const BINS: usize = 12;
const MAX_LEAF_SIZE: usize = 8;
/// Deepest node level; deeper subtrees become leaves, so the traversal stack cannot overflow.
const MAX_DEPTH: usize = 60;

/// A ray `origin + t · direction`, `t ≥ 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Point3<f32>,
    /// Direction; need not be unit length.
    pub direction: Vector3<f32>,
}

/// The nearest intersection along a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Index of the triangle in the list the BVH was built from.
    pub triangle: u32,
}

/// A triangle prepared for Möller–Trumbore: one corner and the two edges leaving it.
#[derive(Debug, Clone, Copy)]
struct PreparedTriangle {
    v0: Vector3<f32>,
    e1: Vector3<f32>,
    e2: Vector3<f32>,
}

impl PreparedTriangle {
    fn new([a, b, c]: [Point3<f32>; 3]) -> Self {
        Self {
            v0: a.coords,
            e1: b - a,
            e2: c - a,
        }
    }

    /// Ray parameter of the intersection in `(T_MIN, t_max)`, if any.
    #[inline]
    fn intersect(&self, origin: &Vector3<f32>, direction: &Vector3<f32>, t_max: f32) -> Option<f32> {
        let p = direction.cross(&self.e2);
        let det = self.e1.dot(&p);
        if det.abs() < 1e-12 {
            return None;
        }
        let inv_det = 1.0 / det;
        let s = origin - self.v0;
        let u = s.dot(&p) * inv_det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(&self.e1);
        let v = direction.dot(&q) * inv_det;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = self.e2.dot(&q) * inv_det;
        (t > T_MIN && t < t_max).then_some(t)
    }
}

/// Axis-aligned box as min/max arrays (cheap to grow and to slab-test).
#[derive(Debug, Clone, Copy)]
struct Bounds {
    min: [f32; 3],
    max: [f32; 3],
}

impl Bounds {
    const EMPTY: Self = Self {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    };

    fn grow_point(&mut self, p: &Point3<f32>) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(p[k]);
            self.max[k] = self.max[k].max(p[k]);
        }
    }

    fn grow(&mut self, b: &Bounds) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(b.min[k]);
            self.max[k] = self.max[k].max(b.max[k]);
        }
    }

    /// Half the surface area (enough for comparing SAH costs); 0 for an empty box.
    fn half_area(&self) -> f32 {
        let e = [0, 1, 2].map(|k| (self.max[k] - self.min[k]).max(0.0));
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }

    /// Distance at which the ray enters the box, or `f32::INFINITY` when it misses the box or
    /// enters it only at or after `t_max`. Plain comparisons (not `f32::min`) keep this cheap; a NaN
    /// slab (origin on a plane the ray is parallel to) fails every comparison and constrains nothing.
    #[inline(always)]
    fn entry(&self, origin: &[f32; 3], inv_dir: &[f32; 3], t_max: f32) -> f32 {
        let (mut near, mut far) = (T_MIN, t_max);
        for k in 0..3 {
            let t0 = (self.min[k] - origin[k]) * inv_dir[k];
            let t1 = (self.max[k] - origin[k]) * inv_dir[k];
            let (lo, hi) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
            if lo > near {
                near = lo;
            }
            if hi < far {
                far = hi;
            }
        }
        if near <= far && near < t_max {
            near
        } else {
            f32::INFINITY
        }
    }
}

/// A node: a leaf holds `count > 0` triangles from `first`; an interior node (`count == 0`) has
/// its left child right after it and its right child at `first`.
#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Bounds,
    first: u32,
    count: u32,
}

/// Bounding volume hierarchy over a fixed list of triangles.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangles in leaf order.
    triangles: Vec<PreparedTriangle>,
    /// Original index of each triangle in leaf order.
    original: Vec<u32>,
}

/// Per-triangle data used while building.
struct BuildItem {
    bounds: Bounds,
    centroid: [f32; 3],
    index: u32,
}

impl Bvh {
    /// Builds the hierarchy over `triangles` (corner positions).
    pub fn build(triangles: &[[Point3<f32>; 3]]) -> Self {
        let mut items: Vec<BuildItem> = triangles
            .iter()
            .enumerate()
            .map(|(i, tri)| {
                let mut bounds = Bounds::EMPTY;
                tri.iter().for_each(|p| bounds.grow_point(p));
                let centroid = [0, 1, 2].map(|k| (tri[0][k] + tri[1][k] + tri[2][k]) / 3.0);
                BuildItem {
                    bounds,
                    centroid,
                    index: u32::try_from(i).expect("fewer than 2³² triangles"),
                }
            })
            .collect();
        let mut nodes = Vec::with_capacity(2 * items.len().max(1));
        build_node(&mut items, 0, 0, &mut nodes);
        let original: Vec<u32> = items.iter().map(|it| it.index).collect();
        let triangles = original
            .iter()
            .map(|&i| PreparedTriangle::new(triangles[i as usize]))
            .collect();
        Self {
            nodes,
            triangles,
            original,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// True when the BVH holds no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The nearest hit with `T_MIN < t < t_max`, if any.
    pub fn nearest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.triangles.is_empty() {
            return None;
        }
        let origin = [ray.origin.x, ray.origin.y, ray.origin.z];
        let inv_dir = [1.0 / ray.direction.x, 1.0 / ray.direction.y, 1.0 / ray.direction.z];
        let (o, d) = (ray.origin.coords, ray.direction);
        let mut best: Option<(f32, usize)> = None;
        let mut best_t = t_max;
        // Pending nodes with the distance at which the ray enters them.
        let mut stack = [(0_u32, 0.0_f32); 64];
        stack[0] = (0, self.nodes[0].bounds.entry(&origin, &inv_dir, t_max));
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let (index, entry) = stack[depth];
            if entry >= best_t {
                continue; // missed, or a nearer hit was found after this node was queued
            }
            let node = &self.nodes[index as usize];
            if node.count > 0 {
                for i in node.first as usize..(node.first + node.count) as usize {
                    if let Some(t) = self.triangles[i].intersect(&o, &d, best_t) {
                        best_t = t;
                        best = Some((t, i));
                    }
                }
                continue;
            }
            let (left, right) = (index + 1, node.first);
            let t_left = self.nodes[left as usize].bounds.entry(&origin, &inv_dir, best_t);
            let t_right = self.nodes[right as usize].bounds.entry(&origin, &inv_dir, best_t);
            // Push the farther child first so that the nearer one is visited next; a missed child
            // (infinite entry) is pushed too and dropped when popped.
            let (near, far) = if t_right < t_left {
                ((right, t_right), (left, t_left))
            } else {
                ((left, t_left), (right, t_right))
            };
            debug_assert!(depth + 2 <= stack.len(), "BVH deeper than the traversal stack");
            stack[depth] = far;
            stack[depth + 1] = near;
            depth += 2;
        }
        best.map(|(t, i)| Hit {
            t,
            triangle: self.original[i],
        })
    }
}

/// Builds the subtree at `depth` over `items` (whose first element has leaf index `offset`);
/// returns its node index.
fn build_node(items: &mut [BuildItem], offset: usize, depth: usize, nodes: &mut Vec<Node>) -> u32 {
    let mut bounds = Bounds::EMPTY;
    items.iter().for_each(|it| bounds.grow(&it.bounds));
    let node_index = nodes.len();
    let leaf = Node {
        bounds,
        first: offset as u32,
        count: items.len() as u32,
    };
    nodes.push(leaf);
    if items.len() <= 2 || depth >= MAX_DEPTH {
        return node_index as u32;
    }
    let split = match best_sah_split(items, &bounds) {
        Some(split) => split,
        None if items.len() > MAX_LEAF_SIZE => median_split(items),
        None => return node_index as u32,
    };
    let (left, right) = items.split_at_mut(split);
    build_node(left, offset, depth + 1, nodes);
    let right_index = build_node(right, offset + split, depth + 1, nodes);
    nodes[node_index] = Node {
        bounds,
        first: right_index,
        count: 0,
    };
    node_index as u32
}

/// Partitions `items` by the cheapest binned SAH plane and returns the split position, or `None`
/// when staying a leaf is cheaper (or no plane separates the centroids).
fn best_sah_split(items: &mut [BuildItem], bounds: &Bounds) -> Option<usize> {
    let mut centroid_bounds = Bounds::EMPTY;
    items
        .iter()
        .for_each(|it| centroid_bounds.grow_point(&Point3::from(it.centroid)));
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bins left of the plane)
    for axis in 0..3 {
        let (lo, hi) = (centroid_bounds.min[axis], centroid_bounds.max[axis]);
        if hi - lo <= 1e-9 {
            continue;
        }
        let mut bins = [(0_usize, Bounds::EMPTY); BINS];
        for it in items.iter() {
            let b = &mut bins[bin_index(it.centroid[axis], lo, hi)];
            b.0 += 1;
            b.1.grow(&it.bounds);
        }
        let mut right_cost = [0.0_f32; BINS];
        let (mut count, mut acc) = (0, Bounds::EMPTY);
        for k in (1..BINS).rev() {
            count += bins[k].0;
            acc.grow(&bins[k].1);
            right_cost[k] = count as f32 * acc.half_area();
        }
        let (mut count, mut acc) = (0, Bounds::EMPTY);
        for k in 1..BINS {
            count += bins[k - 1].0;
            acc.grow(&bins[k - 1].1);
            let cost = count as f32 * acc.half_area() + right_cost[k];
            if count > 0 && count < items.len() && best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, k));
            }
        }
    }
    let (cost, axis, k) = best?;
    let leaf_cost = items.len() as f32 * bounds.half_area();
    if cost >= leaf_cost && items.len() <= MAX_LEAF_SIZE {
        return None;
    }
    let (lo, hi) = (centroid_bounds.min[axis], centroid_bounds.max[axis]);
    let split = partition_in_place(items, |it| bin_index(it.centroid[axis], lo, hi) < k);
    (split > 0 && split < items.len()).then_some(split)
}

/// SAH bin of centroid coordinate `c` within `[lo, hi]`.
fn bin_index(c: f32, lo: f32, hi: f32) -> usize {
    (((c - lo) / (hi - lo) * BINS as f32) as usize).min(BINS - 1)
}

/// Splits at the median centroid along the longest axis of the centroids.
fn median_split(items: &mut [BuildItem]) -> usize {
    let mut cb = Bounds::EMPTY;
    items.iter().for_each(|it| cb.grow_point(&Point3::from(it.centroid)));
    let axis = (0..3)
        .max_by(|&a, &b| (cb.max[a] - cb.min[a]).total_cmp(&(cb.max[b] - cb.min[b])))
        .unwrap_or(0);
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
    mid
}

/// Moves the items satisfying `pred` to the front; returns how many there are.
fn partition_in_place(items: &mut [BuildItem], pred: impl Fn(&BuildItem) -> bool) -> usize {
    let mut split = 0;
    for i in 0..items.len() {
        if pred(&items[i]) {
            items.swap(split, i);
            split += 1;
        }
    }
    split
}

#[cfg(test)]
mod tests;
