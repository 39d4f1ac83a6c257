//! [`TensorStore`]: named 1-D `f32` tensors (field weights, optimiser moments, codes), stored as
//! one safetensors file.

use std::collections::BTreeMap;
use std::path::Path;

use safetensors::tensor::{Dtype, SafeTensors, TensorView};

use crate::error::{CatmapError, Result};

/// Named `f32` vectors, in name order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TensorStore {
    tensors: BTreeMap<String, Vec<f32>>,
}

impl TensorStore {
    /// An empty store.
    pub fn new() -> Self {
        Self::default()
    }

    /// Stores `values` under `name` (replacing an earlier tensor of that name).
    pub fn insert(&mut self, name: impl Into<String>, values: Vec<f32>) {
        self.tensors.insert(name.into(), values);
    }

    /// Removes and returns the tensor `name`; `file` is named in the error when it is missing.
    pub fn take(&mut self, name: &str, file: &Path) -> Result<Vec<f32>> {
        self.tensors
            .remove(name)
            .ok_or_else(|| CatmapError::checkpoint(file, format!("tensor {name:?} is missing")))
    }

    /// Number of tensors.
    pub fn len(&self) -> usize {
        self.tensors.len()
    }

    /// Whether the store is empty.
    pub fn is_empty(&self) -> bool {
        self.tensors.is_empty()
    }

    /// Tensor names, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.tensors.keys().map(String::as_str)
    }

    /// The safetensors encoding (little-endian `F32`, shape `[len]`; deterministic: sorted names).
    pub fn to_safetensors(&self) -> Result<Vec<u8>> {
        let bytes: Vec<(&str, Vec<u8>)> = self
            .tensors
            .iter()
            .map(|(name, values)| (name.as_str(), values.iter().flat_map(|v| v.to_le_bytes()).collect()))
            .collect();
        let views = bytes
            .iter()
            .zip(self.tensors.values())
            .map(|((name, data), values)| {
                TensorView::new(Dtype::F32, vec![values.len()], data).map(|view| (*name, view))
            })
            .collect::<std::result::Result<Vec<_>, _>>()?;
        Ok(safetensors::tensor::serialize(views, None)?)
    }

    /// Decodes a safetensors buffer read from `file` (every tensor must be 1-D `F32`).
    pub fn from_safetensors(bytes: &[u8], file: &Path) -> Result<Self> {
        let bad = |reason: String| CatmapError::checkpoint(file, reason);
        let decoded = SafeTensors::deserialize(bytes).map_err(|e| bad(format!("not a safetensors file: {e}")))?;
        let mut tensors = BTreeMap::new();
        for (name, view) in decoded.tensors() {
            if view.dtype() != Dtype::F32 || view.shape().len() != 1 {
                return Err(bad(format!(
                    "tensor {name:?} is {:?} {:?}, expected 1-D F32",
                    view.dtype(),
                    view.shape()
                )));
            }
            let values = view
                .data()
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            tensors.insert(name, values);
        }
        Ok(Self { tensors })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tensors_round_trip_bit_exactly_through_safetensors() {
        let mut store = TensorStore::new();
        store.insert("b/moments", vec![f32::NAN, -0.0, 1e-38, f32::INFINITY]);
        store.insert("a/params", vec![1.5, -2.25, 3.0e7]);
        store.insert("empty", Vec::new());
        let bytes = store.to_safetensors().expect("encodes");
        let back = TensorStore::from_safetensors(&bytes, Path::new("t.safetensors")).expect("decodes");
        assert_eq!(back.names().collect::<Vec<_>>(), ["a/params", "b/moments", "empty"]);
        for name in ["a/params", "b/moments", "empty"] {
            let a: Vec<u32> = store.tensors[name].iter().map(|v| v.to_bits()).collect();
            let b: Vec<u32> = back.tensors[name].iter().map(|v| v.to_bits()).collect();
            assert_eq!(a, b, "{name}");
        }
        assert_eq!(
            store.to_safetensors().expect("encodes"),
            bytes,
            "deterministic encoding"
        );
    }

    #[test]
    fn garbage_and_missing_tensors_are_named_errors() {
        let err = TensorStore::from_safetensors(b"not safetensors", Path::new("x.safetensors")).unwrap_err();
        assert!(err.to_string().contains("x.safetensors"), "{err}");
        let err = TensorStore::new().take("w", Path::new("y.safetensors")).unwrap_err();
        assert!(err.to_string().contains("\"w\" is missing"), "{err}");
    }
}
