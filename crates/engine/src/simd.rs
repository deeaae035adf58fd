//! Run-time choice of the instruction set for the hot loops.
//!
//! The default build targets baseline x86-64 (SSE2), so that the binary runs
//! on any x86-64 machine. Where the CPU has AVX2, the pair loop and FIRE's
//! vector passes run a second copy of the *same* Rust code compiled with
//! AVX2 enabled: wider registers, more registers, three-operand forms.
//!
//! NOTE: this changes no result. Rust never contracts `a * b + c` into a
//! fused multiply-add unless asked (`f64::mul_add`), and every operation
//! (including `sqrt` and division) is IEEE-exact in both copies, so both give
//! the same bits; `tests` check whole minimisations for bit equality.

/// True when the AVX2 copies of the hot loops may run on this CPU.
///
/// `JAMKIT_PORTABLE=1` in the environment forces the baseline copies (to
/// check that both give the same packings, or to time them).
#[inline]
pub fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        use std::sync::OnceLock;
        static CHOICE: OnceLock<bool> = OnceLock::new();
        *CHOICE.get_or_init(|| {
            std::env::var_os("JAMKIT_PORTABLE").is_none_or(|v| v.is_empty() || v == "0")
                && std::is_x86_feature_detected!("avx2")
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
