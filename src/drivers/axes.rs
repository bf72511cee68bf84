//! Sensor-to-body axis mapping.
//!
//! IMUs are soldered in one of 24 right-angle orientations, so the rotation from
//! the sensor frame to body FRD is a signed permutation: exact in f32 (no
//! multiply-add rounding) and cheap in the IMU interrupt.

/// Body FRD axis `i` = `sign[i]` × sensor axis `src[i]`.
///
/// Constructed only through [`AxisMap::new`], which rejects maps that are not
/// proper rotations (a reflection would silently flip handedness and turn a
/// right turn into a left one for the gyro).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AxisMap {
    src: [u8; 3],
    neg: [bool; 3],
}

impl AxisMap {
    /// Sensor axes already are body FRD.
    pub const IDENTITY: AxisMap = AxisMap { src: [0, 1, 2], neg: [false, false, false] };

    /// Matek F405-Wing / F405-SE / F405-WTE (MPU-6000 on SPI1): body = (−y, −x, −z)
    /// of the sensor. Both public target definitions agree:
    /// INAV `MATEKF405SE/target.h` `IMU_MPU6000_ALIGN CW270_DEG` (INAV body is
    /// x fwd, y left, z up: (−y, x, z), then FLU→FRD negates y and z), and ArduPilot
    /// `MatekF405-Wing/hwdef.dat` `ROTATION_YAW_180` applied after its Invensense
    /// driver's fixed (y, x, −z) swap.
    pub const MATEK_F405_WING: AxisMap = AxisMap { src: [1, 0, 2], neg: [true, true, true] };

    /// A signed permutation: body axis `i` = (−1 if `neg[i]`) × sensor axis `src[i]`.
    /// Returns `None` unless `src` is a permutation of 0, 1, 2 and the map is a
    /// proper rotation (determinant +1).
    pub const fn new(src: [u8; 3], neg: [bool; 3]) -> Option<AxisMap> {
        if src[0] > 2 || src[1] > 2 || src[2] > 2 {
            return None;
        }
        if src[0] == src[1] || src[1] == src[2] || src[0] == src[2] {
            return None;
        }
        // Permutation parity: even (cyclic) permutations have det +1.
        let even = (src[0] == 0 && src[1] == 1)
            || (src[0] == 1 && src[1] == 2)
            || (src[0] == 2 && src[1] == 0);
        let negs = neg[0] as u8 + neg[1] as u8 + neg[2] as u8;
        let det_positive = even == (negs % 2 == 0);
        if det_positive {
            Some(AxisMap { src, neg })
        } else {
            None
        }
    }

    /// Sensor-frame vector → body FRD (any unit; exact).
    #[inline]
    pub fn apply(&self, v: [f32; 3]) -> [f32; 3] {
        let mut out = [0.0; 3];
        let mut i = 0;
        while i < 3 {
            let x = v[self.src[i] as usize];
            out[i] = if self.neg[i] { -x } else { x };
            i += 1;
        }
        out
    }

    /// The same map as a rotation matrix `R_body_sensor` (rows = body axes).
    pub fn matrix(&self) -> [[f32; 3]; 3] {
        let mut m = [[0.0; 3]; 3];
        for (i, row) in m.iter_mut().enumerate() {
            row[self.src[i] as usize] = if self.neg[i] { -1.0 } else { 1.0 };
        }
        m
    }
}
