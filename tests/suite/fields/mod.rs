//! The neural fields: gradients against a reference, training in the mapper, and the shared
//! category fields.

mod category_field_gradients;
mod category_fields;
mod field_gradients;
mod field_training;

/// Multiplies the named tensors of `params` (laid out as `layout` says) by `factor`.
///
/// The gradient tests scale each network's α head down by 10 so that occupancies stay away from
/// 0 and 1: saturated occupancies make `1 − o` cancel in f32 (as in PyTorch), and the f64
/// reference would then measure f32 conditioning rather than the gradient code.
fn scale_tensors(params: &mut [f32], layout: &catmap::field::ParamLayout, names: &[&str], factor: f32) {
    for name in names {
        let range = layout.get(name).expect("the layout has this tensor").range();
        for p in &mut params[range] {
            *p *= factor;
        }
    }
}

/// `work`'s result on a rayon pool of `threads` threads (the bit-identity tests compare them).
fn on_threads<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool")
        .install(work)
}
