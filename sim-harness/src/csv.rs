//! Flight-log CSV read/write (docs/formats.md).
//!
//! Header names are fixed, an empty cell means "none this row", extra columns are
//! ignored. Record splitting is done by the `csv` crate (quoting, CRLF); the cells are
//! parsed here so every error names the line and the column. Malformed input is an
//! error, never a panic.

use crate::log::{FlightLog, GpsSample, LogRow};
use anyhow::{bail, Context, Result};
use std::io::{Read, Write};
use std::path::Path;

/// Columns every log must have.
const REQUIRED: [&str; 7] = ["t", "gx", "gy", "gz", "ax", "ay", "az"];

/// Column indices of the optional channels.
struct Columns {
    req: [usize; 7],
    gps_t: Option<usize>,
    gps_sacc: Option<usize>,
    vel: [Option<usize>; 3],
    lla: [Option<usize>; 3],
    airspeed: Option<usize>,
    baro_alt: Option<usize>,
    truth: [Option<usize>; 3],
    truth_bias: [Option<usize>; 3],
    reference: [Option<usize>; 3],
    truth_wind: [Option<usize>; 3],
}

impl Columns {
    fn from_header(h: &csv::StringRecord) -> Result<Self> {
        let find = |name: &str| h.iter().position(|c| c.trim() == name);
        let mut req = [0; 7];
        for (k, name) in REQUIRED.iter().enumerate() {
            req[k] = find(name).with_context(|| {
                format!("header: missing required column `{name}` (need {})", REQUIRED.join(","))
            })?;
        }
        let tri = |a: &str, b: &str, c: &str| [find(a), find(b), find(c)];
        let cols = Columns {
            req,
            gps_t: find("gps_t"),
            gps_sacc: find("gps_sacc"),
            vel: tri("vn", "ve", "vd"),
            lla: tri("lat", "lon", "alt"),
            airspeed: find("airspeed"),
            baro_alt: find("baro_alt"),
            truth: tri("true_roll", "true_pitch", "true_yaw"),
            truth_bias: tri("true_bp", "true_bq", "true_br"),
            reference: tri("ref_roll", "ref_pitch", "ref_yaw"),
            truth_wind: tri("true_wind_n", "true_wind_e", "true_wind_d"),
        };
        if cols.gps_t.is_some() && cols.vel.iter().any(Option::is_none) {
            bail!("header: column `gps_t` present but `vn`, `ve` and `vd` are not all present");
        }
        Ok(cols)
    }
}

/// Parses one cell: `Ok(None)` when empty, an error naming line and column when not a number.
fn cell(
    rec: &csv::StringRecord,
    h: &csv::StringRecord,
    idx: usize,
    line: u64,
) -> Result<Option<f64>> {
    let Some(s) = rec.get(idx) else {
        bail!(
            "line {line}: row has {} cells, column {} (`{}`) is missing",
            rec.len(),
            idx + 1,
            &h[idx]
        );
    };
    let s = s.trim();
    if s.is_empty() {
        return Ok(None);
    }
    match s.parse::<f64>() {
        Ok(v) => Ok(Some(v)),
        Err(_) => {
            bail!("line {line}, column {} (`{}`): cannot parse {s:?} as a number", idx + 1, &h[idx])
        }
    }
}

/// A group of three columns: all empty → None, all present → Some, mixed → error.
fn triple(
    rec: &csv::StringRecord,
    h: &csv::StringRecord,
    idx: &[Option<usize>; 3],
    line: u64,
) -> Result<Option<[f64; 3]>> {
    let mut v = [None; 3];
    for k in 0..3 {
        if let Some(i) = idx[k] {
            v[k] = cell(rec, h, i, line)?;
        }
    }
    match v {
        [Some(a), Some(b), Some(c)] => Ok(Some([a, b, c])),
        [None, None, None] => Ok(None),
        _ => {
            let names: Vec<&str> = idx.iter().flatten().map(|&i| &h[i]).collect();
            bail!("line {line}: columns {} must be all filled or all empty", names.join(","))
        }
    }
}

/// Reads a flight log from any reader. `name` labels errors. A fix whose `gps_t` equals
/// the previous fix's (GPS cells forward-filled on every row, a common export artefact) is
/// used once; the repeats are dropped and counted in a note on stderr.
pub fn parse_log<R: Read>(reader: R, name: &str) -> Result<FlightLog> {
    let (log, repeated) = parse_log_counted(reader, name)?;
    if repeated > 0 {
        eprintln!(
            "note: {name}: {repeated} rows repeat the previous fix's gps_t (forward-filled GPS cells): each epoch used once"
        );
    }
    let same_t = log.rows.windows(2).filter(|w| w[1].t == w[0].t).count();
    if same_t > 0 {
        let first = log.rows.windows(2).position(|w| w[1].t == w[0].t).unwrap_or(0);
        eprintln!(
            "warning: {name}: {same_t} rows repeat the previous row's time `t` (first at data row {}, t = {}): the estimator rejects an IMU sample that does not advance the time",
            first + 2,
            log.rows[first].t
        );
    }
    Ok(log)
}

/// [`parse_log`] returning the number of repeated-epoch GPS cells it dropped.
pub fn parse_log_counted<R: Read>(reader: R, name: &str) -> Result<(FlightLog, usize)> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(reader);
    let header =
        rdr.headers().with_context(|| format!("{name}: cannot read the CSV header"))?.clone();
    let cols = Columns::from_header(&header).with_context(|| name.to_string())?;
    let mut rows = Vec::new();
    let mut rec = csv::StringRecord::new();
    let (mut last_epoch, mut repeated) = (None, 0usize);
    loop {
        match rdr.read_record(&mut rec) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => bail!("{name}: {e}"),
        }
        let line = rec.position().map_or(0, |p| p.line());
        if rec.iter().all(|c| c.trim().is_empty()) {
            continue; // blank line
        }
        let mut row = parse_row(&rec, &header, &cols, line).with_context(|| name.to_string())?;
        if row.t < 0.0 {
            bail!("{name}: line {line}, column 1 (`t`): time is negative ({})", row.t);
        }
        if let Some(g) = row.gps {
            if last_epoch == Some(g.t) {
                row.gps = None;
                repeated += 1;
            }
            last_epoch = Some(g.t);
        }
        if let Some(prev) = rows.last() {
            let prev: &LogRow = prev;
            if row.t < prev.t {
                bail!(
                    "{name}: line {line}, column 1 (`t`): time goes backwards ({} after {})",
                    row.t,
                    prev.t
                );
            }
        }
        rows.push(row);
    }
    if rows.is_empty() {
        bail!("{name}: no data rows");
    }
    let (t0, t1) = (rows[0].t, rows[rows.len() - 1].t);
    if rows.len() > 1 && t1 == t0 {
        bail!(
            "{name}: all {} rows have the same time t = {t0}: column `t` is not a time axis",
            rows.len()
        );
    }
    Ok((FlightLog { rows }, repeated))
}

fn parse_row(
    rec: &csv::StringRecord,
    h: &csv::StringRecord,
    c: &Columns,
    line: u64,
) -> Result<LogRow> {
    let mut req = [0.0; 7];
    for k in 0..7 {
        let i = c.req[k];
        req[k] = cell(rec, h, i, line)?.with_context(|| {
            format!("line {line}, column {} (`{}`): required value is empty", i + 1, REQUIRED[k])
        })?;
    }
    if !req[0].is_finite() {
        bail!("line {line}, column {} (`t`): time is not finite", c.req[0] + 1);
    }
    // docs/formats.md: every number finite. A NaN or ∞ IMU value is refused here, with its
    // place, rather than read and left to the estimator to count and reject.
    for k in 1..7 {
        if !req[k].is_finite() {
            bail!("line {line}, column {} (`{}`): not a finite number", c.req[k] + 1, REQUIRED[k]);
        }
    }
    let gps = match c.gps_t {
        Some(i) => match cell(rec, h, i, line)? {
            Some(t) => {
                let vel = triple(rec, h, &c.vel, line)?.with_context(|| {
                    format!("line {line}: `gps_t` is set but `vn`,`ve`,`vd` are empty")
                })?;
                let speed_acc = match c.gps_sacc {
                    Some(k) => cell(rec, h, k, line)?,
                    None => None,
                };
                if speed_acc.is_some_and(|a| !(a.is_finite() && a >= 0.0)) {
                    bail!("line {line}, column {} (`gps_sacc`): speed accuracy must be a finite number ≥ 0", c.gps_sacc.unwrap_or(0) + 1);
                }
                let lla = triple(rec, h, &c.lla, line)?;
                if let Some([lat, lon, alt]) = lla {
                    if !(lat.abs() <= 90.0 && lon.abs() <= 180.0 && alt.is_finite()) {
                        bail!("line {line}: `lat`,`lon`,`alt` must be within ±90°, ±180° and finite, got {lat}, {lon}, {alt}");
                    }
                }
                Some(GpsSample { t, vel, speed_acc, lla })
            }
            None => {
                if triple(rec, h, &c.lla, line)?.is_some() {
                    bail!("line {line}: `lat`,`lon`,`alt` are set but `gps_t` is empty (position belongs to a fix row)");
                }
                None
            }
        },
        None => None,
    };
    Ok(LogRow {
        t: req[0],
        gyro: [req[1], req[2], req[3]],
        accel: [req[4], req[5], req[6]],
        gps,
        airspeed: match c.airspeed {
            Some(i) => cell(rec, h, i, line)?,
            None => None,
        },
        baro_alt: match c.baro_alt {
            Some(i) => cell(rec, h, i, line)?,
            None => None,
        },
        truth: triple(rec, h, &c.truth, line)?,
        truth_bias: triple(rec, h, &c.truth_bias, line)?,
        reference: triple(rec, h, &c.reference, line)?,
        truth_wind: triple(rec, h, &c.truth_wind, line)?,
    })
}

/// Reads a flight log file.
pub fn read_log(path: &Path) -> Result<FlightLog> {
    use std::io::{BufRead, BufReader};
    let f = std::fs::File::open(path)
        .with_context(|| format!("cannot open flight log {}", path.display()))?;
    let mut r = BufReader::new(f);
    let gzip = r.fill_buf().is_ok_and(|b| b.starts_with(&[0x1f, 0x8b]));
    let name = path.display().to_string();
    if gzip {
        // A `.csv.gz` log, decompressed as it is read.
        return parse_log(BufReader::new(flate2::bufread::GzDecoder::new(r)), &name);
    }
    parse_log(r, &name)
}

/// Writes a flight log with every column of docs/formats.md (optional channels left empty
/// where a row has none). Numbers use Rust's shortest round-trip form, so
/// write → read is lossless.
pub fn write_log<W: Write>(w: W, log: &FlightLog) -> Result<()> {
    let mut w = std::io::BufWriter::new(w);
    writeln!(w, "t,gx,gy,gz,ax,ay,az,gps_t,vn,ve,vd,airspeed,true_roll,true_pitch,true_yaw,true_bp,true_bq,true_br,ref_roll,ref_pitch,ref_yaw,gps_sacc,true_wind_n,true_wind_e,true_wind_d,lat,lon,alt,baro_alt")?;
    let mut line = String::new();
    for r in &log.rows {
        line.clear();
        use std::fmt::Write as _;
        let _ = write!(
            line,
            "{},{},{},{},{},{},{}",
            r.t, r.gyro[0], r.gyro[1], r.gyro[2], r.accel[0], r.accel[1], r.accel[2]
        );
        match r.gps {
            Some(g) => {
                let _ = write!(line, ",{},{},{},{}", g.t, g.vel[0], g.vel[1], g.vel[2]);
            }
            None => line.push_str(",,,,"),
        }
        match r.airspeed {
            Some(v) => {
                let _ = write!(line, ",{v}");
            }
            None => line.push(','),
        }
        for t in [r.truth, r.truth_bias, r.reference] {
            match t {
                Some(v) => {
                    let _ = write!(line, ",{},{},{}", v[0], v[1], v[2]);
                }
                None => line.push_str(",,,"),
            }
        }
        if let Some(a) = r.gps.and_then(|g| g.speed_acc) {
            let _ = write!(line, ",{a}");
        } else {
            line.push(',');
        }
        match r.truth_wind {
            Some(v) => {
                let _ = write!(line, ",{},{},{}", v[0], v[1], v[2]);
            }
            None => line.push_str(",,,"),
        }
        match r.gps.and_then(|g| g.lla) {
            Some([lat, lon, alt]) => {
                let _ = write!(line, ",{lat},{lon},{alt}");
            }
            None => line.push_str(",,,"),
        }
        match r.baro_alt {
            Some(b) => {
                let _ = write!(line, ",{b}");
            }
            None => line.push(','),
        }
        writeln!(w, "{line}")?;
    }
    w.flush()?;
    Ok(())
}

/// Writes a flight log file.
pub fn write_log_file(path: &Path, log: &FlightLog) -> Result<()> {
    let f =
        std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    write_log(f, log).with_context(|| format!("writing {}", path.display()))
}
