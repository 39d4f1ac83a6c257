//! How the fields trained, as `summary.json`'s `training` and the end table's rows: the schedule,
//! every field's steps and final state, why the phases after the stream ended, and what
//! re-registrations did to the category fields (fields ended, members' frames replaced).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

/// How the fields trained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainingReport {
    /// `fast` or `paper`.
    pub schedule: catmap::training::SchedulePolicy,
    /// Per field (`object 3`, `category 0`): steps taken, its final state, and the step count at
    /// which it last converged.
    pub fields: BTreeMap<String, FieldTraining>,
    /// Why the training right after the stream ended.
    pub after_stream_end: Option<catmap::training::PhaseEnd>,
    /// Why the category phase ended (when there was one).
    pub category_end: Option<catmap::training::PhaseEnd>,
    /// Category members whose frame a registration replaced while they kept their field (each
    /// got a fresh code; `categories.frames`).
    #[serde(default)]
    pub frames_replaced: u32,
}

/// What the training report reads of the category fields beyond the scheduler.
#[derive(Debug, Clone, Copy)]
pub struct CategoryHistory<'a> {
    /// Fields a membership change ended.
    pub retired: &'a [catmap::categories::field_set::RetiredField],
    /// Members whose frame was replaced.
    pub frames_replaced: u32,
}

/// One field's training.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldTraining {
    /// Steps it took.
    pub steps: u64,
    /// Its state at the end.
    pub state: catmap::training::FieldState,
    /// Steps it had taken when it last converged.
    pub converged_at: Option<u64>,
    /// Of its samples inside the region its object is meshed in, the share that carved free
    /// space (`fields.object_rays.box_free_samples`); `None` when it sampled none there. A
    /// category field's counts start again when its membership changes.
    #[serde(default)]
    pub carving_share: Option<f64>,
    /// For an object alone in its class, the cells of its box its priors last drew from
    /// (`fields.object_rays.hidden_solid_rays`, `seen_free_rays`); `None` for the others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior_cells: Option<catmap::objects::hidden_space::PriorCells>,
    /// A category field a membership change ended before the run did: why, at which change
    /// (1 = the first) and its members then. Its steps are the steps it had had.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ended: Option<catmap::categories::field_set::RetiredField>,
}

impl TrainingReport {
    /// The report of a mapper's schedule and phases.
    pub fn new(
        schedule: catmap::training::SchedulePolicy,
        scheduler: &catmap::training::StepScheduler,
        phases: &crate::run_state::PhaseProgress,
        carving: &std::collections::BTreeMap<catmap::training::FieldKey, catmap::field::free_space::CarveCounts>,
        priors: &std::collections::BTreeMap<catmap::training::FieldKey, catmap::objects::hidden_space::PriorCells>,
        categories: CategoryHistory<'_>,
    ) -> Self {
        use catmap::training::FieldKey;
        let fields = scheduler
            .progress()
            .iter()
            .map(|(key, p)| {
                let name = match key {
                    FieldKey::Object(id) => format!("object {id}"),
                    FieldKey::Category(k) => format!("category {k}"),
                    FieldKey::Background => "background".to_owned(),
                };
                let row = FieldTraining {
                    steps: p.steps,
                    state: p.state,
                    converged_at: p.converged_at,
                    carving_share: carving.get(key).filter(|c| c.inside > 0).map(|c| c.share()),
                    prior_cells: priors.get(key).copied(),
                    ended: match key {
                        FieldKey::Category(n) => categories.retired.iter().find(|r| r.id == *n).cloned(),
                        _ => None,
                    },
                };
                (name, row)
            })
            .collect();
        Self {
            schedule,
            fields,
            after_stream_end: phases.after_stream_end,
            category_end: phases.category_end,
            frames_replaced: categories.frames_replaced,
        }
    }
}

impl TrainingReport {
    /// Appends the report's lines and its field table to the end table `out`.
    pub fn write_table(&self, out: &mut String) {
        let ended = |end: Option<catmap::training::PhaseEnd>| match end {
            Some(catmap::training::PhaseEnd::Converged) => "every field converged",
            Some(catmap::training::PhaseEnd::StepCap) => "step cap reached",
            Some(catmap::training::PhaseEnd::FinishTime) => "live finishing time spent",
            None => "–",
        };
        let _ = writeln!(
            out,
            "\ntraining ({:?} schedule): after the stream, {}",
            self.schedule,
            ended(self.after_stream_end)
        );
        if self.category_end.is_some() {
            let _ = writeln!(out, "category phase: {}", ended(self.category_end));
        }
        let _ = writeln!(out, "\n| field | steps | state | carving [%] |\n|---|---:|---|---:|");
        for (name, field) in &self.fields {
            let carving = field
                .carving_share
                .map_or_else(|| "–".to_owned(), |s| format!("{:.1}", 100.0 * s));
            let state = field
                .ended
                .as_ref()
                .map_or_else(|| format!("{:?}", field.state), ended_field);
            let _ = writeln!(out, "| {name} | {} | {state} | {carving} |", field.steps);
        }
        if self.frames_replaced > 0 {
            let _ = writeln!(
                out,
                "\n{} category member frames replaced by a registration (fresh codes)",
                self.frames_replaced
            );
        }
    }
}

/// How the table names a category field a membership change ended.
fn ended_field(field: &catmap::categories::field_set::RetiredField) -> String {
    use catmap::categories::field_set::Retirement;
    let cause = match field.cause {
        Retirement::Dropped => "dropped",
        Retirement::Restarted => "restarted",
    };
    let members: Vec<String> = field.members.iter().map(ToString::to_string).collect();
    format!(
        "{cause} at membership change {} (members {})",
        field.remap,
        members.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use catmap::ObjectId;
    use catmap::categories::field_set::{RetiredField, Retirement};
    use catmap::training::{FieldState, PhaseEnd, SchedulePolicy};

    use super::*;

    #[test]
    fn the_table_says_which_category_fields_a_re_registration_ended_and_their_steps() {
        let row = |steps, ended| FieldTraining {
            steps,
            state: FieldState::Training,
            converged_at: None,
            carving_share: None,
            prior_cells: None,
            ended,
        };
        let dropped = RetiredField {
            id: 1,
            members: vec![ObjectId(5), ObjectId(6)],
            remap: 2,
            cause: Retirement::Dropped,
        };
        let report = TrainingReport {
            schedule: SchedulePolicy::Fast,
            fields: BTreeMap::from([
                ("category 0".to_owned(), row(900, None)),
                ("category 1".to_owned(), row(120, Some(dropped))),
            ]),
            after_stream_end: Some(PhaseEnd::Converged),
            category_end: Some(PhaseEnd::Converged),
            frames_replaced: 3,
        };
        let mut table = String::new();
        report.write_table(&mut table);
        assert!(
            table.contains("| category 1 | 120 | dropped at membership change 2 (members 5, 6) |"),
            "{table}"
        );
        assert!(table.contains("| category 0 | 900 | Training |"), "{table}");
        assert!(table.contains("3 category member frames replaced"), "{table}");
        let json = serde_json::to_string(&report).expect("serialises");
        let back: TrainingReport = serde_json::from_str(&json).expect("reads back");
        assert_eq!(back, report);
    }
}
