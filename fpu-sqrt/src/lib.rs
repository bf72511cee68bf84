//! `sqrt(x)` for f32, correctly rounded (IEEE 754), in one place:
//!
//! - on hard-float ARM (`thumbv7em-none-eabihf`, the Cortex-M4F) the FPU's `VSQRT.F32`,
//!   about 10 instructions with the moves around it against libm's 57 in software;
//! - elsewhere `libm::sqrtf` (one `sqrtss` on x86-64).
//!
//! Both round correctly, so a host replay and the firmware agree to the bit. Checked where it
//! matters, on the M4F: the firmware's boot-time benchmark compares this with libm's software
//! `sqrtf` over every binade (`fw_sqrt_mismatches` of `cargo xtask bench-fw`, which fails
//! unless it is 0); the host's root is libm's (`tests/math_f32.rs` checks it in every binade).
//!
//! Hand-written because no crate reaches `VSQRT` on stable Rust: `core` has no `f32::sqrt`
//! (`core::f32::math` is unstable), the `sreg` register class needs the unstable `vfp2`
//! target feature, and libm's `arch` module has no ARM routine. The unsafe block lives here
//! so that the estimator's core can stay `forbid(unsafe_code)`.
#![no_std]

/// √x, correctly rounded. Negative input gives NaN (whose payload may differ by target).
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    imp::sqrt(x)
}

#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
mod imp {
    #[inline(always)]
    pub fn sqrt(x: f32) -> f32 {
        let r: f32;
        // SAFETY: the instructions touch one FPU register, s15, which they save and restore
        // on the stack, and the two core registers named; no Rust-visible memory, no flags.
        // (Core registers because the `sreg` class needs the unstable `vfp2` feature.)
        unsafe {
            core::arch::asm!(
                "vpush {{s15}}",
                "vmov s15, {x}",
                "vsqrt.f32 s15, s15",
                "vmov {r}, s15",
                "vpop {{s15}}",
                x = in(reg) x,
                r = lateout(reg) r,
                options(pure, nomem, preserves_flags),
            )
        };
        r
    }
}

#[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
mod imp {
    #[inline(always)]
    pub fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
}
