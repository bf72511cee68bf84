//! A pymavlink listener on a free loopback UDP port (`py/udp_listen.py`), shared by the
//! tests that check a ground station sees our MAVLink.
use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStdout, Command, Stdio};

/// Whether `python3` with pymavlink is here.
pub fn pymavlink_available() -> bool {
    sim_harness::data::python_has("pymavlink")
}

/// A listener that has said "ready"; it exits after `quiet_s` s without a message.
pub struct Listener {
    /// Where to send, `127.0.0.1:port`.
    pub addr: String,
    child: Child,
    out: BufReader<ChildStdout>,
}

/// Starts the listener and waits until it is bound.
pub fn start(quiet_s: u32) -> Listener {
    let port = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/py/udp_listen.py");
    let mut child = Command::new("python3")
        .arg(script)
        .arg(port.to_string())
        .arg(quiet_s.to_string())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    assert_eq!(line.trim(), "ready");
    Listener { addr: format!("127.0.0.1:{port}"), child, out }
}

impl Listener {
    /// Waits for the listener to fall quiet and returns its summary ("MSG count" lines).
    pub fn finish(mut self) -> String {
        let text: String = (&mut self.out).lines().map(|l| l.unwrap() + "\n").collect();
        assert!(self.child.wait().unwrap().success());
        text
    }
}

/// How many `msg` messages the summary `text` counts (0 if none).
pub fn count(text: &str, msg: &str) -> usize {
    text.lines()
        .find_map(|l| l.strip_prefix(&format!("{msg} ")).map(|n| n.parse().unwrap()))
        .unwrap_or(0)
}
