//! End to end in headless Chromium (Debian's /usr/bin/chromium, installed by `make test`):
//! the page served by the server, with the simulated tracker (`?sim=1`), turns its check
//! green after simulated `track` messages. Chromium is driven over the DevTools protocol.

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::*;
use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use sv_stream::Server;
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::WebSocketStream;

const CHROMIUM: &str = "/usr/bin/chromium";

/// A headless Chromium, killed on drop.
struct Chromium {
    child: Child,
    _profile: tempfile::TempDir,
    ws_url: String,
}

impl Drop for Chromium {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn launch() -> Chromium {
    assert!(
        std::path::Path::new(CHROMIUM).exists(),
        "{CHROMIUM} is missing: `make test` installs it (apt-get install chromium)"
    );
    let profile = tempfile::tempdir().unwrap();
    let mut child = Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--enable-unsafe-swiftshader",
            "--no-first-run",
            "--disable-extensions",
            "--remote-debugging-port=0",
            "--window-size=1024,768",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg("about:blank")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start chromium");
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if let Some(url) = line.strip_prefix("DevTools listening on ") {
                let _ = tx.send(url.trim().to_string());
            }
        }
    });
    let ws_url = rx
        .recv_timeout(Duration::from_secs(60))
        .expect("chromium printed its DevTools address");
    Chromium {
        child,
        _profile: profile,
        ws_url,
    }
}

/// A DevTools protocol session on one page.
struct Page {
    ws: WebSocketStream<TcpStream>,
    next_id: u64,
    session: Option<String>,
    /// Every `Network.webSocketCreated` / `Network.requestWillBeSent` URL seen.
    urls: Vec<String>,
}

impl Page {
    async fn open(browser: &Chromium, url: &str) -> Page {
        let addr = browser
            .ws_url
            .trim_start_matches("ws://")
            .split('/')
            .next()
            .unwrap()
            .to_string();
        let tcp = TcpStream::connect(addr).await.unwrap();
        let (ws, _) = tokio_tungstenite::client_async(browser.ws_url.as_str(), tcp)
            .await
            .unwrap();
        let mut page = Page {
            ws,
            next_id: 1,
            session: None,
            urls: Vec::new(),
        };
        let target = page
            .call("Target.createTarget", json!({"url": "about:blank"}))
            .await;
        let target_id = target["targetId"].as_str().unwrap().to_string();
        let attached = page
            .call(
                "Target.attachToTarget",
                json!({"targetId": target_id, "flatten": true}),
            )
            .await;
        page.session = Some(attached["sessionId"].as_str().unwrap().to_string());
        page.call("Network.enable", json!({})).await;
        page.call("Page.enable", json!({})).await;
        page.call("Page.navigate", json!({"url": url})).await;
        page
    }

    async fn call(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if let Some(s) = &self.session {
            msg["sessionId"] = json!(s);
        }
        self.ws.send(Message::text(msg.to_string())).await.unwrap();
        loop {
            let next = tokio::time::timeout(Duration::from_secs(30), self.ws.next())
                .await
                .expect("DevTools answer")
                .expect("DevTools connection open")
                .unwrap();
            let Message::Text(t) = next else { continue };
            let v: Value = serde_json::from_str(t.as_str()).unwrap();
            match v["method"].as_str() {
                Some("Network.requestWillBeSent") => {
                    self.urls
                        .push(v["params"]["request"]["url"].as_str().unwrap_or("").into());
                }
                Some("Network.webSocketCreated") => {
                    self.urls
                        .push(v["params"]["url"].as_str().unwrap_or("").into());
                }
                _ => {}
            }
            if v["id"] == id {
                assert!(v.get("error").is_none(), "{method}: {v}");
                return v["result"].clone();
            }
        }
    }

    async fn eval(&mut self, js: &str) -> Value {
        let r = self
            .call(
                "Runtime.evaluate",
                json!({"expression": js, "returnByValue": true}),
            )
            .await;
        r["result"]["value"].clone()
    }

    /// Poll a predicate until it is true; panics with `what` after `timeout`.
    async fn wait_for(&mut self, js: &str, timeout: Duration, what: &str) {
        let start = Instant::now();
        loop {
            if self.eval(js).await == json!(true) {
                return;
            }
            if start.elapsed() > timeout {
                let state = self
                    .eval("JSON.stringify(document.body && document.body.dataset)")
                    .await;
                panic!("timed out waiting for {what}; page state {state}");
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn simulated_tracker_turns_the_check_green() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = config();
    cfg.state_path = Some(dir.path().join("state.sqlite"));
    let server = Server::start(cfg).await.unwrap();
    let browser = launch();
    let url = format!("{}?sim=1#token={TOKEN}", server.url());
    let mut page = Page::open(&browser, &url).await;

    page.wait_for(
        "document.body.dataset.connection === 'ready'",
        Duration::from_secs(60),
        "the page to connect",
    )
    .await;
    assert_eq!(page.eval("document.body.dataset.progress").await, "0/36");
    page.wait_for(
        "document.body.dataset.check === 'ok'",
        Duration::from_secs(60),
        "a green check",
    )
    .await;
    assert_eq!(
        page.eval("document.getElementById('check').dataset.check")
            .await,
        "ok"
    );
    // the simulated tracker starts off target: the first check was red, a later one green
    let checks = page.eval("window.__sv.checks").await;
    let checks = checks.as_array().unwrap();
    assert_eq!(checks.first(), Some(&json!(false)), "{checks:?}");
    assert!(checks.contains(&json!(true)));
    // the next unit is on the page; no AR button in headless Chromium
    let next = page
        .eval("document.getElementById('next').dataset.unit")
        .await;
    assert!(frame().units.iter().any(|u| json!(u.id) == next), "{next}");
    assert_eq!(
        page.eval("document.getElementById('enter-ar').hidden")
            .await,
        true
    );
    // the token never went to the server in a URL
    page.eval("0").await;
    assert!(
        page.urls.iter().any(|u| u.ends_with("/ws")),
        "{:?}",
        page.urls
    );
    assert!(
        page.urls.iter().all(|u| !u.contains(TOKEN)),
        "token in a URL: {:?}",
        page.urls
    );
    drop(page);
    drop(browser);
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
