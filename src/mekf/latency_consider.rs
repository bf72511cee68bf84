//! The latency error as a Schmidt consider parameter of the GPS-acceleration update.
//!
//! A latency error `c` (s) that the tracker ([`super::latency`]) has not yet learnt leaves
//! `ȧ·c` in every GPS-acceleration residual of a manoeuvre, `ȧ` the jerk (NED, m/s³). It is
//! the same error in consecutive updates: as white noise in R the filter would average it
//! away and grow confident in a heading the latency made. Here `c` is carried, not
//! estimated (Schmidt–Kalman): its variance σ_c² and its cross-covariances with the error
//! state, `E[δx·c]`, and with the last fix's velocity noise, `E[e·c]`, enter PHᵀ and S
//! of the update, and every update, propagation and reset keeps them. The state is never
//! corrected by `c`; moving the latency is the tracker's job (docs/design.md, "The
//! untracked latency, carried"). Compiled in with the `latency-consider` feature only;
//! without it [`LatencyConsider`] is empty and every method a no-op.

use crate::math::{Mat3, Mat6, Vec3};

/// Smallest σ_c², s² ((1 ms)²): keeps the covariances defined when the tracker is off or
/// has settled.
#[cfg(feature = "latency-consider")]
const MIN_VAR: f32 = 1e-6;

/// The consider parameter's covariances.
#[cfg(feature = "latency-consider")]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LatencyConsider {
    /// `E[δx·c]`: attitude (rad·s, NED) then gyro biases (rad/s·s, body).
    pub(super) cross: [f32; 6],
    /// `E[e·c]`, the last fix's velocity noise with `c`, m/s·s (NED).
    pub(super) fix: Vec3,
    /// σ_c², s² (0 until the first [`LatencyConsider::set`]: off, nothing is carried).
    pub(super) var: f32,
    /// The pending update's jerk, m/s³ NED (zero: `c` is not in it).
    pub(super) jerk: Vec3,
}

#[cfg(feature = "latency-consider")]
impl LatencyConsider {
    /// Sets σ_c² (s², at least `MIN_VAR`) and the jerk of the next GPS-acceleration update
    /// (m/s³ NED; zero where none is known). A changed σ_c rescales the covariances with
    /// it: the tracker has taken that share of the error out.
    pub fn set(&mut self, var: f32, jerk: Vec3) {
        let var = crate::math::max(var, MIN_VAR);
        if self.var > 0.0 && var != self.var {
            let k = crate::math::sqrt(var / self.var);
            self.cross = self.cross.map(|v| v * k);
            self.fix = self.fix.map(|v| v * k);
        }
        self.var = var;
        self.jerk = jerk;
    }

    /// A propagation `[[I, −M], [0, I]]` of the error state.
    #[inline(always)]
    pub fn transition(&mut self, m: &Mat3) {
        if self.var == 0.0 {
            return;
        }
        let b = [self.cross[3], self.cross[4], self.cross[5]];
        for (i, row) in m.iter().enumerate() {
            self.cross[i] -= row[0] * b[0] + row[1] * b[1] + row[2] * b[2];
        }
    }

    /// Its share of one update that does not see `c` (gain `k`, Jacobian `h`, `S⁻¹`;
    /// `hc` = H·E[δx·e] where the fix noise is carried): `E[δx·c] −= K·H·E[δx·c]`,
    /// `E[e·c] −= (H·E[δx·e])ᵀ·S⁻¹·H·E[δx·c]`. Left out, the joint covariance loses
    /// positive definiteness (a run's bias σ collapsed to 0.003 °/s).
    pub fn fused<const M: usize>(
        &mut self,
        k: &[[f32; M]; 6],
        h: &[[f32; 3]; M],
        s_inv: &[[f32; M]; M],
        hc: Option<&[[f32; 3]; M]>,
    ) {
        if self.var == 0.0 {
            return;
        }
        let u: [f32; M] = core::array::from_fn(|a| dot3(&h[a], &self.cross));
        if let Some(hc) = hc {
            let siu: [f32; M] = core::array::from_fn(|a| (0..M).map(|b| s_inv[a][b] * u[b]).sum());
            for j in 0..3 {
                self.fix[j] -= (0..M).map(|a| hc[a][j] * siu[a]).sum::<f32>();
            }
        }
        for (c, ki) in self.cross.iter_mut().zip(k) {
            *c -= (0..M).map(|a| ki[a] * u[a]).sum::<f32>();
        }
    }

    /// Adds `c` to the prior of the fix-noise update, whose residual is
    /// `y = H·δx + (e_k − e_{k−1})/Δt + ȧ·c + w`: PHᵀ gains `E[δx·c]·ȧᵀ`, and S gains
    /// `u·ȧᵀ + ȧ·uᵀ + σ_c²·ȧȧᵀ`, `u = H·E[δx·c] − E[e_{k−1}·c]/Δt`. Returns `g = u + σ_c²·ȧ`,
    /// the covariance of `c` with the residual, for [`LatencyConsider::posterior`]; `None`
    /// where the update has no jerk.
    #[inline(always)]
    pub fn augment(
        &self,
        h: &[[f32; 3]; 3],
        inv_dt: f32,
        fix_valid: bool,
        px: &mut [[f32; 3]; 6],
        s: &mut Mat3,
    ) -> Option<Vec3> {
        let j = self.jerk;
        if j == [0.0; 3] {
            return None;
        }
        let e = if fix_valid { self.fix } else { [0.0; 3] };
        let u: Vec3 = core::array::from_fn(|a| dot3(&h[a], &self.cross) - inv_dt * e[a]);
        for (row, c) in px.iter_mut().zip(self.cross) {
            for (p, jz) in row.iter_mut().zip(j) {
                *p += c * jz;
            }
        }
        for x in 0..3 {
            for z in 0..3 {
                s[x][z] += u[x] * j[z] + j[x] * u[z] + self.var * j[x] * j[z];
            }
        }
        Some(core::array::from_fn(|a| u[a] + self.var * j[a]))
    }

    /// The posterior after the fix-noise update with gains `kx` (δx) and `d[a]·S⁻¹[a]`
    /// (the new fix's noise), `g` from [`LatencyConsider::augment`]; `p` the
    /// posterior covariance of δx (its diagonal is read). Each correlation is held within ±1.
    pub fn posterior(&mut self, g: &Vec3, kx: &[[f32; 3]; 6], d: &Vec3, s_inv: &Mat3, p: &Mat6) {
        // The new fix's noise is fresh, uncorrelated with c before the update.
        self.fix = core::array::from_fn(|a| -d[a] * dot3(&s_inv[a], g));
        for i in 0..6 {
            let c = self.cross[i] - dot3(&kx[i], g);
            let lim2 = crate::math::max(p[i][i], 0.0) * self.var;
            // Squared, so the root is taken only where the bound binds (rarely).
            self.cross[i] = if c * c <= lim2 {
                c
            } else if c < 0.0 {
                -crate::math::sqrt(lim2)
            } else {
                crate::math::sqrt(lim2)
            };
        }
    }

    /// Forgets `E[e·c]` (the fix noise is forgotten).
    pub fn forget_fix(&mut self) {
        self.fix = [0.0; 3];
    }

    /// Zeroes `E[δx_i·c]` (state `i` reset).
    pub fn zero(&mut self, i: usize) {
        self.cross[i] = 0.0;
    }

    /// Scales `E[δx_i·c]` by `s` (state `i`'s σ scaled).
    pub fn scale(&mut self, i: usize, s: f32) {
        self.cross[i] *= s;
    }
}

/// Without the `latency-consider` feature: nothing is carried, at no cost.
#[cfg(not(feature = "latency-consider"))]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LatencyConsider {}

#[cfg(not(feature = "latency-consider"))]
#[allow(missing_docs)]
impl LatencyConsider {
    #[inline(always)]
    pub fn set(&mut self, _: f32, _: Vec3) {}
    #[inline(always)]
    pub fn transition(&mut self, _: &Mat3) {}
    #[inline(always)]
    pub fn fused<const M: usize>(
        &mut self,
        _: &[[f32; M]; 6],
        _: &[[f32; 3]; M],
        _: &[[f32; M]; M],
        _: Option<&[[f32; 3]; M]>,
    ) {
    }
    #[inline(always)]
    pub fn augment(&self, _: &[[f32; 3]; 3], _: f32, _: bool, _: &mut [[f32; 3]; 6], _: &mut Mat3) -> Option<Vec3> {
        None
    }
    #[inline(always)]
    pub fn posterior(&mut self, _: &Vec3, _: &[[f32; 3]; 6], _: &Vec3, _: &Mat3, _: &Mat6) {}
    #[inline(always)]
    pub fn forget_fix(&mut self) {}
    #[inline(always)]
    pub fn zero(&mut self, _: usize) {}
    #[inline(always)]
    pub fn scale(&mut self, _: usize, _: f32) {}
}

#[cfg(feature = "latency-consider")]
fn dot3(a: &[f32; 3], b: &[f32]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
