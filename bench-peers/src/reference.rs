//! The host's PX4 EKF2 on the same flight (`build.rs` runs `sim-harness`'s own adapter over
//! the log and stores its quaternion every [`EVERY`] samples), to check that the M4F build
//! computes the same filter: the rotation angle between the two quaternions, per checkpoint.

use wing_ahrs::math::{asin, sqrt};

static REFERENCE: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/host_ekf2.bin"));
/// Samples between checkpoints (1 s at the flights' 100 Hz); `build.rs` uses the same.
pub const EVERY: usize = 100;
/// Agreement is judged from this time into the flight, s: EKF2 fuses no GNSS before its
/// 10 s of GNSS health, and its tilt is still settling for a while after.
const CONVERGED_S: f32 = 20.0;

/// Size of the embedded reference, bytes (in flash, not the estimator's).
pub fn bytes() -> usize {
    REFERENCE.len()
}

fn host(j: usize) -> Option<[f32; 4]> {
    let b = REFERENCE.get(j * 16..(j + 1) * 16)?;
    let f = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap_or([0; 4]));
    Some([f(0), f(4), f(8), f(12)])
}

/// Rotation angle between two unit quaternions (w x y z), rad: 2·asin|vec(a* ⊗ b)|.
fn angle(a: [f32; 4], b: [f32; 4]) -> f32 {
    let (aw, av, bw, bv) = (a[0], [a[1], a[2], a[3]], b[0], [b[1], b[2], b[3]]);
    let cross = [
        av[1] * bv[2] - av[2] * bv[1],
        av[2] * bv[0] - av[0] * bv[2],
        av[0] * bv[1] - av[1] * bv[0],
    ];
    let v: [f32; 3] = core::array::from_fn(|i| aw * bv[i] - bw * av[i] - cross[i]);
    2.0 * asin(sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).min(1.0))
}

/// Running comparison of the M4F's quaternion with the host's.
#[derive(Default)]
pub struct Agreement {
    t0_us: Option<u64>,
    /// Largest angle after [`CONVERGED_S`], rad, and its time, s.
    max: (f32, f32),
    last: f32,
    checked: usize,
    /// Angle at every 10th checkpoint (10 s), rad.
    every_10s: [f32; 16],
}

impl Agreement {
    /// After sample `k` (time `t_us`), with the M4F quaternion `q`.
    pub fn check(&mut self, k: usize, t_us: u64, q: [f32; 4]) {
        let t0 = *self.t0_us.get_or_insert(t_us);
        if k % EVERY != EVERY - 1 {
            return;
        }
        let j = k / EVERY;
        let Some(h) = host(j) else { return };
        let a = angle(q, h);
        let t = (t_us - t0) as f32 * 1e-6;
        if t >= CONVERGED_S && a > self.max.0 {
            self.max = (a, t);
        }
        if j % 10 == 9 {
            if let Some(slot) = self.every_10s.get_mut(j / 10) {
                *slot = a;
            }
        }
        self.last = a;
        self.checked += 1;
    }

    pub fn print(&self, key: &str) {
        semihosting::println!(
            "{key}.host_agreement_max_deg: {:.4} (at {:.0} s; max over checkpoints from {CONVERGED_S:.0} s: rotation angle M4F vs host EKF2, {} checkpoints every {EVERY} samples)",
            self.max.0.to_degrees(),
            self.max.1,
            self.checked
        );
        semihosting::println!("{key}.host_agreement_final_deg: {:.4}", self.last.to_degrees());
        semihosting::print!("{key}.host_agreement_every_10s_deg:");
        let n = (self.checked / 10).min(self.every_10s.len());
        for a in &self.every_10s[..n] {
            semihosting::print!(" {:.3}", a.to_degrees());
        }
        semihosting::println!();
    }
}
