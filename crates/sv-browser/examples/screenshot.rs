//! Look at a page as the tests see it: `cargo run -p sv-browser --example screenshot -- URL
//! OUT.png [JS]` waits for `document.readyState === 'complete'`, evaluates JS when given
//! (e.g. a click), waits a second and writes a PNG of the viewport.

use std::time::Duration;

use base64::Engine as _;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (Some(url), Some(out)) = (args.next(), args.next()) else {
        return Err("usage: screenshot URL OUT.png [JS]".into());
    };
    let browser = sv_browser::Browser::launch()?;
    let mut page = browser.open(&url)?;
    page.wait_for(
        "document.readyState === 'complete'",
        Duration::from_secs(60),
        "the page to load",
    )?;
    page.pump(Duration::from_millis(500))?;
    if let Some(js) = args.next() {
        page.eval(&js)?;
    }
    page.pump(Duration::from_secs(1))?;
    let shot = page.call(
        "Page.captureScreenshot",
        serde_json::json!({"format": "png"}),
    )?;
    let png =
        base64::engine::general_purpose::STANDARD.decode(shot["data"].as_str().unwrap_or(""))?;
    std::fs::write(&out, png)?;
    for e in page.errors() {
        eprintln!("page error: {e}");
    }
    Ok(())
}
