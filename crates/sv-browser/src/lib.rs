//! Dev-only test support: drive a headless Chromium over the Chrome DevTools Protocol (CDP).
//!
//! Used by the browser tests of the AR client (`sv-stream`) and of the build report
//! (`spinvalence` e2e). A small blocking client on one websocket, no async runtime:
//!
//! - [`Browser::launch`] starts `/usr/bin/chromium` headless (swiftshader WebGL, a throwaway
//!   profile, killed on drop); [`Browser::open`] opens a [`Page`] on a URL.
//! - [`Page::eval`] evaluates JavaScript (promises awaited, results by value);
//!   [`Page::wait_for`] polls a predicate.
//! - [`Page::requests`] is every request the page made (`Network.requestWillBeSent`,
//!   `Network.webSocketCreated`), recorded from before the first navigation, so a test can
//!   prove that a page made no network request.
//! - [`Page::errors`] collects uncaught exceptions, `console.error` and browser log errors
//!   (failed loads, content-security-policy violations).
//! - [`Page::screenshot`] returns the pixels of an element as Chromium composited them
//!   ([`Image`]), to prove that a WebGL canvas drew something.
//! - [`Page::click`] sends a real mouse click (pointer events included).
//!
//! ```no_run
//! use std::time::Duration;
//! let browser = sv_browser::Browser::launch().unwrap();
//! let mut page = browser.open("file:///tmp/out/report.html").unwrap();
//! page.wait_for("document.body.dataset.ready === 'yes'", Duration::from_secs(60), "the page")
//!     .unwrap();
//! let image = page.screenshot("canvas").unwrap();
//! assert!(image.distinct_colours() > 1);
//! assert!(page.requests().iter().all(|r| r.url.starts_with("file:")));
//! ```
//!
//! Nothing here prints; every failure is a [`BrowserError`].

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use base64::Engine as _;
use serde_json::{json, Value};
use tungstenite::{Message, WebSocket};

/// Where Debian's `chromium` package (installed by `make browser`) puts the browser.
pub const DEFAULT_CHROMIUM: &str = "/usr/bin/chromium";

/// Default time to wait for one DevTools answer.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(60);

/// What went wrong talking to the browser.
#[derive(Debug, thiserror::Error)]
pub enum BrowserError {
    /// The executable is not there.
    #[error("{0} is missing: `make browser` installs it (apt-get install chromium)")]
    Missing(PathBuf),
    /// The browser did not start or did not print its DevTools address.
    #[error("chromium did not start: {0}")]
    Launch(String),
    /// The DevTools connection failed or answered with an error.
    #[error("devtools: {0}")]
    Protocol(String),
    /// Nothing came in time.
    #[error("timed out after {seconds:.0} s waiting for {what}")]
    Timeout {
        /// What we waited for.
        what: String,
        /// How long.
        seconds: f64,
    },
    /// A script evaluated in the page threw.
    #[error("script threw: {0}")]
    Script(String),
}

/// Result of this crate.
pub type Result<T> = std::result::Result<T, BrowserError>;

/// How to start the browser.
#[derive(Clone, Debug)]
pub struct LaunchOptions {
    /// The executable (default [`DEFAULT_CHROMIUM`]).
    pub executable: PathBuf,
    /// Window (viewport) size in CSS pixels (default 1024 x 768).
    pub window: (u32, u32),
    /// Longest wait for one DevTools answer (default [`DEFAULT_TIMEOUT`]).
    pub timeout: Duration,
}

impl Default for LaunchOptions {
    fn default() -> Self {
        Self {
            executable: PathBuf::from(DEFAULT_CHROMIUM),
            window: (1024, 768),
            timeout: DEFAULT_TIMEOUT,
        }
    }
}

/// A headless Chromium, killed on drop.
pub struct Browser {
    child: Child,
    _profile: tempfile::TempDir,
    ws_url: String,
    timeout: Duration,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Browser {
    /// Start [`DEFAULT_CHROMIUM`] with the default options.
    pub fn launch() -> Result<Self> {
        Self::launch_with(&LaunchOptions::default())
    }

    /// Start the browser: headless, software WebGL (swiftshader), a fresh profile, no
    /// extensions, DevTools on an ephemeral port.
    pub fn launch_with(options: &LaunchOptions) -> Result<Self> {
        if !Path::new(&options.executable).exists() {
            return Err(BrowserError::Missing(options.executable.clone()));
        }
        let profile = tempfile::Builder::new()
            .prefix("sv-browser-")
            .tempdir()
            .map_err(|e| BrowserError::Launch(format!("profile directory: {e}")))?;
        let mut child = Command::new(&options.executable)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--enable-unsafe-swiftshader",
                "--no-first-run",
                "--no-default-browser-check",
                "--disable-extensions",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-quic",
                "--disable-sync",
                "--remote-debugging-port=0",
            ])
            .arg(format!(
                "--window-size={},{}",
                options.window.0, options.window.1
            ))
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| BrowserError::Launch(format!("{}: {e}", options.executable.display())))?;
        let Some(stderr) = child.stderr.take() else {
            let _ = child.kill();
            return Err(BrowserError::Launch("no stderr".into()));
        };
        let (tx, rx) = std::sync::mpsc::channel();
        // Keeps draining stderr for the browser's whole life (a full pipe would block it).
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(|l| l.ok()) {
                if let Some(url) = line.strip_prefix("DevTools listening on ") {
                    let _ = tx.send(url.trim().to_string());
                }
            }
        });
        match rx.recv_timeout(options.timeout) {
            Ok(ws_url) => Ok(Self {
                child,
                _profile: profile,
                ws_url,
                timeout: options.timeout,
            }),
            Err(_) => {
                let _ = child.kill();
                let _ = child.wait();
                Err(BrowserError::Launch(
                    "no DevTools address on stderr".to_string(),
                ))
            }
        }
    }

    /// Open a new tab on `url` with the network, runtime and log domains enabled before the
    /// navigation, so that every request and error of the page is recorded.
    pub fn open(&self, url: &str) -> Result<Page> {
        self.open_with(url, &OpenOptions::default())
    }

    /// [`Browser::open`] with scripts run before the page's own and an emulated device.
    pub fn open_with(&self, url: &str, options: &OpenOptions) -> Result<Page> {
        let addr = self
            .ws_url
            .trim_start_matches("ws://")
            .split('/')
            .next()
            .unwrap_or_default()
            .to_string();
        let tcp = TcpStream::connect(&addr)
            .map_err(|e| BrowserError::Protocol(format!("connect {addr}: {e}")))?;
        let (ws, _) = tungstenite::client(self.ws_url.as_str(), tcp)
            .map_err(|e| BrowserError::Protocol(format!("websocket handshake: {e}")))?;
        let mut page = Page {
            ws,
            next_id: 1,
            session: None,
            requests: Vec::new(),
            errors: Vec::new(),
            timeout: self.timeout,
        };
        let target = page.call("Target.createTarget", json!({"url": "about:blank"}))?;
        let target_id = target["targetId"]
            .as_str()
            .ok_or_else(|| BrowserError::Protocol(format!("no targetId in {target}")))?
            .to_string();
        let attached = page.call(
            "Target.attachToTarget",
            json!({"targetId": target_id, "flatten": true}),
        )?;
        let session = attached["sessionId"]
            .as_str()
            .ok_or_else(|| BrowserError::Protocol(format!("no sessionId in {attached}")))?;
        page.session = Some(session.to_string());
        for domain in ["Network", "Runtime", "Log", "Page"] {
            page.call(&format!("{domain}.enable"), json!({}))?;
        }
        if let Some(d) = &options.device {
            page.call(
                "Emulation.setDeviceMetricsOverride",
                json!({"width": d.width, "height": d.height,
                       "deviceScaleFactor": d.scale, "mobile": d.mobile}),
            )?;
        }
        for source in &options.init_scripts {
            page.call(
                "Page.addScriptToEvaluateOnNewDocument",
                json!({"source": source}),
            )?;
        }
        page.call("Page.navigate", json!({"url": url}))?;
        Ok(page)
    }
}

/// How [`Browser::open_with`] prepares a tab.
#[derive(Clone, Debug, Default)]
pub struct OpenOptions {
    /// JavaScript run in every document before its own scripts (a test runtime, a stub).
    pub init_scripts: Vec<String>,
    /// Emulate this screen (a phone) instead of the window.
    pub device: Option<Device>,
}

/// An emulated screen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Device {
    /// Viewport width (CSS pixels).
    pub width: u32,
    /// Viewport height (CSS pixels).
    pub height: u32,
    /// Device pixels per CSS pixel.
    pub scale: f64,
    /// A mobile device (meta viewport honoured, overlay scrollbars).
    pub mobile: bool,
}

impl Device {
    /// A 390 x 844 phone at 3x (an iPhone 12 to 14's screen).
    pub const PHONE: Device = Device {
        width: 390,
        height: 844,
        scale: 3.0,
        mobile: true,
    };
}

/// One request a page made.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Request {
    /// The URL (`file:`, `data:`, `blob:`, `http:`, `ws:` ...).
    pub url: String,
    /// CDP resource type: `Document`, `Script`, `Image`, `Fetch`, `WebSocket`, ...
    pub kind: String,
}

/// A DevTools session on one tab.
pub struct Page {
    ws: WebSocket<TcpStream>,
    next_id: u64,
    session: Option<String>,
    requests: Vec<Request>,
    errors: Vec<String>,
    timeout: Duration,
}

impl Page {
    /// Every request the page made so far, in order.
    pub fn requests(&self) -> &[Request] {
        &self.requests
    }

    /// Uncaught exceptions, `console.error` messages and browser log errors so far.
    pub fn errors(&self) -> &[String] {
        &self.errors
    }

    /// Call a DevTools method on this page and return its `result`.
    pub fn call(&mut self, method: &str, params: Value) -> Result<Value> {
        let id = self.next_id;
        self.next_id += 1;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if let Some(s) = &self.session {
            msg["sessionId"] = json!(s);
        }
        let mut sent = self.ws.send(Message::text(msg.to_string()));
        // a signal interrupted the write: the frame is queued, flush it again
        while matches!(&sent, Err(tungstenite::Error::Io(e)) if e.kind() == std::io::ErrorKind::Interrupted)
        {
            sent = self.ws.flush();
        }
        sent.map_err(|e| BrowserError::Protocol(format!("{method}: {e}")))?;
        let deadline = Instant::now() + self.timeout;
        loop {
            let Some(v) = self.next_message(deadline)? else {
                return Err(BrowserError::Timeout {
                    what: format!("the answer to {method}"),
                    seconds: self.timeout.as_secs_f64(),
                });
            };
            if v["id"] == id {
                if let Some(err) = v.get("error") {
                    return Err(BrowserError::Protocol(format!("{method}: {err}")));
                }
                return Ok(v["result"].clone());
            }
        }
    }

    /// Evaluate `js` in the page (a promise is awaited) and return its value as JSON.
    pub fn eval(&mut self, js: &str) -> Result<Value> {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": js, "returnByValue": true, "awaitPromise": true}),
        )?;
        if let Some(details) = r.get("exceptionDetails") {
            let text = details["exception"]["description"]
                .as_str()
                .or_else(|| details["text"].as_str())
                .unwrap_or("exception")
                .to_string();
            return Err(BrowserError::Script(text));
        }
        Ok(r["result"]["value"].clone())
    }

    /// Poll the predicate `js` every 100 ms until it is `true`. A predicate that throws
    /// (`document.body` is null while the page loads) counts as false; the timeout error
    /// names the last exception.
    pub fn wait_for(&mut self, js: &str, timeout: Duration, what: &str) -> Result<()> {
        let start = Instant::now();
        let mut last_error = None;
        loop {
            match self.eval(js) {
                Ok(Value::Bool(true)) => return Ok(()),
                Ok(_) => {}
                Err(BrowserError::Script(e)) => last_error = Some(e),
                Err(e) => return Err(e),
            }
            if start.elapsed() > timeout {
                let what = match last_error {
                    Some(e) => format!("{what} (last: {e})"),
                    None => what.to_string(),
                };
                return Err(BrowserError::Timeout {
                    what,
                    seconds: timeout.as_secs_f64(),
                });
            }
            self.pump(Duration::from_millis(100))?;
        }
    }

    /// Record the events that arrive during `duration` (late requests, errors).
    pub fn pump(&mut self, duration: Duration) -> Result<()> {
        let deadline = Instant::now() + duration;
        while self.next_message(deadline)?.is_some() {}
        Ok(())
    }

    /// A left click at `(x, y)` (CSS pixels in the viewport), as a user would make it.
    pub fn click(&mut self, x: f64, y: f64) -> Result<()> {
        self.call(
            "Input.dispatchMouseEvent",
            json!({"type": "mouseMoved", "x": x, "y": y}),
        )?;
        for kind in ["mousePressed", "mouseReleased"] {
            self.call(
                "Input.dispatchMouseEvent",
                json!({"type": kind, "x": x, "y": y, "button": "left", "buttons": 1, "clickCount": 1}),
            )?;
        }
        Ok(())
    }

    /// The pixels of the first element matching `selector` (scrolled into view), as the
    /// browser composited them: a PNG screenshot of its box, decoded in the page with
    /// `createImageBitmap` (no request is made).
    pub fn screenshot(&mut self, selector: &str) -> Result<Image> {
        let sel = serde_json::to_string(selector).unwrap_or_default();
        let rect = self.eval(&format!(
            "(() => {{ const e = document.querySelector({sel}); if (!e) return null; \
             e.scrollIntoView({{block: 'center'}}); const r = e.getBoundingClientRect(); \
             return [r.left + window.scrollX, r.top + window.scrollY, r.width, r.height]; }})()"
        ))?;
        let r: Vec<f64> = rect
            .as_array()
            .ok_or_else(|| BrowserError::Script(format!("no element matches {selector}")))?
            .iter()
            .filter_map(Value::as_f64)
            .collect();
        if r.len() != 4 || r[2] < 1.0 || r[3] < 1.0 {
            return Err(BrowserError::Script(format!(
                "{selector} has no visible box: {rect}"
            )));
        }
        let shot = self.call(
            "Page.captureScreenshot",
            json!({"format": "png", "clip": {"x": r[0], "y": r[1], "width": r[2], "height": r[3], "scale": 1}}),
        )?;
        let png = shot["data"]
            .as_str()
            .ok_or_else(|| BrowserError::Protocol("screenshot without data".into()))?;
        let decoded = self.eval(&format!(
            "(async () => {{ const b = Uint8Array.from(atob('{png}'), (c) => c.charCodeAt(0)); \
             const bmp = await createImageBitmap(new Blob([b], {{type: 'image/png'}})); \
             const c = new OffscreenCanvas(bmp.width, bmp.height); const g = c.getContext('2d'); \
             g.drawImage(bmp, 0, 0); const d = g.getImageData(0, 0, bmp.width, bmp.height).data; \
             let s = ''; for (let i = 0; i < d.length; i += 0x8000) \
             s += String.fromCharCode.apply(null, d.subarray(i, i + 0x8000)); \
             return {{width: bmp.width, height: bmp.height, rgba: btoa(s)}}; }})()"
        ))?;
        let width = decoded["width"].as_u64().unwrap_or(0) as usize;
        let height = decoded["height"].as_u64().unwrap_or(0) as usize;
        let rgba = base64::engine::general_purpose::STANDARD
            .decode(decoded["rgba"].as_str().unwrap_or_default())
            .map_err(|e| BrowserError::Protocol(format!("pixels: {e}")))?;
        if rgba.len() != 4 * width * height {
            return Err(BrowserError::Protocol(format!(
                "{} bytes of pixels for {width} x {height}",
                rgba.len()
            )));
        }
        Ok(Image {
            width,
            height,
            rgba,
        })
    }

    /// The next message before `deadline`, events recorded on the way; `None` on timeout.
    fn next_message(&mut self, deadline: Instant) -> Result<Option<Value>> {
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            self.ws
                .get_mut()
                .set_read_timeout(Some(left.max(Duration::from_millis(1))))
                .map_err(|e| BrowserError::Protocol(e.to_string()))?;
            let msg = match self.ws.read() {
                Ok(m) => m,
                // a signal (another test's child exiting) interrupted the read: read again
                Err(tungstenite::Error::Io(e)) if e.kind() == std::io::ErrorKind::Interrupted => {
                    continue
                }
                Err(tungstenite::Error::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    return Ok(None)
                }
                Err(e) => return Err(BrowserError::Protocol(format!("connection: {e}"))),
            };
            let Message::Text(text) = msg else { continue };
            let v: Value = serde_json::from_str(text.as_str())
                .map_err(|e| BrowserError::Protocol(format!("bad message: {e}")))?;
            self.record(&v);
            return Ok(Some(v));
        }
    }

    /// Keep the requests and errors an event of our session reports.
    fn record(&mut self, v: &Value) {
        let Some(method) = v["method"].as_str() else {
            return;
        };
        if self.session.is_some() && v["sessionId"].as_str() != self.session.as_deref() {
            return;
        }
        let p = &v["params"];
        let text = |x: &Value| x.as_str().unwrap_or_default().to_string();
        match method {
            "Network.requestWillBeSent" => self.requests.push(Request {
                url: text(&p["request"]["url"]),
                kind: text(&p["type"]),
            }),
            "Network.webSocketCreated" => self.requests.push(Request {
                url: text(&p["url"]),
                kind: "WebSocket".into(),
            }),
            "Runtime.exceptionThrown" => {
                let d = &p["exceptionDetails"];
                let what = d["exception"]["description"]
                    .as_str()
                    .or_else(|| d["text"].as_str())
                    .unwrap_or("exception");
                self.errors.push(format!("uncaught: {what}"));
            }
            "Runtime.consoleAPICalled" if p["type"] == "error" => {
                let args: Vec<String> = p["args"]
                    .as_array()
                    .map(|a| {
                        a.iter()
                            .map(|x| {
                                x["value"]
                                    .as_str()
                                    .map(str::to_string)
                                    .or_else(|| x["description"].as_str().map(str::to_string))
                                    .unwrap_or_else(|| x["value"].to_string())
                            })
                            .collect()
                    })
                    .unwrap_or_default();
                self.errors
                    .push(format!("console.error: {}", args.join(" ")));
            }
            "Log.entryAdded" if p["entry"]["level"] == "error" => {
                self.errors.push(format!(
                    "log ({}): {} {}",
                    text(&p["entry"]["source"]),
                    text(&p["entry"]["text"]),
                    text(&p["entry"]["url"])
                ));
            }
            _ => {}
        }
    }
}

/// RGBA pixels, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `4 * width * height` bytes, R G B A.
    pub rgba: Vec<u8>,
}

impl Image {
    /// The pixel at `(x, y)`.
    pub fn pixel(&self, x: usize, y: usize) -> [u8; 4] {
        let i = 4 * (y * self.width + x);
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// How many different colours the image has.
    pub fn distinct_colours(&self) -> usize {
        let mut colours: Vec<[u8; 4]> = self
            .rgba
            .chunks_exact(4)
            .map(|p| [p[0], p[1], p[2], p[3]])
            .collect();
        colours.sort_unstable();
        colours.dedup();
        colours.len()
    }

    /// Fraction of the pixels that differ from `colour` (RGB) by more than `tolerance` in
    /// some channel.
    pub fn fraction_unlike(&self, colour: [u8; 3], tolerance: u8) -> f64 {
        let n = self.width * self.height;
        if n == 0 {
            return 0.0;
        }
        let differ = self
            .rgba
            .chunks_exact(4)
            .filter(|p| (0..3).any(|k| p[k].abs_diff(colour[k]) > tolerance))
            .count();
        differ as f64 / n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(pixels: &[[u8; 4]], width: usize) -> Image {
        Image {
            width,
            height: pixels.len() / width,
            rgba: pixels.iter().flatten().copied().collect(),
        }
    }

    #[test]
    fn colours_are_counted_and_compared() {
        let bg = [16, 19, 23, 255];
        let blank = image(&[bg; 6], 3);
        assert_eq!(blank.distinct_colours(), 1);
        assert_eq!(blank.fraction_unlike([16, 19, 23], 0), 0.0);
        let drawn = image(&[bg, bg, [200, 10, 10, 255], bg, bg, [17, 19, 23, 255]], 3);
        assert_eq!(drawn.distinct_colours(), 3);
        assert_eq!(drawn.pixel(2, 0), [200, 10, 10, 255]);
        assert!((drawn.fraction_unlike([16, 19, 23], 2) - 1.0 / 6.0).abs() < 1e-12);
    }

    #[test]
    fn a_missing_browser_is_an_error_naming_it() {
        let options = LaunchOptions {
            executable: "/nonexistent/chromium".into(),
            ..LaunchOptions::default()
        };
        let err = Browser::launch_with(&options).err().map(|e| e.to_string());
        assert_eq!(
            err.as_deref(),
            Some("/nonexistent/chromium is missing: `make browser` installs it (apt-get install chromium)")
        );
    }
}
