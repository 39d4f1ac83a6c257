//! The CodeNeRF-style category field (METHOD.md §5): one network per (sub)category, shared by its
//! members, each member with its own shape code z_s and texture code z_t, trained as one fused
//! batched step over all categories. By default (`category_fields.shape_codes = "shared"`,
//! [`ShapeCodes`]) every member's z_s is zero and stays so: one shape per subcategory, each
//! member's texture its own.
//!
//! Points are in the category's NOCS (unit) frame; the vMAP encoding (x' = x / scale, scale 1.0
//! by default, trainable B) gives e_geo (87) and e_col (42). With W = 32 and code dimension D:
//!
//! ```text
//! y0 = ReLU(encoding_xyz(e_geo))                 y0' = y0 + ReLU(shape_latent_layer_1(z_s))
//! y1 = ReLU(shape_layer_1(y0'))                  y1' = y1 + ReLU(cat_latent_layer(z_s))
//! y2 = ReLU(cat_layer(y1' ‖ e_geo))              y2' = y2 + ReLU(shape_latent_layer_2(z_s))
//! y3 = ReLU(shape_layer_2(y2'))
//! y4 = encoding_shape(y3)                        (no activation)
//! α  = 10 · sigma(y4)                            occupancy o = sigmoid(α), as the object field
//! y5 = ReLU(encoding_viewdir(y4 ‖ e_col))        y5' = y5 + ReLU(texture_latent_layer_1(z_t))
//! y6 = ReLU(texture_layer_1(y5'))
//! colour = sigmoid(rgb.2(ReLU(rgb.0(y6))))       (rgb.0: W → W/2, rgb.2: W/2 → 3)
//! ```
//!
//! (module names of CodeNeRF's `model.py` as the paper's code uses it, `shape_blocks = 2`,
//! `texture_blocks = 1`). At W = D = 32 the network has 18 179 parameters (the paper's count;
//! the encoding matrix B included), plus 2·D per member for the codes.
//!
//! Rendering and the three losses are the object field's ([`super::render_ray`], vMAP's loss),
//! with masked means over all the category's rays, plus the code regulariser
//! `CODE_REG_WEIGHT · Σ_members (‖z_s‖₂ + ‖z_t‖₂)` over **every member** of the category, each
//! code once (the paper's code: `step_batch_loss_reg`, `torch.norm(codes, dim=-1).sum()`; the
//! paper writes squared norms). Codes start as N(0, 2/D) (CodeNeRF's
//! `randn(d, D) / sqrt(D / 2)`), drawn from the seeded RNG. Weights and codes use AdamW with the
//! same settings; each member's code has its own AdamW state, so adding a member never resets
//! another's.
//!
//! | file | concept |
//! |---|---|
//! | `net` | packed layers, the per-member code table, the forward pass |
//! | `train` | the fused forward + render + loss + backward of a chunk |
//! | `model` | [`CategoryField`]: weights, codes, optimiser states, evaluation |
//! | `member_codes` | [`MemberCodes`]: the codes' dimension, and whether a member's shape is its own ([`ShapeCodes`]) |
//! | `batch` | [`CategoryBatch`]: the category network in the fused step |
//! | `tensors` | weights and codes as named candle tensors |
//! | `reference` | the same model in candle autograd |

mod batch;
mod config;
mod member_codes;
mod member_rays;
mod model;
mod net;
pub mod reference;
mod tensors;
mod train;

pub use batch::{CategoryBatch, CategoryGradients, CategoryModel, PreparedCategory};
pub use config::{CategoryFieldConfig, CategoryRayBudget};
pub use member_codes::{MemberCodes, ShapeCodes};
pub use model::CategoryField;

use super::loss::FieldLosses;
use super::samples::RaySamples;
use crate::error::{CatmapError, Result};

/// Hidden width W of a category field.
pub const CATEGORY_HIDDEN: usize = 32;
/// Default dimension of each code (z_s and z_t).
pub const DEFAULT_CODE_DIM: usize = 32;
/// Weight of the code regulariser Σ (‖z_s‖ + ‖z_t‖).
pub const CODE_REG_WEIGHT: f32 = 5e-4;

/// One category's rays for one training step: rays of several members, in NOCS coordinates.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CategorySamples {
    /// The rays; sample points are in the category's NOCS frame.
    pub rays: RaySamples,
    /// Member (code index) of each ray, `R`.
    pub members: Vec<usize>,
}

impl CategorySamples {
    /// Checks the ray arrays and that every member index is below `members`.
    pub fn validate(&self, members: usize) -> Result<()> {
        self.rays.validate()?;
        if self.members.len() != self.rays.num_rays() {
            return Err(CatmapError::mismatch(
                "category samples' member indices",
                self.rays.num_rays(),
                self.members.len(),
            ));
        }
        match self.members.iter().find(|&&m| m >= members) {
            Some(&m) => Err(CatmapError::NoSuchIndex {
                what: "category samples' member",
                index: m,
                len: members,
            }),
            None => Ok(()),
        }
    }
}

/// One category's losses for one step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CategoryLosses {
    /// The rendering losses, as for an object field.
    pub field: FieldLosses,
    /// The code regulariser, [`CODE_REG_WEIGHT`] · Σ_members (‖z_s‖ + ‖z_t‖).
    pub code_reg: f32,
    /// `field.total + code_reg`.
    pub total: f32,
}
