//! Shared test helpers: a solved frame, a websocket client that validates every received
//! message against `schema/<type>.json`.
#![allow(dead_code)]

use std::collections::HashMap;
use std::sync::OnceLock;
use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use sv_frame::{solve, FrameFile, QuadMesh, SolveOptions};
use sv_stream::{ServeConfig, Server};
use tokio::io::{AsyncRead, AsyncWrite};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::WebSocketStream;

/// How long a message that is due may take: long enough that a busy machine's pause is
/// never taken for silence (a test that passes waits far less).
pub const WAIT: Duration = Duration::from_secs(30);

/// Operator token used by the tests.
pub const TOKEN: &str = "op-secret-2026";
/// Viewer token used by the tests.
pub const VIEWER: &str = "view-secret-2026";

/// A 6x6 sphere cap frame (R 3000 mm, 300 mm units), strips by mesh row.
pub fn frame() -> FrameFile {
    static FRAME: OnceLock<FrameFile> = OnceLock::new();
    FRAME
        .get_or_init(|| {
            let mesh = QuadMesh::sphere_cap(6, 6, 3000.0, 300.0);
            let solved = solve(&mesh, &SolveOptions::default(), &mut |_| {}).unwrap();
            let mut file = solved.to_frame_file(&mesh);
            for u in &mut file.units {
                if u.strip.is_empty() {
                    u.strip = format!("S{}", u.face / 6);
                }
            }
            file
        })
        .clone()
}

/// A config with both tokens on an ephemeral port. Its timers (the wait for `hello`, the
/// silence before a peer is dropped, the undo window) are set far beyond any pause of a busy
/// machine, so that none of them decides a test by accident; the tests of a timer set it
/// short themselves.
pub fn config() -> ServeConfig {
    let mut c = ServeConfig::new(frame());
    c.bind = "127.0.0.1:0".into();
    c.token = Some(TOKEN.into());
    c.viewer_token = Some(VIEWER.into());
    c.hello_timeout = 10 * WAIT;
    c.heartbeat = 10 * WAIT;
    c.undo_window = 100 * WAIT;
    c
}

fn validators() -> &'static HashMap<String, jsonschema::Validator> {
    static V: OnceLock<HashMap<String, jsonschema::Validator>> = OnceLock::new();
    V.get_or_init(|| {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/schema");
        let mut map = HashMap::new();
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let schema: Value =
                serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            let name = path.file_stem().unwrap().to_string_lossy().to_string();
            map.insert(name, jsonschema::validator_for(&schema).unwrap());
        }
        map
    })
}

/// Panic unless `msg` is valid against the schema named by its `type`.
pub fn validate(msg: &Value) {
    let kind = msg["type"].as_str().expect("message has a type");
    let v = validators()
        .get(kind)
        .unwrap_or_else(|| panic!("no schema for {kind}"));
    if let Err(e) = v.validate(msg) {
        panic!("{kind} violates its schema: {e}\n{msg}");
    }
    if kind == "ready" {
        for ev in msg["events"].as_array().into_iter().flatten() {
            validate(ev);
        }
    }
}

/// A test client.
pub struct Client<S> {
    pub ws: WebSocketStream<S>,
}

/// Connect over plain TCP with the subprotocol.
pub async fn connect(server: &Server) -> Client<TcpStream> {
    let tcp = TcpStream::connect(server.local_addr()).await.unwrap();
    connect_on(tcp, &format!("ws://{}/ws", server.local_addr())).await
}

/// Handshake on an existing stream.
pub async fn connect_on<S: AsyncRead + AsyncWrite + Unpin>(stream: S, url: &str) -> Client<S> {
    let mut req = url.into_client_request().unwrap();
    req.headers_mut()
        .insert("sec-websocket-protocol", "spinvalence.v1".parse().unwrap());
    let (ws, resp) = tokio_tungstenite::client_async(req, stream).await.unwrap();
    assert_eq!(
        resp.headers().get("sec-websocket-protocol").unwrap(),
        "spinvalence.v1"
    );
    Client { ws }
}

impl<S: AsyncRead + AsyncWrite + Unpin> Client<S> {
    /// Send a JSON value as text.
    pub async fn send(&mut self, v: Value) {
        self.ws.send(Message::text(v.to_string())).await.unwrap();
    }

    /// Send raw text.
    pub async fn send_raw(&mut self, t: &str) {
        self.ws.send(Message::text(t.to_string())).await.unwrap();
    }

    /// Next text message (validated), `Err` with the close code when the connection ends,
    /// or `None` when nothing came within `wait`.
    pub async fn try_recv(&mut self, wait: Duration) -> Option<Result<Value, Option<u16>>> {
        loop {
            let next = tokio::time::timeout(wait, self.ws.next()).await.ok()?;
            match next {
                Some(Ok(Message::Text(t))) => {
                    let v: Value = serde_json::from_str(t.as_str()).unwrap();
                    validate(&v);
                    return Some(Ok(v));
                }
                Some(Ok(Message::Close(frame))) => {
                    return Some(Err(frame.map(|f| u16::from(f.code))));
                }
                Some(Ok(_)) => continue,
                Some(Err(_)) | None => return Some(Err(None)),
            }
        }
    }

    /// Next text message (validated); panics on timeout or close.
    pub async fn recv(&mut self) -> Value {
        match self.try_recv(WAIT).await {
            Some(Ok(v)) => v,
            other => panic!("expected a message, got {other:?}"),
        }
    }

    /// Next message, which must have this type.
    pub async fn expect(&mut self, kind: &str) -> Value {
        let v = self.recv().await;
        assert_eq!(v["type"], kind, "unexpected message {v}");
        v
    }

    /// Welcome + hello + ready with a token.
    pub async fn join(&mut self, token: &str, client_id: &str) -> (Value, Value) {
        let welcome = self.expect("welcome").await;
        self.send(json!({"type": "hello", "token": token, "client_id": client_id}))
            .await;
        let ready = self.expect("ready").await;
        (welcome, ready)
    }

    /// Wait for the close code (skipping messages).
    pub async fn closed(&mut self) -> Option<u16> {
        loop {
            match self.try_recv(WAIT).await {
                Some(Ok(_)) => continue,
                Some(Err(code)) => return code,
                None => panic!("connection did not close"),
            }
        }
    }
}

/// A synthetic flat frame of `nx x ny` units on a 300 mm grid (no solve: for size tests).
/// Hubs are diamonds at z = 100, primary tiles turned squares at z = 0, strips by row,
/// links between grid neighbours with a 10 mm design overlap. Records are cloned from the
/// solved [`frame`] and only their corners, ids and links changed, so the helper keeps up
/// with new fields of `frame.json`.
pub fn big_frame(nx: usize, ny: usize) -> FrameFile {
    let base = frame();
    let step = 300.0;
    let mut units = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (cx, cy) = ((i as f64 + 0.5) * step, (j as f64 + 0.5) * step);
            let r = 0.5 * step;
            let (c, s) = (0.3f64.cos() * 0.45 * step, 0.3f64.sin() * 0.45 * step);
            let mut u = base.units[0].clone();
            u.id = format!("A{j:03}-{i:03}");
            u.strip = format!("A{j:03}");
            u.face = j * nx + i;
            u.hub = [
                [cx + r, cy, 100.0],
                [cx, cy + r, 100.0],
                [cx - r, cy, 100.0],
                [cx, cy - r, 100.0],
            ];
            u.primary = [
                [cx + c, cy + s, 0.0],
                [cx - s, cy + c, 0.0],
                [cx - c, cy - s, 0.0],
                [cx + s, cy - c, 0.0],
            ];
            units.push(u);
        }
    }
    let mut links = Vec::new();
    let link = |a: usize, b: usize| {
        let mut l = base.links[0].clone();
        l.units = [a, b];
        l.hub_overlap = 10.0;
        l
    };
    for j in 0..ny {
        for i in 0..nx {
            let u = j * nx + i;
            if i + 1 < nx {
                links.push(link(u, u + 1));
            }
            if j + 1 < ny {
                links.push(link(u, u + nx));
            }
        }
    }
    // one hub mesh face per unit (a frame has one unit on every face)
    let grid = sv_frame::QuadMesh::grid(nx, ny, step);
    let mesh = sv_frame::MeshData {
        vertices: grid.vertices.iter().map(|p| [p.x, p.y, 100.0]).collect(),
        faces: grid.faces,
    };
    FrameFile {
        units,
        links,
        mesh,
        ..base
    }
}

/// Connect from a chosen loopback source address (127.0.0.x all route to `lo` on Linux).
pub async fn connect_from(server: &Server, source: [u8; 4]) -> Client<TcpStream> {
    let socket = tokio::net::TcpSocket::new_v4().unwrap();
    socket
        .bind(std::net::SocketAddr::from((source, 0)))
        .unwrap();
    let tcp = socket.connect(server.local_addr()).await.unwrap();
    connect_on(tcp, &format!("ws://{}/ws", server.local_addr())).await
}
