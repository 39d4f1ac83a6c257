//! `catmap run --live`: the small scene replayed at 200 frames/s, faster than the mapper maps
//! it. The run ends with whole outputs; `summary.json` lists the frames taken and dropped and
//! the seconds from the stream's end to the final meshes; the log's stream line names the drops.

use super::{assert_outputs_whole, catmap, json, small_scene};

#[test]
fn a_live_run_drops_what_it_cannot_take_and_writes_whole_outputs() {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    small_scene(work);
    let config = work.join("config.toml");
    let mut text = std::fs::read_to_string(&config).expect("config readable");
    text.push_str("\n[stream.live]\nfinish_seconds = 1.0\n");
    std::fs::write(&config, text).expect("config written");
    let out = work.join("out");
    let output = catmap()
        .env("RUST_LOG", "info")
        .arg("run")
        .arg("--dataset")
        .arg(work.join("scene"))
        .arg("--config")
        .arg(&config)
        .args(["--live", "--fps", "200", "--out"])
        .arg(&out)
        .output()
        .expect("catmap runs");
    let log = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "the live run succeeds: {log}");
    assert_outputs_whole(&out);
    let summary = json(&out.join("summary.json"));
    let live = &summary["live"];
    let (taken, dropped) = (live["frames_taken"].as_u64(), live["frames_dropped"].as_u64());
    assert_eq!(live["fps"].as_f64(), Some(200.0), "{summary}");
    assert_eq!(
        taken.zip(dropped).map(|(t, d)| t + d),
        Some(5),
        "every frame of stream.max_frames is taken or dropped: {live}"
    );
    assert!(
        dropped.is_some_and(|d| d > 0),
        "5 frames in 25 ms: some dropped: {live}"
    );
    assert!(live["seconds_after_stream"].as_f64().is_some_and(|s| s > 0.0), "{live}");
    // 40 steps at most after the stream (the config's cap), or 1 s of finishing time.
    let end = &summary["training"]["after_stream_end"];
    assert!(
        ["converged", "step_cap", "finish_time"].contains(&end.as_str().unwrap_or("")),
        "the finishing phase ended: {end}"
    );
    assert!(log.contains("dropped"), "the stream's line names the drops: {log}");
    assert!(!out.join("checkpoint").exists(), "a live run keeps no checkpoint");
}
