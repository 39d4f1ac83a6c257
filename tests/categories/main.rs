//! The category half: registration on the default scene, the uncertainty fixture, registration
//! trials.
//!
//! One test binary of modules (a binary per file would link the whole dependency set once each).

#[path = "../common/mod.rs"]
mod common;

mod category_registration;
mod registration_trials;
mod uncertainty_fixture;
