use super::*;
use crate::metrics::report::report_of_completions as report;

fn job(mode: &str) -> SweepJob {
    SweepJob {
        index: 0,
        preset: "small".into(),
        scene_seed: 0,
        noise: "none".into(),
        mode: mode.into(),
        schedule: "fast".into(),
        seed: 0,
    }
}

fn runs() -> Vec<SweepRun> {
    vec![
        SweepRun {
            job: job("category"),
            metrics: Some(report(&[(1, "chair", 4.0), (2, "chair", 2.0), (3, "lamp", 1.0)])),
            facts: RunFacts {
                frames: Some(30),
                seconds: Some(12.25),
                peak_mib: Some(410.4),
                version: Some("0.1.0 (abc1234)".into()),
            },
        },
        SweepRun {
            job: job("instance"),
            metrics: None,
            facts: RunFacts::default(),
        },
    ]
}

#[test]
fn the_groups_rows_are_each_runs_summary_and_a_run_without_metrics_is_dashes() {
    let text = render("t", &runs(), Tables::Metrics);
    let section = |title: &str| {
        text.split("#### ")
            .find(|s| s.starts_with(&format!("t: {title}")))
            .unwrap_or_else(|| panic!("a {title} table: {text}"))
            .to_owned()
    };
    assert!(
        section("all objects").contains("| small:0 | none | category | fast | 0 | 3 | 0 | 2.00 | 2.33 | 90.0 | 30.0 |"),
        "{text}"
    );
    assert!(section("repeated").contains("| 2 | 0 | 2.00 | 3.00 |"), "{text}");
    assert!(section("unique").contains("| 1 | 0 | 2.00 | 1.00 |"), "{text}");
    assert!(
        section("all objects").contains("| small:0 | none | instance | fast | 0 | – | – | – | – | – | – |"),
        "{text}"
    );
    let classes = section("per class");
    assert!(
        classes.contains("| chair | small:0 | none | category | fast | 0 | 2 |"),
        "{text}"
    );
    assert!(classes.find("| chair").expect("chair") < classes.find("| lamp").expect("lamp"));
    assert!(!text.contains("wall clock"), "the metric tables alone");
}

#[test]
fn the_time_table_gives_each_runs_wall_clock_memory_and_build() {
    let text = render("t", &runs(), Tables::MetricsAndTime);
    assert!(
        text.contains("| small0-none-category-fast-m0 | 30 | 12.2 | 410 | 0.1.0 (abc1234) |"),
        "{text}"
    );
    assert!(
        text.contains("| small0-none-instance-fast-m0 | – | – | – | – |"),
        "{text}"
    );
}
