//! The small HTTP side of the server: read a request head (bounded in size and time), serve
//! the embedded page, hand `/ws` over to the websocket upgrade with the head put back.

use std::io;
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt, ReadBuf};

/// Largest HTTP request head.
pub const MAX_HTTP_HEAD: usize = 16 * 1024;
/// Time a client has to send its whole request head (junk or a trickle cannot extend it).
pub const HTTP_HEAD_TIMEOUT: Duration = Duration::from_secs(10);

/// A request head: method, path (no query or fragment) and the raw bytes read.
pub struct Head {
    /// `GET`, `HEAD`, ...
    pub method: String,
    /// The path, without `?query` or `#fragment`.
    pub path: String,
    /// Every byte read so far (the head and whatever followed it).
    pub bytes: Vec<u8>,
}

/// Read a request head within [`HTTP_HEAD_TIMEOUT`] (absolute) and [`MAX_HTTP_HEAD`] bytes;
/// `None` on timeout, overflow or a closed connection.
pub async fn read_head<S: AsyncRead + Unpin>(stream: &mut S) -> Option<Head> {
    let mut buf = Vec::with_capacity(1024);
    let read = async {
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
    if !matches!(
        tokio::time::timeout(HTTP_HEAD_TIMEOUT, read).await,
        Ok(true)
    ) {
        return None;
    }
    let line_end = buf.iter().position(|&b| b == b'\r').unwrap_or(0);
    let line = String::from_utf8_lossy(&buf[..line_end]).to_string();
    let mut parts = line.split(' ');
    let method = parts.next().unwrap_or("").to_string();
    let target = parts.next().unwrap_or("");
    let path = target.split(['?', '#']).next().unwrap_or("").to_string();
    Some(Head {
        method,
        path,
        bytes: buf,
    })
}

/// The page, embedded: content type and bytes of a path.
pub fn static_file(path: &str) -> Option<(&'static str, &'static [u8])> {
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

/// Answer a static request (`GET` / `HEAD` of a page file, else 404 or 405) and close.
pub async fn serve_static<S: AsyncWrite + Unpin>(stream: &mut S, head: &Head) {
    let head_only = head.method == "HEAD";
    if head.method != "GET" && !head_only {
        reply(
            stream,
            "405 Method Not Allowed",
            "text/plain",
            b"method not allowed\n",
            false,
        )
        .await;
        return;
    }
    match static_file(&head.path) {
        Some((ctype, body)) => reply(stream, "200 OK", ctype, body, head_only).await,
        None => {
            reply(
                stream,
                "404 Not Found",
                "text/plain",
                b"not found\n",
                head_only,
            )
            .await
        }
    }
}

async fn reply<S: AsyncWrite + Unpin>(
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
    let write = async {
        let _ = stream.write_all(head.as_bytes()).await;
        if !head_only {
            let _ = stream.write_all(body).await;
        }
        let _ = stream.shutdown().await;
    };
    // a client that does not read cannot hold the connection
    let _ = tokio::time::timeout(Duration::from_secs(30), write).await;
}

/// A stream with some already-read bytes put back in front.
pub struct Rewind<S> {
    prefix: Vec<u8>,
    pos: usize,
    inner: S,
}

impl<S> Rewind<S> {
    /// `prefix` is read first, then `inner`.
    pub fn new(prefix: Vec<u8>, inner: S) -> Self {
        Self {
            prefix,
            pos: 0,
            inner,
        }
    }
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
