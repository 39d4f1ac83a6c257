//! The category half: registration on the default scene, the uncertainty fixture, registration
//! trials.

mod category_registration;
mod registration_trials;
mod uncertainty_fixture;
