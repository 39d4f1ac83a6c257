//! The category half of the method (METHOD.md §3–§5): ray-based uncertainty and the
//! representative of a class, registration of its members and their subcategories, the members'
//! normalised frames (NOCS), and which category field each subcategory gets.

pub mod class_registration;
pub mod class_update;
pub mod field_plan;
pub mod field_set;
pub mod grown_box;
pub mod held_frames;
pub mod member_hidden;
pub mod nocs;
pub mod subcategories;
pub mod uncertainty;
