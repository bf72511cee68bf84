//! MAVLink v2 telemetry (common dialect): encodes the IMU task's per-sample output
//! into whole frames in the TX ring. Runs in the lowest-priority task.
//!
//! Frames are serialised with the `mavlink` crate's per-message `MessageData` and
//! v2 framing (so LTO keeps only the messages sent). When the ring cannot take a
//! whole frame the frame is dropped and counted — the sequence number still
//! advances, so a receiver sees the gap too. Nothing here ever waits.
//!
//! Two senders on one link. Component 1 (the autopilot) sends the ground-station
//! profile of docs/mavlink.md whatever the mode: HEARTBEAT 1 Hz (fixed wing), ATTITUDE
//! at `attitude_hz` (with body rates), GPS_RAW_INT + DEBUG_VECT `GPSVEL` per fix,
//! HIGHRES_IMU at `raw_imu_hz`, DEBUG_VECT `BIAS`/`SD_ATT`/`SD_BIAS` at 10 Hz, WIND_COV
//! at 1 Hz once the wind is estimated, `INNOV`/`INNOV_VAR`/`INNOV_ST` per update,
//! SYS_STATUS + ESTIMATOR_STATUS + NAMED_VALUE_INT counters 1 Hz, STATUSTEXT on events.
//! In per-sample (HIL) mode component [`COMP_HIL`] adds the HIL records (ATTITUDE,
//! BIAS, SD_*, WIND_COV, `FLAGS` every sample) with its own sequence numbers, so the
//! harness can keep them from a ground station and the autopilot's stream stays gap-free.

use heapless::spsc::Producer;
use mavlink::dialects::common::{
    EstimatorStatusFlags, GpsFixType, HighresImuUpdatedFlags, MavAutopilot, MavModeFlag,
    MavSeverity, MavState, MavSysStatusSensor, MavType, ATTITUDE_DATA, DEBUG_VECT_DATA,
    ESTIMATOR_STATUS_DATA, GPS_RAW_INT_DATA, HEARTBEAT_DATA, HIGHRES_IMU_DATA,
    NAMED_VALUE_INT_DATA, STATUSTEXT_DATA, SYS_STATUS_DATA, WIND_COV_DATA,
};
use mavlink::{MAVLinkV2MessageRaw, MavHeader, MessageData};
use wing_ahrs::hil_record::TelemetryConfig;
use wing_ahrs::{AxisStatus, Flags, GpsFix, Health, UpdateRecord};

use crate::doubt::{Change, Gates, Monitor};

/// The autopilot component (`MAV_COMP_ID_AUTOPILOT1`): the ground-station profile.
pub const COMP_AUTOPILOT: u8 = 1;
/// The per-sample HIL records (`MAV_COMP_ID_USER1`): for the harness, not a ground station.
pub const COMP_HIL: u8 = 25;

/// TX ring size, bytes (power of two; one slot is kept free by heapless).
pub const RING: usize = 2048;

/// Instruction-cost statistics of the IMU task (QEMU `-icount`; instructions, not cycles).
#[derive(Clone, Copy, Debug, Default)]
pub struct Costs {
    /// Sum and count of predict-only samples (`Ahrs::predict`: the IMU sample [+ airspeed]).
    pub predict_sum: u64,
    /// Predict-only samples counted.
    pub predict_n: u32,
    /// Sum and count over samples that ran predict and a measurement update.
    pub update_sum: u64,
    /// Predict+update samples counted.
    pub update_n: u32,
    /// Largest whole IMU-task run for one sample.
    pub isr_max: u32,
    /// Largest predict-only sample (with decimated covariance propagation the mean hides
    /// the samples that propagate P).
    pub predict_max: u32,
}

/// Counters owned by other contexts, sampled from atomics when a status goes out.
#[derive(Clone, Copy, Debug, Default)]
pub struct LinkCounters {
    /// HIL records dropped (bad checksum/length/kind).
    pub record_errors: u32,
    /// Sensor-record queue overflows.
    pub record_overflows: u32,
    /// GPS parser frame errors (checksum, oversize, truncated, malformed).
    pub gps_errors: u32,
    /// GPS fix queue overflows.
    pub gps_queue_overflows: u32,
    /// UART receive overruns (sensor + GPS).
    pub uart_overruns: u32,
    /// Per-sample outputs dropped because the telemetry queue was full.
    pub out_dropped: u32,
    /// Samples processed with a GPS fix still missing (escape from deferral).
    pub gps_late: u32,
}

/// One processed IMU sample, as the IMU task hands it to telemetry.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// Sample time, µs.
    pub t_us: u64,
    /// Whether the estimator accepted the IMU sample.
    pub accepted: bool,
    /// Attitude (roll, pitch, yaw), rad.
    pub att: [f32; 3],
    /// Bias-corrected body rates, rad/s.
    pub rates: [f32; 3],
    /// Gyro bias estimate, rad/s.
    pub bias: [f32; 3],
    /// 1-σ of the six states.
    pub sd: [f32; 6],
    /// Status flags.
    pub flags: u16,
    /// Wind `[w_N, w_E, w_D]` (m/s NED) and the σ of its horizontal part, once estimated.
    pub wind: Option<([f32; 3], [f32; 2])>,
    /// The update record when an update ran at this sample.
    pub update: Option<UpdateRecord>,
    /// Raw IMU (for HIGHRES_IMU).
    pub gyro: [f32; 3],
    /// Raw accelerometer, m/s².
    pub accel: [f32; 3],
    /// The last GPS fix consumed at this sample.
    pub fix: Option<GpsFix>,
    /// Instructions the IMU task spent on this sample.
    pub isr_instructions: u32,
}

/// What the IMU task sends to the telemetry task.
#[derive(Clone, Copy, Debug)]
pub enum Out {
    /// A processed sample.
    Sample(Sample),
    /// 1 Hz health snapshot (and the final one before exit).
    Status(Health, Costs),
    /// End of flight: emit the final report; the TX drain exits when the ring is empty.
    Stop,
    /// New telemetry configuration.
    Config(TelemetryConfig),
}

/// The telemetry encoder (lives in the telemetry task).
pub struct Telemetry {
    ring: Producer<'static, u8, RING>,
    /// Frame being serialised: kept here, not on the handler's stack (~280 bytes).
    raw: MAVLinkV2MessageRaw,
    /// Sequence numbers of the autopilot and of the HIL component.
    seq: u8,
    seq_hil: u8,
    /// Whether the attitude can be trusted (the one predicate: `doubt::unreliable`).
    doubt: Monitor,
    cfg: TelemetryConfig,
    next_att_us: u64,
    next_raw_us: u64,
    next_slow_us: u64,
    next_wind_us: u64,
    next_hb_us: u64,
    last_flags: Option<u16>,
    last_gate: u32,
    last_gps_errors: u32,
    last_imu_rejected: u32,
    last_t_us: u64,
    breakdown: crate::costs::Breakdown,
    /// Frames dropped because the ring was full.
    pub dropped: u32,
    /// Frames queued.
    pub frames: u32,
}

/// NAMED_VALUE_INT counters sent with each status (order matches `Telemetry::status`).
const STATUS_NAMES: [&str; 36] = [
    "CAL_20K",
    "INS_UBXB",
    "INS_NMEAB",
    "INS_STEP",
    "INS_PROP",
    "INS_SINF",
    "INS_ATAN2",
    "INS_SQRT",
    "SQRT_MISS",
    "INS_FUSE",
    "REC_OVF",
    "GPS_QOVF",
    "IMU_N",
    "IMU_REJ",
    "GPS_FIX",
    "GPS_REJ",
    "GPS_OUT",
    "GPS_ERR",
    "GPS_LATE",
    "UART_OVR",
    "REC_ERR",
    "TX_DROP",
    "OUT_DROP",
    "GATE_R",
    "GATE_P",
    "GATE_Y",
    "VIB",
    "IMU_CLIP",
    "INS_PRED",
    "INS_UPD",
    "INS_MAX",
    "INS_PMAX",
    "STACK",
    "STACK_BOOT",
    "STACK_MAIN",
    "STACK_ISR",
];

const PERIOD_SLOW_US: u64 = 100_000;
const PERIOD_HB_US: u64 = 1_000_000;

fn name10(s: &str) -> mavlink::types::CharArray<10> {
    let mut b = [0u8; 10];
    for (d, c) in b.iter_mut().zip(s.bytes()) {
        *d = c;
    }
    b.into()
}

fn period_us(hz: u16) -> Option<u64> {
    if hz == 0 {
        None
    } else {
        Some(1_000_000 / hz as u64)
    }
}

/// Rate decimation on the sample clock: due when `t` reaches `next` (2 ms slack
/// for sample jitter); schedules the next slot.
fn due(next: &mut u64, t: u64, period: u64) -> bool {
    if t + 2_000 < *next {
        return false;
    }
    *next = if *next + period > t { *next + period } else { t + period };
    true
}

impl Telemetry {
    /// An encoder writing into `ring`.
    pub fn new(
        ring: Producer<'static, u8, RING>,
        breakdown: crate::costs::Breakdown,
        gates: Gates,
    ) -> Self {
        Telemetry {
            ring,
            raw: MAVLinkV2MessageRaw::new(),
            seq: 0,
            seq_hil: 0,
            doubt: Monitor::new(gates),
            cfg: TelemetryConfig { attitude_hz: 50, raw_imu_hz: 0, per_sample: false },
            next_att_us: 0,
            next_raw_us: 0,
            next_slow_us: 0,
            next_wind_us: 0,
            next_hb_us: 0,
            last_flags: None,
            last_gate: 0,
            last_gps_errors: 0,
            last_imu_rejected: 0,
            last_t_us: 0,
            breakdown,
            dropped: 0,
            frames: 0,
        }
    }

    /// Queues one message of the autopilot as a whole frame, or drops it (counted).
    fn send<D: MessageData>(&mut self, msg: &D) -> bool {
        self.send_as(COMP_AUTOPILOT, msg)
    }

    /// Queues one message from `component` of system 1, or drops it (counted).
    fn send_as<D: MessageData>(&mut self, component: u8, msg: &D) -> bool {
        let seq = if component == COMP_HIL { &mut self.seq_hil } else { &mut self.seq };
        let sequence = *seq;
        *seq = seq.wrapping_add(1);
        self.raw.serialize_message_data(
            MavHeader { system_id: 1, component_id: component, sequence },
            msg,
        );
        let bytes = self.raw.raw_bytes();
        if self.ring.capacity() - self.ring.len() < bytes.len() {
            self.dropped = self.dropped.wrapping_add(1);
            return false;
        }
        for &b in bytes {
            // Cannot fail: space was checked and this task is the only producer.
            let _ = self.ring.enqueue(b);
        }
        self.frames = self.frames.wrapping_add(1);
        true
    }

    fn debug_vect(&mut self, name: &str, t_us: u64, v: [f32; 3]) {
        self.debug_vect_as(COMP_AUTOPILOT, name, t_us, v);
    }

    fn debug_vect_as(&mut self, component: u8, name: &str, t_us: u64, v: [f32; 3]) {
        self.send_as(
            component,
            &DEBUG_VECT_DATA { time_usec: t_us, x: v[0], y: v[1], z: v[2], name: name10(name) },
        );
    }

    fn named_int(&mut self, name: &str, t_us: u64, value: u32) {
        self.send(&NAMED_VALUE_INT_DATA {
            time_boot_ms: (t_us / 1000) as u32,
            value: value as i32,
            name: name10(name),
        });
    }

    /// Queues a STATUSTEXT (≤ 50 chars).
    pub fn text(&mut self, severity: MavSeverity, s: &str) {
        self.text_count(severity, s, None);
    }

    /// Queues a STATUSTEXT of `prefix` and the decimal `n`, written straight into the
    /// message's 50 bytes (one buffer: this is the telemetry task's deepest frame).
    fn text_count(&mut self, severity: MavSeverity, prefix: &str, n: Option<u32>) {
        let mut b = [0u8; 50];
        let mut len = 0;
        for (d, c) in b.iter_mut().zip(prefix.bytes()) {
            *d = c;
            len += 1;
        }
        if let Some(n) = n {
            push_u32(&mut b[len..], n);
        }
        self.send(&STATUSTEXT_DATA { severity, text: b.into(), ..Default::default() });
    }

    /// Encodes one item from the IMU task.
    pub fn handle(&mut self, out: &Out, link: &LinkCounters) {
        match out {
            Out::Sample(s) => self.sample(s),
            Out::Status(h, c) => self.status(h, c, link),
            Out::Stop => self.text(MavSeverity::MAV_SEVERITY_INFO, "wing-ahrs: end of flight"),
            Out::Config(c) => {
                self.cfg = *c;
                self.next_att_us = self.last_t_us;
                self.next_raw_us = self.last_t_us;
            }
        }
    }

    // Not inlined: the per-sample and the status messages are never on the stack together.
    #[inline(never)]
    fn sample(&mut self, s: &Sample) {
        let t = s.t_us;
        self.last_t_us = t;
        if self.cfg.per_sample {
            self.hil_records(s);
        }
        if let Some(u) = &s.update {
            self.doubt.on_update(u);
        }
        self.health_events(t, s.flags);
        if due(&mut self.next_hb_us, t, PERIOD_HB_US) {
            self.heartbeat();
        }
        if period_us(self.cfg.attitude_hz).is_some_and(|p| due(&mut self.next_att_us, t, p)) {
            self.attitude(COMP_AUTOPILOT, s);
        }
        if due(&mut self.next_slow_us, t, PERIOD_SLOW_US) {
            self.bias_sd(COMP_AUTOPILOT, s);
        }
        // WIND_COV at 1 Hz: the wind is slow and the link is not wide.
        if due(&mut self.next_wind_us, t, PERIOD_HB_US) {
            if let Some(w) = s.wind {
                self.wind(COMP_AUTOPILOT, t, w);
            }
        }
        if let Some(u) = &s.update {
            let a = &u.axes;
            self.debug_vect("INNOV", t, [a[0].innovation, a[1].innovation, a[2].innovation]);
            self.debug_vect("INNOV_VAR", t, [a[0].variance, a[1].variance, a[2].variance]);
            let code = |st: AxisStatus| st as u8 as f32;
            self.debug_vect(
                "INNOV_ST",
                t,
                [code(a[0].status), code(a[1].status), code(a[2].status)],
            );
        }
        if let Some(f) = &s.fix {
            self.gps(t, f);
        }
        if let Some(p) = period_us(self.cfg.raw_imu_hz) {
            if due(&mut self.next_raw_us, t, p) {
                self.send(&HIGHRES_IMU_DATA {
                    time_usec: t,
                    xacc: s.accel[0],
                    yacc: s.accel[1],
                    zacc: s.accel[2],
                    xgyro: s.gyro[0],
                    ygyro: s.gyro[1],
                    zgyro: s.gyro[2],
                    fields_updated: HighresImuUpdatedFlags::from_bits_truncate(0b11_1111),
                    ..Default::default()
                });
            }
        }
        self.events(s.flags, t);
    }

    /// The per-sample HIL records (component [`COMP_HIL`]), first of the sample's frames:
    /// the harness builds a sample on `BIAS` and attaches what follows with its time.
    fn hil_records(&mut self, s: &Sample) {
        let t = s.t_us;
        self.attitude(COMP_HIL, s);
        self.bias_sd(COMP_HIL, s);
        if let Some(w) = s.wind {
            self.wind(COMP_HIL, t, w);
        }
        let accepted = if s.accepted { 1.0 } else { 0.0 };
        self.debug_vect_as(
            COMP_HIL,
            "FLAGS",
            t,
            [s.flags as f32, s.isr_instructions as f32, accepted],
        );
    }

    fn attitude(&mut self, component: u8, s: &Sample) {
        self.send_as(
            component,
            &ATTITUDE_DATA {
                time_boot_ms: (s.t_us / 1000) as u32,
                roll: s.att[0],
                pitch: s.att[1],
                yaw: s.att[2],
                rollspeed: s.rates[0],
                pitchspeed: s.rates[1],
                yawspeed: s.rates[2],
            },
        );
    }

    fn bias_sd(&mut self, component: u8, s: &Sample) {
        let t = s.t_us;
        self.debug_vect_as(component, "BIAS", t, s.bias);
        self.debug_vect_as(component, "SD_ATT", t, [s.sd[0], s.sd[1], s.sd[2]]);
        self.debug_vect_as(component, "SD_BIAS", t, [s.sd[3], s.sd[4], s.sd[5]]);
    }

    /// The attitude became unreliable or recovered: say so at once, in the ground
    /// station's terms (the HEARTBEAT state and SYS_STATUS follow at their own rate).
    fn health_events(&mut self, t: u64, flags: u16) {
        match self.doubt.step(t, Flags::from_bits_truncate(flags)) {
            Some(Change::Raised(r)) => {
                self.text(MavSeverity::MAV_SEVERITY_WARNING, r.text());
                defmt::warn!("{=str}", r.text());
            }
            Some(Change::Recovered) => {
                self.text(MavSeverity::MAV_SEVERITY_NOTICE, "AHRS recovered");
                defmt::info!("AHRS recovered");
            }
            None => {}
        }
    }

    fn wind(&mut self, component: u8, t: u64, (w, sd): ([f32; 3], [f32; 2])) {
        let var = sd[0] * sd[0] + sd[1] * sd[1];
        self.send_as(
            component,
            &WIND_COV_DATA {
                time_usec: t,
                wind_x: w[0],
                wind_y: w[1],
                wind_z: w[2],
                var_horiz: var,
                var_vert: f32::NAN, // not estimated
                wind_alt: f32::NAN,
                horiz_accuracy: libm::sqrtf(var),
                vert_accuracy: f32::NAN,
            },
        );
    }

    fn events(&mut self, flags: u16, _t: u64) {
        let prev = self.last_flags.replace(flags);
        let Some(prev) = prev else { return };
        let changed = |f: Flags| (prev ^ flags) & f.bits() != 0;
        let on = |f: Flags| flags & f.bits() != 0;
        if changed(Flags::GPS_LOST) {
            if on(Flags::GPS_LOST) {
                // A NOTICE: the WARNING is "AHRS unreliable: GPS lost" (`doubt`), one per incident.
                self.text(MavSeverity::MAV_SEVERITY_NOTICE, "GPS lost: attitude by gyro only");
                defmt::warn!("GPS lost");
            } else {
                self.text(MavSeverity::MAV_SEVERITY_NOTICE, "GPS regained");
                defmt::info!("GPS regained");
            }
        }
        if changed(Flags::YAW_UNOBSERVABLE) {
            if on(Flags::YAW_UNOBSERVABLE) {
                self.text(MavSeverity::MAV_SEVERITY_NOTICE, "yaw unobservable: ground speed low");
            } else {
                self.text(MavSeverity::MAV_SEVERITY_NOTICE, "yaw observable again");
            }
        }
        if changed(Flags::NEAR_GIMBAL_LOCK) && on(Flags::NEAR_GIMBAL_LOCK) {
            self.text(MavSeverity::MAV_SEVERITY_WARNING, "pitch near 90 deg: Euler guard");
        }
    }

    fn heartbeat(&mut self) {
        let status = if !self.doubt.aligned_once() {
            MavState::MAV_STATE_CALIBRATING
        } else if self.doubt.raised().is_some() {
            MavState::MAV_STATE_CRITICAL
        } else {
            MavState::MAV_STATE_ACTIVE
        };
        self.send(&HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_FIXED_WING,
            autopilot: MavAutopilot::MAV_AUTOPILOT_GENERIC,
            base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            system_status: status,
            mavlink_version: 3,
        });
    }

    fn gps(&mut self, t: u64, f: &GpsFix) {
        let v = f.vel_ne;
        let gs = libm::sqrtf(v[0] * v[0] + v[1] * v[1]);
        let mut cog = libm::atan2f(v[1], v[0]).to_degrees();
        if cog < 0.0 {
            cog += 360.0;
        }
        let fix_type = match f.fix_type {
            wing_ahrs::FixType::Fix3D | wing_ahrs::FixType::GnssDeadReckoning => {
                GpsFixType::GPS_FIX_TYPE_3D_FIX
            }
            wing_ahrs::FixType::Fix2D => GpsFixType::GPS_FIX_TYPE_2D_FIX,
            _ => GpsFixType::GPS_FIX_TYPE_NO_FIX,
        };
        self.send(&GPS_RAW_INT_DATA {
            time_usec: t,
            lat: f.lat_e7,
            lon: f.lon_e7,
            alt: f.alt_msl_mm,
            eph: u16::MAX,
            epv: u16::MAX,
            vel: (gs * 100.0) as u16,
            cog: (cog * 100.0) as u16,
            fix_type,
            satellites_visible: f.num_sats,
            ..Default::default()
        });
        // Exact f32 NED velocity (GPS_RAW_INT has only cm/s ground speed and course); a fix
        // without vD (NMEA) sends 0 there, as the estimator takes it.
        self.debug_vect("GPSVEL", t, f.vel_ned_or_level());
    }

    // Not inlined: the per-sample and the status messages are never on the stack together.
    #[inline(never)]
    fn status(&mut self, h: &Health, c: &Costs, link: &LinkCounters) {
        let t = self.last_t_us;
        let flags = Flags::from_bits_truncate(self.last_flags.unwrap_or(0));
        let resets = h.gate_resets.iter().fold(0u32, |a, x| a.wrapping_add(*x));
        self.doubt.on_resets(t, resets);
        let attitude_ok = flags.has(Flags::ALIGNED) && self.doubt.raised().is_none();
        self.sys_status(h, link, flags, attitude_ok);
        self.estimator_status(t, flags, attitude_ok);
        self.named_counters(t, h, c, link);
        self.count_texts(h, link);
    }

    /// SYS_STATUS: the sensors' health and the link's error counters.
    fn sys_status(&mut self, h: &Health, link: &LinkCounters, flags: Flags, attitude_ok: bool) {
        let sensors = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
            | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL
            | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_GPS
            | MavSysStatusSensor::MAV_SYS_STATUS_AHRS;
        // A health bit is cleared only for an error detected: what the board does not have
        // is not in error (MAVProxy takes a clear GEOFENCE bit for a fence breach).
        let mut health = MavSysStatusSensor::all();
        if flags.has(Flags::GPS_LOST) || flags.has(Flags::NO_GPS_YET) {
            health.remove(MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_GPS);
        }
        if !attitude_ok {
            health.remove(MavSysStatusSensor::MAV_SYS_STATUS_AHRS);
        }
        let sat = |x: u32| x.min(u16::MAX as u32) as u16;
        let sent = self.frames.wrapping_add(self.dropped).max(1);
        self.send(&SYS_STATUS_DATA {
            onboard_control_sensors_present: sensors,
            onboard_control_sensors_enabled: sensors,
            onboard_control_sensors_health: health,
            load: 0,
            voltage_battery: u16::MAX,
            current_battery: -1,
            drop_rate_comm: ((self.dropped as u64 * 10_000) / sent as u64) as u16,
            errors_comm: sat(link.record_errors.wrapping_add(link.uart_overruns)),
            errors_count1: sat(h.imu_rejected),
            errors_count2: sat(link.gps_errors),
            errors_count3: sat(self.dropped),
            errors_count4: sat(link.out_dropped),
            battery_remaining: -1,
            ..Default::default()
        });
    }

    /// The NAMED_VALUE_INT counters of docs/mavlink.md, in `STATUS_NAMES` order.
    fn named_counters(&mut self, t: u64, h: &Health, c: &Costs, link: &LinkCounters) {
        let pred = if c.predict_n > 0 { (c.predict_sum / c.predict_n as u64) as u32 } else { 0 };
        let upd = if c.update_n > 0 { (c.update_sum / c.update_n as u64) as u32 } else { 0 };
        let b = self.breakdown;
        let stack = crate::board::stack::usage();
        // Names and values apart: a table of (&str, u32) pairs would be ~350 bytes of stack.
        let values: [u32; STATUS_NAMES.len()] = [
            b.calibration,
            b.gps_ubx_per_byte,
            b.gps_nmea_per_byte,
            b.step,
            b.propagate,
            b.sinf,
            b.atan2,
            b.sqrt,
            b.sqrt_mismatches,
            b.fuse,
            link.record_overflows,
            link.gps_queue_overflows,
            h.imu_samples,
            h.imu_rejected,
            h.gps_fixes,
            h.gps_rejected,
            h.gps_outages,
            link.gps_errors,
            link.gps_late,
            link.uart_overruns,
            link.record_errors,
            self.dropped,
            link.out_dropped,
            h.gate_rejections[0],
            h.gate_rejections[1],
            h.gate_rejections[2],
            h.vibration,
            h.imu_clipped,
            pred,
            upd,
            c.isr_max,
            c.predict_max,
            stack.whole,
            stack.boot,
            stack.main_idle,
            stack.isr,
        ];
        for (n, v) in STATUS_NAMES.iter().zip(values) {
            self.named_int(n, t, v);
        }
    }

    /// A STATUSTEXT for each error total that grew since the last status.
    fn count_texts(&mut self, h: &Health, link: &LinkCounters) {
        let gate: u32 = h.gate_rejections.iter().fold(0u32, |a, x| a.wrapping_add(*x));
        if gate != self.last_gate {
            self.text_count(MavSeverity::MAV_SEVERITY_NOTICE, "gate rejections total ", Some(gate));
            self.last_gate = gate;
        }
        if link.gps_errors != self.last_gps_errors {
            self.text_count(
                MavSeverity::MAV_SEVERITY_WARNING,
                "GPS parser errors total ",
                Some(link.gps_errors),
            );
            self.last_gps_errors = link.gps_errors;
        }
        if h.imu_rejected != self.last_imu_rejected {
            self.text_count(
                MavSeverity::MAV_SEVERITY_WARNING,
                "IMU samples rejected total ",
                Some(h.imu_rejected),
            );
            self.last_imu_rejected = h.imu_rejected;
        }
    }
}

impl Telemetry {
    /// ESTIMATOR_STATUS: the attitude's validity and the largest innovation test ratios
    /// of the last second (GPS acceleration as `vel_ratio`, the course as `mag_ratio`:
    /// it does a compass's job). No position is estimated: those fields stay 0.
    fn estimator_status(&mut self, t: u64, flags: Flags, attitude_ok: bool) {
        let (vel, heading) = self.doubt.take_ratios();
        let mut f = EstimatorStatusFlags::empty();
        if attitude_ok {
            f |= EstimatorStatusFlags::ESTIMATOR_ATTITUDE;
        }
        if matches!(
            self.doubt.raised(),
            Some(crate::doubt::Reason::Gating | crate::doubt::Reason::Realigned)
        ) {
            f |= EstimatorStatusFlags::ESTIMATOR_GPS_GLITCH;
        }
        if flags.has(Flags::IMU_CLIPPED) || flags.has(Flags::VIBRATION) {
            f |= EstimatorStatusFlags::ESTIMATOR_ACCEL_ERROR;
        }
        self.send(&ESTIMATOR_STATUS_DATA {
            time_usec: t,
            vel_ratio: vel,
            mag_ratio: heading,
            flags: f,
            ..Default::default()
        });
    }
}

/// Writes the decimal `n` at the start of `out`, as much of it as fits (most significant
/// digits first).
fn push_u32(out: &mut [u8], mut n: u32) {
    let mut d = [0u8; 10];
    let mut i = d.len();
    loop {
        i -= 1;
        d[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    for (o, c) in out.iter_mut().zip(&d[i..]) {
        *o = *c;
    }
}
