//! The gyro's scale factors about body x and y as two more states, kept beside the
//! six-state filter as the blocks of the augmented covariance that its P does not hold:
//! `E[δx·δsᵀ]` (6×2) and `E[δs·δsᵀ]` (2×2).
//!
//! The gyro reads `(1 + sᵢ)·ωᵢ + bᵢ` about body axis i. A scale error is coherent over a
//! manoeuvre — 0.5 % of a 360° roll is 1.8° — and the bias states, which are constant
//! in body axes, take it in during rolls and loops and keep it after them. Here the
//! filter compensates `ŝ`, so the rate error is `diag(ω)·δs + δb` and a propagation block
//! adds `G·δs` to the NED attitude error, `G = −Σ R̂·diag(φ)` (φ each step's rotation),
//! which is `−(M/T)·diag(Δθ)` for a steady rate (`M = Σ R̂·Δt`, `Δθ = Σ φ`): the block's
//! own sums, no per-sample work. No aid measures `s` directly (their Jacobians in `δs`
//! are zero): the GPS acceleration sees it through the attitude, as it sees the biases.
//!
//! Only x and y: aerobatics roll and loop about them at 100–300 °/s, while yaw rates stay
//! small and a z state traded heading for nothing on the tuning table (docs/tuning.md).

use crate::math::{Mat3, Vec3};

/// States: the scale factors about body x and y.
pub const N: usize = 2;

/// The scale states and their covariance blocks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// `1 − ŝᵢ`: the factor each axis' bias-corrected rate is multiplied by.
    pub(super) gain: [f32; N],
    /// `E[δx·δsᵀ]`, rows the six error states.
    pub(super) pxs: [[f32; N]; 6],
    /// `E[δs·δsᵀ]`.
    pub(super) ps: [[f32; N]; N],
    /// `E[δs·e_kᵀ]` with the carried fix noise (`filter::FixNoise`); zero without one.
    pub(super) se: [[f32; 3]; N],
    /// Seconds of quiet blocks left before the cross-covariances are dropped; ≤ 0: asleep.
    pub(super) awake: f32,
}

/// The body rate about x or y (rad/s) that wakes the states: below it a block's `G·σ_s`
/// is a few thousandths of a degree.
pub const WAKE_RATE: f32 = 0.3;
/// How long the states stay awake after the last fast block, s.
pub const STAY_AWAKE: f32 = 60.0;

impl Scale {
    /// No scale error yet, prior σ `sigma` (dimensionless) per axis.
    pub fn new(sigma: f32) -> Self {
        let v = sigma * sigma;
        Scale {
            gain: [1.0; N],
            pxs: [[0.0; N]; 6],
            ps: [[v, 0.0], [0.0, v]],
            se: [[0.0; 3]; N],
            awake: 0.0,
        }
    }

    /// The estimated scale factors about body x and y, dimensionless.
    pub fn estimate(&self) -> [f32; N] {
        self.gain.map(|g| 1.0 - g)
    }

    /// Whether the cross-covariances are carried (a fast rotation in the last
    /// [`STAY_AWAKE`] s); else they are zero and the updates leave the states alone.
    #[inline(always)]
    pub fn is_awake(&self) -> bool {
        self.awake > 0.0
    }

    /// Compensates a bias-corrected rate `w` (rad/s, body) in place.
    #[inline(always)]
    pub fn compensate(&self, w: &mut Vec3) {
        w[0] *= self.gain[0];
        w[1] *= self.gain[1];
    }

    /// The augmented propagation `[[Φ, G], [0, I]]`, `Φ = [[I, −M], [0, I]]`, on the blocks
    /// with `s`, after P's own (`p` holds `Φ·P·Φᵀ + Q`): with `C = Φ·P_xs`, the attitude
    /// block gains `C_θ·Gᵀ + G·C_θᵀ + G·P_ss·Gᵀ`, the bias–attitude block `C_b·Gᵀ`,
    /// `P_xs ← C + [G·P_ss; 0]`, and the carried fix noise' attitude rows `G·E[δs·eᵀ]`.
    /// `m`, `t`, `dth`: the block's `Σ R̂·Δt`, `Σ Δt` (s) and `Σ φ` (rad, body).
    #[inline(never)]
    pub fn propagate(
        &mut self,
        m: &Mat3,
        t: f32,
        dth: &Vec3,
        p: &mut [[f32; 6]; 6],
        fix_cross: &mut [[f32; 3]; 6],
    ) {
        let lim = WAKE_RATE * t;
        if crate::math::max(libm::fabsf(dth[0]), libm::fabsf(dth[1])) > lim {
            self.awake = STAY_AWAKE;
        } else if self.awake > 0.0 {
            self.awake -= t;
            if self.awake <= 0.0 {
                self.pxs = [[0.0; N]; 6];
                self.se = [[0.0; 3]; N];
            }
        }
        if self.awake <= 0.0 {
            return;
        }
        let inv_t = 1.0 / t;
        let w: [f32; N] = core::array::from_fn(|a| dth[a] * inv_t);
        let g: [[f32; N]; 3] = core::array::from_fn(|i| core::array::from_fn(|a| -m[i][a] * w[a]));
        let mut c = [[0.0f32; N]; 3];
        for i in 0..3 {
            for a in 0..N {
                let mb: f32 = (0..3).map(|k| m[i][k] * self.pxs[3 + k][a]).sum();
                c[i][a] = self.pxs[i][a] - mb;
            }
        }
        let gp: [[f32; N]; 3] = core::array::from_fn(|i| {
            core::array::from_fn(|a| (0..N).map(|b| g[i][b] * self.ps[b][a]).sum())
        });
        for i in 0..3 {
            for j in i..3 {
                let v: f32 = (0..N).map(|a| c[i][a] * g[j][a] + (g[i][a] * c[j][a] + gp[i][a] * g[j][a])).sum();
                p[i][j] += v;
                if j != i {
                    p[j][i] = p[i][j];
                }
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                let v: f32 = (0..N).map(|a| self.pxs[3 + i][a] * g[j][a]).sum();
                p[3 + i][j] += v;
                p[j][3 + i] = p[3 + i][j];
            }
        }
        for i in 0..3 {
            for a in 0..N {
                self.pxs[i][a] = c[i][a] + gp[i][a];
            }
            for j in 0..3 {
                fix_cross[i][j] += (0..N).map(|a| g[i][a] * self.se[a][j]).sum::<f32>();
            }
        }
    }

    /// The update of [`super::filter::Mekf::fuse`]: `h` the attitude Jacobian, `k` the
    /// state gain, `S⁻¹`, `S⁻¹ν`. Returns the scale gain `Ks` for [`Scale::fix_noise_seen`].
    #[inline(never)]
    pub fn fuse<const M: usize>(
        &mut self,
        h: &[[f32; 3]; M],
        k: &[[f32; M]; 6],
        s_inv: &[[f32; M]; M],
        siy: &[f32; M],
    ) -> [[f32; M]; N] {
        let psh = self.pht(h);
        self.update(&psh, k, s_inv, siy)
    }

    /// After [`Scale::fuse`] with the fix noise carried: `E[δs·eᵀ] −= Ks·(H·C_θ)`, `hc`
    /// the filter's own `H·C_θ` of that update.
    pub fn fix_noise_seen<const M: usize>(&mut self, ks: &[[f32; M]; N], hc: &[[f32; 3]; M]) {
        for a in 0..N {
            for j in 0..3 {
                self.se[a][j] -= (0..M).map(|x| ks[a][x] * hc[x][j]).sum::<f32>();
            }
        }
    }

    /// The update of [`super::filter::Mekf::fuse_with_fix_noise`]: the scale rows of PHᵀ
    /// include `−E[δs·e_{k−1}ᵀ]/Δt`; afterwards `E[δs·e_kᵀ] = −Ks·diag(d)`, `d` the new
    /// fix' PHᵀ diagonal (`new_var/Δt`).
    #[inline(never)]
    pub fn fuse_with_fix_noise(
        &mut self,
        h: &[[f32; 3]; 3],
        k: &[[f32; 3]; 6],
        s_inv: &[[f32; 3]; 3],
        siy: &[f32; 3],
        inv_dt: f32,
        d: &Vec3,
    ) {
        let mut psh = self.pht(h);
        for a in 0..N {
            for x in 0..3 {
                psh[a][x] -= inv_dt * self.se[a][x];
            }
        }
        let ks = self.update(&psh, k, s_inv, siy);
        for a in 0..N {
            for j in 0..3 {
                self.se[a][j] = -(ks[a][j] * d[j]);
            }
        }
    }

    /// `P_sx·Hᵀ` (N×M) over H's attitude columns.
    #[inline(always)]
    fn pht<const M: usize>(&self, h: &[[f32; 3]; M]) -> [[f32; M]; N] {
        core::array::from_fn(|a| {
            core::array::from_fn(|k| (0..3).map(|j| self.pxs[j][a] * h[k][j]).sum())
        })
    }

    /// The update, with `psh` the scale rows of PHᵀ, the state gain `k` (6×M), `S⁻¹` and
    /// `S⁻¹·ν`: `ŝ += psh·S⁻¹ν`, `P_ss −= Ks·pshᵀ`, `P_xs −= K·pshᵀ`. Returns the scale gain
    /// `Ks = psh·S⁻¹` (N×M) for the fix-noise cross-covariance.
    fn update<const M: usize>(
        &mut self,
        psh: &[[f32; M]; N],
        k: &[[f32; M]; 6],
        s_inv: &[[f32; M]; M],
        siy: &[f32; M],
    ) -> [[f32; M]; N] {
        let ks: [[f32; M]; N] = core::array::from_fn(|a| {
            core::array::from_fn(|b| (0..M).map(|x| psh[a][x] * s_inv[x][b]).sum())
        });
        for a in 0..N {
            let ds: f32 = (0..M).map(|x| psh[a][x] * siy[x]).sum();
            // ŝ += δs, as 1 − ŝ; held within ±10 % (a wrong sign or unit, not a scale).
            self.gain[a] = (self.gain[a] - ds).clamp(0.9, 1.1);
            for b in a..N {
                let v = self.ps[a][b] - (0..M).map(|x| ks[a][x] * psh[b][x]).sum::<f32>();
                self.ps[a][b] = v;
                self.ps[b][a] = v;
            }
        }
        for i in 0..6 {
            for a in 0..N {
                self.pxs[i][a] -= (0..M).map(|x| k[i][x] * psh[a][x]).sum::<f32>();
            }
        }
        ks
    }
}
