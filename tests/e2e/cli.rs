//! Help, version and usage errors.

use crate::util::Dir;

#[test]
fn help_lists_the_commands_with_examples() {
    let dir = Dir::new();
    let out = dir.run(&["--help"]);
    out.expect_code(0);
    for word in [
        "solve",
        "check",
        "Examples:",
        "spinvalence solve --mesh",
        "spinvalence check",
    ] {
        assert!(out.stdout.contains(word), "--help lacks {word:?}:{out:?}");
    }
    for (command, example) in [
        ("solve", "spinvalence solve --mesh fixtures/"),
        ("check", "spinvalence check out/"),
    ] {
        let out = dir.run(&[command, "--help"]);
        out.expect_code(0);
        assert!(
            out.stdout.contains("Examples:") && out.stdout.contains(example),
            "{out:?}"
        );
    }
}

#[test]
fn version_is_the_package_version() {
    let out = Dir::new().run(&["--version"]);
    out.expect_code(0);
    assert_eq!(
        out.stdout.trim(),
        format!("spinvalence {}", env!("CARGO_PKG_VERSION"))
    );
}

#[test]
fn usage_errors_are_one_line() {
    let dir = Dir::new();
    for args in [
        &["solve", "--mesh", "m.obj"][..],
        &["solve", "--mesh", "m.obj", "--out", "o", "--frobnicate"],
        &["solve", "--mesh", "m.obj", "--out", "o", "--side", "upside"],
        &["transmogrify"],
        &["check"],
    ] {
        let out = dir.run(args);
        out.expect_code(2);
        out.one_error_line();
    }
    assert!(dir.entries("o").is_empty());
}

#[test]
fn no_arguments_show_the_help() {
    let out = Dir::new().run(&[]);
    out.expect_code(2);
    assert!(out.stderr.contains("Usage:"), "{out:?}");
}
