//! Splitting one batched step into independent tasks, running them on rayon, and reducing their
//! gradients deterministically.
//!
//! A task is a contiguous run of one field's work units (rays, or points for a plain MLP).
//! The split depends only on the batch's shapes (never on the thread count), each task writes
//! its own gradient buffer, and a field's gradient is the sum of its tasks' buffers in task
//! order. So results are bit-identical for any number of threads.

use rayon::prelude::*;

/// Applies `update(k, field, gradient)` to each field of `active` (ascending indices; `k` is
/// its position there and `grads[k]` its gradient), in parallel; the other fields are not touched.
pub(crate) fn update_active<F: Send, G: Sync>(
    fields: &mut [F],
    active: &[usize],
    grads: &[G],
    update: impl Fn(usize, &mut F, &G) + Sync,
) {
    let mut updates: Vec<(usize, &mut F, &G)> = fields
        .iter_mut()
        .enumerate()
        .filter_map(|(i, field)| active.binary_search(&i).ok().map(|k| (k, field, &grads[k])))
        .collect();
    updates
        .par_iter_mut()
        .for_each(|(k, field, grad)| update(*k, field, grad));
}

/// One task: units `start..end` of field `field`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Task {
    /// Field index.
    pub field: usize,
    /// First unit.
    pub start: usize,
    /// One past the last unit.
    pub end: usize,
}

/// Splits each field's `units` into tasks of at most `max_cost`, where a unit of field f costs
/// `cost[f]`; fields come in order and a field's tasks are contiguous and near-equal.
pub(crate) fn plan_tasks(units: &[usize], cost: &[usize], max_cost: usize) -> Vec<Task> {
    let mut tasks = Vec::new();
    for (field, (&n, &c)) in units.iter().zip(cost).enumerate() {
        if n == 0 {
            continue;
        }
        let parts = (n * c).div_ceil(max_cost.max(1)).clamp(1, n);
        for p in 0..parts {
            tasks.push(Task {
                field,
                start: n * p / parts,
                end: n * (p + 1) / parts,
            });
        }
    }
    tasks
}

/// Reusable per-task scratch and gradient buffers.
#[derive(Debug, Default)]
pub(crate) struct TaskPool<Sc> {
    scratch: Vec<Sc>,
    grads: Vec<Vec<f32>>,
}

impl<Sc: Default + Send> TaskPool<Sc> {
    /// Runs `work(task, scratch, grad)` for every task in parallel, each with a zeroed gradient
    /// buffer of `grad_len(field)` floats; returns each task's result, in task order.
    pub(crate) fn run<L: Send>(
        &mut self,
        tasks: &[Task],
        grad_len: impl Fn(usize) -> usize + Sync,
        work: impl Fn(&Task, &mut Sc, &mut [f32]) -> L + Sync,
    ) -> Vec<L> {
        self.scratch
            .resize_with(tasks.len().max(self.scratch.len()), Sc::default);
        self.grads.resize_with(tasks.len().max(self.grads.len()), Vec::new);
        tasks
            .par_iter()
            .zip(self.scratch.par_iter_mut())
            .zip(self.grads.par_iter_mut())
            .map(|((task, scratch), grad)| {
                let len = grad_len(task.field);
                grad.clear();
                grad.resize(len, 0.0);
                work(task, scratch, grad)
            })
            .collect()
    }

    /// The gradient buffers of the last run, task by task.
    pub(crate) fn grads(&self) -> &[Vec<f32>] {
        &self.grads
    }
}

/// For each field, the indices of its tasks (in order).
pub(crate) fn tasks_by_field(tasks: &[Task], fields: usize) -> Vec<Vec<usize>> {
    let mut by_field = vec![Vec::new(); fields];
    for (i, t) in tasks.iter().enumerate() {
        by_field[t.field].push(i);
    }
    by_field
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tasks_cover_every_unit_once_and_respect_the_cost_cap() {
        let tasks = plan_tasks(&[120, 0, 120], &[10, 10, 160], 1500);
        assert_eq!(
            tasks.iter().filter(|t| t.field == 0).count(),
            1,
            "a small field is one task"
        );
        let bg: Vec<&Task> = tasks.iter().filter(|t| t.field == 2).collect();
        assert_eq!(bg.len(), 13, "120·160 / 1500 → 13 tasks");
        assert_eq!(bg.first().map(|t| t.start), Some(0));
        assert!(bg.windows(2).all(|w| w[0].end == w[1].start), "contiguous");
        assert_eq!(bg.last().map(|t| t.end), Some(120));
    }
}
