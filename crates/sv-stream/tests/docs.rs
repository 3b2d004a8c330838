//! Every JSON example in `docs/protocol.md` is valid against its schema, and every client
//! example parses as the server parses it.

mod common;

use serde_json::Value;
use sv_stream::protocol::{parse_client, CLIENT_TYPES};

#[test]
fn protocol_doc_examples_match_the_schemas() {
    let doc = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../docs/protocol.md"
    ))
    .unwrap();
    let mut seen = std::collections::BTreeSet::new();
    let mut rest = doc.as_str();
    while let Some(start) = rest.find("```json\n") {
        let body = &rest[start + 8..];
        let end = body.find("```").expect("closed code block");
        let text = &body[..end];
        let v: Value = serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"));
        common::validate(&v);
        let kind = v["type"].as_str().unwrap().to_string();
        if CLIENT_TYPES.contains(&kind.as_str()) {
            parse_client(text).unwrap_or_else(|e| panic!("{e:?}: {text}"));
        }
        seen.insert(kind);
        rest = &body[end + 3..];
    }
    let schemas: std::collections::BTreeSet<String> =
        std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/schema"))
            .unwrap()
            .map(|e| {
                e.unwrap()
                    .path()
                    .file_stem()
                    .unwrap()
                    .to_string_lossy()
                    .to_string()
            })
            .collect();
    assert_eq!(
        seen, schemas,
        "every message has an example in docs/protocol.md"
    );
}
