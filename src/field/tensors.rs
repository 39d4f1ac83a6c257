//! A field's parameters as named candle tensors (vMAP's parameter names and shapes), for
//! inspection, interchange and checkpoints; the training kernels work on the flat vector.

use candle_core::{Device, Tensor};

use super::object_field::OccupancyField;
use crate::error::{CatmapError, Result};

impl OccupancyField {
    /// Every parameter tensor as `(name, tensor)` in layout order (weights `[out, in]`, biases
    /// `[out, 1]`, the encoding matrix `[21, 3]`), on the CPU.
    pub fn to_tensors(&self) -> Result<Vec<(String, Tensor)>> {
        let params = self.params();
        self.layout()
            .tensors()
            .iter()
            .map(|t| {
                let tensor = Tensor::from_slice(&params[t.range()], (t.shape[0], t.shape[1]), &Device::Cpu)
                    .map_err(CatmapError::tensor(&t.name))?;
                Ok((t.name.clone(), tensor))
            })
            .collect()
    }

    /// A field from named tensors (as [`OccupancyField::to_tensors`] gives them; any order) with
    /// fresh optimiser state. Errors name a missing tensor or a wrong shape.
    pub fn from_tensors(hidden: usize, scale: f32, tensors: &[(String, Tensor)]) -> Result<Self> {
        let layout = super::ParamLayout::occupancy(hidden);
        let mut params = vec![0.0f32; layout.len()];
        for spec in layout.tensors() {
            let (_, tensor) = tensors
                .iter()
                .find(|(name, _)| *name == spec.name)
                .ok_or_else(|| CatmapError::missing(format!("tensor {}", spec.name)))?;
            if tensor.dims() != [spec.shape[0], spec.shape[1]] {
                return Err(CatmapError::mismatch(
                    format!("shape of tensor {}", spec.name),
                    format!("{:?}", spec.shape),
                    format!("{:?}", tensor.dims()),
                ));
            }
            let values = tensor
                .flatten_all()
                .and_then(|t| t.to_vec1::<f32>())
                .map_err(CatmapError::tensor(&spec.name))?;
            params[spec.range()].copy_from_slice(&values);
        }
        Self::from_params(hidden, scale, params)
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn tensors_round_trip_with_vmap_names_and_shapes() {
        let field = OccupancyField::new(32, 2.0, &mut ChaCha8Rng::seed_from_u64(3));
        let tensors = field.to_tensors().expect("tensors");
        let names: Vec<&str> = tensors.iter().map(|(n, _)| n.as_str()).collect();
        assert!(names.contains(&"cat_layer.weight"), "{names:?}");
        let (_, cat) = tensors
            .iter()
            .find(|(n, _)| n == "cat_layer.weight")
            .expect("cat layer");
        assert_eq!(cat.dims(), [32, 32 + 87]);
        let mut reversed = tensors.clone();
        reversed.reverse();
        let back = OccupancyField::from_tensors(32, 2.0, &reversed).expect("round trip");
        assert_eq!(back.params(), field.params());
        let err = OccupancyField::from_tensors(32, 2.0, &tensors[1..]).expect_err("missing tensor");
        assert!(err.to_string().contains("missing"), "{err}");
    }
}
