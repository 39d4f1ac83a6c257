//! Per-object neural fields (vMAP-style): encoding, occupancy MLP, rendering, loss, AdamW, and a
//! fused batched training step in plain Rust.
//!
//! Every object has its own small occupancy field (H = 32; the background H = 128). All fields
//! train together: [`FieldBatch::train_step`] runs forward, rendering, loss, backward and AdamW
//! for every field in one pass over each field's samples, in chunks that stay in cache, with
//! SIMD micro-kernels chosen at run time and rayon across tasks. Results are bit-identical for
//! any thread count. [`reference`] holds the same model in candle autograd, used to check it.
//!
//! | file | concept |
//! |---|---|
//! | `directions` | the 21 fixed encoding directions |
//! | `encoding` | x' = x/scale, sin(π 2^k B x'), and its backward |
//! | `layout` | named flat parameters, initialisation |
//! | `render` | occupancy rendering of a ray and its backward |
//! | `loss` | vMAP's depth / colour / opacity loss |
//! | `heads` | the heads every network ends in: sigmoids, a chunk's render, loss and head gradients |
//! | `adamw` | PyTorch AdamW, per-field state |
//! | `gemm`, `simd`, `dense` | SIMD GEMM micro-kernels and packed linear layers |
//! | `narrow_gradient` | the weight gradient of the 1- and 3-wide heads without padded panels |
//! | `occupancy` | the occupancy MLP on a chunk (fused forward + backward) |
//! | `fused_batch`, `tasks` | the one fused training step of any batch of fields, its parallel plan |
//! | `object_field`, `batch`, `samples` | the occupancy field and its batch ([`FieldBatch`]) |
//! | `ray_sampler` | the depth-guided sampler: keyframes, pixels, depths along rays |
//! | `ray_sampler_config` | the sampler's settings (`RaySamplerConfig`): rays, samples, priors |
//! | `free_space` | where free-space samples go: the part of a ray that crosses the object's box |
//! | `tensors` | parameters as named candle tensors |
//! | `category` | the CodeNeRF-style category field (shared weights, per-member codes), batched |
//! | `bench` | benchmark-only (feature `bench`): a plain MLP batch on the same machinery, its candle twin |

mod adamw;
mod batch;
#[cfg(any(test, feature = "bench"))]
pub mod bench;
pub mod category;
mod config;
mod dense;
mod directions;
mod encoding;
pub mod free_space;
mod fused_batch;
mod gemm;
mod heads;
mod layout;
mod loss;
mod narrow_gradient;
mod object_field;
mod occupancy;
mod ray_sampler;
mod ray_sampler_config;
pub mod reference;
mod render;
mod samples;
mod simd;
mod solid_prior;
mod tasks;
mod tensors;

pub use adamw::{AdamWConfig, AdamWState};
pub use batch::{FieldBatch, OccupancyModel};
pub use category::{CategoryBatch, CategoryField, CategoryGradients, CategoryLosses, CategoryModel, CategorySamples};
pub use config::FieldConfig;
pub use directions::{NUM_DIRECTIONS, icosphere_directions};
pub use encoding::{COL_DIMS, EMB_DIMS, GEO_DIMS, NUM_BANDS, SIN_DIMS};
pub use fused_batch::{CHUNK_SAMPLES, FieldStep, FusedBatch, FusedModel};
pub use heads::ALPHA_SCALE;
pub use layout::{InitKind, ParamLayout, TensorSpec};
pub use loss::{COLOUR_WEIGHT, DEPTH_STD_EPS, FieldLosses, OPACITY_WEIGHT};
pub use object_field::{BACKGROUND_HIDDEN, FieldEval, OBJECT_HIDDEN, OccupancyField};
pub use ray_sampler::{
    RaySamplerConfig, choose_step_views, sample_member_rays, sample_training_rays, sample_window_rays,
};
pub use render::{FREE_EPS, RayRender, RenderGrad, render_ray, render_ray_backward, sigmoid};
pub use samples::RaySamples;
pub use simd::Backend;
pub use solid_prior::{PriorRays, append_prior_rays};
