//! MAVLink v2 byte stream → messages, counting what a link checker needs: CRC
//! errors, sequence gaps (frames the sender dropped or the link lost) and
//! per-message counts. Framing is scanned here (not with the `mavlink` crate's
//! reader, which silently skips bad-CRC frames and so cannot count them); CRC and
//! payload decoding use the `mavlink` crate.

use mavlink::dialects::common::MavMessage;
use mavlink::{MavlinkVersion, Message};
use std::collections::BTreeMap;

const STX_V2: u8 = 0xFD;
const HEADER: usize = 10; // STX..msgid
const SIGNATURE: usize = 13;

/// One decoded frame.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Sender system id.
    pub system: u8,
    /// Sender component id.
    pub component: u8,
    /// Sequence number.
    pub seq: u8,
    /// The message.
    pub msg: MavMessage,
    /// The whole frame as received.
    pub bytes: Vec<u8>,
}

/// Link statistics.
#[derive(Debug, Clone, Default)]
pub struct LinkStats {
    /// Frames decoded.
    pub frames: u64,
    /// Frames whose CRC did not match (or unknown message ids).
    pub crc_errors: u64,
    /// Frames missing according to the sequence numbers (each sender, system and
    /// component, numbers its own frames).
    pub seq_lost: u64,
    /// Bytes skipped while hunting for a frame start.
    pub bytes_skipped: u64,
    /// Count per message name.
    pub per_message: BTreeMap<&'static str, u64>,
}

/// Incremental scanner: push bytes, pop frames.
#[derive(Default)]
pub struct Scanner {
    buf: Vec<u8>,
    last_seq: std::collections::HashMap<(u8, u8), u8>,
    /// Statistics so far.
    pub stats: LinkStats,
}

impl Scanner {
    /// Appends received bytes and returns every complete frame in them.
    pub fn push(&mut self, bytes: &[u8]) -> Vec<Frame> {
        self.buf.extend_from_slice(bytes);
        let mut out = Vec::new();
        let mut i = 0;
        loop {
            // Hunt for STX.
            while i < self.buf.len() && self.buf[i] != STX_V2 {
                i += 1;
                self.stats.bytes_skipped += 1;
            }
            if self.buf.len() < i + HEADER {
                break;
            }
            let len = self.buf[i + 1] as usize;
            let incompat = self.buf[i + 2];
            let total = HEADER + len + 2 + if incompat & 1 != 0 { SIGNATURE } else { 0 };
            if self.buf.len() < i + total {
                break;
            }
            let f = &self.buf[i..i + total];
            let msgid = u32::from_le_bytes([f[7], f[8], f[9], 0]);
            let crc = u16::from_le_bytes([f[HEADER + len], f[HEADER + len + 1]]);
            let extra = MavMessage::extra_crc(msgid);
            let known = MavMessage::default_message_from_id(msgid).is_some();
            if !known || mavlink::calculate_crc(&f[1..HEADER + len], extra) != crc {
                // Not a frame (or corrupted): resume the hunt one byte later.
                self.stats.crc_errors += 1;
                i += 1;
                continue;
            }
            match MavMessage::parse(MavlinkVersion::V2, msgid, &f[HEADER..HEADER + len]) {
                Ok(msg) => {
                    let (seq, system, component) = (f[4], f[5], f[6]);
                    if let Some(prev) = self.last_seq.insert((system, component), seq) {
                        self.stats.seq_lost += seq.wrapping_sub(prev).wrapping_sub(1) as u64;
                    }
                    self.stats.frames += 1;
                    *self.stats.per_message.entry(msg_name(&msg)).or_default() += 1;
                    out.push(Frame { system, component, seq, msg, bytes: f.to_vec() });
                }
                Err(_) => self.stats.crc_errors += 1,
            }
            i += total;
        }
        self.buf.drain(..i);
        out
    }
}

/// Static name of a message (for rate tables).
pub fn msg_name(m: &MavMessage) -> &'static str {
    use MavMessage::*;
    match m {
        HEARTBEAT(_) => "HEARTBEAT",
        ATTITUDE(_) => "ATTITUDE",
        GPS_RAW_INT(_) => "GPS_RAW_INT",
        HIGHRES_IMU(_) => "HIGHRES_IMU",
        SCALED_IMU(_) => "SCALED_IMU",
        DEBUG_VECT(_) => "DEBUG_VECT",
        NAMED_VALUE_INT(_) => "NAMED_VALUE_INT",
        NAMED_VALUE_FLOAT(_) => "NAMED_VALUE_FLOAT",
        SYS_STATUS(_) => "SYS_STATUS",
        ESTIMATOR_STATUS(_) => "ESTIMATOR_STATUS",
        WIND_COV(_) => "WIND_COV",
        STATUSTEXT(_) => "STATUSTEXT",
        _ => "other",
    }
}

/// A fixed-size MAVLink char array as a trimmed string.
pub fn name_str(b: &[u8]) -> String {
    let end = b.iter().position(|c| *c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).into_owned()
}
