//! Float functions that `core` lacks.
//!
//! With std (the host build and tests) these are std's, which the compiler can vectorize;
//! without it, libm's. Both square roots are correctly rounded IEEE operations, so results are
//! bit-identical on the host and on the device.

/// Square root.
#[inline(always)]
pub(crate) fn sqrt(x: f32) -> f32 {
    #[cfg(any(test, feature = "std"))]
    {
        x.sqrt()
    }
    #[cfg(not(any(test, feature = "std")))]
    {
        libm::sqrtf(x)
    }
}
