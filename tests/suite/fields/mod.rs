//! The neural fields: gradients against a reference, training in the mapper, and the shared
//! category fields.

mod category_field_gradients;
mod category_fields;
mod field_gradients;
mod field_training;
