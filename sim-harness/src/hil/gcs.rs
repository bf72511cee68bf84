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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::telemetry::stream::Scanner;
    use mavlink::dialects::common::{ATTITUDE_DATA, HEARTBEAT_DATA};
    use mavlink::MavHeader;

    fn frame(component: u8, seq: u8, msg: MavMessage) -> Frame {
        let mut b = Vec::new();
        let h = MavHeader { system_id: 1, component_id: component, sequence: seq };
        mavlink::write_v2_msg(&mut b, h, &msg).unwrap();
        Scanner::default().push(&b).pop().unwrap()
    }

    fn attitude(ms: u32) -> MavMessage {
        MavMessage::ATTITUDE(ATTITUDE_DATA { time_boot_ms: ms, ..Default::default() })
    }

    /// Sends `frames` through a link and returns each datagram with its arrival time.
    fn through(frames: &[Frame], all: bool) -> Vec<(Instant, Vec<u8>)> {
        let rx = UdpSocket::bind("127.0.0.1:0").unwrap();
        rx.set_read_timeout(Some(Duration::from_millis(500))).unwrap();
        let to = rx.local_addr().unwrap();
        let listener = std::thread::spawn(move || {
            let mut got = Vec::new();
            let mut buf = [0u8; 512];
            while let Ok(n) = rx.recv(&mut buf) {
                got.push((Instant::now(), buf[..n].to_vec()));
            }
            got
        });
        let mut link = GcsLink::start(to, all).unwrap();
        for f in frames {
            link.push(f);
        }
        let sent = link.finish();
        let got = listener.join().unwrap();
        assert_eq!(sent as usize, got.len());
        got
    }

    #[test]
    fn whole_frames_of_the_autopilot_only_at_flight_time() {
        let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
        let frames = [
            frame(1, 0, hb.clone()), // untimed before any time: at once
            frame(1, 1, attitude(1_000)),
            frame(COMP_HIL, 0, attitude(1_000)),
            frame(1, 2, hb), // untimed: with the frame before it
            frame(COMP_HIL, 1, attitude(1_250)),
            frame(1, 3, attitude(1_300)),
        ];
        let got = through(&frames, false);
        let want: Vec<&Frame> = frames.iter().filter(|f| f.component == 1).collect();
        assert_eq!(got.len(), want.len());
        for ((_, d), f) in got.iter().zip(&want) {
            assert_eq!(d, &f.bytes, "one whole frame per datagram");
        }
        // 300 ms of flight time between the first and the last ATTITUDE.
        let dt = got[3].0 - got[1].0;
        assert!(dt >= Duration::from_millis(290), "{dt:?}");
        assert!(dt < Duration::from_millis(450), "{dt:?}");
        // Asked for, the HIL records go too.
        assert_eq!(through(&frames, true).len(), frames.len());
    }
}
