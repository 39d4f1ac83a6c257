//! [`MemberCodes`]: what codes each member of a category field has — their dimension, and
//! whether its shape is its own ([`ShapeCodes`]).

use serde::{Deserialize, Serialize};

/// Whose shape a category field draws for a member.
///
/// METHOD.md §5 (CodeNeRF) gives every member its own shape code z_s. A member's code is taught
/// only by its own rays: where its cameras never looked, nothing holds its shape to its twins'.
/// A subcategory is one design by construction (its members lie within the subcategory rule's
/// Chamfer distance of one representative), and a member's own shape code fits what only it
/// shows — its registration error and its sensor's noise — and may drop what only its twins
/// saw: under a Kinect-like camera the chair seen at 20 % under the default scene's table lost
/// one or two of the legs it never saw on some mapper seeds (completion 2.3–4.4 cm against
/// 1.0–1.2), and the chair seen from 5 m kept its noise (1.1–1.3 cm). With one shape for the
/// subcategory every member's mesh is the shape all of its members' rays teach.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ShapeCodes {
    /// Each member has its own shape code (METHOD.md §5).
    #[default]
    PerMember,
    /// Every member's shape code is zero and stays so (its gradient is dropped): the network
    /// draws one shape per subcategory, each member in its own frame; texture codes stay each
    /// member's own.
    Shared,
}

/// The codes of a category field's members.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemberCodes {
    /// Dimension D of each shape and texture code.
    pub dim: usize,
    /// Whose shape each member draws.
    pub shape: ShapeCodes,
}

impl MemberCodes {
    /// Codes of dimension `dim`, each member with its own shape (METHOD.md §5).
    pub fn per_member(dim: usize) -> Self {
        Self {
            dim,
            shape: ShapeCodes::PerMember,
        }
    }
}

impl ShapeCodes {
    /// `code` (`[z_s ‖ z_t]` of dimension `dim` each) as a member's code must be: its shape half
    /// zeroed when shapes are shared.
    pub fn fit(self, code: &mut [f32], dim: usize) {
        if self == Self::Shared {
            let dim = dim.min(code.len());
            code[..dim].fill(0.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shared_shape_zeroes_the_shape_half_and_keeps_the_texture_half() {
        let mut code = vec![1.0, 2.0, 3.0, 4.0];
        ShapeCodes::PerMember.fit(&mut code, 2);
        assert_eq!(code, [1.0, 2.0, 3.0, 4.0], "own shapes are kept");
        ShapeCodes::Shared.fit(&mut code, 2);
        assert_eq!(code, [0.0, 0.0, 3.0, 4.0]);
    }
}
