//! The server: the accept loop (per-address admission, optional TLS), the HTTP head and
//! websocket upgrade, and the [`Hub`] every connection shares: the [`Plan`] (the frame, no
//! lock), the ledger and state file behind one lock (events numbered, stored, fsynced, applied
//! and broadcast in order) and the measurement writer. The rules themselves are in
//! [`crate::site`]; one connection's loop is in [`crate::conn`].

use std::collections::HashMap;
use std::io;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, RwLock};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use sv_geom::Isometry3;
use tokio::io::{AsyncRead, AsyncWrite};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{watch, Semaphore};
use tokio_rustls::TlsAcceptor;
use tokio_tungstenite::tungstenite::handshake::server::{ErrorResponse, Request, Response};
use tokio_tungstenite::tungstenite::http::{HeaderValue, StatusCode};
use tokio_tungstenite::tungstenite::protocol::WebSocketConfig;
use tokio_tungstenite::tungstenite::Utf8Bytes;

use crate::conn::{run_ws, Outbox, CLIENT_QUEUE_BYTES};
use crate::guard::{Guard, Ticket};
use crate::http::{self, Rewind};
use crate::protocol::*;
use crate::site::{Decision, Ledger, Plan, Refusal, Who};
use crate::store::{Fnv, Measurement, MeasurementWriter, Store};
use crate::{ServeConfig, Stats, StreamError};

/// Server time (ms since the Unix epoch).
pub(crate) fn now_ms() -> u64 {
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

/// The ledger, its state file and the ready clients, behind one lock.
struct Book {
    ledger: Ledger,
    store: Store,
    clients: HashMap<u64, (String, Outbox)>,
}

/// What every connection shares.
pub(crate) struct Hub {
    pub plan: Plan,
    pub config: ServeConfig,
    pub guard: Arc<Guard>,
    pub shutdown: watch::Receiver<bool>,
    /// The accepted registration, readable by checks without the book's lock.
    site: RwLock<Option<Isometry3>>,
    book: Arc<Mutex<Book>>,
    measurements: Mutex<MeasurementWriter>,
    dropped_measurements: AtomicU64,
    failed_measurements: Arc<AtomicU64>,
    store_errors: AtomicU64,
    fsyncs: Arc<AtomicU64>,
    next_conn: AtomicU64,
}

fn lock(book: &Mutex<Book>) -> std::sync::MutexGuard<'_, Book> {
    book.lock().unwrap_or_else(|p| p.into_inner())
}

impl Hub {
    fn new(config: ServeConfig, shutdown: watch::Receiver<bool>) -> Result<Hub, StreamError> {
        let frame = &config.frame;
        let plan = Plan::new(frame, config.tolerance).map_err(StreamError::Frame)?;
        let mut hash = Fnv::default();
        hash.write(serde_json::to_string(frame).unwrap_or_default().as_bytes());
        let frame_hash = format!("{:016x}", hash.0);
        let path = config.state_path.as_deref();
        let (store, loaded) = Store::open(path, &frame_hash, config.state_max_pages)?;
        let window = config.undo_window.as_millis() as u64;
        let mut ledger = Ledger::new(loaded.epoch, plan.len(), window);
        for ev in &loaded.events {
            ledger.apply(&plan, ev, None);
        }
        let fsyncs = store.fsyncs.clone();
        let book = Arc::new(Mutex::new(Book {
            ledger,
            store,
            clients: HashMap::new(),
        }));
        // measurements that cannot be written are an error to the client that sent them
        let failed = Arc::new(AtomicU64::new(0));
        let weak = Arc::downgrade(&book);
        let on_failure = Box::new(move |client: &str, n: u64, why: &str| {
            let Some(book) = weak.upgrade() else { return };
            let msg = ServerMessage::Error {
                code: ErrorCode::Internal,
                message: format!("{n} measurement(s) could not be stored: {why}"),
            };
            for (id, out) in lock(&book).clients.values() {
                if id == client {
                    out.push(&msg);
                }
            }
        });
        let measurements =
            MeasurementWriter::start(path, config.state_max_pages, failed.clone(), on_failure)?;
        let site = book.lock().map(|b| b.ledger.registration()).unwrap_or(None);
        Ok(Hub {
            plan,
            guard: Guard::new(config.address_limits),
            config,
            shutdown,
            site: RwLock::new(site),
            book,
            measurements: Mutex::new(measurements),
            dropped_measurements: AtomicU64::new(0),
            failed_measurements: failed,
            store_errors: AtomicU64::new(0),
            fsyncs,
            next_conn: AtomicU64::new(1),
        })
    }

    pub fn next_conn(&self) -> u64 {
        self.next_conn.fetch_add(1, Ordering::Relaxed)
    }

    pub fn site(&self) -> Option<Isometry3> {
        *self.site.read().unwrap_or_else(|p| p.into_inner())
    }

    /// The role a token grants, if any.
    pub fn role_of(&self, token: &str) -> Option<Role> {
        let cfg = &self.config;
        let is = |t: &Option<String>| {
            t.as_deref()
                .is_some_and(|t| ct_eq(t.as_bytes(), token.as_bytes()))
        };
        if is(&cfg.token) {
            Some(Role::Operator)
        } else if is(&cfg.viewer_token) {
            Some(Role::Viewer)
        } else if cfg.token.is_none() {
            Some(Role::Operator)
        } else {
            None
        }
    }

    pub fn welcome(&self) -> ServerMessage {
        let book = lock(&self.book);
        ServerMessage::Welcome {
            protocol: PROTOCOL_VERSION,
            epoch: book.ledger.epoch().to_string(),
            seq: book.ledger.seq(),
            heartbeat_ms: self.config.heartbeat.as_millis() as u64,
            frame: FrameInfo {
                units: self.plan.len(),
                length_unit: "mm".into(),
                up: "+Z".into(),
                quaternion: "xyzw".into(),
            },
            tolerance: self.config.tolerance,
        }
    }

    /// Answer `hello` with `ready` and start broadcasting to the client.
    pub fn join(
        &self,
        conn: u64,
        role: Role,
        client_id: &str,
        last: Option<&Cursor>,
        out: &Outbox,
    ) {
        let mut book = lock(&self.book);
        out.push(&book.ledger.ready(&self.plan, role, client_id.into(), last));
        book.clients.insert(conn, (client_id.into(), out.clone()));
    }

    pub fn leave(&self, conn: u64) {
        lock(&self.book).clients.remove(&conn);
    }

    /// A ledger request: decided, stored (fsynced), applied and broadcast under one lock.
    pub fn request(&self, who: Who<'_>, msg: &ClientMessage, out: &Outbox) -> Result<(), Refusal> {
        let mut book = lock(&self.book);
        let decision = match book.ledger.decide(&self.plan, who, msg, now_ms()) {
            Some(d) => d?,
            None => return Ok(()),
        };
        match decision {
            Decision::Reply(m) => out.push(&m),
            Decision::Commit { first, event, then } => {
                let json = to_text(&event);
                if let Err(e) = book.store.append(&event, &json) {
                    self.store_errors.fetch_add(1, Ordering::Relaxed);
                    return Err((ErrorCode::Internal, format!("not applied: {e}")));
                }
                if let Some(m) = first {
                    out.push(&m);
                }
                book.ledger.apply(&self.plan, &event, Some(now_ms()));
                if let Event::Registration { .. } = event {
                    *self.site.write().unwrap_or_else(|p| p.into_inner()) =
                        book.ledger.registration();
                }
                let text = Utf8Bytes::from(json);
                for (_, client) in book.clients.values() {
                    client.push_text(text.clone());
                }
                if let Some(m) = then {
                    out.push(&m);
                }
            }
        }
        Ok(())
    }

    fn record(&self, client_id: &str, kind: &'static str, unit: &str, json: String) {
        if self.config.state_path.is_none() {
            return;
        }
        let m = Measurement {
            t_ms: now_ms(),
            client_id: client_id.into(),
            kind,
            unit: unit.into(),
            json,
        };
        let guard = self.measurements.lock().unwrap_or_else(|p| p.into_inner());
        if !guard.push(m) {
            let n = self.dropped_measurements.fetch_add(1, Ordering::Relaxed) + 1;
            drop(guard);
            // say so, without flooding a client that keeps sending
            if n.is_power_of_two() {
                self.notify(
                    client_id,
                    format!("measurement queue full: {n} measurement(s) not stored"),
                );
            }
        }
    }

    fn notify(&self, client_id: &str, message: String) {
        let msg = ServerMessage::Error {
            code: ErrorCode::Internal,
            message,
        };
        for (id, out) in lock(&self.book).clients.values() {
            if id == client_id {
                out.push(&msg);
            }
        }
    }

    /// Check one `track` message (anything else is ignored) and answer it.
    pub fn track(&self, client_id: &str, msg: ClientMessage, coalesced: u64, out: &Outbox) {
        let ClientMessage::Track {
            unit,
            part,
            pose,
            source,
            frame,
            reference,
        } = msg
        else {
            return;
        };
        let site = self.site();
        let checked = self.plan.check(
            &unit,
            part,
            &pose,
            source,
            frame,
            reference,
            coalesced,
            site.as_ref(),
        );
        match checked {
            Ok(c) => {
                out.push(&c.check);
                self.record(client_id, "track", &unit, c.record.to_string());
            }
            Err(e) => out.error(e),
        }
    }

    /// Check a measured overlap and answer it.
    pub fn overlap(
        &self,
        client_id: &str,
        units: [String; 2],
        measured_mm: f64,
        out: &Outbox,
    ) -> Result<(), Refusal> {
        let msg = self.plan.overlap(units, measured_mm)?;
        let text = to_text(&msg);
        if let ServerMessage::OverlapCheck { units, .. } = &msg {
            let key = format!("{}+{}", units[0], units[1]);
            self.record(client_id, "overlap", &key, text.clone());
        }
        out.push_text(text.into());
        Ok(())
    }

    fn stats(&self) -> Stats {
        let c = &self.guard.counts;
        Stats {
            refused_connections: c.refused.load(Ordering::Relaxed),
            auth_failures: c.auth_failures.load(Ordering::Relaxed),
            auth_throttled: c.auth_throttled.load(Ordering::Relaxed),
            event_fsyncs: self.fsyncs.load(Ordering::Acquire),
            store_errors: self.store_errors.load(Ordering::Relaxed),
            measurements_dropped: self.dropped_measurements.load(Ordering::Relaxed),
            measurements_failed: self.failed_measurements.load(Ordering::Relaxed),
        }
    }
}

/// Read the request head, answer static files, upgrade `/ws`.
// the handshake callback's error type is fixed by tungstenite
#[allow(clippy::result_large_err)]
async fn handle_stream<S>(hub: Arc<Hub>, mut stream: S, peer: SocketAddr, ticket: Ticket)
where
    S: AsyncRead + AsyncWrite + Unpin + Send + 'static,
{
    let Some(head) = http::read_head(&mut stream).await else {
        return;
    };
    if head.path != "/ws" || head.method != "GET" {
        http::serve_static(&mut stream, &head).await;
        return;
    }
    let rewind = Rewind::new(head.bytes, stream);
    let callback = |req: &Request, mut resp: Response| -> Result<Response, ErrorResponse> {
        let offered = req
            .headers()
            .get_all("sec-websocket-protocol")
            .iter()
            .filter_map(|v| v.to_str().ok())
            .flat_map(|v| v.split(','))
            .any(|p| p.trim() == SUBPROTOCOL);
        if !offered {
            let mut err = ErrorResponse::new(Some(format!("subprotocol {SUBPROTOCOL} required")));
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
    // room for the largest message the server makes (one snapshot may exceed a page)
    config.max_write_buffer_size = 2 * CLIENT_QUEUE_BYTES + 64 * 1024;
    let accept = tokio_tungstenite::accept_hdr_async_with_config(rewind, callback, Some(config));
    if let Ok(Ok(ws)) = tokio::time::timeout(Duration::from_secs(10), accept).await {
        run_ws(hub, ws, peer.ip(), ticket).await;
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

/// Most connections waiting in the kernel for `accept`: a flood of connects from one address
/// must not push another address's SYN out of the queue (a dropped SYN costs its client a
/// 1 s retransmit).
const LISTEN_BACKLOG: u32 = 4096;

/// Bind `addr` (the first address it resolves to) with [`LISTEN_BACKLOG`].
async fn listen(addr: &str) -> io::Result<TcpListener> {
    let mut last = io::Error::new(io::ErrorKind::InvalidInput, "resolves to no address");
    for a in tokio::net::lookup_host(addr).await? {
        let socket = if a.is_ipv4() {
            tokio::net::TcpSocket::new_v4()?
        } else {
            tokio::net::TcpSocket::new_v6()?
        };
        socket.set_reuseaddr(true)?;
        match socket.bind(a).and_then(|()| socket.listen(LISTEN_BACKLOG)) {
            Ok(l) => return Ok(l),
            Err(e) => last = e,
        }
    }
    Err(last)
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
        config.check()?;
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
        let listener = listen(&config.bind)
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
                let (tcp, peer): (TcpStream, SocketAddr) = tokio::select! {
                    _ = stop_accept.changed() => break,
                    r = listener.accept() => match r {
                        Ok(x) => x,
                        Err(_) => { tokio::time::sleep(Duration::from_millis(50)).await; continue; }
                    },
                };
                // an address at its limit is closed at once: it cannot hold slots others need
                let Ok(ticket) = accept_hub.guard.admit(peer.ip(), Instant::now()) else {
                    continue;
                };
                let Ok(permit) = limit.clone().try_acquire_owned() else {
                    continue; // too many connections in all: drop this one
                };
                let _ = tcp.set_nodelay(true);
                let hub = accept_hub.clone();
                let acceptor = acceptor.clone();
                tokio::spawn(async move {
                    match acceptor {
                        Some(a) => {
                            if let Ok(Ok(s)) =
                                tokio::time::timeout(http::HTTP_HEAD_TIMEOUT, a.accept(tcp)).await
                            {
                                handle_stream(hub, s, peer, ticket).await;
                            }
                        }
                        None => handle_stream(hub, tcp, peer, ticket).await,
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

    /// Counters: refused connections, wrong tokens, fsyncs, write failures.
    pub fn stats(&self) -> Stats {
        self.hub.stats()
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
