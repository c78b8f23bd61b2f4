//! Which vector width a multiversioned loop runs at (issue 8).

/// A compiled build of a vectorised loop, chosen at run time from the CPU's features: the
/// exact-mode densities (`ArcGeometry::densities_into`) and the quality rows and row tests
/// (`quality::kernel`) are each compiled for every one of these, with the same IEEE
/// operations (no fused multiply-add), so every build gives the same bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Lanes {
    /// The baseline build (SSE2 on x86-64).
    Base,
    /// AVX2, 4 lanes.
    Avx2,
    /// AVX-512 F, DQ and VL, 8 lanes.
    Avx512,
}

impl Lanes {
    /// Every build, narrowest first.
    pub(crate) const ALL: [Lanes; 3] = [Lanes::Base, Lanes::Avx2, Lanes::Avx512];

    /// True when the CPU can run this build.
    pub(crate) fn available(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            match self {
                Lanes::Base => true,
                Lanes::Avx2 => has!("avx2"),
                Lanes::Avx512 => {
                    has!("avx512f") && has!("avx512dq") && has!("avx512vl") && has!("avx2")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self == Lanes::Base
        }
    }

    /// The widest build the CPU can run.
    pub(crate) fn best() -> Lanes {
        [Lanes::Avx512, Lanes::Avx2]
            .into_iter()
            .find(|l| l.available())
            .unwrap_or(Lanes::Base)
    }
}
