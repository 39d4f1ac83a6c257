//! A category field as named candle tensors: the network's tensors (CodeNeRF module names, see
//! [`super::super::ParamLayout::category`]) plus `shape_codes.weight` and `texture_codes.weight`
//! (`[members, D]`, as CodeNeRF's `nn.Embedding`s), for checkpoints.

use candle_core::{Device, Tensor};

use super::model::CategoryField;
use crate::error::{CatmapError, Result};

/// Name of the shape-code tensor.
const SHAPE_CODES: &str = "shape_codes.weight";
/// Name of the texture-code tensor.
const TEXTURE_CODES: &str = "texture_codes.weight";

fn tensor(values: &[f32], shape: (usize, usize), name: &str) -> Result<Tensor> {
    Tensor::from_slice(values, shape, &Device::Cpu).map_err(CatmapError::tensor(name))
}

fn find<'a>(tensors: &'a [(String, Tensor)], name: &str) -> Result<&'a Tensor> {
    tensors
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, t)| t)
        .ok_or_else(|| CatmapError::missing(format!("tensor {name}")))
}

fn values(t: &Tensor, name: &str, dims: &[usize]) -> Result<Vec<f32>> {
    if t.dims() != dims {
        return Err(CatmapError::mismatch(
            format!("shape of tensor {name}"),
            format!("{dims:?}"),
            format!("{:?}", t.dims()),
        ));
    }
    t.flatten_all()
        .and_then(|t| t.to_vec1::<f32>())
        .map_err(CatmapError::tensor(name))
}

impl CategoryField {
    /// Every network tensor in layout order (weights `[out, in]`, biases `[out, 1]`, B
    /// `[21, 3]`), then the codes `[members, D]`, on the CPU.
    pub fn to_tensors(&self) -> Result<Vec<(String, Tensor)>> {
        let params = self.params();
        let mut out = self
            .layout()
            .tensors()
            .iter()
            .map(|t| {
                Ok((
                    t.name.clone(),
                    tensor(&params[t.range()], (t.shape[0], t.shape[1]), &t.name)?,
                ))
            })
            .collect::<Result<Vec<_>>>()?;
        let (m, d) = (self.num_members(), self.code_dim());
        let codes = self.codes();
        let shape: Vec<f32> = codes.iter().flat_map(|c| c[..d].to_vec()).collect();
        let texture: Vec<f32> = codes.iter().flat_map(|c| c[d..].to_vec()).collect();
        out.push((SHAPE_CODES.to_owned(), tensor(&shape, (m, d), SHAPE_CODES)?));
        out.push((TEXTURE_CODES.to_owned(), tensor(&texture, (m, d), TEXTURE_CODES)?));
        Ok(out)
    }

    /// A field from named tensors (as [`CategoryField::to_tensors`] gives them; any order) with
    /// fresh optimiser states; the member count is the codes' row count. Errors name a missing
    /// tensor or a wrong shape.
    pub fn from_tensors(hidden: usize, code_dim: usize, scale: f32, tensors: &[(String, Tensor)]) -> Result<Self> {
        let layout = super::super::ParamLayout::category(hidden, code_dim);
        let mut params = vec![0.0f32; layout.len()];
        for spec in layout.tensors() {
            let v = values(find(tensors, &spec.name)?, &spec.name, &spec.shape)?;
            params[spec.range()].copy_from_slice(&v);
        }
        let shape_t = find(tensors, SHAPE_CODES)?;
        let members = shape_t.dims().first().copied().unwrap_or(0);
        let shape = values(shape_t, SHAPE_CODES, &[members, code_dim])?;
        let texture = values(find(tensors, TEXTURE_CODES)?, TEXTURE_CODES, &[members, code_dim])?;
        let codes = shape
            .chunks_exact(code_dim.max(1))
            .zip(texture.chunks_exact(code_dim.max(1)))
            .map(|(s, t)| [s, t].concat())
            .collect();
        Self::from_params(hidden, code_dim, scale, params, codes)
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn weights_and_codes_round_trip_through_named_tensors() {
        let field = CategoryField::new(32, 8, 1.0, 3, &mut ChaCha8Rng::seed_from_u64(4));
        let tensors = field.to_tensors().expect("tensors");
        let (_, codes) = tensors.iter().find(|(n, _)| n == SHAPE_CODES).expect("shape codes");
        assert_eq!(codes.dims(), [3, 8], "one row per member");
        let mut reversed = tensors.clone();
        reversed.reverse();
        let back = CategoryField::from_tensors(32, 8, 1.0, &reversed).expect("round trip");
        assert_eq!(back.params(), field.params());
        assert_eq!(back.codes(), field.codes());
        let without_texture: Vec<_> = tensors.into_iter().filter(|(n, _)| n != TEXTURE_CODES).collect();
        let err = CategoryField::from_tensors(32, 8, 1.0, &without_texture).expect_err("missing codes");
        assert!(err.to_string().contains("texture_codes"), "{err}");
    }
}
