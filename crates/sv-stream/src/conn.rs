//! One websocket connection: the bounded send queue, the `hello` handshake (tokens, throttling),
//! the `track` rate limit, `targets` paging, and the loop that hands requests to the
//! [`Hub`](crate::server::Hub).

use std::net::IpAddr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use sv_geom::Isometry3;
use tokio::io::{AsyncRead, AsyncWrite};
use tokio::sync::{mpsc, Notify};
use tokio_tungstenite::tungstenite::protocol::frame::coding::CloseCode;
use tokio_tungstenite::tungstenite::protocol::CloseFrame;
use tokio_tungstenite::tungstenite::{Message, Utf8Bytes};

use crate::guard::Ticket;
use crate::protocol::*;
use crate::server::{now_ms, Hub};
use crate::site::{valid_id, Refusal, Who};

/// Messages queued per client before it counts as too slow and is disconnected.
pub const CLIENT_QUEUE: usize = 1024;
/// Bytes queued per client before it counts as too slow and is disconnected (a single
/// message larger than this still goes out when the queue is empty).
pub const CLIENT_QUEUE_BYTES: usize = 4 * 1024 * 1024;
/// `targets` pages are made while less than this is queued, so a frame of any size streams
/// to a slow reader without filling its queue.
const PAGE_LOW_WATER: usize = 1024 * 1024;
/// Messages a client may send before `hello`; more closes the connection (4408).
const MAX_BEFORE_HELLO: usize = 16;
/// `get_targets` answers a client may leave unread; one more and it counts as too slow.
const MAX_PAGINGS: usize = 4;

pub(crate) enum Out {
    Text(Utf8Bytes),
    Close(u16, String),
}

/// The sending side of one client's bounded queue: at most [`CLIENT_QUEUE`] messages and
/// [`CLIENT_QUEUE_BYTES`] bytes wait for the socket; beyond either the client is dropped.
#[derive(Clone)]
pub(crate) struct Outbox {
    tx: mpsc::Sender<Out>,
    queued_bytes: Arc<AtomicUsize>,
    kick: Arc<Notify>,
}

impl Outbox {
    /// Queue a text message; a full queue kicks the client (never blocks).
    pub fn push_text(&self, text: Utf8Bytes) {
        let len = text.len();
        let before = self.queued_bytes.fetch_add(len, Ordering::AcqRel);
        let over = before > 0 && before + len > CLIENT_QUEUE_BYTES;
        if over || self.tx.try_send(Out::Text(text)).is_err() {
            self.queued_bytes.fetch_sub(len, Ordering::AcqRel);
            self.kick.notify_one();
        }
    }

    /// Queue a message.
    pub fn push(&self, msg: &ServerMessage) {
        self.push_text(to_text(msg).into());
    }

    /// Queue an `error`.
    pub fn error(&self, (code, message): Refusal) {
        self.push(&ServerMessage::Error { code, message });
    }

    /// Queue a close frame (best effort).
    pub fn close(&self, code: u16, reason: &str) {
        let _ = self.tx.try_send(Out::Close(code, reason.into()));
    }

    fn queued(&self) -> usize {
        self.queued_bytes.load(Ordering::Acquire)
    }
}

/// Token bucket with coalescing of excess tracks (latest per unit and part wins).
struct Limiter {
    tokens: f64,
    last: Instant,
    rate: f64,
    burst: f64,
    /// Waiting tracks: key, the latest message, how many earlier ones it replaced.
    pending: Vec<((String, Part), ClientMessage, u64)>,
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

/// Per-connection session after `hello`.
struct Session {
    role: Role,
    client_id: String,
}

/// `targets` pages still to send: next offset, coordinates, and the registration they use.
struct Paging {
    offset: usize,
    frame: CoordFrame,
    site: Option<Isometry3>,
}

enum Flow {
    Continue,
    Close,
}

struct Conn {
    hub: Arc<Hub>,
    id: u64,
    ip: IpAddr,
    ticket: Ticket,
    out: Outbox,
    session: Option<Session>,
    before_hello: usize,
    limiter: Limiter,
    /// `get_targets` answers being sent, oldest first.
    paging: std::collections::VecDeque<Paging>,
}

impl Conn {
    fn on_text(&mut self, text: &str) -> Flow {
        let msg = match parse_client(text) {
            Ok(m) => m,
            Err(e) => {
                self.out.error(e);
                return self.count_before_hello();
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
                    self.out
                        .error((ErrorCode::NotReady, "send hello first".into()));
                    self.count_before_hello()
                }
            };
        };
        let who = Who {
            role: session.role,
            client_id: &session.client_id.clone(),
        };
        let result = match msg {
            ClientMessage::Hello { .. } => Err((ErrorCode::NotReady, "hello sent twice".into())),
            ClientMessage::GetTargets { frame } => {
                if self.paging.len() >= MAX_PAGINGS {
                    // asks and asks, never reads: dropped like a full queue
                    self.out.kick.notify_one();
                    return Flow::Continue;
                }
                self.paging.push_back(Paging {
                    offset: 0,
                    frame,
                    site: self.hub.site(),
                });
                self.send_pages();
                Ok(())
            }
            ClientMessage::Ping { t } => {
                self.out.push(&ServerMessage::Pong {
                    t,
                    server_ms: now_ms(),
                });
                Ok(())
            }
            _ if who.role != Role::Operator => Err((
                ErrorCode::Forbidden,
                "viewers may only get_targets and ping".into(),
            )),
            ClientMessage::Track { ref unit, part, .. } => match self.hub.plan.unit(unit) {
                Ok(_) => {
                    let key = (unit.clone(), part);
                    if self.limiter.pending.is_empty() && self.limiter.take() {
                        self.hub.track(who.client_id, msg, 0, &self.out);
                    } else if let Some(slot) =
                        self.limiter.pending.iter_mut().find(|(k, _, _)| *k == key)
                    {
                        slot.1 = msg;
                        slot.2 += 1;
                    } else {
                        self.limiter.pending.push((key, msg, 0));
                    }
                    Ok(())
                }
                Err(e) => Err(e),
            },
            ClientMessage::Overlap { units, measured_mm } => {
                self.hub
                    .overlap(who.client_id, units, measured_mm, &self.out)
            }
            other => self.hub.request(who, &other, &self.out),
        };
        if let Err(e) = result {
            self.out.error(e);
        }
        Flow::Continue
    }

    /// Junk before `hello` gets an error each, but cannot keep the connection pending: the
    /// hello deadline is fixed, and too many messages close it.
    fn count_before_hello(&mut self) -> Flow {
        if self.session.is_some() {
            return Flow::Continue;
        }
        self.before_hello += 1;
        if self.before_hello >= MAX_BEFORE_HELLO {
            self.out.close(CLOSE_HELLO_TIMEOUT, "no hello");
            return Flow::Close;
        }
        Flow::Continue
    }

    /// Send `targets` pages while the queue has room.
    fn send_pages(&mut self) {
        while let Some(p) = self.paging.front_mut() {
            if self.out.queued() >= PAGE_LOW_WATER {
                return;
            }
            match self
                .hub
                .plan
                .targets_page(p.offset, p.frame, p.site.as_ref())
            {
                Some(page) => {
                    if let ServerMessage::Targets { units, .. } = &page {
                        p.offset += units.len();
                    }
                    self.out.push(&page);
                }
                None => {
                    self.paging.pop_front();
                }
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
            self.hub.track(&client_id, msg, coalesced, &self.out);
        }
    }

    fn hello(&mut self, token: &str, client_id: Option<String>, last: Option<Cursor>) -> Flow {
        let now = Instant::now();
        if let Err(wait) = self.hub.guard.check_auth(self.ip, now) {
            self.out.error((
                ErrorCode::Throttled,
                format!(
                    "too many wrong tokens from this address: retry in {:.0} s",
                    wait.as_secs_f64().ceil()
                ),
            ));
            self.out.close(CLOSE_THROTTLED, "too many wrong tokens");
            return Flow::Close;
        }
        let Some(role) = self.hub.role_of(token) else {
            self.hub.guard.auth_failed(self.ip, now);
            self.out
                .error((ErrorCode::Unauthorized, "bad token".into()));
            self.out.close(CLOSE_UNAUTHORIZED, "unauthorized");
            return Flow::Close;
        };
        let client_id = match client_id {
            Some(c) if valid_id(&c) => c,
            Some(_) => {
                self.out.error((
                    ErrorCode::BadMessage,
                    format!("client_id must be 1..={MAX_ID_LEN} of [A-Za-z0-9-_.:]"),
                ));
                return self.count_before_hello();
            }
            None => format!("anon-{}", self.id),
        };
        self.ticket.authenticated();
        self.hub
            .join(self.id, role, &client_id, last.as_ref(), &self.out);
        self.session = Some(Session { role, client_id });
        Flow::Continue
    }
}

/// Serve one upgraded websocket from `ip` (its guard `ticket` released when it ends).
pub(crate) async fn run_ws<S>(
    hub: Arc<Hub>,
    ws: tokio_tungstenite::WebSocketStream<S>,
    ip: IpAddr,
    ticket: Ticket,
) where
    S: AsyncRead + AsyncWrite + Unpin + Send + 'static,
{
    let (mut sink, mut stream) = ws.split();
    let (tx, mut rx) = mpsc::channel::<Out>(CLIENT_QUEUE);
    let queued_bytes = Arc::new(AtomicUsize::new(0));
    let written = queued_bytes.clone();
    let drained = Arc::new(Notify::new());
    let drained_tx = drained.clone();
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
                        let left = written.fetch_sub(len, Ordering::AcqRel) - len;
                        if left < PAGE_LOW_WATER {
                            drained_tx.notify_one();
                        }
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
    let id = hub.next_conn();
    let rate = hub.config.rate;
    let mut conn = Conn {
        hub: hub.clone(),
        id,
        ip,
        ticket,
        out: Outbox {
            tx,
            queued_bytes,
            kick: Arc::new(Notify::new()),
        },
        session: None,
        before_hello: 0,
        limiter: Limiter {
            tokens: rate.burst,
            last: Instant::now(),
            rate: rate.per_second.max(0.001),
            burst: rate.burst.max(1.0),
            pending: Vec::new(),
        },
        paging: Default::default(),
    };
    conn.out.push(&hub.welcome());
    let hello_deadline = tokio::time::sleep(hub.config.hello_timeout);
    tokio::pin!(hello_deadline);
    let mut shutdown = hub.shutdown.clone();
    let silence = heartbeat * 3;
    let kick = conn.out.kick.clone();
    let mut kicked = false;
    loop {
        let pending_at = conn.limiter.next_ready();
        let has_pending = !conn.limiter.pending.is_empty();
        let paging = !conn.paging.is_empty();
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
            _ = drained.notified(), if paging => conn.send_pages(),
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
                Ok(Some(Ok(Message::Binary(_)))) => {
                    conn.out.error((ErrorCode::BadMessage, "binary frames are not supported".into()));
                    if let Flow::Close = conn.count_before_hello() { break; }
                }
                Ok(Some(Ok(Message::Close(_)))) => break,
                Ok(Some(Ok(_))) => {}
            }
        }
    }
    hub.leave(id);
    let Conn { out, ticket, .. } = conn;
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
    drop(ticket);
}
