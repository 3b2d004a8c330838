//! End to end in headless Chromium (Debian's /usr/bin/chromium, installed by `make test`):
//! the page served by the server, with the simulated tracker (`?sim=1`), turns its check
//! green after simulated `track` messages. Chromium is driven over the DevTools protocol.

mod common;

use std::time::Duration;

use common::*;
use serde_json::json;
use sv_browser::Browser;
use sv_stream::Server;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn simulated_tracker_turns_the_check_green() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = config();
    cfg.state_path = Some(dir.path().join("state.sqlite"));
    let server = Server::start(cfg).await.unwrap();
    let url = format!("{}?sim=1#token={TOKEN}", server.url());
    // the DevTools client blocks: off the runtime's threads, the server keeps running
    tokio::task::spawn_blocking(move || drive_the_page(&url))
        .await
        .unwrap();
    server.shutdown().await;

    // the server recorded the simulated tracks
    let conn = rusqlite::Connection::open(dir.path().join("state.sqlite")).unwrap();
    let sims: i64 = conn
        .query_row(
            "SELECT COUNT(*) FROM measurements WHERE kind = 'track' AND json LIKE '%\"source\":\"sim\"%'",
            [],
            |r| r.get(0),
        )
        .unwrap();
    assert!(sims >= 2, "{sims} simulated tracks stored");
}

fn drive_the_page(url: &str) {
    let browser = Browser::launch().unwrap();
    let mut page = browser.open(url).unwrap();
    page.wait_for(
        "document.body.dataset.connection === 'ready'",
        Duration::from_secs(60),
        "the page to connect",
    )
    .unwrap();
    assert_eq!(page.eval("document.body.dataset.progress").unwrap(), "0/36");
    page.wait_for(
        "document.body.dataset.check === 'ok'",
        Duration::from_secs(60),
        "a green check",
    )
    .unwrap();
    assert_eq!(
        page.eval("document.getElementById('check').dataset.check")
            .unwrap(),
        "ok"
    );
    // the simulated tracker starts off target: the first check was red, a later one green
    let checks = page.eval("window.__sv.checks").unwrap();
    let checks = checks.as_array().unwrap();
    assert_eq!(checks.first(), Some(&json!(false)), "{checks:?}");
    assert!(checks.contains(&json!(true)));
    // the next unit is on the page; no AR button in headless Chromium
    let next = page
        .eval("document.getElementById('next').dataset.unit")
        .unwrap();
    assert!(frame().units.iter().any(|u| json!(u.id) == next), "{next}");
    assert_eq!(
        page.eval("document.getElementById('enter-ar').hidden")
            .unwrap(),
        true
    );
    // the 3D view drew the frame: more than the background colour
    let image = page.screenshot("#view canvas").unwrap();
    assert!(
        image.fraction_unlike([0x10, 0x13, 0x17], 8) > 0.01,
        "blank 3D view: {} colours",
        image.distinct_colours()
    );
    // figures with enough digits to tell ok from bad, and a malformed check clears the verdict
    let unit = next.as_str().unwrap();
    let text = |page: &mut sv_browser::Page, pos: f64, ok: bool| {
        page.eval(&format!(
            "window.__sv.handle({{type: 'check', unit: '{unit}', part: 'hub', ok: {ok}, \
             position_error_mm: {pos}, angle_error_deg: 0.2, move_mm: [1, 0, 0], frame: 'model', \
             coalesced: 0}}); document.getElementById('check').textContent"
        ))
        .unwrap()
        .as_str()
        .unwrap()
        .to_string()
    };
    let ok = text(&mut page, 4.99, true);
    assert!(ok.contains("4.99 mm <= 5.00 mm"), "{ok}");
    let bad = text(&mut page, 5.01, false);
    assert!(bad.contains("5.01 mm > 5.00 mm"), "{bad}");
    let close = text(&mut page, 5.0004, false);
    assert!(close.contains("5.0004 mm > 5.00 mm"), "{close}");
    // (one script: the simulated tracker's next check cannot come in between)
    let after = page
        .eval(&format!(
            "window.__sv.handle({{type: 'check', unit: '{unit}', part: 'hub', ok: true, \
             position_error_mm: null, angle_error_deg: 0.1, move_mm: [0, 0, 0], coalesced: 0}}); \
             document.body.dataset.check"
        ))
        .unwrap();
    assert_eq!(after, "none", "a malformed check left a verdict");
    assert!(page.errors().is_empty(), "page errors: {:?}", page.errors());
    // the token never went to the server in a URL
    let urls: Vec<&str> = page.requests().iter().map(|r| r.url.as_str()).collect();
    assert!(urls.iter().any(|u| u.ends_with("/ws")), "{urls:?}");
    assert!(
        urls.iter().all(|u| !u.contains(TOKEN)),
        "token in a URL: {urls:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_twenty_thousand_unit_frame_loads_in_the_page() {
    let mut cfg = config();
    cfg.frame = big_frame(200, 100);
    let server = Server::start(cfg).await.unwrap();
    let url = format!("{}#token={TOKEN}", server.url());
    tokio::task::spawn_blocking(move || {
        let browser = Browser::launch().unwrap();
        let mut page = browser.open(&url).unwrap();
        page.wait_for(
            "document.body.dataset.units === '20000' && document.body.dataset.progress === '0/20000'",
            Duration::from_secs(120),
            "20,000 units in the page",
        )
        .unwrap();
        page.pump(Duration::from_millis(500)).unwrap();
        let image = page.screenshot("#view canvas").unwrap();
        assert!(
            image.fraction_unlike([0x10, 0x13, 0x17], 8) > 0.01,
            "blank 3D view of 20,000 units"
        );
        // one connection: the pages never closed it
        let sockets = page
            .requests()
            .iter()
            .filter(|r| r.kind == "WebSocket")
            .count();
        assert_eq!(sockets, 1, "{:?}", page.requests());
        assert!(page.errors().is_empty(), "page errors: {:?}", page.errors());
    })
    .await
    .unwrap();
    server.shutdown().await;
}
