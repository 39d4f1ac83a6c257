//! catmap's integration tests, in one binary of modules: a binary per area would link the whole
//! dependency set (candle, rerun, bevy) once each, and one binary lets libtest interleave the long
//! pipeline tests of every area. Run one area with `cargo test --test suite <area>::`.

mod common;
mod fuzz_support;

mod categories;
mod fields;
mod mapping;
mod readers;
mod scenes;
