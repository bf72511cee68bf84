//! The 2× rule of docs/peers.md, checked without running `compare`: every (flight, peer)
//! pair that the generated per-flight table (`<!-- ratio-matched -->`, written by
//! `sim-harness compare --config matched --doc docs/peers.md`) names as over 2× of ours must
//! have a row in the hand-written reasons table (`<!-- reasons -->`) with a reason and its
//! evidence (a command in backticks that prints the figure).

use sim_harness::headline::{block, over_limit_pairs, RATIO_LIMIT, RULE_PEERS};
use std::collections::BTreeMap;

fn peers_md() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/peers.md");
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("reading {path}: {e}"))
}

/// (flight, peer) → (reason, evidence) from the reasons table.
fn reasons(md: &str) -> BTreeMap<(String, String), (String, String)> {
    let table = block(md, "reasons").expect("docs/peers.md has a <!-- reasons:begin/end --> table");
    let mut m = BTreeMap::new();
    for line in table.lines().filter(|l| l.starts_with("| ")) {
        let cells: Vec<String> =
            line.trim().trim_matches('|').split('|').map(|c| c.trim().to_string()).collect();
        if cells.len() < 4 || cells[0] == "flight" {
            continue;
        }
        let key = (cells[0].clone(), cells[1].clone());
        let dup = m.insert(key.clone(), (cells[2].clone(), cells[3].clone()));
        assert!(dup.is_none(), "reasons table: {key:?} twice");
    }
    m
}

#[test]
fn every_peer_over_2x_of_ours_has_an_evidenced_reason() {
    let md = peers_md();
    let ratio = block(&md, "ratio-matched")
        .expect("docs/peers.md has the generated <!-- ratio-matched:begin/end --> table");
    let rows = ratio.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| flight")).count();
    assert!(
        rows > 1,
        "the generated table has no flights: regenerate it (docs/compare.md's command)"
    );
    let reasons = reasons(&md);
    let peers: Vec<&str> = RULE_PEERS.iter().map(|p| p.1).collect();
    let mut missing = Vec::new();
    for (flight, peer) in over_limit_pairs(ratio) {
        assert!(peers.contains(&peer.as_str()), "unknown peer {peer:?} in the generated table");
        match reasons.get(&(flight.clone(), peer.clone())) {
            Some((reason, evidence)) if !reason.is_empty() && evidence.contains('`') => {}
            Some(_) => missing.push(format!("{flight} / {peer}: reason or command empty")),
            None => missing.push(format!("{flight} / {peer}: no row")),
        }
    }
    assert!(
        missing.is_empty(),
        "peers over {RATIO_LIMIT}× of ours without an evidenced reason in docs/peers.md:\n{}",
        missing.join("\n")
    );
}

/// The parser reads what the generator writes: a table row's last cell lists the peers.
#[test]
fn over_limit_pairs_reads_the_last_column() {
    let t = "| flight | wing-ahrs | fusion-nav | × ours | EKF2 | × ours | over 2× |\n|---|---|---|---|---|---|---|\n| a | 1° | 3° | 3.00 | 1° | 1.00 | fusion-nav |\n| b | 1° | 1° | 1.00 | 1° | 1.00 | — |\n| c | 1° | 3° | 3.00 | 9° | 9.00 | fusion-nav, EKF2 |\n";
    let got = over_limit_pairs(t);
    let want = [("a", "fusion-nav"), ("c", "fusion-nav"), ("c", "EKF2")];
    assert_eq!(got, want.map(|(f, p)| (f.to_string(), p.to_string())));
}
