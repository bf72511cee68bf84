//! The configuration a user can touch stays small and documented: the public fields of
//! `config::*` (from the generated docs/api.md, which lists what rustdoc sees with the
//! default features) plus the fields of the public enums' variants, at most 45; and each
//! public field's doc comment gives its default, and a numeric one its unit and range.

use std::fs;

const MAX_PUBLIC_FIELDS: usize = 45;

/// Field names of the `config::` structs in docs/api.md that configure the estimator.
fn api_config_fields(api: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_config = false;
    for line in api.lines() {
        if let Some(item) = line.strip_prefix("- `") {
            let name = item.trim_end_matches('`');
            in_config = name.starts_with("config::")
                && !matches!(name, "config::ConfigError" | "config::ConfigErrors");
        } else if in_config {
            if let Some(list) = line.trim().strip_prefix("- fields: ") {
                out.extend(list.split(", ").map(|f| f.trim_matches('`').to_string()));
            }
        }
    }
    out
}

/// Named fields of the variants of each `pub enum` in src/config.rs (always public).
fn enum_variant_fields(src: &str) -> usize {
    let mut n = 0;
    let mut depth = 0i32;
    let mut in_enum = false;
    for line in src.lines() {
        let code = line.split("//").next().unwrap_or("");
        if code.starts_with("pub enum ") {
            in_enum = true;
            depth = 0;
        }
        if in_enum {
            // Inside a variant's braces (depth 2), `name: Type` is a field.
            let t = code.trim();
            if depth == 2 && t.contains(':') && !t.starts_with('#') {
                n += 1;
            }
            depth += code.matches('{').count() as i32 - code.matches('}').count() as i32;
            if depth == 0 && code.contains('}') {
                in_enum = false;
            }
        }
    }
    n
}

#[test]
fn at_most_45_public_configuration_fields() {
    let api = fs::read_to_string("docs/api.md").expect("docs/api.md");
    let src = fs::read_to_string("src/config.rs").expect("src/config.rs");
    let fields = api_config_fields(&api);
    let variants = enum_variant_fields(&src);
    assert!(fields.len() > 10 && variants > 0, "parsed {fields:?} and {variants}");
    let total = fields.len() + variants;
    println!(
        "public configuration fields: {} in structs + {variants} in enum variants = {total}",
        fields.len()
    );
    assert!(total <= MAX_PUBLIC_FIELDS, "{total} public configuration fields: {fields:?}");
}

/// Whether a field's doc states its allowed range (as `Config::validate` checks it).
fn states_range(doc: &str) -> bool {
    ["Range:", "each in [", "in [", "`f32::INFINITY` disables"].iter().any(|m| doc.contains(m))
}

/// Whether a field's doc states its unit (SI, or dimensionless, a χ² value, a count).
fn states_unit(doc: &str) -> bool {
    ["rad", "m/s", ", s ", ", s,", " s (", "dimensionless", "χ²", "samples"]
        .iter()
        .any(|u| doc.contains(u))
}

/// Whether a field's type is a number or an array of numbers (enums, flags and
/// sub-configurations have no range to state).
fn numeric(decl: &str) -> bool {
    let ty = decl.split_once(':').map_or("", |(_, t)| t).trim().trim_end_matches(',');
    ["f32", "u8", "u16", "usize"].iter().any(|n| ty == *n || ty.starts_with(&format!("[{n};")))
}

#[test]
fn every_public_configuration_field_gives_its_default() {
    let src = fs::read_to_string("src/config.rs").expect("src/config.rs");
    let mut doc = String::new();
    let mut checked = 0;
    for line in src.lines() {
        let t = line.trim();
        if let Some(d) = t.strip_prefix("///") {
            doc.push_str(d);
            continue;
        }
        // A public struct field (expert fields are `pub(crate)`).
        let is_field = t.starts_with("pub ")
            && !t.starts_with("pub fn")
            && !t.starts_with("pub const")
            && !t.starts_with("pub struct")
            && !t.starts_with("pub enum")
            && !t.starts_with("pub use")
            && t.ends_with(',')
            && t.contains(':');
        if is_field {
            checked += 1;
            assert!(doc.to_lowercase().contains("default"), "no default documented: {t}\n{doc}");
            assert!(!numeric(t) || states_range(&doc), "no range documented: {t}\n{doc}");
            assert!(!numeric(t) || states_unit(&doc), "no unit documented: {t}\n{doc}");
        }
        if !t.starts_with("#[") {
            doc.clear();
        }
    }
    assert!(checked > 10, "only {checked} fields found");
}

#[test]
fn the_parsers_see_what_they_count() {
    let api = "- `config::Config`\n  - fields: `a`, `b`\n- `config::ConfigError`\n  - fields: `x`\n- `Other`\n  - fields: `y`\n";
    assert_eq!(api_config_fields(api), ["a", "b"]);
    let src = "pub enum E {\n    /// doc\n    A { x: f32, },\n    B {\n        y: f32,\n        z: f32,\n    },\n    C,\n}\npub struct S {\n    w: f32,\n}\n";
    // A's one-line braces hold `x` at depth 1 before the line is counted: only B's count.
    assert_eq!(enum_variant_fields(src), 2);
    assert!(numeric("pub a: f32,") && numeric("pub b: [f32; 3],") && numeric("pub c: u8,"));
    assert!(!numeric("pub d: bool,") && !numeric("pub e: Model,"));
    assert!(states_range("x. Range: > 0.") && !states_range("the default is 3"));
    assert!(states_unit("Receiver latency, s (default 0)") && !states_unit("a number (default 3)"));
}
