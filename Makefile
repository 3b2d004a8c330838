# One entry point: `make test` is what CI runs (.ci/run).

CARGO ?= cargo

export PROPTEST_RNG_SEED ?= 20261122

.PHONY: acceptance test toolchain browser xr-deps fmt-check clippy unit-tests bench bench-primary fixtures bench-stream

## Everything CI checks: formatting, lints (warnings denied), unit, integration, e2e and doc tests.
test: toolchain browser xr-deps fmt-check clippy unit-tests

## Headless Chromium for the browser tests (the AR client, the build report), from Debian's
## packages when it is missing.
browser:
	@if ! command -v chromium >/dev/null 2>&1; then \
		echo "installing chromium from Debian packages for the browser tests"; \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -qq && \
		DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq chromium; \
	fi

## The emulated XR devices of the AR browser tests: Meta's Immersive Web Emulation Runtime
## (npm iwer), exactly as crates/sv-stream/tests/xr/package-lock.json pins it (Node.js and
## npm from Debian's packages when missing). Test-only: the binary never serves it.
XR_DIR := crates/sv-stream/tests/xr
xr-deps:
	@if ! command -v npm >/dev/null 2>&1; then \
		echo "installing nodejs and npm from Debian packages for the XR browser tests"; \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -qq && \
		DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq nodejs npm; \
	fi
	npm ci --prefix $(XR_DIR) --no-audit --no-fund --loglevel=error

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

## Issue 14's acceptance at 200 mm on all five targets (about ten minutes on 2 cores; `make
## test` runs the saddle's) and issue 15's constant overlap at 300 mm (about ten more).
acceptance:
	$(CARGO) test --workspace --test e2e -- --ignored at_200_mm_every_target constant_overlap_holds

## Criterion benchmarks of every crate that has them (figures go to docs/).
bench: bench-primary
	$(CARGO) bench --workspace

## The primary solve against the paper's SciPy SLSQP baseline, whole process against whole
## process, plus the 10,000-unit case (needs python3; makes a venv with numpy and scipy in
## target/bench-venv). UNITS=n sets the n x n baseline frames, BENCH_FULL=1 adds SLSQP on the
## 12 x 12 fixtures. Table in target/bench/primary.md, figures in docs/benchmarks.md.
bench-primary:
	bash bench/primary_vs_slsqp.sh

## Regenerate the OBJ fixtures in fixtures/ (a test fails when they are stale).
fixtures:
	$(CARGO) run -p spinvalence --example make_fixtures

## AR streamer load test: 50 websocket clients x 30 track/s x 10 s on loopback; prints sent,
## checked, coalesced and lost messages and the track -> check latency (docs/protocol.md).
bench-stream:
	$(CARGO) run --release -p sv-stream --example load -- --clients 50 --rate 30 --seconds 10
