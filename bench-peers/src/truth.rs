//! Each estimator's attitude against the simulator's truth, embedded with every sample
//! (`build.rs`): RMS and largest error of roll, pitch and yaw from [`FROM_US`] into the
//! flight, and how many attitudes were not finite. Evaluated after every counted step,
//! outside the stopwatch, so the figures say the counted work was a working filter.

use wing_ahrs::math::sqrt;

/// The statistics start this far into the flight, µs (20 s): EKF2 fuses no GNSS before its
/// 10 s of GNSS health and its tilt is still settling after (as `reference::CONVERGED_S`).
pub const FROM_US: u64 = 20_000_000;

/// Running errors against truth.
#[derive(Default)]
pub struct Errors {
    t0_us: Option<u64>,
    /// Sums of squared errors (roll, pitch, yaw), rad².
    sum_sq: [f64; 3],
    /// Largest absolute errors, rad.
    max: [f32; 3],
    /// Samples in the statistics (from [`FROM_US`] on, with truth).
    n: u64,
    /// Attitudes with a NaN or infinite angle, over the whole flight.
    nonfinite: u64,
    /// Samples from [`FROM_US`] on without truth in the log.
    no_truth: u64,
}

impl Errors {
    /// After the step of the sample at `t_us`: the estimate `est` and the truth, rad.
    pub fn add(&mut self, t_us: u64, est: [f32; 3], truth: [f32; 3]) {
        let t0 = *self.t0_us.get_or_insert(t_us);
        if est.iter().any(|x| !x.is_finite()) {
            self.nonfinite += 1;
            return;
        }
        if t_us.saturating_sub(t0) < FROM_US {
            return;
        }
        if truth.iter().any(|x| !x.is_finite()) {
            self.no_truth += 1;
            return;
        }
        for i in 0..3 {
            let e = wrap(est[i] - truth[i]).abs();
            self.sum_sq[i] += e as f64 * e as f64;
            self.max[i] = self.max[i].max(e);
        }
        self.n += 1;
    }

    pub fn print(&self, key: &str) {
        let rms = |i: usize| sqrt((self.sum_sq[i] / self.n.max(1) as f64) as f32).to_degrees();
        semihosting::println!(
            "{key}.truth_rms_deg: {:.3} {:.3} {:.3} (roll pitch yaw against the simulator's truth, from {} s)",
            rms(0),
            rms(1),
            rms(2),
            FROM_US / 1_000_000
        );
        semihosting::println!(
            "{key}.truth_max_deg: {:.3} {:.3} {:.3}",
            self.max[0].to_degrees(),
            self.max[1].to_degrees(),
            self.max[2].to_degrees()
        );
        semihosting::println!("{key}.truth_samples: {}", self.n);
        semihosting::println!("{key}.truth_missing_samples: {}", self.no_truth);
        semihosting::println!("{key}.nonfinite_attitudes: {}", self.nonfinite);
    }
}

/// An angle difference wrapped to [−π, π], rad.
fn wrap(a: f32) -> f32 {
    use core::f32::consts::{PI, TAU};
    let a = a % TAU;
    if a > PI {
        a - TAU
    } else if a < -PI {
        a + TAU
    } else {
        a
    }
}
