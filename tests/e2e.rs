//! End-to-end tests: the `spinvalence` binary run in fresh temporary directories on the
//! fixtures in `fixtures/` and on bad input built from them.

#[path = "e2e/util.rs"]
mod util;

#[path = "e2e/fixtures.rs"]
mod fixtures;

#[path = "../crates/sv-export/tests/ezdxf/mod.rs"]
mod ezdxf;

#[path = "e2e/bad_input.rs"]
mod bad_input;
#[path = "e2e/build.rs"]
mod build;
#[path = "e2e/check.rs"]
mod check;
#[path = "e2e/cli.rs"]
mod cli;
#[path = "e2e/dxf_inputs.rs"]
mod dxf_inputs;
#[path = "e2e/etch.rs"]
mod etch;
#[path = "e2e/fold.rs"]
mod fold;
#[path = "e2e/hygiene.rs"]
mod hygiene;
#[path = "e2e/nest.rs"]
mod nest;
#[path = "e2e/report.rs"]
mod report;
#[path = "e2e/serve.rs"]
mod serve;
#[path = "e2e/sheets.rs"]
mod sheets;
#[path = "e2e/solve.rs"]
mod solve;
#[path = "e2e/surface.rs"]
mod surface;
