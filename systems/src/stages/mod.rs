//! The systems, one file per stage of the schedule (`crate::schedule` orders them). Each reads
//! components, calls one `catmap::` function and writes components back.
//!
//! | stage | file |
//! |---|---|
//! | the tick's clock, its steps, the run's next phase | `tick` |
//! | frames leave the stream | `ingest` |
//! | masks become per-object observations | `segment` |
//! | objects appear and take in their views (class votes, keyframes) | `track` |
//! | observed clouds grow, oriented boxes follow | `clouds` |
//! | an object found to be part of another is taken into it | `merge` |
//! | objects join their class's category | `categorize` |
//! | fields appear and train (object fields, background) | `train` |
//! | classes are registered, subcategories split | `register` |
//! | category fields follow the subcategories and train | `category_fields` |
//! | fields are meshed (previews, final) | `meshes` |
//! | what changed is logged to Rerun | `log_rerun`, `log_camera`, `log_categories`, `log_stream` |
//! | the frame's entity is despawned | `cleanup` |

pub mod categorize;
pub mod category_fields;
pub mod cleanup;
pub mod clouds;
pub mod ingest;
pub mod log_camera;
pub mod log_categories;
pub mod log_rerun;
pub mod log_stream;
pub mod merge;
pub mod meshes;
pub mod register;
pub mod segment;
pub mod tick;
pub mod track;
pub mod train;
