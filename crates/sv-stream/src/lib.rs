//! AR deployment streamer for Spin-Valence frames: protocol v1 types, tolerance checks,
//! site registration, the assembly sequence, SQLite persistence and the websocket server
//! behind `spinvalence serve`.
//!
//! - [`protocol`]: wire types (`docs/protocol.md`, `schema/*.json`).
//! - [`geometry`]: tile poses, checks, Kabsch registration, assembly sequence.
//! - [`serve`] / [`serve_blocking`] / [`Server::start`]: the server (page at `/`, websocket at
//!   `/ws`, subprotocol `spinvalence.v1`, optional TLS).
//!
//! ```no_run
//! # fn frame() -> sv_frame::FrameFile { unimplemented!() }
//! let mut config = sv_stream::ServeConfig::new(frame());
//! config.token = Some("secret".into());
//! sv_stream::serve_blocking(config, |server| eprintln!("serving {}", server.url())).unwrap();
//! ```

pub mod geometry;
pub mod protocol;
mod server;
mod store;

use std::path::PathBuf;
use std::time::Duration;

pub use protocol::Tolerance;
pub use server::{serve, serve_blocking, Server, CLIENT_QUEUE};
use sv_frame::FrameFile;

/// Default listen address.
pub const DEFAULT_BIND: &str = "127.0.0.1:8765";
/// Default websocket ping interval; a peer silent for 3 intervals is dropped.
pub const DEFAULT_HEARTBEAT: Duration = Duration::from_secs(10);
/// Default time a client has to send `hello`.
pub const DEFAULT_HELLO_TIMEOUT: Duration = Duration::from_secs(5);

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
        }
    }
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
