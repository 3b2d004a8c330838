# One entry point: `make test` is what CI runs (.ci/run).

CARGO ?= cargo

export PROPTEST_RNG_SEED ?= 20261122

.PHONY: test toolchain fmt-check clippy unit-tests bench fixtures

## Everything CI checks: formatting, lints (warnings denied), unit, integration, e2e and doc tests.
test: toolchain fmt-check clippy unit-tests

## rustfmt and clippy, added through rustup when missing.
toolchain:
	@$(CARGO) fmt --version >/dev/null 2>&1 || rustup component add rustfmt
	@$(CARGO) clippy --version >/dev/null 2>&1 || rustup component add clippy

fmt-check:
	$(CARGO) fmt --all -- --check

clippy:
	$(CARGO) clippy --workspace --all-targets -- -D warnings

unit-tests:
	$(CARGO) test --workspace

## Criterion benchmarks of every crate that has them (figures go to docs/).
bench:
	$(CARGO) bench --workspace

## Regenerate the OBJ fixtures in fixtures/ (a test fails when they are stale).
fixtures:
	$(CARGO) run -p spinvalence --example make_fixtures
