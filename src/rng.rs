//! Seeded random generators: every random choice in catmap draws from one of these.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::ids::{ClassId, ObjectId};

/// Who owns a random stream. Each owner gets an independent ChaCha stream of the run's seed,
/// so adding an object never changes another object's draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RngStream {
    /// The mapper itself (global choices).
    Mapper,
    /// The background.
    Background,
    /// One object.
    Object(ObjectId),
    /// The background's field: initial weights and training samples.
    BackgroundField,
    /// One object's field: initial weights and training samples.
    ObjectField(ObjectId),
    /// The k-th category field: initial weights and codes.
    CategoryField(u32),
    /// The k-th remapping of category members (fresh codes of members joining a field).
    CategoryCodes(u32),
    /// The sensor and segmenter imperfections of a synthetic scene's frame at this position.
    SensorFrame(u64),
}

/// Field streams start here, above every object stream.
const FIELD_STREAMS: u64 = 1 << 40;

/// The generator of `stream` for a run seeded with `seed`.
pub fn seeded_rng(seed: u64, stream: RngStream) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(match stream {
        RngStream::Mapper => 0,
        RngStream::Background => 1,
        RngStream::Object(ObjectId(id)) => 2 + u64::from(id),
        RngStream::BackgroundField => FIELD_STREAMS + 1,
        RngStream::ObjectField(ObjectId(id)) => FIELD_STREAMS + 2 + u64::from(id),
        RngStream::CategoryField(k) => 2 * FIELD_STREAMS + u64::from(k),
        RngStream::CategoryCodes(k) => 3 * FIELD_STREAMS + u64::from(k),
        RngStream::SensorFrame(position) => 4 * FIELD_STREAMS + position,
    });
    rng
}

/// The seed of class `class`'s registration in a run seeded with `seed`: its representative
/// choice and each pair's search draw from generators seeded with it (see
/// `categories::class_registration`).
pub fn class_registration_seed(seed: u64, class: ClassId) -> u64 {
    seed ^ (u64::from(class.0) << 32)
}

/// One N(0, 1) draw in double precision (Box–Muller; consumes two `f64` draws).
pub fn standard_normal_f64<R: rand::Rng + ?Sized>(rng: &mut R) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// One N(0, 1) draw in single precision (Box–Muller; consumes two `f32` draws).
pub fn standard_normal_f32<R: rand::Rng + ?Sized>(rng: &mut R) -> f32 {
    let u1 = 1.0 - rng.random::<f32>(); // (0, 1]
    let u2: f32 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;

    #[test]
    fn streams_are_reproducible_and_independent() {
        let a: u64 = seeded_rng(5, RngStream::Object(ObjectId(3))).random();
        let b: u64 = seeded_rng(5, RngStream::Object(ObjectId(3))).random();
        let c: u64 = seeded_rng(5, RngStream::Object(ObjectId(4))).random();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn each_class_registers_from_its_own_seed() {
        assert_eq!(class_registration_seed(5, ClassId(0)), 5);
        assert_eq!(class_registration_seed(5, ClassId(3)), 5 ^ (3 << 32));
        assert_ne!(
            class_registration_seed(5, ClassId(3)),
            class_registration_seed(5, ClassId(4))
        );
    }
}
