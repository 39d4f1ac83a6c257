//! Helpers shared by the integration tests: fixture image writers, error-text checks, and
//! mapping a synthetic scene ([`mapping`]).
#![allow(dead_code, reason = "each test crate uses a different subset")]

pub mod mapping;

use std::path::Path;

use catmap::{CatmapError, RgbdFrame};
use image::{ImageBuffer, Luma, Rgb};

pub fn write_grey16(path: &Path, (w, h): (u32, u32), f: impl Fn(u32, u32) -> u16) {
    std::fs::create_dir_all(path.parent().expect("file in a folder")).expect("mkdir");
    ImageBuffer::<Luma<u16>, Vec<u16>>::from_fn(w, h, |u, v| Luma([f(u, v)]))
        .save(path)
        .expect("write png");
}

pub fn write_grey8(path: &Path, (w, h): (u32, u32), f: impl Fn(u32, u32) -> u8) {
    std::fs::create_dir_all(path.parent().expect("file in a folder")).expect("mkdir");
    ImageBuffer::<Luma<u8>, Vec<u8>>::from_fn(w, h, |u, v| Luma([f(u, v)]))
        .save(path)
        .expect("write png");
}

pub fn write_rgb(path: &Path, (w, h): (u32, u32), f: impl Fn(u32, u32) -> [u8; 3]) {
    std::fs::create_dir_all(path.parent().expect("file in a folder")).expect("mkdir");
    ImageBuffer::<Rgb<u8>, Vec<u8>>::from_fn(w, h, |u, v| Rgb(f(u, v)))
        .save(path)
        .expect("write image");
}

pub fn pixel(frame: &RgbdFrame, u: u32, v: u32) -> usize {
    (v * frame.intrinsics.width + u) as usize
}

pub fn assert_mentions(err: &CatmapError, parts: &[&str]) {
    let text = err.to_string();
    for part in parts {
        assert!(text.contains(part), "error should mention {part:?}: {text}");
    }
}

/// Warnings logged (on this thread) while `f` runs, one line each, and `f`'s result.
pub fn with_warnings<T>(f: impl FnOnce() -> T) -> (T, String) {
    #[derive(Clone, Default)]
    struct Sink(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);
    impl std::io::Write for Sink {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.0.lock().expect("not poisoned").extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }
    let sink = Sink::default();
    let writer = sink.clone();
    let subscriber = tracing_subscriber::fmt()
        .with_max_level(tracing::Level::WARN)
        .with_ansi(false)
        .with_writer(move || writer.clone())
        .finish();
    let result = tracing::subscriber::with_default(subscriber, f);
    let text = String::from_utf8(sink.0.lock().expect("not poisoned").clone()).expect("utf-8 log");
    (result, text)
}
