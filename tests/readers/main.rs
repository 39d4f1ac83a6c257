//! Reading datasets: the Replica and ScanNet readers, the corpus of inputs the fuzzers found, and the
//! fuzzers themselves (`fuzz_readers`, `fuzz_folders`).
//!
//! One test binary of modules (a binary per file would link the whole dependency set once each).

#[path = "../common/mod.rs"]
mod common;
#[path = "../fuzz_support/mod.rs"]
mod fuzz_support;

mod corpus_replay;
mod fuzz_folders;
mod fuzz_readers;
mod readers;
mod readers_scannet;
