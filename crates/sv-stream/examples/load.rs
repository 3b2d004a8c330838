//! Load benchmark of the streamer (`make bench-stream`): N websocket clients on loopback each
//! send `track` messages at a fixed rate; every `check` is matched to its `track` by `ref`.
//!
//! ```sh
//! cargo run --release -p sv-stream --example load -- --clients 50 --rate 30 --seconds 10
//! ```
//!
//! Prints the messages sent, checks received, tracks coalesced by the rate limit (counted by
//! the server in `check.coalesced`), the difference (lost, must be 0) and the track -> check
//! latency percentiles. The server runs in this process on its own 2-thread runtime with a
//! SQLite state file (every track is recorded), the clients on another runtime.

use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use sv_frame::{solve, FrameFile, QuadMesh, SolveOptions};
use sv_stream::geometry::{pose_of, tile_pose};
use sv_stream::{ServeConfig, Server};
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;

struct Options {
    clients: usize,
    rate: f64,
    seconds: f64,
    frame: Option<String>,
}

fn options() -> Result<Options, String> {
    let mut o = Options {
        clients: 50,
        rate: 30.0,
        seconds: 10.0,
        frame: None,
    };
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        let value = args.next().ok_or(format!("{flag} needs a value"))?;
        let bad = |_| format!("invalid {flag} {value:?}");
        match flag.as_str() {
            "--clients" => o.clients = value.parse().map_err(bad)?,
            "--rate" => o.rate = value.parse().map_err(|_| format!("invalid {flag}"))?,
            "--seconds" => o.seconds = value.parse().map_err(|_| format!("invalid {flag}"))?,
            "--frame" => o.frame = Some(value),
            _ => {
                return Err(format!(
                    "unknown option {flag} (--clients --rate --seconds --frame)"
                ))
            }
        }
    }
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if o.clients == 0 || !positive(o.rate) || !positive(o.seconds) {
        return Err("--clients, --rate and --seconds must be positive".into());
    }
    Ok(o)
}

fn frame(path: Option<&str>) -> Result<FrameFile, String> {
    match path {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| format!("{p}: {e}"))?;
            serde_json::from_str(&text).map_err(|e| format!("{p}: {e}"))
        }
        None => {
            let mesh = QuadMesh::sphere_cap(12, 12, 3000.0, 300.0);
            let solved = solve(&mesh, &SolveOptions::default(), &mut |_| {})
                .map_err(|e| format!("solve: {e}"))?;
            Ok(solved.to_frame_file(&mesh))
        }
    }
}

/// What one client saw.
#[derive(Default)]
struct Tally {
    sent: u64,
    checks: u64,
    coalesced: u64,
    errors: u64,
    latencies_us: Vec<u64>,
}

async fn client(
    url: String,
    unit: String,
    pose: Value,
    rate: f64,
    count: u64,
    start: tokio::time::Instant,
) -> Result<Tally, String> {
    let mut req = url.into_client_request().map_err(|e| e.to_string())?;
    req.headers_mut()
        .insert("sec-websocket-protocol", "spinvalence.v1".parse().unwrap());
    let addr = req
        .uri()
        .authority()
        .map(|a| a.to_string())
        .unwrap_or_default();
    let tcp = tokio::net::TcpStream::connect(addr)
        .await
        .map_err(|e| format!("connect: {e}"))?;
    tcp.set_nodelay(true).map_err(|e| e.to_string())?;
    let (ws, _) = tokio_tungstenite::client_async(req, tcp)
        .await
        .map_err(|e| format!("handshake: {e}"))?;
    let (mut sink, mut stream) = ws.split();
    let text = |v: Value| Message::text(v.to_string());
    sink.send(text(json!({"type": "hello", "token": "bench-token-0123"})))
        .await
        .map_err(|e| e.to_string())?;
    // welcome, ready
    for _ in 0..2 {
        stream
            .next()
            .await
            .ok_or("closed before ready")?
            .map_err(|e| e.to_string())?;
    }
    let mut tally = Tally::default();
    let mut sent_at: Vec<Option<Instant>> = vec![None; count as usize];
    let mut tick = tokio::time::interval_at(start, Duration::from_secs_f64(1.0 / rate));
    let deadline_after_last = Duration::from_secs(5);
    let mut last_sent: Option<Instant> = None;
    loop {
        if tally.sent == count && tally.checks + tally.coalesced + tally.errors >= count {
            break;
        }
        if last_sent.is_some_and(|t| t.elapsed() > deadline_after_last) {
            break;
        }
        tokio::select! {
            _ = tick.tick(), if tally.sent < count => {
                let k = tally.sent;
                let msg = json!({"type": "track", "unit": unit, "part": "hub", "pose": pose,
                                 "source": "sim", "ref": k});
                sent_at[k as usize] = Some(Instant::now());
                sink.send(text(msg)).await.map_err(|e| format!("send: {e}"))?;
                tally.sent += 1;
                if tally.sent == count {
                    last_sent = Some(Instant::now());
                }
            }
            m = stream.next() => {
                let Some(Ok(Message::Text(t))) = m else {
                    match m {
                        Some(Ok(_)) => continue,
                        _ => return Err("connection ended".into()),
                    }
                };
                let now = Instant::now();
                let v: Value = serde_json::from_str(t.as_str()).map_err(|e| e.to_string())?;
                match v["type"].as_str() {
                    Some("check") => {
                        tally.checks += 1;
                        tally.coalesced += v["coalesced"].as_u64().unwrap_or(0);
                        let k = v["ref"].as_u64().unwrap_or(u64::MAX) as usize;
                        if let Some(Some(t0)) = sent_at.get(k) {
                            tally.latencies_us.push(now.duration_since(*t0).as_micros() as u64);
                        }
                    }
                    Some("error") => tally.errors += 1,
                    _ => {}
                }
            }
            _ = tokio::time::sleep(Duration::from_millis(200)), if tally.sent == count => {}
        }
    }
    let _ = sink.close().await;
    Ok(tally)
}

fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "n/a".into())
}

fn percentile(sorted: &[u64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((p / 100.0) * (sorted.len() - 1) as f64).round() as usize;
    sorted[i.min(sorted.len() - 1)] as f64 / 1000.0
}

fn main() {
    let o = match options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let frame = match frame(o.frame.as_deref()) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let state = tempfile::tempdir().expect("temporary directory");
    let mut config = ServeConfig::new(frame.clone());
    config.bind = "127.0.0.1:0".into();
    config.token = Some("bench-token-0123".into());
    config.state_path = Some(state.path().join("bench.sqlite"));
    // every bench client connects from 127.0.0.1: lift the per-address limits for them
    config.address_limits.connections = 2 * o.clients;
    config.address_limits.pending = 2 * o.clients;
    let server_rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name("server")
        .enable_all()
        .build()
        .expect("server runtime");
    let server = match server_rt.block_on(Server::start(config)) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let url = format!("ws://{}/ws", server.local_addr());
    let client_rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name("clients")
        .enable_all()
        .build()
        .expect("client runtime");
    let count = (o.rate * o.seconds).round() as u64;
    let n_units = frame.units.len();
    eprintln!(
        "load: {} clients x {} track/s x {} s on {} ({} units), load average before {}",
        o.clients,
        o.rate,
        o.seconds,
        server.local_addr(),
        n_units,
        loadavg()
    );
    let wall = Instant::now();
    let results = client_rt.block_on(async {
        let start = tokio::time::Instant::now() + Duration::from_millis(500);
        let tasks: Vec<_> = (0..o.clients)
            .map(|i| {
                let unit = &frame.units[i % n_units];
                let mut iso = tile_pose(&unit.hub).expect("tile pose");
                iso.translation.vector.x += (i % 7) as f64; // a few mm off, some not ok
                let pose = serde_json::to_value(pose_of(&iso)).unwrap();
                // spread the clients' phases over one period
                let phase = Duration::from_secs_f64(i as f64 / o.clients as f64 / o.rate);
                tokio::spawn(client(
                    url.clone(),
                    unit.id.clone(),
                    pose,
                    o.rate,
                    count,
                    start + phase,
                ))
            })
            .collect();
        let mut out = Vec::new();
        for t in tasks {
            out.push(t.await.map_err(|e| e.to_string()).and_then(|r| r));
        }
        out
    });
    let elapsed = wall.elapsed().as_secs_f64();
    let load_after = loadavg();
    let dropped = server.dropped_measurements();
    server_rt.block_on(server.shutdown());
    let stored: i64 = rusqlite::Connection::open(state.path().join("bench.sqlite"))
        .and_then(|c| c.query_row("SELECT COUNT(*) FROM measurements", [], |r| r.get(0)))
        .unwrap_or(-1);
    let mut total = Tally::default();
    let mut failed = 0;
    for r in results {
        match r {
            Ok(t) => {
                total.sent += t.sent;
                total.checks += t.checks;
                total.coalesced += t.coalesced;
                total.errors += t.errors;
                total.latencies_us.extend(t.latencies_us);
            }
            Err(e) => {
                failed += 1;
                eprintln!("client failed: {e}");
            }
        }
    }
    total.latencies_us.sort_unstable();
    let l = &total.latencies_us;
    let lost = total.sent as i64 - (total.checks + total.coalesced + total.errors) as i64;
    println!("clients          {} ({} failed)", o.clients, failed);
    println!(
        "rate             {} track/s per client, {:.1} s wall",
        o.rate, elapsed
    );
    println!("tracks sent      {}", total.sent);
    println!("checks received  {}", total.checks);
    println!(
        "coalesced        {} (latest wins, counted by the server)",
        total.coalesced
    );
    println!("errors           {}", total.errors);
    println!("lost             {lost}");
    println!(
        "latency ms       p50 {:.3}  p90 {:.3}  p99 {:.3}  p99.9 {:.3}  max {:.3}",
        percentile(l, 50.0),
        percentile(l, 90.0),
        percentile(l, 99.0),
        percentile(l, 99.9),
        percentile(l, 100.0)
    );
    println!(
        "tracks stored    {stored} rows in the state file ({dropped} dropped: writer queue full)"
    );
    println!("load average     before/after: see above / {load_after}");
    if lost != 0 || failed != 0 {
        std::process::exit(1);
    }
}
