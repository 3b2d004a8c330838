//! `spinvalence serve`: the binary on a free port, a websocket round trip, bad input.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use serde_json::{json, Value};
use tungstenite::client::IntoClientRequest;
use tungstenite::Message;

use crate::fixtures;
use crate::util::Dir;

/// The longest a read waits: it ends a test against a hung server, it never decides one (a
/// busy machine's pause is far shorter).
const READ_CAP: Duration = Duration::from_secs(60);

/// A directory with `out/frame.json` solved from the small flat grid.
fn solved() -> Dir {
    let dir = Dir::new();
    let mesh = fixtures::path("grid_small.obj");
    dir.run(&[
        "solve",
        "-q",
        "--mesh",
        mesh.to_str().unwrap(),
        "--out",
        "out",
    ])
    .expect_code(0);
    dir
}

/// A running `spinvalence serve`, killed on drop.
struct Served {
    child: Child,
    addr: String,
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Start the server on port 0 and read the address it prints.
fn serve(dir: &Dir, extra: &[&str]) -> Served {
    let mut child = Command::new(env!("CARGO_BIN_EXE_spinvalence"))
        .args([
            "serve",
            "--frame",
            "out/frame.json",
            "--bind",
            "127.0.0.1:0",
        ])
        .args(extra)
        .current_dir(dir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start spinvalence serve");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let Some(addr) = line
        .split("http://")
        .nth(1)
        .and_then(|rest| rest.split('/').next())
        .map(String::from)
    else {
        let _ = child.kill();
        let mut err = String::new();
        let _ = child.stderr.take().unwrap().read_to_string(&mut err);
        panic!("no URL printed: {line:?}, stderr {err:?}");
    };
    Served { child, addr }
}

fn recv(ws: &mut tungstenite::WebSocket<TcpStream>) -> Value {
    loop {
        match ws.read().expect("read a message") {
            Message::Text(t) => return serde_json::from_str(t.as_str()).unwrap(),
            Message::Close(f) => panic!("closed: {f:?}"),
            _ => continue,
        }
    }
}

#[test]
fn serve_answers_hello_and_targets_and_serves_the_page() {
    let dir = solved();
    let server = serve(
        &dir,
        &["--token", "op-token-0123", "--position-tolerance", "3"],
    );

    let tcp = TcpStream::connect(&server.addr).unwrap();
    tcp.set_read_timeout(Some(READ_CAP)).unwrap();
    let mut req = format!("ws://{}/ws", server.addr)
        .into_client_request()
        .unwrap();
    req.headers_mut()
        .insert("sec-websocket-protocol", "spinvalence.v1".parse().unwrap());
    let (mut ws, _) = tungstenite::client(req, tcp).expect("websocket handshake");
    let welcome = recv(&mut ws);
    assert_eq!(welcome["type"], "welcome");
    assert_eq!(welcome["protocol"], 1);
    assert_eq!(welcome["frame"]["units"], 12, "grid_small has 4 x 3 units");
    assert_eq!(welcome["tolerance"]["position_mm"], 3.0);
    ws.send(Message::text(
        json!({"type": "hello", "token": "op-token-0123", "client_id": "e2e"}).to_string(),
    ))
    .unwrap();
    let ready = recv(&mut ws);
    assert_eq!(ready["type"], "ready");
    assert_eq!(ready["role"], "operator");
    assert_eq!(ready["snapshot"]["total"], 12);
    ws.send(Message::text(json!({"type": "get_targets"}).to_string()))
        .unwrap();
    let targets = recv(&mut ws);
    assert_eq!(targets["units"].as_array().unwrap().len(), 12);
    assert_eq!(targets["units"][0]["id"], "U0000");

    // the page on the same port
    let mut http = TcpStream::connect(&server.addr).unwrap();
    http.set_read_timeout(Some(READ_CAP)).unwrap();
    http.write_all(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
        .unwrap();
    let mut page = String::new();
    http.read_to_string(&mut page).unwrap();
    assert!(
        page.starts_with("HTTP/1.1 200"),
        "{}",
        &page[..page.len().min(80)]
    );
    assert!(page.contains("data-progress"));

    // a wrong token is refused
    let tcp = TcpStream::connect(&server.addr).unwrap();
    tcp.set_read_timeout(Some(READ_CAP)).unwrap();
    let mut req = format!("ws://{}/ws", server.addr)
        .into_client_request()
        .unwrap();
    req.headers_mut()
        .insert("sec-websocket-protocol", "spinvalence.v1".parse().unwrap());
    let (mut ws, _) = tungstenite::client(req, tcp).unwrap();
    recv(&mut ws);
    ws.send(Message::text(
        json!({"type": "hello", "token": "nope"}).to_string(),
    ))
    .unwrap();
    assert_eq!(recv(&mut ws)["code"], "unauthorized");
}

#[test]
fn serve_bad_input_is_a_one_line_error() {
    let dir = solved();
    let bad = dir.write("bad.json", "{\"format\": \"spin-valence/frame\", ");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--frame", bad.to_str().unwrap()], "bad.json"),
        (vec!["--frame", "missing.json"], "missing.json"),
        (
            vec!["--frame", "out/frame.json", "--bind", "nowhere"],
            "--bind",
        ),
        (
            vec!["--frame", "out/frame.json", "--bind", "127.0.0.1:99999"],
            "--bind",
        ),
        (
            vec![
                "--frame",
                "out/frame.json",
                "--tls-cert",
                "cert.pem",
                "--tls-key",
                "key.pem",
            ],
            "cert.pem",
        ),
        (
            vec!["--frame", "out/frame.json", "--angle-tolerance", "0"],
            "--angle-tolerance",
        ),
        (
            vec!["--frame", "out/frame.json", "--token", "short"],
            "--token has 5 characters, at least 12",
        ),
    ];
    let busy = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let busy_addr = busy.local_addr().unwrap().to_string();
    let mut cases = cases;
    cases.push((
        vec!["--frame", "out/frame.json", "--bind", busy_addr.as_str()],
        "cannot listen",
    ));
    for (args, needle) in cases {
        let mut all = vec!["serve"];
        all.extend(args);
        let out = dir.run(&all);
        out.expect_code(2);
        let line = out.stderr.trim_end();
        assert_eq!(line.lines().count(), 1, "{out:?}");
        assert!(
            line.starts_with("error: ") && line.contains(needle),
            "{out:?}"
        );
        assert!(!out.stderr.contains("panicked"), "{out:?}");
    }
}

/// A websocket to a running server, past `hello`.
fn join(addr: &str, token: &str, client_id: &str) -> tungstenite::WebSocket<TcpStream> {
    let tcp = TcpStream::connect(addr).unwrap();
    tcp.set_read_timeout(Some(READ_CAP)).unwrap();
    let mut req = format!("ws://{addr}/ws").into_client_request().unwrap();
    req.headers_mut()
        .insert("sec-websocket-protocol", "spinvalence.v1".parse().unwrap());
    let (mut ws, _) = tungstenite::client(req, tcp).expect("websocket handshake");
    assert_eq!(recv(&mut ws)["type"], "welcome");
    ws.send(Message::text(
        json!({"type": "hello", "token": token, "client_id": client_id}).to_string(),
    ))
    .unwrap();
    assert_eq!(recv(&mut ws)["type"], "ready");
    ws
}

#[test]
fn every_acknowledged_complete_survives_kill_9() {
    let dir = solved();
    let token = "op-token-0123";
    let mut acked: Vec<(String, String)> = Vec::new();
    let mut units: Vec<String> = Vec::new();
    for round in 0..3 {
        let mut server = serve(&dir, &["--token", token, "--state", "state.sqlite"]);
        let mut ws = join(&server.addr, token, "welder");
        if units.is_empty() {
            ws.send(Message::text(json!({"type": "get_targets"}).to_string()))
                .unwrap();
            let t = recv(&mut ws);
            units = t["units"]
                .as_array()
                .unwrap()
                .iter()
                .map(|u| u["id"].as_str().unwrap().to_string())
                .collect();
        }
        // four completes per round; kill -9 the moment the last ack arrives
        for k in 0..4 {
            let unit = units[round * 4 + k].clone();
            let op_id = format!("round{round}-{k}");
            ws.send(Message::text(
                json!({"type": "complete", "unit": unit, "op_id": op_id}).to_string(),
            ))
            .unwrap();
            loop {
                let m = recv(&mut ws);
                if m["type"] == "ack" {
                    assert_eq!(m["applied"], true, "{m}");
                    acked.push((unit, op_id));
                    break;
                }
                assert_ne!(m["type"], "error", "{m}");
            }
        }
        server.child.kill().unwrap(); // SIGKILL: no shutdown, no flush
        server.child.wait().unwrap();
        // every acknowledged complete is in the state file, with its op id
        let db = rusqlite::Connection::open(dir.path().join("state.sqlite")).unwrap();
        for (unit, op_id) in &acked {
            let found: Option<String> = db
                .query_row("SELECT op_id FROM completed WHERE unit = ?1", [unit], |r| {
                    r.get(0)
                })
                .ok();
            assert_eq!(
                found.as_deref(),
                Some(op_id.as_str()),
                "round {round}: {unit} lost"
            );
        }
    }
    assert_eq!(acked.len(), 12);
}
