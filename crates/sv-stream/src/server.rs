//! The websocket server: a small HTTP handler for the page, `/ws` upgraded with
//! tokio-tungstenite, one task pair per connection, a bounded send queue per client.

use std::collections::{BTreeMap, HashMap};
use std::io;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, RwLock};
use std::task::{Context, Poll};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use futures_util::{SinkExt, StreamExt};
use sv_geom::Isometry3;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{mpsc, watch, Notify, Semaphore};
use tokio_rustls::TlsAcceptor;
use tokio_tungstenite::tungstenite::handshake::server::{ErrorResponse, Request, Response};
use tokio_tungstenite::tungstenite::http::{HeaderValue, StatusCode};
use tokio_tungstenite::tungstenite::protocol::frame::coding::CloseCode;
use tokio_tungstenite::tungstenite::protocol::{CloseFrame, WebSocketConfig};
use tokio_tungstenite::tungstenite::{Message, Utf8Bytes};

use crate::geometry::{self, compare, iso_of, kabsch, pose_of, tile_pose, transform_of};
use crate::protocol::*;
use crate::store::{Fnv, Measurement, MeasurementWriter, Store};
use crate::{ServeConfig, StreamError};

/// Messages queued per client before it counts as too slow and is disconnected.
pub const CLIENT_QUEUE: usize = 1024;
/// Bytes queued per client before it counts as too slow and is disconnected.
pub const CLIENT_QUEUE_BYTES: usize = 4 * 1024 * 1024;
/// Most events replayed on reconnect; a client further behind gets a snapshot.
const MAX_REPLAY: u64 = 10_000;
/// Largest HTTP request head.
const MAX_HTTP_HEAD: usize = 16 * 1024;

enum Out {
    Text(Utf8Bytes),
    Close(u16, String),
}

/// The sending side of one client's bounded queue: at most [`CLIENT_QUEUE`] messages and
/// [`CLIENT_QUEUE_BYTES`] bytes wait for the socket; beyond either the client is dropped.
#[derive(Clone)]
struct Outbox {
    tx: mpsc::Sender<Out>,
    queued_bytes: Arc<AtomicUsize>,
    kick: Arc<Notify>,
}

impl Outbox {
    /// Queue a text message; a full queue kicks the client (never blocks).
    fn push(&self, text: Utf8Bytes) {
        let len = text.len();
        let before = self.queued_bytes.fetch_add(len, Ordering::AcqRel);
        if before + len > CLIENT_QUEUE_BYTES || self.tx.try_send(Out::Text(text)).is_err() {
            self.queued_bytes.fetch_sub(len, Ordering::AcqRel);
            self.kick.notify_one();
        }
    }

    /// Queue a close frame (best effort).
    fn close(&self, code: u16, reason: &str) {
        let _ = self.tx.try_send(Out::Close(code, reason.into()));
    }
}

/// Mutable shared state, behind one lock so events are numbered, stored and broadcast in order.
struct State {
    epoch: String,
    seq: u64,
    events: Vec<Event>,
    done: Vec<bool>,
    completed: Vec<usize>,
    ops: HashMap<String, usize>,
    claims: HashMap<usize, String>,
    registration: Option<geometry::Fit>,
    clients: HashMap<u64, Outbox>,
    store: Store,
}

/// Immutable frame data plus the shared state.
struct Hub {
    ids: Vec<String>,
    strips: Vec<Option<String>>,
    corners: Vec<[[[f64; 3]; 4]; 2]>,
    poses: Vec<[Isometry3; 2]>,
    index: HashMap<String, usize>,
    overlaps: HashMap<(usize, usize), f64>,
    sequence: Vec<usize>,
    config: ServeConfig,
    registration: RwLock<Option<Isometry3>>,
    state: Mutex<State>,
    measurements: Mutex<MeasurementWriter>,
    dropped_measurements: AtomicU64,
    next_conn: AtomicU64,
    shutdown: watch::Receiver<bool>,
}

fn now_ms() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as u64)
        .unwrap_or(0)
}

/// Constant-time comparison (time depends on the lengths only).
fn ct_eq(a: &[u8], b: &[u8]) -> bool {
    let mut diff = (a.len() ^ b.len()) as u64;
    for i in 0..a.len().max(b.len()) {
        let x = a.get(i).copied().unwrap_or(0);
        let y = b.get(i).copied().unwrap_or(0xff);
        diff |= u64::from(x ^ y);
    }
    diff == 0
}

fn valid_id(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= MAX_ID_LEN
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.:".contains(c))
}

impl State {
    fn apply(&mut self, event: &Event, index: &HashMap<String, usize>) {
        match event {
            Event::Progress { unit, op_id, .. } => {
                if let Some(&u) = index.get(unit) {
                    if !self.done[u] {
                        self.done[u] = true;
                        self.completed.push(u);
                    }
                    self.ops.insert(op_id.clone(), u);
                    self.claims.remove(&u);
                }
            }
            Event::Claimed { unit, by, .. } => {
                if let Some(&u) = index.get(unit) {
                    self.claims.insert(u, by.clone());
                }
            }
            Event::Released { unit, .. } => {
                if let Some(&u) = index.get(unit) {
                    self.claims.remove(&u);
                }
            }
            Event::Registration { .. } => {}
        }
        self.seq = event.seq();
        self.events.push(event.clone());
    }

    /// Store, apply and broadcast an event built for the next `seq`.
    fn commit(
        &mut self,
        hub: &Hub,
        build: impl FnOnce(u64, &State) -> Event,
    ) -> Result<u64, (ErrorCode, String)> {
        let seq = self.seq + 1;
        let mut event = build(seq, self);
        // a completion reports the state after it: count and next unit
        if let Event::Progress {
            unit, done, next, ..
        } = &mut event
        {
            let u = hub.index.get(unit.as_str()).copied();
            *done = self.completed.len() + usize::from(u.is_some_and(|u| !self.done[u]));
            *next = hub
                .sequence
                .iter()
                .find(|&&v| !self.done[v] && Some(v) != u)
                .map(|&v| hub.ids[v].clone());
        }
        let json = to_text(&event);
        self.store
            .append(&event, &json)
            .map_err(|e| (ErrorCode::Internal, e.to_string()))?;
        self.apply(&event, &hub.index);
        let text = Utf8Bytes::from(json);
        for outbox in self.clients.values() {
            outbox.push(text.clone());
        }
        Ok(seq)
    }

    fn snapshot(&self, hub: &Hub) -> Snapshot {
        Snapshot {
            completed: self.completed.iter().map(|&u| hub.ids[u].clone()).collect(),
            claims: self
                .claims
                .iter()
                .map(|(&u, c)| (hub.ids[u].clone(), c.clone()))
                .collect::<BTreeMap<_, _>>(),
            done: self.completed.len(),
            total: hub.ids.len(),
            next: hub.next_unit(self),
            registration: self.registration.as_ref().map(|f| f.transform()),
        }
    }
}

impl Hub {
    fn new(config: ServeConfig, shutdown: watch::Receiver<bool>) -> Result<Hub, StreamError> {
        let frame = &config.frame;
        if frame.units.is_empty() {
            return Err(StreamError::Frame("no units".into()));
        }
        let ids = geometry::unit_ids(frame);
        let mut index = HashMap::new();
        let mut poses = Vec::new();
        for (i, u) in frame.units.iter().enumerate() {
            let id = &ids[i];
            if index.insert(id.clone(), i).is_some() {
                return Err(StreamError::Frame(format!("duplicate unit id {id:?}")));
            }
            let finite = u
                .hub
                .iter()
                .chain(&u.primary)
                .flatten()
                .all(|v| v.is_finite());
            let (true, Some(h), Some(p)) = (finite, tile_pose(&u.hub), tile_pose(&u.primary))
            else {
                return Err(StreamError::Frame(format!(
                    "unit {id} (index {i}) has a degenerate tile"
                )));
            };
            poses.push([h, p]);
        }
        let mut overlaps = HashMap::new();
        for l in &frame.links {
            let [a, b] = l.units;
            if a >= frame.units.len() || b >= frame.units.len() {
                return Err(StreamError::Frame(format!("link {a}-{b} out of range")));
            }
            overlaps.insert((a.min(b), a.max(b)), l.hub_overlap);
        }
        let mut hash = Fnv::default();
        hash.write(serde_json::to_string(frame).unwrap_or_default().as_bytes());
        let frame_hash = format!("{:016x}", hash.0);
        let (store, loaded) = Store::open(config.state_path.as_deref(), &frame_hash)?;
        let n = frame.units.len();
        let mut state = State {
            epoch: loaded.epoch,
            seq: 0,
            events: Vec::new(),
            done: vec![false; n],
            completed: Vec::new(),
            ops: HashMap::new(),
            claims: HashMap::new(),
            registration: None,
            clients: HashMap::new(),
            store,
        };
        let mut reg = None;
        for ev in &loaded.events {
            if let Event::Registration { transform, .. } = ev {
                let iso = iso_of(&Pose {
                    position: transform.translation,
                    rotation: transform.rotation,
                });
                reg = iso.map(|iso| geometry::Fit {
                    iso,
                    rms: transform.rms_mm,
                    residuals: Vec::new(),
                });
            }
            state.apply(ev, &index);
        }
        state.registration = reg.clone();
        let measurements = MeasurementWriter::start(config.state_path.as_deref())?;
        Ok(Hub {
            strips: geometry::unit_strips(frame),
            ids,
            corners: frame.units.iter().map(|u| [u.hub, u.primary]).collect(),
            poses,
            index,
            overlaps,
            sequence: geometry::assembly_sequence(frame),
            registration: RwLock::new(reg.map(|f| f.iso)),
            state: Mutex::new(state),
            measurements: Mutex::new(measurements),
            dropped_measurements: AtomicU64::new(0),
            next_conn: AtomicU64::new(1),
            shutdown,
            config,
        })
    }

    fn next_unit(&self, state: &State) -> Option<String> {
        self.sequence
            .iter()
            .find(|&&u| !state.done[u])
            .map(|&u| self.ids[u].clone())
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn site(&self) -> Option<Isometry3> {
        *self.registration.read().unwrap_or_else(|p| p.into_inner())
    }

    fn welcome(&self) -> ServerMessage {
        let st = self.lock();
        ServerMessage::Welcome {
            protocol: PROTOCOL_VERSION,
            epoch: st.epoch.clone(),
            seq: st.seq,
            heartbeat_ms: self.config.heartbeat.as_millis() as u64,
            frame: FrameInfo {
                units: self.ids.len(),
                length_unit: "mm".into(),
                up: "+Z".into(),
                quaternion: "xyzw".into(),
            },
            tolerance: self.config.tolerance,
        }
    }

    fn record(&self, client_id: &str, kind: &'static str, unit: &str, json: String) {
        let m = Measurement {
            t_ms: now_ms(),
            client_id: client_id.into(),
            kind,
            unit: unit.into(),
            json,
        };
        let guard = self.measurements.lock().unwrap_or_else(|p| p.into_inner());
        if self.config.state_path.is_some() && !guard.push(m) {
            self.dropped_measurements.fetch_add(1, Ordering::Relaxed);
        }
    }

    fn unit(&self, id: &str) -> Result<usize, (ErrorCode, String)> {
        self.index.get(id).copied().ok_or_else(|| {
            let shown: String = id.chars().take(40).collect();
            (ErrorCode::UnknownUnit, format!("no unit {shown:?}"))
        })
    }

    fn targets(&self, frame: CoordFrame) -> ServerMessage {
        let site = match frame {
            CoordFrame::Site => self.site(),
            CoordFrame::Model => None,
        };
        let map_pt = |p: &[f64; 3]| -> [f64; 3] {
            match site {
                Some(t) => {
                    let q = t * sv_geom::Point3::new(p[0], p[1], p[2]);
                    [q.x, q.y, q.z]
                }
                None => *p,
            }
        };
        let map_pose = |iso: &Isometry3| match site {
            Some(t) => pose_of(&(t * iso)),
            None => pose_of(iso),
        };
        let units = (0..self.ids.len())
            .map(|u| Target {
                id: self.ids[u].clone(),
                strip: self.strips[u].clone(),
                hub_pose: map_pose(&self.poses[u][0]),
                primary_pose: map_pose(&self.poses[u][1]),
                hub: self.corners[u][0].map(|p| map_pt(&p)),
                primary: self.corners[u][1].map(|p| map_pt(&p)),
            })
            .collect();
        ServerMessage::Targets {
            frame,
            registered: self.site().is_some(),
            units,
        }
    }

    /// Check one `track` message (anything else is ignored) against its target.
    fn check(
        &self,
        client_id: &str,
        msg: ClientMessage,
        coalesced: u64,
    ) -> Result<Option<ServerMessage>, (ErrorCode, String)> {
        let ClientMessage::Track {
            unit,
            part,
            pose,
            source,
            frame,
            reference,
        } = msg
        else {
            return Ok(None);
        };
        let (unit, pose) = (unit.as_str(), &pose);
        let u = self.unit(unit)?;
        let tracked = iso_of(pose).ok_or((
            ErrorCode::BadMessage,
            "pose must be finite with a non-zero quaternion".to_string(),
        ))?;
        let model = self.poses[u][match part {
            Part::Hub => 0,
            Part::Primary => 1,
        }];
        let target = match (frame, self.site()) {
            (CoordFrame::Site, Some(t)) => t * model,
            _ => model,
        };
        let (position_error_mm, angle_error_deg, move_mm) = compare(&target, &tracked);
        let tol = &self.config.tolerance;
        let ok = position_error_mm <= tol.position_mm && angle_error_deg <= tol.angle_deg;
        let msg = ServerMessage::Check {
            unit: unit.to_string(),
            part,
            ok,
            position_error_mm,
            angle_error_deg,
            move_mm,
            frame,
            coalesced,
            reference,
        };
        if self.config.state_path.is_some() {
            let json = serde_json::json!({
                "part": part, "pose": pose, "source": source, "frame": frame, "ok": ok,
                "position_error_mm": position_error_mm, "angle_error_deg": angle_error_deg,
            });
            self.record(client_id, "track", unit, json.to_string());
        }
        Ok(Some(msg))
    }
}

/// Per-connection session after `hello`.
struct Session {
    role: Role,
    client_id: String,
}

/// Token bucket with coalescing of excess tracks (latest per unit and part wins).
struct Limiter {
    tokens: f64,
    last: Instant,
    rate: f64,
    burst: f64,
    /// Waiting tracks: key, the latest message, how many earlier ones it replaced.
    pending: Vec<((usize, Part), ClientMessage, u64)>,
}

impl Limiter {
    fn refill(&mut self) {
        let now = Instant::now();
        self.tokens =
            (self.tokens + now.duration_since(self.last).as_secs_f64() * self.rate).min(self.burst);
        self.last = now;
    }
    fn take(&mut self) -> bool {
        self.refill();
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
    fn next_ready(&self) -> Instant {
        let wait = ((1.0 - self.tokens).max(0.0) / self.rate).min(1.0);
        self.last + Duration::from_secs_f64(wait)
    }
}

enum Flow {
    Continue,
    Close,
}

struct Conn {
    hub: Arc<Hub>,
    id: u64,
    out: Outbox,
    session: Option<Session>,
    limiter: Limiter,
}

impl Conn {
    fn send(&self, msg: &ServerMessage) {
        self.out.push(to_text(msg).into());
    }

    fn error(&self, (code, message): (ErrorCode, String)) {
        self.send(&ServerMessage::Error { code, message });
    }

    fn on_text(&mut self, text: &str) -> Flow {
        let msg = match parse_client(text) {
            Ok(m) => m,
            Err(e) => {
                self.error(e);
                return Flow::Continue;
            }
        };
        let Some(session) = &self.session else {
            return match msg {
                ClientMessage::Hello {
                    token,
                    client_id,
                    last,
                } => self.hello(&token, client_id, last),
                _ => {
                    self.error((ErrorCode::NotReady, "send hello first".into()));
                    Flow::Continue
                }
            };
        };
        let operator = session.role == Role::Operator;
        let client_id = session.client_id.clone();
        let result = match msg {
            ClientMessage::Hello { .. } => Err((ErrorCode::NotReady, "hello sent twice".into())),
            ClientMessage::GetTargets { frame } => {
                self.send(&self.hub.targets(frame));
                Ok(())
            }
            ClientMessage::Ping { t } => {
                self.send(&ServerMessage::Pong {
                    t,
                    server_ms: now_ms(),
                });
                Ok(())
            }
            _ if !operator => Err((
                ErrorCode::Forbidden,
                "viewers may only get_targets and ping".into(),
            )),
            ClientMessage::Track { ref unit, part, .. } => match self.hub.unit(unit) {
                Ok(u) => {
                    if self.limiter.pending.is_empty() && self.limiter.take() {
                        self.track(&client_id, msg, 0);
                    } else if let Some(slot) = self
                        .limiter
                        .pending
                        .iter_mut()
                        .find(|(k, _, _)| *k == (u, part))
                    {
                        slot.1 = msg;
                        slot.2 += 1;
                    } else {
                        self.limiter.pending.push(((u, part), msg, 0));
                    }
                    Ok(())
                }
                Err(e) => Err(e),
            },
            ClientMessage::Overlap { units, measured_mm } => {
                self.overlap(&client_id, units, measured_mm)
            }
            ClientMessage::Claim { unit } => self.claim(&client_id, &unit, true),
            ClientMessage::Release { unit } => self.claim(&client_id, &unit, false),
            ClientMessage::Complete { unit, op_id } => self.complete(&client_id, &unit, op_id),
            ClientMessage::Register { points } => self.register(&client_id, &points),
        };
        if let Err(e) = result {
            self.error(e);
        }
        Flow::Continue
    }

    fn track(&self, client_id: &str, msg: ClientMessage, coalesced: u64) {
        {
            match self.hub.check(client_id, msg, coalesced) {
                Ok(Some(m)) => self.send(&m),
                Ok(None) => {}
                Err(e) => self.error(e),
            }
        }
    }

    fn flush_pending(&mut self) {
        let client_id = match &self.session {
            Some(s) => s.client_id.clone(),
            None => return,
        };
        while !self.limiter.pending.is_empty() && self.limiter.take() {
            let (_, msg, coalesced) = self.limiter.pending.remove(0);
            self.track(&client_id, msg, coalesced);
        }
    }

    fn hello(&mut self, token: &str, client_id: Option<String>, last: Option<Cursor>) -> Flow {
        let cfg = &self.hub.config;
        let role = if cfg
            .token
            .as_deref()
            .is_some_and(|t| ct_eq(t.as_bytes(), token.as_bytes()))
        {
            Some(Role::Operator)
        } else if cfg
            .viewer_token
            .as_deref()
            .is_some_and(|t| ct_eq(t.as_bytes(), token.as_bytes()))
        {
            Some(Role::Viewer)
        } else if cfg.token.is_none() {
            Some(Role::Operator)
        } else {
            None
        };
        let Some(role) = role else {
            self.error((ErrorCode::Unauthorized, "bad token".into()));
            self.out.close(CLOSE_UNAUTHORIZED, "unauthorized");
            return Flow::Close;
        };
        let client_id = match client_id {
            Some(c) if valid_id(&c) => c,
            Some(_) => {
                self.error((
                    ErrorCode::BadMessage,
                    format!("client_id must be 1..={MAX_ID_LEN} of [A-Za-z0-9-_.:]"),
                ));
                return Flow::Continue;
            }
            None => format!("anon-{}", self.id),
        };
        let hub = self.hub.clone();
        let mut st = hub.lock();
        let replay =
            last.filter(|c| c.epoch == st.epoch && c.seq <= st.seq && st.seq - c.seq <= MAX_REPLAY);
        let (mode, events, snapshot) = match replay {
            Some(c) => ("replay", Some(st.events[c.seq as usize..].to_vec()), None),
            None => ("snapshot", None, Some(st.snapshot(&hub))),
        };
        let ready = ServerMessage::Ready {
            role,
            client_id: client_id.clone(),
            epoch: st.epoch.clone(),
            seq: st.seq,
            mode: mode.into(),
            events,
            snapshot,
        };
        self.send(&ready);
        st.clients.insert(self.id, self.out.clone());
        drop(st);
        self.session = Some(Session { role, client_id });
        Flow::Continue
    }

    fn overlap(
        &self,
        client_id: &str,
        units: [String; 2],
        measured_mm: f64,
    ) -> Result<(), (ErrorCode, String)> {
        let a = self.hub.unit(&units[0])?;
        let b = self.hub.unit(&units[1])?;
        if !measured_mm.is_finite() {
            return Err((ErrorCode::BadMessage, "measured_mm must be finite".into()));
        }
        let design_mm = *self.hub.overlaps.get(&(a.min(b), a.max(b))).ok_or((
            ErrorCode::NotLinked,
            format!("{} and {} share no link", units[0], units[1]),
        ))?;
        let error_mm = measured_mm - design_mm;
        let ok = error_mm.abs() <= self.hub.config.tolerance.overlap_mm;
        let msg = ServerMessage::OverlapCheck {
            units,
            design_mm,
            measured_mm,
            error_mm,
            ok,
        };
        let text = to_text(&msg);
        if let ServerMessage::OverlapCheck { units, .. } = &msg {
            self.hub.record(
                client_id,
                "overlap",
                &format!("{}+{}", units[0], units[1]),
                text,
            );
        }
        self.send(&msg);
        Ok(())
    }

    fn claim(&self, client_id: &str, unit: &str, take: bool) -> Result<(), (ErrorCode, String)> {
        let u = self.hub.unit(unit)?;
        let hub = &*self.hub;
        let mut st = hub.lock();
        if st.done[u] {
            return Err((
                ErrorCode::AlreadyDone,
                format!("{unit} is already complete"),
            ));
        }
        let holder = st.claims.get(&u).cloned();
        let (applied, seq) = match (take, holder) {
            (true, Some(h)) if h == client_id => (false, st.seq),
            (true, Some(h)) => {
                return Err((ErrorCode::Claimed, format!("{unit} is claimed by {h}")))
            }
            (true, None) => {
                let seq = st.commit(hub, |seq, _| Event::Claimed {
                    seq,
                    unit: unit.into(),
                    by: client_id.into(),
                })?;
                (true, seq)
            }
            (false, Some(h)) if h == client_id => {
                let seq = st.commit(hub, |seq, _| Event::Released {
                    seq,
                    unit: unit.into(),
                    by: client_id.into(),
                })?;
                (true, seq)
            }
            (false, _) => {
                return Err((
                    ErrorCode::NotClaimed,
                    format!("{unit} is not claimed by you"),
                ))
            }
        };
        self.send(&ServerMessage::Ack {
            op: if take { "claim" } else { "release" }.into(),
            unit: unit.into(),
            applied,
            seq,
            op_id: None,
        });
        Ok(())
    }

    fn complete(
        &self,
        client_id: &str,
        unit: &str,
        op_id: String,
    ) -> Result<(), (ErrorCode, String)> {
        let u = self.hub.unit(unit)?;
        if !valid_id(&op_id) {
            return Err((
                ErrorCode::BadMessage,
                format!("op_id must be 1..={MAX_ID_LEN} of [A-Za-z0-9-_.:]"),
            ));
        }
        let hub = &*self.hub;
        let mut st = hub.lock();
        let (applied, seq) = match st.ops.get(&op_id) {
            Some(&done) if done == u => (false, st.seq),
            Some(&other) => {
                return Err((
                    ErrorCode::BadMessage,
                    format!("op_id already used for {}", hub.ids[other]),
                ))
            }
            None if st.done[u] => {
                return Err((
                    ErrorCode::AlreadyDone,
                    format!("{unit} is already complete"),
                ))
            }
            None => {
                if let Some(h) = st.claims.get(&u) {
                    if h != client_id {
                        return Err((ErrorCode::Claimed, format!("{unit} is claimed by {h}")));
                    }
                }
                let total = hub.ids.len();
                let seq = st.commit(hub, |seq, _| Event::Progress {
                    seq,
                    unit: unit.into(),
                    by: client_id.into(),
                    op_id: op_id.clone(),
                    done: 0,
                    total,
                    next: None,
                })?;
                (true, seq)
            }
        };
        self.send(&ServerMessage::Ack {
            op: "complete".into(),
            unit: unit.into(),
            applied,
            seq,
            op_id: Some(op_id),
        });
        Ok(())
    }

    fn register(
        &self,
        client_id: &str,
        points: &[[[f64; 3]; 2]],
    ) -> Result<(), (ErrorCode, String)> {
        if points.len() > MAX_REGISTER_POINTS {
            return Err((
                ErrorCode::BadMessage,
                format!("more than {MAX_REGISTER_POINTS} points"),
            ));
        }
        let fit = kabsch(points, geometry::DEFAULT_COLLINEAR_RATIO).map_err(|e| match e {
            geometry::FitError::Degenerate(m) => (ErrorCode::Degenerate, m),
        })?;
        let ok = fit.rms <= self.hub.config.tolerance.position_mm;
        self.send(&ServerMessage::Fit {
            ok,
            transform: fit.transform(),
            residuals_mm: fit.residuals.clone(),
        });
        if ok {
            let hub = &*self.hub;
            let mut st = hub.lock();
            let transform = transform_of(&fit.iso, fit.rms);
            st.commit(hub, |seq, _| Event::Registration {
                seq,
                transform,
                by: client_id.into(),
            })?;
            *hub.registration.write().unwrap_or_else(|p| p.into_inner()) = Some(fit.iso);
            st.registration = Some(fit);
        }
        Ok(())
    }
}

/// Serve one upgraded websocket.
async fn run_ws<S>(hub: Arc<Hub>, ws: tokio_tungstenite::WebSocketStream<S>)
where
    S: AsyncRead + AsyncWrite + Unpin + Send + 'static,
{
    let (mut sink, mut stream) = ws.split();
    let (tx, mut rx) = mpsc::channel::<Out>(CLIENT_QUEUE);
    let queued_bytes = Arc::new(AtomicUsize::new(0));
    let written = queued_bytes.clone();
    let heartbeat = hub.config.heartbeat;
    let writer = tokio::spawn(async move {
        let mut ping = tokio::time::interval(heartbeat);
        ping.tick().await;
        loop {
            tokio::select! {
                out = rx.recv() => match out {
                    Some(Out::Text(t)) => {
                        let len = t.len();
                        let sent = sink.send(Message::Text(t)).await;
                        written.fetch_sub(len, Ordering::AcqRel);
                        if sent.is_err() { break; }
                    }
                    Some(Out::Close(code, reason)) => {
                        let frame = CloseFrame { code: CloseCode::from(code), reason: reason.into() };
                        let _ = sink.send(Message::Close(Some(frame))).await;
                        break;
                    }
                    None => break,
                },
                _ = ping.tick() => {
                    if sink.send(Message::Ping(Default::default())).await.is_err() { break; }
                }
            }
        }
        let _ = tokio::time::timeout(Duration::from_secs(1), sink.close()).await;
    });
    let id = hub.next_conn.fetch_add(1, Ordering::Relaxed);
    let rate = hub.config.rate;
    let mut conn = Conn {
        hub: hub.clone(),
        id,
        out: Outbox {
            tx,
            queued_bytes: queued_bytes.clone(),
            kick: Arc::new(Notify::new()),
        },
        session: None,
        limiter: Limiter {
            tokens: rate.burst,
            last: Instant::now(),
            rate: rate.per_second.max(0.001),
            burst: rate.burst.max(1.0),
            pending: Vec::new(),
        },
    };
    conn.send(&hub.welcome());
    let hello_deadline = tokio::time::sleep(hub.config.hello_timeout);
    tokio::pin!(hello_deadline);
    let mut shutdown = hub.shutdown.clone();
    let silence = heartbeat * 3;
    let kick = conn.out.kick.clone();
    let mut kicked = false;
    loop {
        let pending_at = conn.limiter.next_ready();
        let has_pending = !conn.limiter.pending.is_empty();
        tokio::select! {
            _ = kick.notified() => { kicked = true; break; }
            _ = shutdown.changed() => {
                conn.out.close(1001, "server shutting down");
                break;
            }
            _ = &mut hello_deadline, if conn.session.is_none() => {
                conn.out.close(CLOSE_HELLO_TIMEOUT, "no hello");
                break;
            }
            _ = tokio::time::sleep_until(pending_at.into()), if has_pending => conn.flush_pending(),
            next = tokio::time::timeout(silence, stream.next()) => match next {
                Err(_) | Ok(None) => break,
                Ok(Some(Err(tokio_tungstenite::tungstenite::Error::Capacity(_)))) => {
                    conn.out.close(1009, "message too big");
                    break;
                }
                Ok(Some(Err(_))) => break,
                Ok(Some(Ok(Message::Text(t)))) => {
                    if let Flow::Close = conn.on_text(t.as_str()) { break; }
                }
                Ok(Some(Ok(Message::Binary(_)))) => conn.error((ErrorCode::BadMessage, "binary frames are not supported".into())),
                Ok(Some(Ok(Message::Close(_)))) => break,
                Ok(Some(Ok(_))) => {}
            }
        }
    }
    hub.lock().clients.remove(&id);
    let Conn { out, .. } = conn;
    if kicked {
        writer.abort();
    } else {
        drop(out);
        let abort = writer.abort_handle();
        if tokio::time::timeout(Duration::from_secs(2), writer)
            .await
            .is_err()
        {
            abort.abort();
        }
    }
}

/// A stream with some already-read bytes put back in front.
struct Rewind<S> {
    prefix: Vec<u8>,
    pos: usize,
    inner: S,
}

impl<S: AsyncRead + Unpin> AsyncRead for Rewind<S> {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        if this.pos < this.prefix.len() {
            let n = buf.remaining().min(this.prefix.len() - this.pos);
            buf.put_slice(&this.prefix[this.pos..this.pos + n]);
            this.pos += n;
            return Poll::Ready(Ok(()));
        }
        Pin::new(&mut this.inner).poll_read(cx, buf)
    }
}

impl<S: AsyncWrite + Unpin> AsyncWrite for Rewind<S> {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.get_mut().inner).poll_write(cx, buf)
    }
    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_flush(cx)
    }
    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_shutdown(cx)
    }
}

/// The page, embedded.
fn static_file(path: &str) -> Option<(&'static str, &'static [u8])> {
    const JS: &str = "text/javascript; charset=utf-8";
    Some(match path {
        "/" | "/index.html" => (
            "text/html; charset=utf-8",
            include_bytes!("../client/index.html"),
        ),
        "/app.js" => (JS, include_bytes!("../client/app.js")),
        "/viewer.js" => (JS, sv_viewer::VIEWER_JS.as_bytes()),
        "/style.css" => (
            "text/css; charset=utf-8",
            include_bytes!("../client/style.css"),
        ),
        "/vendor/three.module.js" => (JS, sv_viewer::THREE_JS.as_bytes()),
        "/vendor/OrbitControls.js" => (JS, sv_viewer::ORBIT_CONTROLS_JS.as_bytes()),
        "/vendor/LICENSE-three.txt" => (
            "text/plain; charset=utf-8",
            sv_viewer::THREE_LICENSE.as_bytes(),
        ),
        _ => return None,
    })
}

async fn http_reply<S: AsyncWrite + Unpin>(
    stream: &mut S,
    status: &str,
    ctype: &str,
    body: &[u8],
    head_only: bool,
) {
    let head = format!(
        "HTTP/1.1 {status}\r\nContent-Type: {ctype}\r\nContent-Length: {}\r\nCache-Control: no-cache\r\n\
         X-Content-Type-Options: nosniff\r\nReferrer-Policy: no-referrer\r\n\
         Content-Security-Policy: default-src 'self'; connect-src 'self' ws: wss:; img-src 'self' data: blob:\r\n\
         Connection: close\r\n\r\n",
        body.len()
    );
    let _ = stream.write_all(head.as_bytes()).await;
    if !head_only {
        let _ = stream.write_all(body).await;
    }
    let _ = stream.shutdown().await;
}

/// Read the request head, answer static files, upgrade `/ws`.
// the handshake callback's error type is fixed by tungstenite
#[allow(clippy::result_large_err)]
async fn handle_stream<S>(hub: Arc<Hub>, mut stream: S)
where
    S: AsyncRead + AsyncWrite + Unpin + Send + 'static,
{
    let mut buf = Vec::with_capacity(1024);
    let read_head = async {
        let mut chunk = [0u8; 2048];
        loop {
            if buf.windows(4).any(|w| w == b"\r\n\r\n") {
                return true;
            }
            if buf.len() > MAX_HTTP_HEAD {
                return false;
            }
            match stream.read(&mut chunk).await {
                Ok(0) | Err(_) => return false,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
            }
        }
    };
    match tokio::time::timeout(Duration::from_secs(10), read_head).await {
        Ok(true) => {}
        _ => return,
    }
    let line_end = buf.iter().position(|&b| b == b'\r').unwrap_or(0);
    let line = String::from_utf8_lossy(&buf[..line_end]).to_string();
    let mut parts = line.split(' ');
    let (method, target) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""));
    let path = target.split(['?', '#']).next().unwrap_or("");
    if path == "/ws" && method == "GET" {
        let rewind = Rewind {
            prefix: buf,
            pos: 0,
            inner: stream,
        };
        let callback = |req: &Request, mut resp: Response| -> Result<Response, ErrorResponse> {
            let offered = req
                .headers()
                .get_all("sec-websocket-protocol")
                .iter()
                .filter_map(|v| v.to_str().ok())
                .flat_map(|v| v.split(','))
                .any(|p| p.trim() == SUBPROTOCOL);
            if !offered {
                let mut err =
                    ErrorResponse::new(Some(format!("subprotocol {SUBPROTOCOL} required")));
                *err.status_mut() = StatusCode::BAD_REQUEST;
                return Err(err);
            }
            resp.headers_mut().insert(
                "sec-websocket-protocol",
                HeaderValue::from_static(SUBPROTOCOL),
            );
            Ok(resp)
        };
        let mut config = WebSocketConfig::default();
        config.max_message_size = Some(MAX_TRANSPORT_BYTES);
        config.max_frame_size = Some(MAX_TRANSPORT_BYTES);
        config.write_buffer_size = 64 * 1024;
        config.max_write_buffer_size = 1024 * 1024;
        let accept =
            tokio_tungstenite::accept_hdr_async_with_config(rewind, callback, Some(config));
        if let Ok(Ok(ws)) = tokio::time::timeout(Duration::from_secs(10), accept).await {
            run_ws(hub, ws).await;
        }
        return;
    }
    let head_only = method == "HEAD";
    if method != "GET" && !head_only {
        http_reply(
            &mut stream,
            "405 Method Not Allowed",
            "text/plain",
            b"method not allowed\n",
            false,
        )
        .await;
        return;
    }
    match static_file(path) {
        Some((ctype, body)) => http_reply(&mut stream, "200 OK", ctype, body, head_only).await,
        None => {
            http_reply(
                &mut stream,
                "404 Not Found",
                "text/plain",
                b"not found\n",
                head_only,
            )
            .await
        }
    }
}

fn tls_acceptor(cert: &std::path::Path, key: &std::path::Path) -> Result<TlsAcceptor, StreamError> {
    use tokio_rustls::rustls;
    let tls = |e: &dyn std::fmt::Display| StreamError::Tls(e.to_string());
    let open = |p: &std::path::Path| {
        std::fs::File::open(p).map_err(|e| StreamError::Tls(format!("{}: {e}", p.display())))
    };
    let mut cert_reader = io::BufReader::new(open(cert)?);
    let certs = rustls_pemfile::certs(&mut cert_reader)
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| tls(&e))?;
    if certs.is_empty() {
        return Err(StreamError::Tls(format!(
            "no certificate in {}",
            cert.display()
        )));
    }
    let mut key_reader = io::BufReader::new(open(key)?);
    let key = rustls_pemfile::private_key(&mut key_reader)
        .map_err(|e| tls(&e))?
        .ok_or_else(|| StreamError::Tls(format!("no private key in {}", key.display())))?;
    let config = rustls::ServerConfig::builder_with_provider(Arc::new(
        rustls::crypto::ring::default_provider(),
    ))
    .with_safe_default_protocol_versions()
    .map_err(|e| tls(&e))?
    .with_no_client_auth()
    .with_single_cert(certs, key)
    .map_err(|e| tls(&e))?;
    Ok(TlsAcceptor::from(Arc::new(config)))
}

/// A running server.
pub struct Server {
    addr: SocketAddr,
    tls: bool,
    hub: Arc<Hub>,
    stop: watch::Sender<bool>,
    accept: tokio::task::JoinHandle<()>,
}

impl Server {
    /// Bind, open the state file and start accepting connections.
    pub async fn start(config: ServeConfig) -> Result<Server, StreamError> {
        let acceptor = match (&config.tls_cert, &config.tls_key) {
            (Some(c), Some(k)) => Some(tls_acceptor(c, k)?),
            (None, None) => None,
            _ => {
                return Err(StreamError::Config(
                    "--tls-cert and --tls-key go together".into(),
                ))
            }
        };
        let (stop, stop_rx) = watch::channel(false);
        let listener = TcpListener::bind(&config.bind)
            .await
            .map_err(|e| StreamError::Config(format!("cannot listen on {:?}: {e}", config.bind)))?;
        let addr = listener.local_addr()?;
        let limit = Arc::new(Semaphore::new(config.max_connections.max(1)));
        let hub = Arc::new(Hub::new(config, stop_rx.clone())?);
        let accept_hub = hub.clone();
        let tls = acceptor.is_some();
        let mut stop_accept = stop_rx;
        let accept = tokio::spawn(async move {
            loop {
                let (tcp, _peer): (TcpStream, SocketAddr) = tokio::select! {
                    _ = stop_accept.changed() => break,
                    r = listener.accept() => match r {
                        Ok(x) => x,
                        Err(_) => { tokio::time::sleep(Duration::from_millis(50)).await; continue; }
                    },
                };
                let Ok(permit) = limit.clone().try_acquire_owned() else {
                    continue; // too many connections: drop this one
                };
                let _ = tcp.set_nodelay(true);
                let hub = accept_hub.clone();
                let acceptor = acceptor.clone();
                tokio::spawn(async move {
                    match acceptor {
                        Some(a) => {
                            if let Ok(Ok(s)) =
                                tokio::time::timeout(Duration::from_secs(10), a.accept(tcp)).await
                            {
                                handle_stream(hub, s).await;
                            }
                        }
                        None => handle_stream(hub, tcp).await,
                    }
                    drop(permit);
                });
            }
        });
        Ok(Server {
            addr,
            tls,
            hub,
            stop,
            accept,
        })
    }

    /// The bound address.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// `http(s)://addr/`.
    pub fn url(&self) -> String {
        format!(
            "{}://{}/",
            if self.tls { "https" } else { "http" },
            self.addr
        )
    }

    /// Measurements not written because the writer queue was full.
    pub fn dropped_measurements(&self) -> u64 {
        self.hub.dropped_measurements.load(Ordering::Relaxed)
    }

    /// Close every connection, flush the state file and stop.
    pub async fn shutdown(self) {
        let _ = self.stop.send(true);
        let _ = self.accept.await;
        let deadline = Instant::now() + Duration::from_secs(3);
        while Arc::strong_count(&self.hub) > 1 && Instant::now() < deadline {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
        self.hub
            .measurements
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .stop();
    }
}

/// Serve until Ctrl-C or SIGTERM; `on_start` sees the running server first (to print its URL).
pub async fn serve(config: ServeConfig, on_start: impl FnOnce(&Server)) -> Result<(), StreamError> {
    let server = Server::start(config).await?;
    on_start(&server);
    stop_signal().await?;
    server.shutdown().await;
    Ok(())
}

#[cfg(unix)]
async fn stop_signal() -> Result<(), StreamError> {
    let mut term = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate())?;
    tokio::select! {
        r = tokio::signal::ctrl_c() => r?,
        _ = term.recv() => {}
    }
    Ok(())
}

#[cfg(not(unix))]
async fn stop_signal() -> Result<(), StreamError> {
    tokio::signal::ctrl_c().await?;
    Ok(())
}

/// [`serve`] on a new multi-threaded runtime.
pub fn serve_blocking(
    config: ServeConfig,
    on_start: impl FnOnce(&Server),
) -> Result<(), StreamError> {
    tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?
        .block_on(serve(config, on_start))
}
