//! The ground-station link of a HIL run: what an autopilot's telemetry radio would carry.
//!
//! The firmware's UART carries two senders (docs/mavlink.md): the autopilot (component 1,
//! the ground-station profile) and, in per-sample mode, the HIL records (component 25)
//! the harness needs for its bit-exact comparison. A ground station gets the autopilot's
//! frames only (unless asked for everything), each whole frame in its own datagram, and
//! at real time: a frame leaves when the wall clock reaches its flight time, counted from
//! the first timed frame. QEMU answers a flow-controlled run 2–4× faster than real time;
//! forwarding its reads as they came (cut anywhere, ~600 frames/s) made a ground station
//! that reads more slowly lose datagrams, and with them pieces of frames.

use crate::telemetry::stream::Frame;
use anyhow::{Context, Result};
use mavlink::dialects::common::MavMessage;
use std::net::{SocketAddr, UdpSocket};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The component of the firmware's per-sample HIL records (`MAV_COMP_ID_USER1`).
pub const COMP_HIL: u8 = 25;

/// The flight time a frame carries, µs, if its message has a time field.
pub fn frame_time_us(msg: &MavMessage) -> Option<u64> {
    use MavMessage::*;
    match msg {
        ATTITUDE(m) => Some(m.time_boot_ms as u64 * 1000),
        NAMED_VALUE_INT(m) => Some(m.time_boot_ms as u64 * 1000),
        DEBUG_VECT(m) => Some(m.time_usec),
        GPS_RAW_INT(m) => Some(m.time_usec),
        HIGHRES_IMU(m) => Some(m.time_usec),
        WIND_COV(m) => Some(m.time_usec),
        ESTIMATOR_STATUS(m) => Some(m.time_usec),
        _ => None,
    }
}

/// A running ground-station link.
pub struct GcsLink {
    tx: Option<Sender<(Option<u64>, Vec<u8>)>>,
    thread: Option<JoinHandle<u64>>,
    all: bool,
    /// Flight time of the latest timed frame (untimed frames go out with it; before the
    /// first, at once).
    last_t_us: Option<u64>,
}

impl GcsLink {
    /// Opens the link to `to`; `all` forwards the HIL records too.
    pub fn start(to: SocketAddr, all: bool) -> Result<Self> {
        let local: SocketAddr = match (to.is_ipv4(), to.ip().is_loopback()) {
            (true, true) => "127.0.0.1:0".parse()?,
            (true, false) => "0.0.0.0:0".parse()?,
            (false, true) => "[::1]:0".parse()?,
            (false, false) => "[::]:0".parse()?,
        };
        let sock = UdpSocket::bind(local).context("binding the ground-station UDP socket")?;
        let (tx, rx) = channel();
        let thread = std::thread::spawn(move || pace(rx, &sock, to));
        Ok(GcsLink { tx: Some(tx), thread: Some(thread), all, last_t_us: None })
    }

    /// Queues `f` for the ground station if it belongs on its link.
    pub fn push(&mut self, f: &Frame) {
        if let Some(t) = frame_time_us(&f.msg) {
            self.last_t_us = Some(self.last_t_us.map_or(t, |l| l.max(t)));
        }
        if f.component == COMP_HIL && !self.all {
            return;
        }
        if let Some(tx) = &self.tx {
            let _ = tx.send((self.last_t_us, f.bytes.clone()));
        }
    }

    /// Waits until every queued frame has gone out (at real time); returns the count.
    pub fn finish(mut self) -> u64 {
        self.tx.take();
        self.thread.take().and_then(|t| t.join().ok()).unwrap_or(0)
    }
}

impl Drop for GcsLink {
    fn drop(&mut self) {
        self.tx.take();
    }
}

/// Sends each frame when the wall clock reaches its flight time.
fn pace(rx: Receiver<(Option<u64>, Vec<u8>)>, sock: &UdpSocket, to: SocketAddr) -> u64 {
    let mut origin: Option<(Instant, u64)> = None;
    let mut sent = 0;
    for (t, bytes) in rx {
        if let Some(t) = t {
            let (w0, t0) = *origin.get_or_insert((Instant::now(), t));
            let due = w0 + Duration::from_micros(t.saturating_sub(t0));
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
        }
        // A ground station that is not listening is not an error (UDP).
        if sock.send_to(&bytes, to).is_ok() {
            sent += 1;
        }
    }
    sent
}
