//! The neural fields: gradients against a reference, training in the mapper, and the shared
//! category fields.
//!
//! One test binary of modules (a binary per file would link the whole dependency set once each).

#[path = "../common/mod.rs"]
mod common;

mod category_field_gradients;
mod category_fields;
mod field_gradients;
mod field_training;
