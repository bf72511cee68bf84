//! The docs are reference: no doc outside CHANGELOG.md dates a figure or a fact by the numbered
//! stage of work it came from ("(issue 14)", "since session 16", "before issue #33",
//! "stage 3"). Such a phrase says when something was measured, not what is true now, and it
//! goes stale without anyone noticing; the history belongs in CHANGELOG.md.
//!
//! Covers every `docs/*.md` and `README.md`, generated blocks included (a generator must not
//! write such phrases either).

use std::fs;
use std::path::{Path, PathBuf};

/// The words that name a stage of work, matched case-insensitively as whole words, with an
/// optional plural `s`.
const STAGE_WORDS: [&str; 3] = ["issue", "session", "stage"];

fn is_word_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// A GitHub `owner/repo` name as one token (no further `/`, no file extension), as in
/// "PX4/PX4-Autopilot issue #123": an upstream project's issue, not a stage of this work.
fn is_repo_name(token: &str) -> bool {
    let token = token.trim_start_matches(['(', '[', '"', '\'', '`']);
    let Some((owner, repo)) = token.split_once('/') else {
        return false;
    };
    let name_char = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '_';
    !owner.is_empty()
        && !repo.is_empty()
        && owner.chars().all(name_char)
        && repo.chars().all(name_char)
}

/// Byte offsets of the phrases in `text` that date by a numbered stage of work: `issue`,
/// `session` or `stage` (any case, optionally plural) as a whole word, then whitespace (a line
/// break too, since prose is wrapped), an optional `#` and a digit — the regex
/// `\b(issue|session|stage)s?\s+#?[0-9]` with `i`. Not matched: the word in a URL or path
/// (`PX4/PX4-Autopilot/issues/123`: no whitespace before the number), and an upstream
/// project's issue named after its `owner/repo` ("PX4/PX4-Autopilot issue #123").
fn dating_phrases(text: &str) -> Vec<usize> {
    let mut found = Vec::new();
    for (start, _) in text.char_indices() {
        if text[..start].chars().next_back().is_some_and(is_word_char) {
            continue;
        }
        let rest = &text[start..];
        for word in STAGE_WORDS {
            let Some(head) = rest.get(..word.len()) else {
                continue;
            };
            if !head.eq_ignore_ascii_case(word) {
                continue;
            }
            let mut tail = &rest[word.len()..];
            if tail.starts_with(['s', 'S']) {
                tail = &tail[1..];
            }
            let after_space = tail.trim_start();
            if after_space.len() == tail.len() {
                continue; // no whitespace: a URL path, "issue's", "sessions", …
            }
            let after_hash = after_space.strip_prefix('#').unwrap_or(after_space);
            if !after_hash.starts_with(|c: char| c.is_ascii_digit()) {
                continue;
            }
            let previous_token = text[..start].split_whitespace().next_back().unwrap_or("");
            if is_repo_name(previous_token) {
                continue;
            }
            found.push(start);
        }
    }
    found
}

/// 1-based line of a byte offset, and that line's text.
fn line_at(text: &str, offset: usize) -> (usize, &str) {
    let line_no = text[..offset].matches('\n').count() + 1;
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    (line_no, &text[line_start..line_end])
}

fn reference_docs() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut docs: Vec<PathBuf> = fs::read_dir(root.join("docs"))
        .expect("docs/ is readable")
        .map(|entry| entry.expect("docs/ entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "md"))
        .collect();
    docs.sort();
    docs.push(root.join("README.md"));
    docs.retain(|path| path.file_name().is_some_and(|name| name != "CHANGELOG.md"));
    docs
}

#[test]
fn no_doc_dates_a_figure_by_a_numbered_stage_of_work() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let docs = reference_docs();
    assert!(docs.len() > 10, "docs/*.md not found: {docs:?}");
    let mut failures = Vec::new();
    for path in &docs {
        let text = fs::read_to_string(path).expect("a doc is UTF-8 text");
        for offset in dating_phrases(&text) {
            let (line_no, line) = line_at(&text, offset);
            let shown = path.strip_prefix(root).unwrap_or(path).display();
            failures.push(format!("{shown}:{line_no}: {}", line.trim()));
        }
    }
    assert!(
        failures.is_empty(),
        "{} phrase(s) date a figure by a numbered stage of work; state the fact as reference \
         and move its history to CHANGELOG.md:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn the_matcher_finds_stage_numbers() {
    for text in [
        "measured (issue 14).",
        "since Issue 21 the adapter",
        "before issue #33",
        "in session 12, white differences",
        "SESSION 16's heading-drift term",
        "sessions 12–14",
        "until session\n16, from their names",
        "stage 3",
        "Stages 4 and 5",
        "flags (issues 13, 14)",
    ] {
        assert_eq!(dating_phrases(text).len(), 1, "not found in {text:?}");
    }
}

#[test]
fn the_matcher_leaves_what_is_not_a_stage_of_work() {
    for text in [
        "https://github.com/PX4/PX4-Autopilot/issues/123",
        "PX4/PX4-Autopilot/issues/123",
        "see PX4/PX4-Autopilot issue #123 upstream",
        "(ArduPilot/ardupilot issues 4512)",
        "the estimator issue's cost goal",
        "not tried (session time)",
        "reissue 3 fixes",
        "tissue 3",
        "backstage 2",
        "stagger 3 samples",
        "a two-stage filter",
        "an issue",
        "issue #a",
        "docs/firmware.md",
    ] {
        assert!(dating_phrases(text).is_empty(), "wrongly found in {text:?}");
    }
    // A path before the word is not an upstream repository.
    assert_eq!(dating_phrases("(docs/firmware.md) session 16").len(), 1);
    assert_eq!(dating_phrases("PX4/Hawkeye PR #37, session 9").len(), 1);
}

#[test]
fn line_at_names_the_line_of_the_phrase() {
    let text = "a\nb session 3 c\nd";
    let offsets = dating_phrases(text);
    assert_eq!(offsets.len(), 1);
    assert_eq!(line_at(text, offsets[0]), (2, "b session 3 c"));
}
