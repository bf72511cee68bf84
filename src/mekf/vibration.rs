//! Vibration test of one GPS interval: the accelerometer's sample-to-sample scatter
//! over the interval against what the noise spec makes of it. The window holds each
//! axis' squared standard error of the mean from successive differences
//! ([`WindowMean::noise_sq`]: a manoeuvre, smooth at the IMU rate, does not count —
//! the plain scatter flagged half of a real aerobatic flight); white noise of density
//! N gives a mean over T seconds the variance N²/T, so the test
//! `max noise_sq · T > ratio · N²` needs no division and no extra pass.

use super::dv_window::WindowMean;
use crate::math::max;

/// `ratio · N²` ((m/s²)²/Hz) for [`excessive`], from `QuatConfig`'s `vibration_ratio` and
/// `accel_noise_density`; ∞ disables the test.
pub fn limit(ratio: f32, accel_noise_density: f32) -> f32 {
    ratio * accel_noise_density * accel_noise_density
}

/// Whether an axis of window `w` scatters beyond `limit` ([`limit`]). NaN scatter: false
/// (the window's mean is rejected elsewhere).
#[inline]
pub fn excessive(w: &WindowMean, limit: f32) -> bool {
    let s = w.noise_sq;
    max(max(s[0], s[1]), s[2]) * w.duration > limit
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window(noise_sq: [f32; 3], duration: f32) -> WindowMean {
        WindowMean { f_ned: [0.0; 3], f_body: [0.0; 3], sem_sq: [1e9; 3], noise_sq, duration }
    }

    /// 20 samples of white noise σ = N·√(n/T): σ²/n = N²/T, at the limit for ratio 1; the
    /// manoeuvre's scatter (`sem_sq`, huge here) does not count.
    #[test]
    fn threshold_is_ratio_times_the_white_noise_of_the_window_mean() {
        let (n, t) = (0.01_f32, 0.2_f32);
        let white = n * n / t;
        let lim = limit(100.0, n);
        assert!(!excessive(&window([99.0 * white, 0.0, 0.0], t), lim));
        assert!(excessive(&window([0.0, 0.0, 101.0 * white], t), lim));
        assert!(!excessive(&window([1e9; 3], t), limit(f32::INFINITY, n)));
        assert!(!excessive(&window([f32::NAN; 3], t), lim));
    }
}
