//! Which SIMD instruction set the field kernels run with, chosen at run time.
//!
//! [`Backend::detect`] picks the best of AVX-512, AVX2+FMA and scalar on an x86-64 CPU, NEON or
//! scalar on an ARM one (through `pulp`, so no `unsafe` here and no `-C target-cpu`). The
//! kernels have one arm per lane width: 16 (AVX-512), 8 (AVX2), 4 (NEON) and 1 (scalar).
//! [`Backend::all_available`] forces every arm that can run on the machine at hand, so an
//! AVX-512 machine also tests the 8-lane path an AVX2 laptop runs, and any x86-64 machine with
//! AVX2 tests every lane width: 4 lanes and 16 lanes are run with AVX2 instructions.

use pulp::{Simd, WithSimd};

/// An instruction set and lane width for the field kernels.
#[derive(Debug, Clone, Copy)]
pub enum Backend {
    /// The best set `pulp` detected on this CPU: what the library runs.
    Detected(pulp::Arch),
    /// Plain scalar code (one lane): what a CPU without AVX2 or NEON runs.
    Scalar,
    /// AVX2+FMA, 8 lanes: what an AVX2-only CPU detects, forced on a CPU that has AVX-512.
    #[cfg(target_arch = "x86_64")]
    Avx2(pulp::x86::V3),
    /// 4 lanes with AVX2 instructions: the lane width of ARM's NEON, on x86-64.
    #[cfg(target_arch = "x86_64")]
    Avx2Lanes4(pulp::x86::V3),
    /// 16 lanes emulated with AVX2: the lane width of AVX-512, on a CPU without it.
    #[cfg(target_arch = "x86_64")]
    Avx2Lanes16(pulp::x86::V3),
}

impl Backend {
    /// The best instruction set of this CPU.
    pub fn detect() -> Self {
        Self::Detected(pulp::Arch::new())
    }

    /// Every backend that can run here, the detected one first, then each other lane width or
    /// instruction set the kernels have an arm for (none twice).
    pub fn all_available() -> Vec<Self> {
        let detected = Self::detect();
        let mut all = vec![detected];
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = pulp::x86::V3::try_new() {
            if !matches!(detected, Self::Detected(pulp::Arch::V3(_))) {
                all.push(Self::Avx2(v3));
            }
            all.push(Self::Avx2Lanes4(v3));
            all.push(Self::Avx2Lanes16(v3));
        }
        if detected.lanes() > 1 {
            all.push(Self::Scalar);
        }
        all
    }

    /// Number of f32 lanes of this backend.
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

    /// A short name for reports: `avx512`, `avx2+fma`, `neon`, `scalar`, `avx2 narrowed` (4 lanes)
    /// or `avx2 widened` (16 lanes, emulated).
    pub fn name(self) -> &'static str {
        match self {
            Self::Detected(arch) => match arch {
                #[cfg(target_arch = "x86_64")]
                pulp::Arch::V4(_) => "avx512",
                #[cfg(target_arch = "x86_64")]
                pulp::Arch::V3(_) => "avx2+fma",
                #[cfg(target_arch = "aarch64")]
                pulp::Arch::Neon(_) => "neon",
                _ => "scalar",
            },
            Self::Scalar => "scalar",
            #[cfg(target_arch = "x86_64")]
            Self::Avx2(_) => "avx2+fma",
            #[cfg(target_arch = "x86_64")]
            Self::Avx2Lanes4(_) => "avx2 narrowed",
            #[cfg(target_arch = "x86_64")]
            Self::Avx2Lanes16(_) => "avx2 widened",
        }
    }

    /// `name: N lanes` of every backend in `backends`, comma-separated: what a test ran.
    pub fn describe_all(backends: &[Self]) -> String {
        backends
            .iter()
            .map(|b| match b.lanes() {
                1 => format!("{}: 1 lane", b.name()),
                lanes => format!("{}: {lanes} lanes", b.name()),
            })
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Runs `op` with this backend's SIMD type.
    #[inline]
    pub(crate) fn dispatch<Op: WithSimd>(self, op: Op) -> Op::Output {
        match self {
            Self::Detected(arch) => arch.dispatch(op),
            Self::Scalar => op.with_simd(pulp::Scalar::new()),
            #[cfg(target_arch = "x86_64")]
            Self::Avx2(v3) => Simd::vectorize(v3, op),
            #[cfg(target_arch = "x86_64")]
            Self::Avx2Lanes4(v3) => v3.vectorize(move || op.with_simd(pulp::x86::V3_128b(v3))),
            #[cfg(target_arch = "x86_64")]
            Self::Avx2Lanes16(v3) => v3.vectorize(move || op.with_simd(pulp::x86::V3_512b(v3))),
        }
    }
}

impl Default for Backend {
    fn default() -> Self {
        Self::detect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_lane_width_of_the_kernels_runs_where_avx2_exists() {
        let all = Backend::all_available();
        println!("SIMD paths on this machine: {}", Backend::describe_all(&all));
        let mut lanes: Vec<usize> = all.iter().map(|b| b.lanes()).collect();
        assert_eq!(all[0].name(), Backend::detect().name(), "the detected path comes first");
        assert!(lanes.contains(&1), "the scalar path runs");
        #[cfg(target_arch = "x86_64")]
        if pulp::x86::V3::try_new().is_some() {
            lanes.sort_unstable();
            lanes.dedup();
            assert_eq!(lanes, [1, 4, 8, 16], "every arm of the kernels runs: {all:?}");
            assert!(
                all.iter().any(|b| b.name() == "avx2+fma" && b.lanes() == 8),
                "the native AVX2 path an AVX2-only CPU detects runs here too: {all:?}"
            );
        }
        let names: Vec<(&str, usize)> = all.iter().map(|b| (b.name(), b.lanes())).collect();
        let mut unique = names.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), names.len(), "no path twice: {names:?}");
    }
}
