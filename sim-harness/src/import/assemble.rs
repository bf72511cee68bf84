//! Raw autopilot streams → one row per IMU sample. A GPS fix or airspeed sample goes on
//! the first IMU row at or after its arrival (the replay hands it to the core there, as
//! the firmware would); the reference attitude is interpolated to each row.

use super::{ImportSummary, RawFix, Streams};
use crate::log::{FlightLog, GpsSample, LogRow};
use anyhow::{bail, Result};

/// Reference attitude samples further apart than this are not interpolated across, s.
const MAX_REF_GAP_S: f64 = 0.5;

/// Puts the streams on IMU rows. Errors when there is no usable IMU sample.
pub fn assemble(s: Streams) -> Result<(FlightLog, ImportSummary)> {
    let mut sum = ImportSummary { notes: s.notes, ..ImportSummary::default() };
    let mut imu: Vec<_> = s.imu;
    let before = imu.len();
    imu.retain(|m| m.gyro.iter().chain(&m.accel).all(|v| v.is_finite()));
    sum.imu_nonfinite = before - imu.len();
    imu.sort_by_key(|m| m.t_us);
    let before = imu.len();
    imu.dedup_by_key(|m| m.t_us);
    sum.imu_duplicate_t = before - imu.len();
    if imu.len() < 2 {
        bail!(
            "fewer than two usable IMU samples ({} in the log, {} non-finite)",
            before + sum.imu_nonfinite,
            sum.imu_nonfinite
        );
    }
    let t0 = imu[0].t_us;
    sum.t0_us = t0;
    let sec = |us: u64| (us as i128 - t0 as i128) as f64 * 1e-6;
    let mut rows: Vec<LogRow> = imu
        .iter()
        .map(|m| LogRow { t: sec(m.t_us), gyro: m.gyro, accel: m.accel, ..LogRow::default() })
        .collect();
    let times: Vec<u64> = imu.iter().map(|m| m.t_us).collect();
    let span = (times[times.len() - 1] - t0) as f64 * 1e-6;
    sum.imu_rows = rows.len();
    sum.imu_rate_hz = (rows.len() - 1) as f64 / span;
    let (mut lo, mut hi) = (f64::INFINITY, 0.0_f64);
    for w in times.windows(2) {
        let d = (w[1] - w[0]) as f64 * 1e-6;
        lo = lo.min(d);
        hi = hi.max(d);
    }
    sum.imu_dt_range = [lo, hi];
    // The row a sample arriving at `us` reaches: the first IMU sample at or after it.
    let row_of = |us: u64| -> Option<usize> {
        let i = times.partition_point(|&t| t < us);
        (us >= t0 && i < times.len()).then_some(i)
    };

    place_gps(s.gps, &mut rows, &row_of, &sec, &mut sum);

    let mut air = s.airspeed;
    air.sort_by_key(|a| a.0);
    for (us, v) in air {
        if !(v.is_finite() && v >= 0.0) {
            continue;
        }
        if let Some(i) = row_of(us) {
            rows[i].airspeed = Some(v);
            sum.airspeed += 1;
        }
    }
    let mut baro = s.baro;
    baro.sort_by_key(|b| b.0);
    for (us, h) in baro {
        // Beyond −1 km … 100 km is a sensor fault, not an altitude.
        if !(h.is_finite() && (-1e3..1e5).contains(&h)) {
            continue;
        }
        if let Some(i) = row_of(us) {
            sum.baro += rows[i].baro_alt.is_none() as usize;
            rows[i].baro_alt = Some(h);
        }
    }

    let mut att = s.attitude;
    att.retain(|a| a.1.iter().all(|v| v.is_finite()));
    att.sort_by_key(|a| a.0);
    let mut k = 0;
    for (row, &us) in rows.iter_mut().zip(&times) {
        while k + 1 < att.len() && att[k + 1].0 <= us {
            k += 1;
        }
        row.reference = interpolate(&att, k, us);
        sum.reference_rows += row.reference.is_some() as usize;
    }
    Ok((FlightLog { rows }, sum))
}

fn place_gps(
    mut gps: Vec<RawFix>,
    rows: &mut [LogRow],
    row_of: &dyn Fn(u64) -> Option<usize>,
    sec: &dyn Fn(u64) -> f64,
    sum: &mut ImportSummary,
) {
    gps.sort_by_key(|g| g.arrival_us);
    let mut last_epoch = None;
    let mut last_row = None;
    let mut lat = Vec::new();
    for g in gps {
        if g.fix_type < 3 || !g.vel.iter().all(|v| v.is_finite()) {
            sum.gps_no_3d += 1;
            continue;
        }
        let epoch = g.epoch_us.unwrap_or(g.arrival_us);
        if last_epoch == Some(epoch) {
            sum.gps_repeated += 1;
            continue;
        }
        let Some(i) = row_of(g.arrival_us) else {
            sum.gps_outside += 1;
            continue;
        };
        if last_row == Some(i) {
            sum.gps_repeated += 1; // the newer fix replaces the one already on this row
            sum.gps_fixes -= 1;
        }
        if let Some(e) = g.epoch_us {
            lat.push((g.arrival_us as f64 - e as f64) * 1e-6);
        }
        let speed_acc = g.speed_acc.filter(|a| a.is_finite() && *a >= 0.0);
        let lla = g.pos.filter(|p| position_usable(*p));
        if last_row == Some(i) && rows[i].gps.is_some_and(|f| f.lla.is_some()) {
            sum.gps_positions -= 1;
        }
        sum.gps_positions += lla.is_some() as usize;
        rows[i].gps = Some(GpsSample { t: sec(epoch), vel: g.vel, speed_acc, lla });
        sum.gps_fixes += 1;
        last_epoch = Some(epoch);
        last_row = Some(i);
    }
    if !lat.is_empty() {
        lat.sort_by(f64::total_cmp);
        sum.logged_gps_latency = Some(lat[lat.len() / 2]);
    }
}

/// A logged position worth writing: finite, on the globe, not the (0°, 0°) a receiver logs
/// before it has one, height within −1 km … 100 km.
fn position_usable([lat, lon, h]: [f64; 3]) -> bool {
    lat.abs() <= 90.0
        && lon.abs() <= 180.0
        && !(lat == 0.0 && lon == 0.0)
        && h.is_finite()
        && (-1e3..1e5).contains(&h)
}

/// The reference attitude at `us` from samples `k` (at or before) and `k + 1`, angles
/// interpolated on the shortest way round; `None` when no sample is within reach.
fn interpolate(att: &[(u64, [f64; 3])], k: usize, us: u64) -> Option<[f64; 3]> {
    let a = att.get(k)?;
    if a.0 > us {
        // Before the first sample: only if it is close.
        return ((a.0 - us) as f64 * 1e-6 <= 0.02).then_some(a.1);
    }
    let Some(b) = att.get(k + 1) else {
        return ((us - a.0) as f64 * 1e-6 <= 0.02).then_some(a.1);
    };
    let gap = (b.0 - a.0) as f64 * 1e-6;
    if gap > MAX_REF_GAP_S {
        return ((us - a.0) as f64 * 1e-6 <= 0.02).then_some(a.1);
    }
    let f = (us - a.0) as f64 * 1e-6 / gap;
    Some(core::array::from_fn(|i| {
        let d = crate::metrics::wrap(b.1[i] - a.1[i]);
        crate::metrics::wrap(a.1[i] + f * d)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::ImuSample;

    fn imu(t_us: u64) -> ImuSample {
        ImuSample { t_us, gyro: [0.0; 3], accel: [0.0, 0.0, -9.8] }
    }

    fn fix(arrival_us: u64, epoch_us: Option<u64>, fix_type: u8) -> RawFix {
        RawFix {
            arrival_us,
            epoch_us,
            vel: [10.0, 0.0, 0.0],
            speed_acc: Some(0.3),
            fix_type,
            pos: None,
        }
    }

    #[test]
    fn fixes_land_on_the_first_row_at_or_after_arrival_and_repeats_are_dropped() {
        let s = Streams {
            imu: (0..100).map(|k| imu(1_000_000 + k * 10_000)).chain([imu(1_000_000)]).collect(),
            gps: vec![
                fix(1_105_000, Some(1_000_000), 3), // → row 11 (1.11 s), epoch 0
                fix(1_205_000, Some(1_000_000), 3), // repeated epoch
                fix(1_305_000, Some(1_200_000), 2), // 2-D: dropped
                fix(1_405_000, None, 3),            // → row 41, epoch = arrival
                fix(9_000_000, None, 3),            // after the IMU
            ],
            attitude: vec![(1_000_000, [0.0, 0.0, 3.1]), (1_100_000, [0.1, 0.0, -3.1])],
            ..Streams::default()
        };
        let (log, sum) = assemble(s).unwrap();
        assert_eq!(sum.imu_duplicate_t, 1);
        assert_eq!(log.rows.len(), 100);
        let with: Vec<usize> = (0..100).filter(|&i| log.rows[i].gps.is_some()).collect();
        assert_eq!(with, vec![11, 41]);
        assert_eq!(log.rows[11].gps.unwrap().t, 0.0);
        assert!((log.rows[41].gps.unwrap().t - 0.405).abs() < 1e-12);
        assert_eq!((sum.gps_fixes, sum.gps_repeated, sum.gps_no_3d, sum.gps_outside), (2, 1, 1, 1));
        assert!((sum.logged_gps_latency.unwrap() - 0.105).abs() < 1e-9);
        // Yaw interpolated across ±π the short way: halfway between 3.1 and −3.1 is π.
        let r = log.rows[5].reference.unwrap();
        assert!((r[0] - 0.05).abs() < 1e-9);
        assert!((r[2].abs() - std::f64::consts::PI).abs() < 1e-6, "{r:?}");
        // Beyond the last reference sample: none.
        assert!(log.rows[50].reference.is_none());
    }

    #[test]
    fn no_imu_is_an_error() {
        let s = Streams { imu: vec![imu(5)], ..Streams::default() };
        assert!(assemble(s).unwrap_err().to_string().contains("IMU"));
    }
}
