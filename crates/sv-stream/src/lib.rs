//! AR deployment streamer for Spin-Valence frames: protocol v1 types, tolerance checks,
//! site registration, the assembly sequence, SQLite persistence and the websocket server
//! behind `spinvalence serve`.
//!
//! - [`protocol`]: wire types (`docs/protocol.md`, `schema/*.json`).
//! - [`geometry`]: tile poses, checks, Kabsch registration, assembly sequence, and the one
//!   place targets and design overlaps are read from a frame.
//! - [`site`]: the site rules as pure functions (claims, completions, undo, registration,
//!   checks, pages), tested without sockets.
//! - [`guard`]: per-address connection limits and wrong-token throttling.
//! - [`serve`] / [`serve_blocking`] / [`Server::start`]: the server (page at `/`, websocket at
//!   `/ws`, subprotocol `spinvalence.v1`, optional TLS); `http` and `conn` are its HTTP side
//!   and one connection's loop.
//!
//! ```no_run
//! # fn frame() -> sv_frame::FrameFile { unimplemented!() }
//! let mut config = sv_stream::ServeConfig::new(frame());
//! config.token = Some("secret".into());
//! sv_stream::serve_blocking(config, |server| eprintln!("serving {}", server.url())).unwrap();
//! ```

mod conn;
pub mod geometry;
pub mod guard;
mod http;
pub mod protocol;
mod server;
pub mod site;
mod store;

use std::path::PathBuf;
use std::time::Duration;

pub use conn::CLIENT_QUEUE;
pub use guard::AddressLimits;
pub use protocol::Tolerance;
pub use server::{serve, serve_blocking, Server};
use sv_frame::FrameFile;

/// Default listen address.
pub const DEFAULT_BIND: &str = "127.0.0.1:8765";
/// Default websocket ping interval; a peer silent for 3 intervals is dropped.
pub const DEFAULT_HEARTBEAT: Duration = Duration::from_secs(10);
/// Default time a client has to send `hello`.
pub const DEFAULT_HELLO_TIMEOUT: Duration = Duration::from_secs(5);
/// Default time a welder has to take back a `complete` (`undo`).
pub const DEFAULT_UNDO_WINDOW: Duration = Duration::from_secs(60);

/// Per-connection `track` rate limit (token bucket); excess tracks are coalesced, the latest
/// per unit and part winning.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateLimit {
    /// Sustained rate (messages per second).
    pub per_second: f64,
    /// Bucket size.
    pub burst: f64,
}

impl Default for RateLimit {
    fn default() -> Self {
        Self {
            per_second: 30.0,
            burst: 60.0,
        }
    }
}

/// Everything `spinvalence serve` configures.
#[derive(Clone, Debug)]
pub struct ServeConfig {
    /// The frame to serve.
    pub frame: FrameFile,
    /// Listen address (`host:port`; port 0 picks a free one).
    pub bind: String,
    /// Operator token; `None` lets every client in as operator (trusted bench only).
    pub token: Option<String>,
    /// Read-only viewer token.
    pub viewer_token: Option<String>,
    /// SQLite state file; `None` keeps state in memory (lost on exit, new epoch each start).
    pub state_path: Option<PathBuf>,
    /// PEM certificate chain for HTTPS/WSS.
    pub tls_cert: Option<PathBuf>,
    /// PEM private key for HTTPS/WSS.
    pub tls_key: Option<PathBuf>,
    /// Acceptance tolerances.
    pub tolerance: Tolerance,
    /// Websocket ping interval.
    pub heartbeat: Duration,
    /// Time allowed before `hello`.
    pub hello_timeout: Duration,
    /// Track rate limit per connection.
    pub rate: RateLimit,
    /// Most simultaneous connections.
    pub max_connections: usize,
    /// Per-address limits (connections, pending handshakes, wrong tokens).
    pub address_limits: AddressLimits,
    /// How long after a `complete` its client may `undo` it.
    pub undo_window: Duration,
    /// Test hook: cap the state file at this many SQLite pages (a full disk).
    #[doc(hidden)]
    pub state_max_pages: Option<u64>,
}

impl ServeConfig {
    /// Defaults for everything but the frame.
    pub fn new(frame: FrameFile) -> Self {
        Self {
            frame,
            bind: DEFAULT_BIND.into(),
            token: None,
            viewer_token: None,
            state_path: None,
            tls_cert: None,
            tls_key: None,
            tolerance: Tolerance::default(),
            heartbeat: DEFAULT_HEARTBEAT,
            hello_timeout: DEFAULT_HELLO_TIMEOUT,
            rate: RateLimit::default(),
            max_connections: 1024,
            address_limits: AddressLimits::default(),
            undo_window: DEFAULT_UNDO_WINDOW,
            state_max_pages: None,
        }
    }

    /// Refuse a configuration that cannot be served safely: a token shorter than
    /// [`protocol::MIN_TOKEN_LEN`] (it falls to guessing), equal tokens, zero limits.
    pub fn check(&self) -> Result<(), StreamError> {
        for (flag, token) in [
            ("--token", &self.token),
            ("--viewer-token", &self.viewer_token),
        ] {
            if let Some(t) = token {
                let n = t.chars().count();
                if n < protocol::MIN_TOKEN_LEN {
                    return Err(StreamError::Config(format!(
                        "{flag} has {n} characters, at least {} are needed (a short token \
                         falls to guessing; e.g. `openssl rand -hex 16`)",
                        protocol::MIN_TOKEN_LEN
                    )));
                }
            }
        }
        if self.token.is_some() && self.token == self.viewer_token {
            return Err(StreamError::Config(
                "--token and --viewer-token must differ".into(),
            ));
        }
        let l = &self.address_limits;
        if l.connections == 0 || l.pending == 0 || l.auth_burst.is_nan() || l.auth_burst < 1.0 {
            return Err(StreamError::Config(
                "per-address limits must allow at least one connection and one try".into(),
            ));
        }
        Ok(())
    }
}

/// Counters of a running server ([`Server::stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Connections refused at accept because their address held its limit.
    pub refused_connections: u64,
    /// `hello`s with a wrong token.
    pub auth_failures: u64,
    /// `hello`s refused unread: too many wrong tokens from their address.
    pub auth_throttled: u64,
    /// fsyncs of the state file's log, one per stored event (0 without `--state`).
    pub event_fsyncs: u64,
    /// Events that could not be stored (answered `error` `internal`, not applied).
    pub store_errors: u64,
    /// Measurements not stored because the writer's queue was full.
    pub measurements_dropped: u64,
    /// Measurements whose write failed (disk full, I/O error).
    pub measurements_failed: u64,
}

/// Server errors.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// Socket or file error.
    #[error("i/o: {0}")]
    Io(#[from] std::io::Error),
    /// The frame cannot be served.
    #[error("frame: {0}")]
    Frame(String),
    /// The state file cannot be used.
    #[error("state file: {0}")]
    State(String),
    /// Certificate or key problem.
    #[error("tls: {0}")]
    Tls(String),
    /// Bad configuration.
    #[error("config: {0}")]
    Config(String),
}
