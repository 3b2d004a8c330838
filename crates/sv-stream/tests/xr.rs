//! The AR page in headless Chromium with an emulated headset (Meta Quest 3) and an emulated
//! phone, both from Meta's Immersive Web Emulation Runtime (npm `iwer`, pinned by
//! `tests/xr/package-lock.json`, installed by `make test`).
//!
//! iwer is injected by DevTools before the page's own scripts (`Page.addScriptToEvaluateOn
//! NewDocument`): the binary never serves it, so the production page has no emulator. The
//! emulated world is one flat plate, the physical hub of the next unit, placed where the test
//! says (a few mm off its target or 20 mm off); WebXR hit-tests are answered against it
//! (iwer's synthetic-environment hook), so the page measures it exactly as it would measure
//! steel: by hit-test along a controller ray (headset) or a screen tap (phone).
//!
//! One scenario per device: enter AR; the XR framebuffer shows the frame and the ghost; a
//! registration from another operator moves it (the scene is not rebuilt); three picked hub
//! corners send a `track` (`source: "ar"`) that turns the check green, then red for a plate
//! 20 mm off; the server is stopped: offline shown in AR, a Complete confirmed and queued;
//! the server restarts on the same port and state file: the page is still in AR, and the
//! queued Complete is applied once.

mod common;

use std::sync::Mutex;
use std::time::Duration;

use common::*;
use serde_json::{json, Value};
use sv_browser::{Browser, Device, OpenOptions, Page};
use sv_geom::{Isometry3, Point3, Vector3};
use sv_stream::{ServeConfig, Server};

/// One browser at a time: two software-rendered WebGL pages on 2 cores only slow each other.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

const WAIT: Duration = Duration::from_secs(60);

fn iwer_script() -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/xr/node_modules/iwer/build/iwer.min.js"
    );
    std::fs::read_to_string(path).unwrap_or_else(|e| {
        panic!("{path}: {e}: `make test` installs it (npm ci in crates/sv-stream/tests/xr)")
    })
}

/// The emulated device and world, run before the page's scripts.
fn setup_script(phone: bool) -> String {
    format!(
        r#"(() => {{
  const phone = {phone};
  const config = phone ? {{
    name: 'Phone (test profile)', controllerConfig: undefined,
    supportedSessionModes: ['inline', 'immersive-ar'],
    supportedFeatures: ['viewer', 'local', 'local-floor', 'hit-test', 'dom-overlay'],
    supportedFrameRates: [60], isSystemKeyboardSupported: false, internalNominalFrameRate: 60,
    environmentBlendModes: {{ 'immersive-ar': 'alpha-blend' }}, interactionMode: 'screen-space',
    userAgent: navigator.userAgent,
  }} : IWER.metaQuest3;
  const device = new IWER.XRDevice(config, {{ stereoEnabled: !phone }});
  device.installRuntime({{ forceInstall: true }});
  window.__xrDevice = device;
  // the physical world: one plate (XR metres, local-floor), set by the test
  class World {{
    constructor() {{
      this.version = 'test'; this.planesVisible = false; this.boundingBoxesVisible = false;
      this.meshesVisible = false; this.trackedPlanes = new Set(); this.trackedMeshes = new Set();
      this.canvas = document.createElement('canvas'); this.canvas.width = 1; this.canvas.height = 1;
      this.canvas.style.display = 'none';
    }}
    get environmentCanvas() {{ return this.canvas; }}
    render() {{}} loadEnvironment() {{}} loadDefaultEnvironment() {{}} deleteAll() {{}}
    computeDepthBuffer() {{ return null; }}
    computeHitTestResults(m) {{
      const w = window.__world;
      if (!w) return [];
      const o = [m[12], m[13], m[14]];
      const d = [-m[8], -m[9], -m[10]];
      const n = w.normal;
      const den = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
      if (Math.abs(den) < 1e-9) return [];
      const t = ((w.point[0] - o[0]) * n[0] + (w.point[1] - o[1]) * n[1] + (w.point[2] - o[2]) * n[2]) / den;
      if (t <= 0) return [];
      const r = new Float32Array(16);
      r[0] = r[5] = r[10] = r[15] = 1;
      r[12] = o[0] + t * d[0]; r[13] = o[1] + t * d[1]; r[14] = o[2] + t * d[2];
      window.__hits = (window.__hits || 0) + 1;
      return [r];
    }}
  }}
  device.installSEM(World);
  // a quaternion turning -Z (a ray, a camera) toward d
  window.__toward = (d) => {{
    const l = Math.hypot(d[0], d[1], d[2]);
    const v = [d[0] / l, d[1] / l, d[2] / l];
    const c = -v[2]; // cos of the angle between -Z and v
    const cx = [v[1], -v[0], 0]; // (0, 0, -1) x v
    const s = Math.hypot(cx[0], cx[1]);
    if (s < 1e-9) return c > 0 ? [0, 0, 0, 1] : [1, 0, 0, 0];
    const angle = Math.atan2(s, c);
    const k = Math.sin(angle / 2) / s;
    return [cx[0] * k, cx[1] * k, 0, Math.cos(angle / 2)];
  }};
  window.__aim = (from, to) => {{
    const c = window.__xrDevice.controllers.right;
    c.position.set(from[0], from[1], from[2]);
    const q = window.__toward([to[0] - from[0], to[1] - from[1], to[2] - from[2]]);
    c.quaternion.set(q[0], q[1], q[2], q[3]);
  }};
  window.__press = async () => {{
    const c = window.__xrDevice.controllers.right;
    const frames = () => new Promise((r) => setTimeout(r, 120));
    await frames();
    c.updateButtonValue('trigger', 1);
    await frames();
    c.updateButtonValue('trigger', 0);
    await frames();
  }};
}})();"#
    )
}

/// Site (mm, Z up) to XR local-floor (m, Y up), as the page maps them.
fn xr_of(p: &Point3) -> [f64; 3] {
    [p.x / 1000.0, p.z / 1000.0, -p.y / 1000.0]
}

fn wait(page: &mut Page, js: &str, what: &str) {
    page.wait_for(js, WAIT, what).unwrap();
}

fn eval(page: &mut Page, js: &str) -> Value {
    page.eval(js).unwrap()
}

/// Fraction of the XR canvas unlike its most common colour, the ghost's cyan pixels, and the
/// mean x of the drawn pixels.
fn drawn(page: &mut Page) -> (f64, usize, f64) {
    let image = page.screenshot("#frame-canvas").unwrap();
    let mut counts = std::collections::HashMap::new();
    for p in image.rgba.chunks_exact(4) {
        *counts.entry([p[0], p[1], p[2]]).or_insert(0usize) += 1;
    }
    let background = *counts.iter().max_by_key(|(_, n)| **n).unwrap().0;
    let fraction = image.fraction_unlike(background, 12);
    let (mut cyan, mut sum, mut n) = (0usize, 0.0f64, 0.0f64);
    for y in 0..image.height {
        for x in 0..image.width {
            let [r, g, b, _] = image.pixel(x, y);
            if (0..3).any(|k| [r, g, b][k].abs_diff(background[k]) > 12) {
                sum += x as f64;
                n += 1.0;
            }
            // the ghost's cyan, translucent over the background: blue over green over red
            let (r, g, b) = (i32::from(r), i32::from(g), i32::from(b));
            if b > 90 && b > r + 60 && g > r + 30 {
                cyan += 1;
            }
        }
    }
    (fraction, cyan, sum / n.max(1.0))
}

struct Scenario {
    rt: tokio::runtime::Runtime,
    cfg: ServeConfig,
    server: Option<Server>,
    _dir: tempfile::TempDir,
}

impl Scenario {
    fn new() -> Scenario {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let mut cfg = config();
        cfg.state_path = Some(dir.path().join("state.sqlite"));
        let server = rt.block_on(Server::start(cfg.clone())).unwrap();
        cfg.bind = server.local_addr().to_string(); // a restart takes the same port
        Scenario {
            rt,
            cfg,
            server: Some(server),
            _dir: dir,
        }
    }

    fn url(&self) -> String {
        format!("http://{}/#token={TOKEN}", self.cfg.bind)
    }

    fn stop(&mut self) {
        if let Some(s) = self.server.take() {
            self.rt.block_on(s.shutdown());
        }
    }

    fn restart(&mut self) {
        let s = self.rt.block_on(Server::start(self.cfg.clone())).unwrap();
        self.server = Some(s);
    }

    /// Another operator registers the site: `site = t model`.
    fn register(&self, t: &Isometry3) {
        let f = frame();
        let pts: Vec<Value> = [0usize, 5, 30, 35, 14]
            .iter()
            .map(|&u| {
                let m = f.units[u].hub[0];
                let s = t * Point3::new(m[0], m[1], m[2]);
                json!([m, [s.x, s.y, s.z]])
            })
            .collect();
        let server = self.server.as_ref().unwrap();
        self.rt.block_on(async {
            let mut c = connect(server).await;
            c.join(TOKEN, "surveyor").await;
            c.send(json!({"type": "register", "points": pts})).await;
            assert_eq!(c.expect("fit").await["ok"], true);
        });
    }

    /// `(unit, op_id)` of every completion in the state file.
    fn completed(&self) -> Vec<(String, String)> {
        let path = self.cfg.state_path.as_ref().unwrap();
        let db = rusqlite::Connection::open(path).unwrap();
        let mut stmt = db.prepare("SELECT unit, op_id FROM completed").unwrap();
        stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))
            .unwrap()
            .map(Result::unwrap)
            .collect()
    }

    fn ar_tracks(&self) -> i64 {
        let path = self.cfg.state_path.as_ref().unwrap();
        let db = rusqlite::Connection::open(path).unwrap();
        db.query_row(
            "SELECT COUNT(*) FROM measurements WHERE kind = 'track' AND json LIKE '%\"source\":\"ar\"%'",
            [],
            |r| r.get(0),
        )
        .unwrap()
    }
}

/// The plate of `unit`'s hub in the emulated world: its target (site frame) moved by `off` mm.
fn place_plate(page: &mut Page, site: &Isometry3, unit: usize, off: Vector3) -> Vec<[f64; 3]> {
    let hub = frame().units[unit].hub;
    let corners: Vec<[f64; 3]> = hub
        .iter()
        .map(|c| xr_of(&(site * Point3::new(c[0], c[1], c[2]) + off)))
        .collect();
    let (a, b, c) = (
        Vector3::from(corners[0]),
        Vector3::from(corners[1]),
        Vector3::from(corners[2]),
    );
    let n = (b - a).cross(&(c - a)).normalize();
    eval(
        page,
        &format!(
            "window.__world = {{point: {:?}, normal: [{}, {}, {}]}}",
            corners[0], n.x, n.y, n.z
        ),
    );
    corners
}

/// Pick the three hub corners: a controller ray from 30 cm above each (headset), or the
/// phone held 40 cm above each, looking down, tapped at the screen centre.
fn pick_corners(page: &mut Page, corners: &[[f64; 3]], phone: bool) {
    let n = eval(page, "window.__sv.measure.need").as_u64().unwrap() as usize;
    for (k, c) in corners.iter().take(n).enumerate() {
        let before = eval(page, "window.__hits || 0").as_u64().unwrap();
        if phone {
            eval(
                page,
                &format!(
                    "(() => {{ const d = window.__xrDevice; d.position.set({}, {}, {}); \
                     d.quaternion.set(-Math.SQRT1_2, 0, 0, Math.SQRT1_2); }})()",
                    c[0],
                    c[1] + 0.4,
                    c[2]
                ),
            );
            page.pump(Duration::from_millis(300)).unwrap();
            page.click(195.0, 422.0).unwrap();
        } else {
            eval(
                page,
                &format!("window.__aim([{}, {}, {}], {c:?})", c[0], c[1] + 0.3, c[2]),
            );
            eval(page, "window.__press()");
        }
        wait(
            page,
            &format!("(window.__hits || 0) > {before} && (!window.__sv.measure || window.__sv.measure.points.length > {k})"),
            &format!("corner {k} picked"),
        );
    }
}

/// Press a HUD button with the controller (headset) or tap its DOM twin (phone overlay).
fn press(page: &mut Page, hud: &str, dom: &str, phone: bool) {
    if phone {
        eval(page, &format!("document.getElementById('{dom}').click()"));
        return;
    }
    let at = eval(page, &format!("window.__sv.hudButtonAt('{hud}')"));
    let at: Vec<f64> = at
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    // from the head (the HUD faces it), at the button
    eval(
        page,
        &format!(
            "window.__aim([0, 1.6, 0], [{}, {}, {}])",
            at[0], at[1], at[2]
        ),
    );
    eval(page, "window.__press()");
}

fn scenario(phone: bool) {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let mut s = Scenario::new();
    let browser = Browser::launch().unwrap();
    let options = OpenOptions {
        init_scripts: vec![iwer_script(), setup_script(phone)],
        device: phone.then_some(Device::PHONE),
    };
    let mut page = browser.open_with(&s.url(), &options).unwrap();
    wait(
        &mut page,
        "document.body.dataset.connection === 'ready' && document.body.dataset.units === '36'",
        "the page to load the frame",
    );

    if phone {
        // glove-size controls, apart, and Enter AR on the screen
        let boxes = eval(
            &mut page,
            "['enter-ar', 'claim', 'complete'].map((id) => { const r = document.getElementById(id)\
             .getBoundingClientRect(); return [r.left, r.top, r.right, r.bottom]; })",
        );
        let b: Vec<Vec<f64>> = serde_json::from_value(boxes).unwrap();
        let (w, h) = (390.0, 844.0);
        assert!(
            b[0][0] >= 0.0 && b[0][1] >= 0.0 && b[0][2] <= w && b[0][3] <= h,
            "Enter AR off the screen: {:?}",
            b[0]
        );
        for r in &b {
            assert!(
                r[2] - r[0] >= 48.0 && r[3] - r[1] >= 48.0,
                "control of {r:?} under 48 px"
            );
        }
        let gap = (b[2][0] - b[1][2]).max(b[2][1] - b[1][3]);
        assert!(gap >= 16.0, "Claim and Complete {gap} px apart");
    }

    // the emulated head looks ahead and down at the floor where the frame is placed
    eval(
        &mut page,
        "(() => { const d = window.__xrDevice; d.position.set(0, 1.6, 0); \
         d.quaternion.set(-0.3826834, 0, 0, 0.9238795); })()",
    );
    let r = eval(
        &mut page,
        "(() => { const r = document.getElementById('enter-ar').getBoundingClientRect(); \
         return [r.left + r.width / 2, r.top + r.height / 2]; })()",
    );
    page.click(r[0].as_f64().unwrap(), r[1].as_f64().unwrap())
        .unwrap();
    wait(
        &mut page,
        "document.body.dataset.xr === 'on' && window.__sv.xrFrames > 10",
        "an immersive-ar session",
    );
    let near = eval(&mut page, "window.__sv.view.camera.near")
        .as_f64()
        .unwrap();
    assert!(near <= 0.1, "near plane {near} m");
    let (fraction, cyan, x0) = drawn(&mut page);
    assert!(fraction > 0.02, "XR framebuffer nearly blank: {fraction}");
    assert!(
        cyan > 30,
        "no ghost in the XR framebuffer ({cyan} cyan pixels)"
    );
    eval(&mut page, "window.__viewBefore = window.__sv.view; true");
    wait(&mut page, "document.body.dataset.hud.includes('ONLINE') && document.body.dataset.hud.includes('Next: ')", "the HUD");

    // another operator registers the site: the frame moves in place, 0.4 m to the right
    let f = frame();
    let centre = f
        .units
        .iter()
        .flat_map(|u| u.hub)
        .fold(Vector3::zeros(), |s, p| s + Vector3::from(p))
        / (4.0 * f.units.len() as f64);
    let floor = f
        .units
        .iter()
        .flat_map(|u| u.hub.into_iter().chain(u.primary))
        .map(|p| p[2])
        .fold(f64::INFINITY, f64::min);
    let site = Isometry3::translation(400.0 - centre.x, 1500.0 - centre.y, -floor);
    s.register(&site);
    wait(&mut page, "document.body.dataset.registered === 'yes' && document.body.dataset.hud.includes('registered')", "the registration");
    page.pump(Duration::from_millis(500)).unwrap();
    let (fraction, _, x1) = drawn(&mut page);
    assert!(fraction > 0.02, "blank after the registration: {fraction}");
    assert!(
        x1 > x0 + 10.0,
        "the frame did not move right: mean x {x0:.0} -> {x1:.0} px"
    );
    assert_eq!(
        eval(&mut page, "window.__sv.view === window.__viewBefore"),
        true,
        "view rebuilt"
    );
    assert_eq!(eval(&mut page, "document.body.dataset.xr"), "on");

    // measure the next unit's hub: 2 mm off its target, then 20 mm off
    let next = eval(&mut page, "window.__sv.next")
        .as_str()
        .unwrap()
        .to_string();
    let u = f.units.iter().position(|x| x.id == next).unwrap();
    for (off, verdict) in [
        (Vector3::new(2.0, -1.0, 0.5), "ok"),
        (Vector3::new(20.0, 0.0, 0.0), "bad"),
    ] {
        let corners = place_plate(&mut page, &site, u, off);
        let checks = eval(&mut page, "window.__sv.checks.length")
            .as_u64()
            .unwrap();
        press(&mut page, "measure", "measure", phone);
        wait(&mut page, "window.__sv.measure !== null", "measure mode");
        pick_corners(&mut page, &corners, phone);
        wait(
            &mut page,
            &format!("window.__sv.checks.length > {checks} && document.body.dataset.check === '{verdict}'"),
            &format!("a {verdict} check from the measurement"),
        );
        let err = eval(&mut page, "window.__sv.lastCheck.position_error_mm")
            .as_f64()
            .unwrap();
        assert!(
            (err - off.norm()).abs() < 0.5,
            "measured {err} mm for a plate {} mm off",
            off.norm()
        );
    }
    assert!(
        s.ar_tracks() >= 2,
        "the measured tracks were not recorded as source ar"
    );

    // a hub overlap picked as two points on the plate, with the first linked neighbour
    let mut neighbours: Vec<usize> = f
        .links
        .iter()
        .filter_map(|l| match l.units {
            [a, b] if a == u => Some(b),
            [a, b] if b == u => Some(a),
            _ => None,
        })
        .collect();
    neighbours.sort_unstable();
    let design = f
        .links
        .iter()
        .find(|l| l.units == [u, neighbours[0]] || l.units == [neighbours[0], u])
        .unwrap()
        .hub_overlap;
    let corners = place_plate(&mut page, &site, u, Vector3::zeros());
    let (a, b) = (Vector3::from(corners[0]), Vector3::from(corners[1]));
    // a length away from a rounding boundary of the 2 decimals shown (hits are float32)
    let picked = ((design.abs() + 0.5) * 100.0).round() / 100.0 + 0.003;
    let end = a + (b - a).normalize() * (picked / 1000.0);
    press(&mut page, "overlap", "measure-overlap", phone);
    wait(&mut page, "window.__sv.measure !== null", "overlap mode");
    pick_corners(&mut page, &[corners[0], [end.x, end.y, end.z]], phone);
    wait(
        &mut page,
        &format!(
            "document.getElementById('message').textContent.includes('{design:.2} mm design')"
        ),
        "the overlap check",
    );
    let shown = eval(&mut page, "document.getElementById('message').textContent");
    assert!(
        shown
            .as_str()
            .unwrap()
            .contains(&format!("{picked:.2} mm measured")),
        "{shown}"
    );

    // the server goes away: offline in AR, Complete confirmed and queued
    s.stop();
    wait(&mut page, "document.body.dataset.connection === 'closed' && document.body.dataset.hud.includes('OFFLINE')", "offline shown in AR");
    wait(
        &mut page,
        "document.body.dataset.check === 'stale'",
        "the last check marked stale",
    );
    press(&mut page, "complete", "complete", phone);
    press(&mut page, "undo", "confirm", phone); // the confirm slot
    wait(
        &mut page,
        "document.body.dataset.queued === '1' && document.body.dataset.hud.includes('queued')",
        "a queued Complete",
    );
    assert_eq!(eval(&mut page, "document.body.dataset.xr"), "on");

    // back on the same port and state file: still in AR, the Complete applied once
    s.restart();
    wait(&mut page, "document.body.dataset.connection === 'ready' && document.body.dataset.queued === '0' && document.body.dataset.progress === '1/36'", "the queued Complete applied");
    page.pump(Duration::from_millis(800)).unwrap();
    let frames = eval(&mut page, "window.__sv.xrFrames").as_u64().unwrap();
    page.pump(Duration::from_millis(500)).unwrap();
    assert!(
        eval(&mut page, "window.__sv.xrFrames").as_u64().unwrap() > frames,
        "the XR loop stopped"
    );
    assert_eq!(eval(&mut page, "document.body.dataset.xr"), "on");
    assert_eq!(
        eval(&mut page, "window.__sv.view === window.__viewBefore"),
        true,
        "view rebuilt"
    );
    let done = s.completed();
    assert_eq!(done.len(), 1, "{done:?}");
    assert_eq!(done[0].0, next);
    let (fraction, _, _) = drawn(&mut page);
    assert!(fraction > 0.02, "blank after the reconnect: {fraction}");
    let errors: Vec<&String> = page
        .errors()
        .iter()
        .filter(|e| !e.contains("ERR_CONNECTION_REFUSED") && !e.contains("WebSocket"))
        .collect();
    assert!(errors.is_empty(), "page errors: {errors:?}");
    s.stop();
}

#[test]
fn headset_ar_measures_survives_a_restart_and_applies_a_queued_complete_once() {
    scenario(false);
}

#[test]
fn phone_ar_measures_by_tap_survives_a_restart_and_applies_a_queued_complete_once() {
    scenario(true);
}
