//! Repository hygiene: the committed fixtures are what the generator writes.

use crate::fixtures;

#[test]
fn fixtures_are_up_to_date() {
    for fixture in fixtures::generated() {
        let path = fixtures::path(fixture.file);
        let committed =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let expected = fixture.obj();
        if committed != expected {
            let line = committed
                .lines()
                .zip(expected.lines())
                .position(|(a, b)| a != b);
            panic!(
                "{} is stale (first differing line: {line:?}); run `cargo run -p spinvalence --example make_fixtures`",
                path.display()
            );
        }
    }
}

#[test]
fn fixtures_readme_mentions_every_fixture() {
    let readme = std::fs::read_to_string(fixtures::path("README.md")).unwrap();
    for fixture in fixtures::generated() {
        assert!(
            readme.contains(fixture.file),
            "fixtures/README.md does not mention {}",
            fixture.file
        );
    }
}

/// docs/config.md shows exactly what `build --print-config` prints.
#[test]
fn config_doc_matches_print_config() {
    let out = crate::util::Dir::new().run(&["build", "--print-config"]);
    out.expect_code(0);
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/config.md"))
        .unwrap();
    let start = doc
        .find("<!-- defaults:begin -->\n```toml\n")
        .expect("defaults block")
        + "<!-- defaults:begin -->\n```toml\n".len();
    let end = doc
        .find("```\n<!-- defaults:end -->")
        .expect("end of defaults block");
    assert_eq!(
        doc[start..end].trim_end(),
        out.stdout.trim_end(),
        "docs/config.md is stale: paste `spinvalence build --print-config` into it"
    );
}
