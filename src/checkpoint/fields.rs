//! Fields in a checkpoint: shapes and step counts in the serde state, parameters, AdamW moments
//! and codes as tensors named `{name}/params`, `{name}/adam_m`, `{name}/adam_v` (and for a
//! category field `{name}/code{j}`, `{name}/code{j}_adam_m`, `{name}/code{j}_adam_v`).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::TensorStore;
use crate::error::{CatmapError, Result};
use crate::field::category::ShapeCodes;
use crate::field::{AdamWState, CategoryField, OccupancyField};

/// What the state records of an occupancy field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OccupancyFieldHeader {
    /// Hidden width H.
    pub hidden: usize,
    /// Encoding scale.
    pub scale: f32,
    /// AdamW steps taken.
    pub step: u64,
}

/// What the state records of a category field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CategoryFieldHeader {
    /// Width W.
    pub hidden: usize,
    /// Code dimension D.
    pub code_dim: usize,
    /// Encoding scale.
    pub scale: f32,
    /// AdamW steps of the network.
    pub step: u64,
    /// AdamW steps of each member's codes.
    pub code_steps: Vec<u64>,
    /// Whose shape the field draws for each member (a checkpoint without it: each member's own).
    #[serde(default)]
    pub shape_codes: ShapeCodes,
}

fn store_adam(store: &mut TensorStore, name: &str, adam: &AdamWState) {
    store.insert(format!("{name}_adam_m"), adam.m.clone());
    store.insert(format!("{name}_adam_v"), adam.v.clone());
}

fn take_adam(store: &mut TensorStore, name: &str, step: u64, file: &Path) -> Result<AdamWState> {
    Ok(AdamWState {
        m: store.take(&format!("{name}_adam_m"), file)?,
        v: store.take(&format!("{name}_adam_v"), file)?,
        step,
    })
}

/// Puts `field` into `store` under `name`; returns what the state keeps.
pub fn store_occupancy_field(field: &OccupancyField, name: &str, store: &mut TensorStore) -> OccupancyFieldHeader {
    store.insert(format!("{name}/params"), field.params().to_vec());
    store_adam(store, &format!("{name}/params"), field.optimiser_state());
    OccupancyFieldHeader {
        hidden: field.hidden(),
        scale: field.scale(),
        step: field.optimiser_state().step,
    }
}

/// Takes the field `name` out of `store` (read from `file`, named in errors).
pub fn load_occupancy_field(
    header: &OccupancyFieldHeader,
    name: &str,
    store: &mut TensorStore,
    file: &Path,
) -> Result<OccupancyField> {
    let params = store.take(&format!("{name}/params"), file)?;
    let adam = take_adam(store, &format!("{name}/params"), header.step, file)?;
    OccupancyField::from_params(header.hidden, header.scale, params)
        .and_then(|f| f.with_optimiser_state(adam))
        .map_err(|e| CatmapError::checkpoint(file, format!("field {name}: {e}")))
}

/// Puts the category field into `store` under `name`; returns what the state keeps.
pub fn store_category_field(field: &CategoryField, name: &str, store: &mut TensorStore) -> CategoryFieldHeader {
    store.insert(format!("{name}/params"), field.params().to_vec());
    store_adam(store, &format!("{name}/params"), field.optimiser_state());
    let mut code_steps = Vec::with_capacity(field.num_members());
    for j in 0..field.num_members() {
        let (Some(code), Some(adam)) = (field.code(j), field.code_optimiser_state(j)) else {
            continue;
        };
        store.insert(format!("{name}/code{j}"), code.to_vec());
        store_adam(store, &format!("{name}/code{j}"), adam);
        code_steps.push(adam.step);
    }
    CategoryFieldHeader {
        hidden: field.hidden(),
        code_dim: field.code_dim(),
        scale: field.scale(),
        step: field.optimiser_state().step,
        code_steps,
        shape_codes: field.shape_codes(),
    }
}

/// Takes the category field `name` out of `store` (read from `file`, named in errors).
pub fn load_category_field(
    header: &CategoryFieldHeader,
    name: &str,
    store: &mut TensorStore,
    file: &Path,
) -> Result<CategoryField> {
    let params = store.take(&format!("{name}/params"), file)?;
    let adam = take_adam(store, &format!("{name}/params"), header.step, file)?;
    let mut codes = Vec::with_capacity(header.code_steps.len());
    let mut code_adams = Vec::with_capacity(header.code_steps.len());
    for (j, &step) in header.code_steps.iter().enumerate() {
        codes.push(store.take(&format!("{name}/code{j}"), file)?);
        code_adams.push(take_adam(store, &format!("{name}/code{j}"), step, file)?);
    }
    CategoryField::from_params(header.hidden, header.code_dim, header.scale, params, codes)
        .map(|f| f.with_shape_codes(header.shape_codes))
        .and_then(|f| f.with_optimiser_states(adam, code_adams))
        .map_err(|e| CatmapError::checkpoint(file, format!("category field {name}: {e}")))
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn fields_with_moments_round_trip_exactly() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let mut field = OccupancyField::new(32, 2.0, &mut rng);
        let n = field.params().len();
        let moved = AdamWState {
            m: (0..n).map(|i| i as f32 * 1e-3).collect(),
            v: (0..n).map(|i| i as f32 * 1e-6).collect(),
            step: 17,
        };
        field = field.with_optimiser_state(moved).expect("fits");
        let mut category = CategoryField::new(32, 8, 1.0, 3, &mut rng);
        category.code_mut(1).expect("member 1")[0] = 0.25;
        let shared = CategoryField::new(32, 8, 1.0, 2, &mut rng).with_shape_codes(ShapeCodes::Shared);
        let mut store = TensorStore::new();
        let h = store_occupancy_field(&field, "objects/3", &mut store);
        let c = store_category_field(&category, "categories/0", &mut store);
        let s = store_category_field(&shared, "categories/1", &mut store);
        assert_eq!(
            (c.shape_codes, s.shape_codes),
            (ShapeCodes::PerMember, ShapeCodes::Shared)
        );
        let file = Path::new("tensors.safetensors");
        let mut back = TensorStore::from_safetensors(&store.to_safetensors().expect("encodes"), file).expect("decodes");
        assert_eq!(
            load_occupancy_field(&h, "objects/3", &mut back, file).expect("loads"),
            field
        );
        assert_eq!(
            load_category_field(&c, "categories/0", &mut back, file).expect("loads"),
            category
        );
        let shared_back = load_category_field(&s, "categories/1", &mut back, file).expect("loads");
        assert_eq!(shared_back, shared, "a shared shape comes back shared");
        let before = r#"{"hidden": 32, "code_dim": 8, "scale": 1.0, "step": 0, "code_steps": []}"#;
        let old: CategoryFieldHeader = serde_json::from_str(before).expect("a header of before");
        assert_eq!(
            old.shape_codes,
            ShapeCodes::PerMember,
            "a checkpoint of before had its own shapes"
        );
        assert!(back.is_empty(), "every tensor was used");
        let err = load_occupancy_field(&h, "objects/3", &mut back, file)
            .unwrap_err()
            .to_string();
        assert!(err.contains("objects/3/params"), "{err}");
    }
}
