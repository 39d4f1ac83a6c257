//! Which SIMD instruction set the field kernels run with, chosen at run time.
//!
//! [`Backend::detect`] picks the best of AVX-512, AVX2+FMA and scalar on this CPU (through
//! `pulp`, so no `unsafe` here and no `-C target-cpu`). Tests can force the scalar path or a
//! 16-lane path emulated with AVX2, so every lane width the kernels support is exercised on
//! any x86-64 machine with AVX2.

use pulp::{Simd, WithSimd};

/// An instruction set for the field kernels.
#[derive(Debug, Clone, Copy)]
pub enum Backend {
    /// The best set `pulp` detected on this CPU.
    Detected(pulp::Arch),
    /// Plain scalar code (one lane).
    Scalar,
    /// 16-lane vectors emulated with AVX2 (tests the AVX-512 code path on AVX2 machines).
    #[cfg(target_arch = "x86_64")]
    Avx2Wide(pulp::x86::V3),
}

impl Backend {
    /// The best instruction set of this CPU.
    pub fn detect() -> Self {
        Self::Detected(pulp::Arch::new())
    }

    /// Every backend that can run here (the detected one first).
    pub fn all_available() -> Vec<Self> {
        let mut all = vec![Self::detect(), Self::Scalar];
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = pulp::x86::V3::try_new() {
            all.push(Self::Avx2Wide(v3));
        }
        all
    }

    /// Number of f32 lanes of the detected set, for reports.
    pub fn lanes(self) -> usize {
        struct Lanes;
        impl WithSimd for Lanes {
            type Output = usize;
            #[inline(always)]
            fn with_simd<S: Simd>(self, _simd: S) -> usize {
                S::F32_LANES
            }
        }
        self.dispatch(Lanes)
    }

    /// A short name for reports: `avx512`, `avx2+fma`, `scalar` or `avx2 (16-lane emulation)`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Detected(arch) => match arch {
                #[cfg(target_arch = "x86_64")]
                pulp::Arch::V4(_) => "avx512",
                #[cfg(target_arch = "x86_64")]
                pulp::Arch::V3(_) => "avx2+fma",
                _ => "scalar",
            },
            Self::Scalar => "scalar",
            #[cfg(target_arch = "x86_64")]
            Self::Avx2Wide(_) => "avx2 (16-lane emulation)",
        }
    }

    /// Runs `op` with this backend's SIMD type.
    #[inline]
    pub(crate) fn dispatch<Op: WithSimd>(self, op: Op) -> Op::Output {
        match self {
            Self::Detected(arch) => arch.dispatch(op),
            Self::Scalar => op.with_simd(pulp::Scalar::new()),
            #[cfg(target_arch = "x86_64")]
            Self::Avx2Wide(v3) => v3.vectorize(move || op.with_simd(pulp::x86::V3_512b(v3))),
        }
    }
}

impl Default for Backend {
    fn default() -> Self {
        Self::detect()
    }
}
