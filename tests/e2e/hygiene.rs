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
