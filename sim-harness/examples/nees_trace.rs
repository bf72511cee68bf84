//! Where the filter is wrong and what it says of it: every `EVERY_S` seconds of a flight
//! log with truth, the NED attitude error and the reported 1-σ about each NED axis (and
//! their ratio z), the gyro-bias error and σ, the learnt GPS velocity σ and the tracked
//! latency, the mean NIS of the GPS acceleration per axis and of the course since the
//! last line, the update status and the flags.
//! `cargo run --release -p sim-harness --example nees_trace -- LOG [EVERY_S] [--told thesis|realistic]`
//! (a robustness-suite world's log: `sim-harness robust --log-dir DIR`; `--told` its
//! sensor grade for the σ the suite scores).
use sim_harness::montecarlo::rotation_error_ned;
use wing_ahrs::{Ahrs, AxisStatus};

/// Sums over the updates since the last printed line.
#[derive(Default)]
struct Since {
    seq: u32,
    n: u32,
    nis: [f64; 3],
    course_n: u32,
    course_nis: f64,
    course_innov_deg: f64,
    course_gated: u32,
}

impl Since {
    fn add(&mut self, ahrs: &Ahrs) {
        let u = ahrs.last_update();
        if u.seq == self.seq {
            return;
        }
        self.seq = u.seq;
        self.n += 1;
        for i in 0..3 {
            self.nis[i] += u.axes[i].nis().unwrap_or(0.0) as f64;
        }
        if let Some(v) = u.course.nis() {
            self.course_n += 1;
            self.course_nis += v as f64;
            self.course_innov_deg += (u.course.innovation as f64).to_degrees();
            self.course_gated += u32::from(u.course.status == AxisStatus::Gated);
        }
    }
}

fn main() {
    sim_harness::quiet_on_closed_pipe();
    let sim_harness::trace_cli::TraceArgs { log, every, config } =
        sim_harness::trace_cli::args("nees_trace");
    let t0 = log.rows[0].t;
    let mut next = 0.0;
    let mut since = Since::default();
    let deg = f64::to_degrees;
    sim_harness::replay::run(&log, config, |row, ahrs| {
        since.add(ahrs);
        let Some(tr) = row.truth else { return };
        if row.t - t0 < next {
            return;
        }
        next += every;
        let x = ahrs.state();
        let e = rotation_error_ned([x[0], x[1], x[2]].map(f64::from), tr).map(deg);
        let p = ahrs.error_covariance().unwrap_or_else(|| ahrs.covariance());
        let sd: [f64; 6] = core::array::from_fn(|i| deg((p[i][i] as f64).sqrt()));
        let b = row.truth_bias.unwrap_or([0.0; 3]);
        let be: [f64; 3] = core::array::from_fn(|i| deg(x[3 + i] as f64 - b[i]));
        let n = since.n.max(1) as f64;
        let cn = since.course_n.max(1) as f64;
        println!(
            "{:6.1} s | err {:6.2} {:6.2} {:6.2}° | σ {:5.2} {:5.2} {:5.2}° | z {:5.1} {:5.1} {:5.1} | roll {:6.1}° | vel σ {:.3} m/s, latency {:.3} s | bias err {:6.3} {:6.3} {:6.3} σ {:5.3} {:5.3} {:5.3}°/s | NIS {:4.1} {:4.1} {:4.1} | course {:2}× NIS {:4.1} innov {:6.2}° gated {} | {:?}",
            row.t - t0, e[0], e[1], e[2], sd[0], sd[1], sd[2],
            e[0] / sd[0], e[1] / sd[1], e[2] / sd[2],
            deg(tr[0]),
            ahrs.gps_vel_sigma().unwrap_or(f32::NAN),
            ahrs.gps_latency(),
            be[0], be[1], be[2], sd[3], sd[4], sd[5],
            since.nis[0] / n, since.nis[1] / n, since.nis[2] / n,
            since.course_n, since.course_nis / cn, since.course_innov_deg / cn, since.course_gated,
            ahrs.flags()
        );
        let seq = since.seq;
        since = Since { seq, ..Since::default() };
    });
}
