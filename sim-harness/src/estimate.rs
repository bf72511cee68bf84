//! The estimate CSV (docs/formats.md), written by `replay` and by `hil`: one row per IMU
//! sample. Column names are a contract with outside tools — do not rename.

use anyhow::{Context, Result};
use std::io::Write;
use wing_ahrs::{Ahrs, AxisStatus, Flags};

/// Header of the estimate CSV, in order.
pub const COLUMNS: [&str; 20] = [
    "t",
    "roll",
    "pitch",
    "yaw",
    "bp",
    "bq",
    "br",
    "sd_roll",
    "sd_pitch",
    "sd_yaw",
    "sd_bp",
    "sd_bq",
    "sd_br",
    "innov_roll",
    "innov_pitch",
    "innov_yaw",
    "innov_sd_roll",
    "innov_sd_pitch",
    "innov_sd_yaw",
    "flags",
];

/// Optional columns after `flags`: the wind estimate (m/s, NED, the air mass' velocity)
/// and its 1-σ, empty before the wind is estimated and for the Euler filter.
pub const WIND_COLUMNS: [&str; 5] = ["wind_n", "wind_e", "wind_d", "sd_wind_n", "sd_wind_e"];

const AXES: [&str; 3] = ["roll", "pitch", "yaw"];

/// One estimate row. Angles rad, rates rad/s, σ are 1-σ.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct EstimateRow {
    /// IMU sample time, s.
    pub t: f64,
    /// Roll, pitch, yaw, rad.
    pub att: [f64; 3],
    /// Gyro bias bp, bq, br, rad/s.
    pub bias: [f64; 3],
    /// 1-σ from P for the six states.
    pub sd: [f64; 6],
    /// Innovation ν per axis on rows where an update measured that axis, rad.
    pub innov: [Option<f64>; 3],
    /// √S (innovation 1-σ) per axis, with `innov`.
    pub innov_sd: [Option<f64>; 3],
    /// Status text, `|`-separated (e.g. `gate_yaw|gps_lost`); empty when nominal.
    pub flags: String,
    /// Wind estimate `[w_N, w_E, w_D]` (m/s, NED) and the 1-σ of its horizontal part.
    pub wind: Option<([f64; 3], [f64; 2])>,
}

impl EstimateRow {
    /// Captures the estimator state after a row was fed. `last_seq` tracks the update
    /// sequence number so innovations appear only on the row where an update ran.
    pub fn capture(t: f64, ahrs: &Ahrs, last_seq: &mut u32) -> Self {
        let a = ahrs.attitude();
        let upd = ahrs.last_update();
        let update = (upd.seq != *last_seq).then_some(upd);
        *last_seq = upd.seq;
        let mut row = Self::from_state(
            t,
            [a.roll, a.pitch, a.yaw],
            ahrs.gyro_bias(),
            ahrs.std_dev(),
            update,
            ahrs.flags(),
        );
        row.wind = ahrs.wind().map(|(w, s)| (w.map(f64::from), s.map(f64::from)));
        row
    }

    /// A row from estimator read-outs (f32, as the core and the firmware's telemetry
    /// carry them): `update` is the update record when an update ran at this row.
    /// `hil` builds its rows from MAVLink with this, so both commands format alike.
    pub fn from_state(
        t: f64,
        att: [f32; 3],
        bias: [f32; 3],
        sd: [f32; 6],
        update: Option<&wing_ahrs::UpdateRecord>,
        f: Flags,
    ) -> Self {
        let mut row = EstimateRow {
            t,
            att: att.map(|v| v as f64),
            bias: bias.map(|v| v as f64),
            sd: sd.map(|v| v as f64),
            ..Default::default()
        };
        let mut flags: Vec<String> = Vec::new();
        if let Some(upd) = update {
            for (i, ax) in upd.axes.iter().enumerate() {
                match ax.status {
                    AxisStatus::NotMeasured => continue,
                    AxisStatus::Initialised => flags.push(format!("init_{}", AXES[i])),
                    AxisStatus::Gated => flags.push(format!("gate_{}", AXES[i])),
                    AxisStatus::ForcedAfterGate => flags.push(format!("forced_{}", AXES[i])),
                    AxisStatus::Accepted => {}
                }
                row.innov[i] = Some(ax.innovation as f64);
                row.innov_sd[i] = Some((ax.variance as f64).sqrt());
            }
            if upd.axes.iter().all(|a| a.status == AxisStatus::NotMeasured) {
                flags.push("no_measurement".into());
            }
        }
        for (bit, name) in [
            (Flags::YAW_UNOBSERVABLE, "yaw_skipped"),
            (Flags::GPS_LOST, "gps_lost"),
            (Flags::NO_GPS_YET, "no_gps_yet"),
            (Flags::NEAR_GIMBAL_LOCK, "near_gimbal"),
            (Flags::VIBRATION, "vibration"),
        ] {
            if f.has(bit) {
                flags.push(name.into());
            }
        }
        if !f.has(Flags::ALIGNED) {
            flags.push("not_aligned".into());
        }
        row.flags = flags.join("|");
        row
    }

    /// Whether the row carries an update (any innovation column filled).
    pub fn is_update(&self) -> bool {
        self.innov.iter().any(Option::is_some)
    }
}

/// Streams estimate rows as CSV. The `hil` command uses this same writer.
pub struct EstimateWriter<W: Write> {
    w: std::io::BufWriter<W>,
    line: String,
}

impl<W: Write> EstimateWriter<W> {
    /// Writes the header.
    pub fn new(w: W) -> Result<Self> {
        let mut w = std::io::BufWriter::new(w);
        writeln!(w, "{},{}", COLUMNS.join(","), WIND_COLUMNS.join(","))?;
        Ok(EstimateWriter { w, line: String::new() })
    }

    /// Writes one row (`{}` formatting: shortest round-trip; empty cell = none).
    pub fn write(&mut self, r: &EstimateRow) -> Result<()> {
        use std::fmt::Write as _;
        let l = &mut self.line;
        l.clear();
        let _ = write!(l, "{}", r.t);
        for v in r.att.iter().chain(&r.bias).chain(&r.sd) {
            let _ = write!(l, ",{v}");
        }
        for v in r.innov.iter().chain(&r.innov_sd) {
            l.push(',');
            if let Some(v) = v {
                let _ = write!(l, "{v}");
            }
        }
        l.push(',');
        l.push_str(&r.flags);
        match r.wind {
            Some((w, sd)) => {
                let _ = write!(l, ",{},{},{},{},{}", w[0], w[1], w[2], sd[0], sd[1]);
            }
            None => l.push_str(",,,,,"),
        }
        writeln!(self.w, "{l}")?;
        Ok(())
    }

    /// Flushes and returns the inner writer.
    pub fn finish(self) -> Result<W> {
        self.w.into_inner().map_err(|e| anyhow::anyhow!("flushing estimate CSV: {}", e.error()))
    }
}

/// Reads an estimate CSV back (for `report` on existing files and for tests).
pub fn read_estimates(path: &std::path::Path) -> Result<Vec<EstimateRow>> {
    let mut rdr = csv::ReaderBuilder::new()
        .flexible(true)
        .from_path(path)
        .with_context(|| format!("cannot open {}", path.display()))?;
    let h = rdr.headers()?.clone();
    let idx: Vec<usize> = COLUMNS
        .iter()
        .map(|c| {
            h.iter()
                .position(|x| x == *c)
                .with_context(|| format!("{}: missing column `{c}`", path.display()))
        })
        .collect::<Result<_>>()?;
    let mut out = Vec::new();
    for rec in rdr.records() {
        let rec = rec.with_context(|| format!("{}", path.display()))?;
        let line = rec.position().map_or(0, |p| p.line());
        let num = |k: usize| -> Result<Option<f64>> {
            let s = rec.get(idx[k]).unwrap_or("").trim();
            if s.is_empty() {
                return Ok(None);
            }
            s.parse::<f64>().map(Some).with_context(|| {
                format!(
                    "{}: line {line}, column {} (`{}`): not a number: {s:?}",
                    path.display(),
                    idx[k] + 1,
                    COLUMNS[k]
                )
            })
        };
        let req = |k: usize| -> Result<f64> {
            num(k)?.with_context(|| {
                format!("{}: line {line}: `{}` is empty", path.display(), COLUMNS[k])
            })
        };
        out.push(EstimateRow {
            t: req(0)?,
            att: [req(1)?, req(2)?, req(3)?],
            bias: [req(4)?, req(5)?, req(6)?],
            sd: [req(7)?, req(8)?, req(9)?, req(10)?, req(11)?, req(12)?],
            innov: [num(13)?, num(14)?, num(15)?],
            innov_sd: [num(16)?, num(17)?, num(18)?],
            flags: rec.get(idx[19]).unwrap_or("").to_string(),
            wind: read_wind(&h, &rec),
        });
    }
    Ok(out)
}

/// The optional wind columns of one row, when all five are present and filled.
fn read_wind(h: &csv::StringRecord, rec: &csv::StringRecord) -> Option<([f64; 3], [f64; 2])> {
    let mut v = [0.0; 5];
    for (k, c) in WIND_COLUMNS.iter().enumerate() {
        let i = h.iter().position(|x| x == *c)?;
        v[k] = rec.get(i)?.trim().parse::<f64>().ok()?;
    }
    Some(([v[0], v[1], v[2]], [v[3], v[4]]))
}

/// Replays `log` through the core (via [`crate::replay::run`], the firmware's call
/// order) and returns one estimate row per log row, plus the final estimator.
pub fn replay_estimates(
    log: &crate::log::FlightLog,
    cfg: wing_ahrs::Config,
) -> (Vec<EstimateRow>, Ahrs) {
    let mut out = Vec::with_capacity(log.rows.len());
    let mut seq = 0;
    let ahrs = crate::replay::run(log, cfg, |row, ahrs| {
        out.push(EstimateRow::capture(row.t, ahrs, &mut seq))
    });
    (out, ahrs)
}
