//! Reading datasets: the Replica, ScanNet and TUM RGB-D readers, smoothed depth, the corpus of inputs the fuzzers
//! found, and the fuzzers themselves (`fuzz_readers`, `fuzz_folders`).

mod corpus_replay;
mod fuzz_folders;
mod fuzz_readers;
mod replica;
mod scannet;
mod smoothed_depth;
mod tum;
