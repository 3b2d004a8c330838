//! Protocol v1 over a real websocket: every message, bad input, roles, two clients, restart.

mod common;

use std::time::Duration;

use common::*;
use serde_json::{json, Value};
use sv_geom::{Isometry3, Point3, UnitQuaternion, Vector3};
use sv_stream::geometry::{pose_of, tile_pose};
use sv_stream::Server;
use tokio::io::{AsyncReadExt, AsyncWriteExt};

fn target(unit: usize) -> Isometry3 {
    tile_pose(&frame().units[unit].hub).unwrap()
}

fn pose_json(iso: &Isometry3) -> Value {
    serde_json::to_value(pose_of(iso)).unwrap()
}

fn approx(a: &Value, b: f64, tol: f64) {
    let x = a.as_f64().unwrap();
    assert!((x - b).abs() <= tol, "{x} != {b}");
}

#[tokio::test]
async fn welcome_hello_targets_ping() {
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    let (welcome, ready) = c.join(TOKEN, "w1").await;
    assert_eq!(welcome["protocol"], 1);
    assert_eq!(welcome["frame"]["units"], 36);
    assert_eq!(welcome["frame"]["quaternion"], "xyzw");
    assert_eq!(welcome["tolerance"]["position_mm"], 5.0);
    assert_eq!(ready["role"], "operator");
    assert_eq!(ready["mode"], "snapshot");
    assert_eq!(ready["snapshot"]["total"], 36);
    assert_eq!(ready["snapshot"]["done"], 0);
    let first = ready["snapshot"]["next"].as_str().unwrap().to_string();

    c.send(json!({"type": "get_targets"})).await;
    let t = c.expect("targets").await;
    let units = t["units"].as_array().unwrap();
    assert_eq!(units.len(), 36);
    assert_eq!(t["registered"], false);
    // pose convention: origin at the centroid, x toward corner 0, z along (c0-c2)x(c1-c3)
    for (i, u) in units.iter().enumerate() {
        let rec = &frame().units[i];
        assert_eq!(u["id"], rec.id.as_str());
        let hub: Vec<Point3> = rec
            .hub
            .iter()
            .map(|p| Point3::new(p[0], p[1], p[2]))
            .collect();
        let centroid =
            Point3::from((hub[0].coords + hub[1].coords + hub[2].coords + hub[3].coords) / 4.0);
        let pos = &u["hub_pose"]["position"];
        for k in 0..3 {
            approx(&pos[k], centroid[k], 1e-9);
        }
        let r = &u["hub_pose"]["rotation"];
        let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            r[3].as_f64().unwrap(),
            r[0].as_f64().unwrap(),
            r[1].as_f64().unwrap(),
            r[2].as_f64().unwrap(),
        ));
        let x = q * Vector3::x();
        let z = q * Vector3::z();
        assert!((x - (hub[0] - centroid).normalize()).norm() < 1e-6);
        let n = (hub[0] - hub[2]).cross(&(hub[1] - hub[3])).normalize();
        assert!((z - n).norm() < 1e-9);
    }
    assert!(units.iter().any(|u| u["id"] == first.as_str()));

    c.send(json!({"type": "get_targets", "frame": "model"}))
        .await;
    assert_eq!(c.expect("targets").await["frame"], "model");

    c.send(json!({"type": "ping", "t": 42})).await;
    let p = c.expect("pong").await;
    assert_eq!(p["t"], 42);
    server.shutdown().await;
}

#[tokio::test]
async fn track_checks() {
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    c.join(TOKEN, "w1").await;
    let id = frame().units[3].id.clone();
    let exact = target(3);
    c.send(json!({"type": "track", "unit": id, "part": "hub", "pose": pose_json(&exact), "source": "sim", "ref": 7})).await;
    let ch = c.expect("check").await;
    assert_eq!(ch["ok"], true);
    assert_eq!(ch["ref"], 7);
    approx(&ch["position_error_mm"], 0.0, 1e-9);
    approx(&ch["angle_error_deg"], 0.0, 1e-5);

    // 10 mm off along +x: not ok, move_mm points back
    let off = Isometry3::from_parts(
        (exact.translation.vector + Vector3::new(10.0, 0.0, 0.0)).into(),
        exact.rotation,
    );
    c.send(json!({"type": "track", "unit": id, "part": "hub", "pose": pose_json(&off), "source": "qr"})).await;
    let ch = c.expect("check").await;
    assert_eq!(ch["ok"], false);
    approx(&ch["position_error_mm"], 10.0, 1e-9);
    approx(&ch["move_mm"][0], -10.0, 1e-9);

    // 3 mm off and 2 degrees turned: angle fails
    let turned = Isometry3::from_parts(
        (exact.translation.vector + Vector3::new(0.0, 3.0, 0.0)).into(),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 2f64.to_radians()) * exact.rotation,
    );
    c.send(json!({"type": "track", "unit": id, "part": "hub", "pose": pose_json(&turned)}))
        .await;
    let ch = c.expect("check").await;
    assert_eq!(ch["ok"], false);
    approx(&ch["angle_error_deg"], 2.0, 1e-6);
    approx(&ch["position_error_mm"], 3.0, 1e-9);

    // primary part, model frame
    let prim = tile_pose(&frame().units[3].primary).unwrap();
    c.send(json!({"type": "track", "unit": id, "part": "primary", "frame": "model", "pose": pose_json(&prim)})).await;
    let ch = c.expect("check").await;
    assert_eq!(
        (ch["ok"].clone(), ch["part"].clone(), ch["frame"].clone()),
        (json!(true), json!("primary"), json!("model"))
    );

    c.send(json!({"type": "track", "unit": "nope", "part": "hub", "pose": pose_json(&prim)}))
        .await;
    assert_eq!(c.expect("error").await["code"], "unknown_unit");
    c.send(json!({"type": "track", "unit": id, "part": "hub", "pose": {"position": [0, 0, 0], "rotation": [0, 0, 0, 0]}})).await;
    assert_eq!(c.expect("error").await["code"], "bad_message");
    server.shutdown().await;
}

#[tokio::test]
async fn overlap_checks() {
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    c.join(TOKEN, "w1").await;
    let f = frame();
    let link = &f.links[0];
    let (a, b) = (&f.units[link.units[0]].id, &f.units[link.units[1]].id);
    c.send(json!({"type": "overlap", "units": [b, a], "measured_mm": link.hub_overlap + 1.0}))
        .await;
    let o = c.expect("overlap_check").await;
    approx(&o["design_mm"], link.hub_overlap, 1e-12);
    assert_eq!(o["ok"], true);
    c.send(json!({"type": "overlap", "units": [a, b], "measured_mm": link.hub_overlap + 3.0}))
        .await;
    assert_eq!(c.expect("overlap_check").await["ok"], false);
    // first and last unit of a 6x6 cap share no link
    c.send(
        json!({"type": "overlap", "units": [f.units[0].id, f.units[35].id], "measured_mm": 1.0}),
    )
    .await;
    assert_eq!(c.expect("error").await["code"], "not_linked");
    server.shutdown().await;
}

#[tokio::test]
async fn bad_messages_keep_the_connection() {
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    c.expect("welcome").await;
    c.send(json!({"type": "get_targets"})).await;
    assert_eq!(c.expect("error").await["code"], "not_ready");
    c.send(json!({"type": "hello", "token": TOKEN})).await;
    assert!(c.expect("ready").await["client_id"]
        .as_str()
        .unwrap()
        .starts_with("anon-"));
    c.send(json!({"type": "hello", "token": TOKEN})).await;
    assert_eq!(c.expect("error").await["code"], "not_ready");
    c.send_raw("{not json").await;
    assert_eq!(c.expect("error").await["code"], "bad_message");
    c.send_raw("[1,2]").await;
    assert_eq!(c.expect("error").await["code"], "unknown_type");
    c.send(json!({"type": "fly"})).await;
    assert_eq!(c.expect("error").await["code"], "unknown_type");
    c.send(json!({"type": "claim", "unit": 5})).await;
    assert_eq!(c.expect("error").await["code"], "bad_message");
    c.send(json!({"type": "ping", "extra": true})).await;
    assert_eq!(c.expect("error").await["code"], "bad_message");
    c.send(json!({"type": "ping", "t": "x".repeat(70_000)}))
        .await;
    assert_eq!(c.expect("error").await["code"], "too_large");
    c.ws.send(tokio_tungstenite::tungstenite::Message::binary(vec![
        1u8, 2, 3,
    ]))
    .await
    .unwrap();
    assert_eq!(c.expect("error").await["code"], "bad_message");
    c.send(json!({"type": "register", "points": [[[0,0,0],[0,0,0]],[[1,1,1],[1,1,1]],[[2,2,2],[2,2,2]]]})).await;
    assert_eq!(c.expect("error").await["code"], "degenerate");
    c.send(json!({"type": "ping"})).await;
    c.expect("pong").await;
    // beyond the transport limit the connection closes with 1009
    c.send(json!({"type": "ping", "t": "x".repeat(200_000)}))
        .await;
    assert_eq!(c.closed().await, Some(1009));
    server.shutdown().await;
}

#[tokio::test]
async fn hostile_names_get_a_short_one_line_error() {
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    c.expect("welcome").await;
    c.send(json!({"type": "hello", "token": TOKEN})).await;
    c.expect("ready").await;
    let long = "k".repeat(5000);
    for hostile in [
        json!({"type": "claim", "unit": "A", "evil\n\r\u{1b}[2Jkey": 1}),
        json!({"type": "claim", "unit": "A", long.as_str(): 1}),
        json!({"type": "track", "unit": "A", "part": format!("{long}\n"), "pose": pose_json(&target(0))}),
    ] {
        c.send(hostile).await;
        let e = c.expect("error").await;
        assert_eq!(e["code"], "bad_message");
        let message = e["message"].as_str().unwrap();
        assert!(!message.chars().any(char::is_control), "{message:?}");
        assert!(
            message.chars().count() <= 200,
            "{} chars",
            message.chars().count()
        );
        assert!(message.contains("unknown"), "{message}");
    }
    server.shutdown().await;
}

use futures_util::{SinkExt, StreamExt};
use tokio_tungstenite::tungstenite::Message;

#[tokio::test]
async fn viewer_role_is_read_only() {
    let server = Server::start(config()).await.unwrap();
    let mut v = connect(&server).await;
    let (_, ready) = v.join(VIEWER, "viewer-1").await;
    assert_eq!(ready["role"], "viewer");
    v.send(json!({"type": "get_targets"})).await;
    v.expect("targets").await;
    let id = frame().units[0].id.clone();
    for msg in [
        json!({"type": "complete", "unit": id, "op_id": "op-1"}),
        json!({"type": "claim", "unit": id}),
        json!({"type": "track", "unit": id, "part": "hub", "pose": pose_json(&target(0))}),
        json!({"type": "register", "points": []}),
    ] {
        v.send(msg).await;
        assert_eq!(v.expect("error").await["code"], "forbidden");
    }
    v.send(json!({"type": "ping"})).await;
    v.expect("pong").await;
    server.shutdown().await;
}

#[tokio::test]
async fn wrong_token_closes_4401_and_silence_closes_4408() {
    // the tests' hello timeout: a busy machine's delay before the hello is not silence
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    c.expect("welcome").await;
    c.send(json!({"type": "hello", "token": "op-secret-2025"}))
        .await;
    assert_eq!(c.expect("error").await["code"], "unauthorized");
    assert_eq!(c.closed().await, Some(4401));
    server.shutdown().await;

    let mut cfg = config();
    cfg.hello_timeout = Duration::from_millis(300);
    let server = Server::start(cfg).await.unwrap();
    let mut c = connect(&server).await;
    c.expect("welcome").await;
    assert_eq!(c.closed().await, Some(4408));
    server.shutdown().await;
}

#[tokio::test]
async fn handshake_needs_subprotocol_and_page_is_served() {
    let server = Server::start(config()).await.unwrap();
    let tcp = tokio::net::TcpStream::connect(server.local_addr())
        .await
        .unwrap();
    let url = format!("ws://{}/ws", server.local_addr());
    assert!(tokio_tungstenite::client_async(url.as_str(), tcp)
        .await
        .is_err());

    for (path, status, needle) in [
        ("/", "200", "data-progress"),
        ("/viewer.js", "200", "export"),
        ("/vendor/three.module.js", "200", "REVISION"),
        ("/vendor/OrbitControls.js", "200", "./three.module.js"),
        ("/", "200", "rel=\"icon\" href=\"data:,\""),
        ("/nope", "404", "not found"),
    ] {
        let mut tcp = tokio::net::TcpStream::connect(server.local_addr())
            .await
            .unwrap();
        tcp.write_all(format!("GET {path} HTTP/1.1\r\nHost: x\r\n\r\n").as_bytes())
            .await
            .unwrap();
        let mut body = Vec::new();
        tcp.read_to_end(&mut body).await.unwrap();
        let text = String::from_utf8_lossy(&body);
        assert!(
            text.starts_with(&format!("HTTP/1.1 {status}")),
            "{path}: {}",
            &text[..40.min(text.len())]
        );
        assert!(text.contains(needle), "{path} lacks {needle}");
    }
    server.shutdown().await;
}

#[tokio::test]
async fn two_clients_claims_and_progress() {
    let server = Server::start(config()).await.unwrap();
    let mut a = connect(&server).await;
    let mut b = connect(&server).await;
    a.join(TOKEN, "welder-a").await;
    b.join(TOKEN, "welder-b").await;
    let f = frame();
    let u = f.units[7].id.clone();

    a.send(json!({"type": "claim", "unit": u})).await;
    let ev = a.expect("claimed").await;
    assert_eq!(ev["by"], "welder-a");
    assert_eq!(a.expect("ack").await["applied"], true);
    assert_eq!(b.expect("claimed").await["seq"], ev["seq"]);

    b.send(json!({"type": "claim", "unit": u})).await;
    assert_eq!(b.expect("error").await["code"], "claimed");
    b.send(json!({"type": "complete", "unit": u, "op_id": "b-1"}))
        .await;
    assert_eq!(b.expect("error").await["code"], "claimed");
    b.send(json!({"type": "release", "unit": u})).await;
    assert_eq!(b.expect("error").await["code"], "not_claimed");
    a.send(json!({"type": "claim", "unit": u})).await;
    assert_eq!(a.expect("ack").await["applied"], false);

    a.send(json!({"type": "complete", "unit": u, "op_id": "a-1"}))
        .await;
    let pa = a.expect("progress").await;
    let ack = a.expect("ack").await;
    assert_eq!(ack["applied"], true);
    let pb = b.expect("progress").await;
    assert_eq!(pa, pb);
    assert_eq!(pa["done"], 1);
    assert_eq!(pa["total"], 36);
    assert_ne!(pa["next"], json!(null));
    // same op_id again: applied once
    a.send(json!({"type": "complete", "unit": u, "op_id": "a-1"}))
        .await;
    let ack = a.expect("ack").await;
    assert_eq!(ack["applied"], false);
    assert_eq!(ack["seq"], pa["seq"]);
    a.send(json!({"type": "complete", "unit": u, "op_id": "a-2"}))
        .await;
    assert_eq!(a.expect("error").await["code"], "already_done");
    b.send(json!({"type": "claim", "unit": u})).await;
    assert_eq!(b.expect("error").await["code"], "already_done");

    // b claims and releases another unit; a sees both events
    let w = f.units[8].id.clone();
    b.send(json!({"type": "claim", "unit": w})).await;
    b.expect("claimed").await;
    b.expect("ack").await;
    b.send(json!({"type": "release", "unit": w})).await;
    b.expect("released").await;
    b.expect("ack").await;
    assert_eq!(a.expect("claimed").await["unit"], w.as_str());
    assert_eq!(a.expect("released").await["unit"], w.as_str());
    server.shutdown().await;
}

#[tokio::test]
async fn progress_follows_the_assembly_sequence() {
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    let (_, ready) = c.join(TOKEN, "w").await;
    let f = frame();
    let index = |id: &str| f.units.iter().position(|u| u.id == id).unwrap();
    let mut next = ready["snapshot"]["next"].as_str().map(String::from);
    let mut placed: Vec<usize> = Vec::new();
    let mut strips_seen: Vec<String> = Vec::new();
    let mut k = 0;
    while let Some(id) = next {
        let u = index(&id);
        if !placed.is_empty() {
            let touches = f.links.iter().any(|l| {
                (l.units[0] == u && placed.contains(&l.units[1]))
                    || (l.units[1] == u && placed.contains(&l.units[0]))
            });
            assert!(touches, "{id} is not next to a placed unit");
        }
        let strip = f.units[u].strip.clone();
        if strips_seen.last() != Some(&strip) {
            assert!(
                !strips_seen.contains(&strip),
                "strip {strip} resumed: not strip by strip"
            );
            strips_seen.push(strip);
        }
        placed.push(u);
        k += 1;
        c.send(json!({"type": "complete", "unit": id, "op_id": format!("op-{k}")}))
            .await;
        let p = c.expect("progress").await;
        c.expect("ack").await;
        assert_eq!(p["done"], k);
        next = p["next"].as_str().map(String::from);
    }
    assert_eq!(k, 36);
    assert_eq!(strips_seen.len(), 6);
    server.shutdown().await;
}

/// Site transform used by the registration tests.
fn site() -> Isometry3 {
    Isometry3::new(
        Vector3::new(1500.0, -800.0, 120.0),
        Vector3::new(0.0, 0.0, 0.7),
    )
}

fn reg_points(noise: f64) -> Value {
    let f = frame();
    let pts: Vec<Value> = [0usize, 5, 30, 35, 14]
        .iter()
        .enumerate()
        .map(|(k, &u)| {
            let m = f.units[u].hub[0];
            let s = site() * Point3::new(m[0], m[1], m[2]);
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            json!([m, [s.x + sign * noise, s.y, s.z - sign * noise]])
        })
        .collect();
    json!(pts)
}

#[tokio::test]
async fn registration_applies_both_ways() {
    let server = Server::start(config()).await.unwrap();
    let mut a = connect(&server).await;
    let mut b = connect(&server).await;
    a.join(TOKEN, "surveyor").await;
    b.join(VIEWER, "screen").await;

    // distinct but collinear model points: rejected
    let line: Vec<Value> = (0..4)
        .map(|i| json!([[100.0 * i as f64, 50.0 * i as f64, 0.0], [0.0, 0.0, 0.0]]))
        .collect();
    a.send(json!({"type": "register", "points": line})).await;
    let e = a.expect("error").await;
    assert_eq!(e["code"], "degenerate");
    assert!(e["message"].as_str().unwrap().contains("collinear"));
    a.send(json!({"type": "register", "points": [[[0, 0, 0], [0, 0, 0]], [[1000, 0, 0], [1000, 0, 0]]]})).await;
    assert_eq!(a.expect("error").await["code"], "degenerate");

    // noisy beyond the 5 mm tolerance: refused, nothing applied
    a.send(json!({"type": "register", "points": reg_points(20.0)}))
        .await;
    let fit = a.expect("fit").await;
    assert_eq!(fit["ok"], false);
    assert!(fit["transform"]["rms_mm"].as_f64().unwrap() > 5.0);
    assert_eq!(fit["residuals_mm"].as_array().unwrap().len(), 5);

    a.send(json!({"type": "register", "points": reg_points(0.5)}))
        .await;
    let fit = a.expect("fit").await;
    assert_eq!(fit["ok"], true);
    assert!(fit["transform"]["rms_mm"].as_f64().unwrap() < 1.0);
    a.expect("registration").await;
    b.expect("registration").await;

    b.send(json!({"type": "get_targets"})).await;
    let t = b.expect("targets").await;
    assert_eq!(t["registered"], true);
    let expect = site() * target(3);
    let p = &t["units"][3]["hub_pose"]["position"];
    for k in 0..3 {
        approx(&p[k], expect.translation.vector[k], 1.0);
    }
    // a site-frame track at the site target passes; the model pose no longer does
    let id = frame().units[3].id.clone();
    a.send(json!({"type": "track", "unit": id, "part": "hub", "pose": pose_json(&expect)}))
        .await;
    assert_eq!(a.expect("check").await["ok"], true);
    a.send(json!({"type": "track", "unit": id, "part": "hub", "pose": pose_json(&target(3))}))
        .await;
    assert_eq!(a.expect("check").await["ok"], false);
    a.send(json!({"type": "track", "unit": id, "part": "hub", "frame": "model", "pose": pose_json(&target(3))})).await;
    assert_eq!(a.expect("check").await["ok"], true);
    server.shutdown().await;
}

#[tokio::test]
async fn rate_limit_coalesces_latest() {
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    c.join(TOKEN, "w").await;
    let id = frame().units[0].id.clone();
    let other = frame().units[1].id.clone();
    let pose = pose_json(&target(0));
    let t0 = std::time::Instant::now();
    for i in 0..200 {
        c.send(json!({"type": "track", "unit": id, "part": "hub", "pose": pose, "ref": i}))
            .await;
    }
    // a different unit has its own latest-wins slot
    c.send(json!({"type": "track", "unit": other, "part": "hub", "pose": pose, "ref": 1000}))
        .await;
    let mut refs = Vec::new();
    let mut coalesced = 0;
    let mut other_seen = false;
    // until the latest track of each unit is checked: a busy machine's pause cannot end
    // the stream early
    let mut last = 0.0;
    while refs.last() != Some(&199) || !other_seen {
        let Some(Ok(m)) = c.try_recv(WAIT).await else {
            break;
        };
        last = t0.elapsed().as_secs_f64();
        assert_eq!(m["type"], "check");
        if m["unit"] == other.as_str() {
            other_seen = true;
            continue;
        }
        refs.push(m["ref"].as_i64().unwrap());
        coalesced += m["coalesced"].as_u64().unwrap();
    }
    // up to the last check received, not the wait after it
    let elapsed = last;
    assert!(other_seen, "the other unit's track was lost");
    // the burst of 60 passes at once; the rest arrive at 30 per second at most
    let bound = 60 + 2 + (elapsed * 30.0).ceil() as usize;
    assert!(
        refs.len() > 60 && refs.len() <= bound,
        "{} checks, bound {bound}",
        refs.len()
    );
    assert!(
        refs.windows(2).all(|w| w[0] < w[1]),
        "checks out of order: {refs:?}"
    );
    assert_eq!(*refs.last().unwrap(), 199, "latest wins");
    // nothing is lost silently: every track is either checked or counted as coalesced
    assert_eq!(refs.len() as u64 + coalesced, 200);
    server.shutdown().await;
}

#[tokio::test]
async fn slow_client_is_dropped_others_unaffected() {
    let server = Server::start(config()).await.unwrap();
    let mut slow = connect(&server).await;
    slow.join(TOKEN, "slow").await;
    let mut fast = connect(&server).await;
    fast.join(TOKEN, "fast").await;
    // the slow client asks for lots and never reads; once its queue overflows the server
    // drops it, and its further writes fail (connection reset): stop sending then
    let ask = Message::text(json!({"type": "get_targets"}).to_string());
    let mut sent = 0;
    for _ in 0..3000 {
        if slow.ws.send(ask.clone()).await.is_err() {
            break;
        }
        sent += 1;
    }
    assert!(sent > 0);
    // the other client is served meanwhile
    fast.send(json!({"type": "ping", "t": 1})).await;
    assert_eq!(fast.expect("pong").await["t"], 1);
    // the slow one got cut off before receiving all its answers, and its connection ended
    let mut got = 0;
    let ended = loop {
        match slow.try_recv(WAIT).await {
            Some(Ok(m)) => {
                assert_eq!(m["type"], "targets");
                got += 1;
            }
            Some(Err(_)) => break true,
            None => break false,
        }
    };
    assert!(ended, "slow client still connected after {got} answers");
    assert!(
        got < sent,
        "slow client was never dropped ({got} of {sent} answers)"
    );
    fast.send(json!({"type": "ping", "t": 2})).await;
    assert_eq!(fast.expect("pong").await["t"], 2);
    server.shutdown().await;
}

#[tokio::test]
async fn silent_peer_is_dropped() {
    let mut cfg = config();
    cfg.heartbeat = Duration::from_millis(100);
    let server = Server::start(cfg).await.unwrap();
    let mut c = connect(&server).await;
    c.join(TOKEN, "w").await;
    // from here on the peer is silent: its socket is read raw, so it never answers the
    // server's pings (a websocket reader would, and a paused test could read them before
    // the server's silence timer ran); the server must end the connection. WAIT only caps
    // a hung server.
    let tcp = c.ws.get_mut();
    let mut buf = [0u8; 256];
    let ended = tokio::time::timeout(WAIT, async {
        loop {
            if matches!(
                tokio::io::AsyncReadExt::read(tcp, &mut buf).await,
                Ok(0) | Err(_)
            ) {
                return;
            }
        }
    })
    .await;
    assert!(
        ended.is_ok(),
        "a silent peer was not dropped within {WAIT:?}"
    );
    server.shutdown().await;
}

#[tokio::test]
async fn restart_keeps_progress_claims_registration() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = config();
    cfg.state_path = Some(dir.path().join("state.sqlite"));
    let f = frame();
    let server = Server::start(cfg.clone()).await.unwrap();
    let mut c = connect(&server).await;
    let (welcome, _) = c.join(TOKEN, "w").await;
    let epoch = welcome["epoch"].as_str().unwrap().to_string();
    c.send(json!({"type": "register", "points": reg_points(0.0)}))
        .await;
    c.expect("fit").await;
    c.expect("registration").await;
    let mut broadcast = Vec::new();
    for k in 0..3 {
        c.send(json!({"type": "complete", "unit": f.units[k].id, "op_id": format!("op-{k}")}))
            .await;
        broadcast.push(c.expect("progress").await);
        c.expect("ack").await;
    }
    c.send(json!({"type": "claim", "unit": f.units[10].id}))
        .await;
    let claimed = c.expect("claimed").await;
    broadcast.push(claimed.clone());
    c.expect("ack").await;
    let seq = claimed["seq"].as_u64().unwrap();
    assert_eq!(seq, 5);
    c.send(json!({"type": "track", "unit": f.units[0].id, "part": "hub", "pose": pose_json(&target(0))})).await;
    c.expect("check").await;
    server.shutdown().await;
    assert_eq!(
        c.closed().await,
        Some(1001),
        "shutdown closes with 1001 going away"
    );

    let server = Server::start(cfg.clone()).await.unwrap();
    // a client that saw seq 2 gets events 3..=5 replayed
    let mut c = connect(&server).await;
    let welcome = c.expect("welcome").await;
    assert_eq!(welcome["epoch"], epoch.as_str());
    assert_eq!(welcome["seq"], 5);
    c.send(json!({"type": "hello", "token": TOKEN, "client_id": "w", "last": {"epoch": epoch, "seq": 2}})).await;
    let ready = c.expect("ready").await;
    assert_eq!(ready["mode"], "replay");
    let kinds: Vec<&str> = ready["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["type"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["progress", "progress", "claimed"]);
    // replayed events are exactly what was broadcast (count and next unit included)
    assert_eq!(ready["events"].as_array().unwrap()[..], broadcast[1..]);
    assert_ne!(broadcast[2]["next"], json!(null));
    // the claim survived: another welder cannot take it, the owner can complete it
    let mut other = connect(&server).await;
    let (_, ready) = other.join(TOKEN, "other").await;
    let snap = &ready["snapshot"];
    assert_eq!(snap["done"], 3);
    assert_eq!(snap["completed"].as_array().unwrap().len(), 3);
    assert_eq!(snap["claims"][f.units[10].id.as_str()], "w");
    assert!(snap["registration"]["rms_mm"].as_f64().unwrap() < 1e-6);
    other
        .send(json!({"type": "claim", "unit": f.units[10].id}))
        .await;
    assert_eq!(other.expect("error").await["code"], "claimed");
    // op ids are remembered across the restart
    c.send(json!({"type": "complete", "unit": f.units[1].id, "op_id": "op-1"}))
        .await;
    assert_eq!(c.expect("ack").await["applied"], false);
    c.send(json!({"type": "get_targets"})).await;
    assert_eq!(c.expect("targets").await["registered"], true);
    // a stale epoch gets a snapshot
    let mut late = connect(&server).await;
    late.expect("welcome").await;
    late.send(json!({"type": "hello", "token": TOKEN, "last": {"epoch": "0000", "seq": 1}}))
        .await;
    assert_eq!(late.expect("ready").await["mode"], "snapshot");
    server.shutdown().await;

    // measurements were written
    let conn = rusqlite::Connection::open(dir.path().join("state.sqlite")).unwrap();
    let n: i64 = conn
        .query_row("SELECT COUNT(*) FROM measurements", [], |r| r.get(0))
        .unwrap();
    assert!(n >= 1);
    let done: i64 = conn
        .query_row("SELECT COUNT(*) FROM completed", [], |r| r.get(0))
        .unwrap();
    assert_eq!(done, 3);
}

#[tokio::test]
async fn unit_labels_give_ids_and_strips() {
    let mut cfg = config();
    for (i, u) in cfg.frame.units.iter_mut().enumerate() {
        u.strip = String::new();
        u.id = match i {
            0 => String::new(),
            1 => "U0001".into(),
            _ => format!("A{:02}-{:02}", i / 6, i % 6),
        };
    }
    let server = Server::start(cfg).await.unwrap();
    let mut c = connect(&server).await;
    let (_, ready) = c.join(TOKEN, "w").await;
    c.send(json!({"type": "get_targets"})).await;
    let t = c.expect("targets").await;
    let units = t["units"].as_array().unwrap();
    assert_eq!(units[0]["id"], "0");
    assert_eq!(units[0]["strip"], json!(null));
    assert_eq!(units[1]["id"], "U0001");
    assert_eq!(units[1]["strip"], json!(null));
    assert_eq!(units[14]["id"], "A02-02");
    assert_eq!(units[14]["strip"], "A02");
    // ids are what the other messages use
    c.send(json!({"type": "track", "unit": "0", "part": "hub", "pose": pose_json(&target(0))}))
        .await;
    assert_eq!(c.expect("check").await["ok"], true);
    let next = ready["snapshot"]["next"].as_str().unwrap();
    assert!(units.iter().any(|u| u["id"] == next));
    server.shutdown().await;
}

#[tokio::test]
async fn duplicate_ids_and_bad_tls_files_are_errors() {
    let mut cfg = config();
    cfg.frame.units[1].id = cfg.frame.units[0].id.clone();
    let err = Server::start(cfg)
        .await
        .err()
        .expect("duplicate ids refused");
    assert!(err.to_string().contains("duplicate unit id"), "{err}");
    let mut cfg = config();
    cfg.tls_cert = Some("/nonexistent/cert.pem".into());
    cfg.tls_key = Some("/nonexistent/key.pem".into());
    assert!(Server::start(cfg).await.is_err());
    let mut cfg = config();
    cfg.tls_cert = Some("/nonexistent/cert.pem".into());
    assert!(Server::start(cfg)
        .await
        .err()
        .unwrap()
        .to_string()
        .contains("together"));
}

#[tokio::test]
async fn tls_serves_page_and_websocket() {
    use std::sync::Arc;
    use tokio_rustls::rustls::{self, pki_types::ServerName};
    let dir = tempfile::tempdir().unwrap();
    let cert = rcgen::generate_simple_self_signed(vec!["localhost".to_string()]).unwrap();
    let (cert_path, key_path) = (dir.path().join("cert.pem"), dir.path().join("key.pem"));
    std::fs::write(&cert_path, cert.cert.pem()).unwrap();
    std::fs::write(&key_path, cert.signing_key.serialize_pem()).unwrap();
    let mut cfg = config();
    cfg.tls_cert = Some(cert_path);
    cfg.tls_key = Some(key_path);
    let server = Server::start(cfg).await.unwrap();
    assert!(server.url().starts_with("https://"));

    let mut roots = rustls::RootCertStore::empty();
    roots.add(cert.cert.der().clone()).unwrap();
    let client = rustls::ClientConfig::builder_with_provider(Arc::new(
        rustls::crypto::ring::default_provider(),
    ))
    .with_safe_default_protocol_versions()
    .unwrap()
    .with_root_certificates(roots)
    .with_no_client_auth();
    let connector = tokio_rustls::TlsConnector::from(Arc::new(client));
    let name = ServerName::try_from("localhost").unwrap();
    let tcp = tokio::net::TcpStream::connect(server.local_addr())
        .await
        .unwrap();
    let tls = connector.connect(name.clone(), tcp).await.unwrap();
    let mut c = connect_on(
        tls,
        &format!("wss://localhost:{}/ws", server.local_addr().port()),
    )
    .await;
    let (welcome, ready) = c.join(TOKEN, "secure").await;
    assert_eq!(welcome["protocol"], 1);
    assert_eq!(ready["role"], "operator");

    // a plain-text client gets nothing useful from a TLS port
    let tcp = tokio::net::TcpStream::connect(server.local_addr())
        .await
        .unwrap();
    let url = format!("ws://{}/ws", server.local_addr());
    let mut req = tokio_tungstenite::tungstenite::client::IntoClientRequest::into_client_request(
        url.as_str(),
    )
    .unwrap();
    req.headers_mut()
        .insert("sec-websocket-protocol", "spinvalence.v1".parse().unwrap());
    assert!(tokio_tungstenite::client_async(req, tcp).await.is_err());
    server.shutdown().await;
}

#[tokio::test]
async fn a_twenty_thousand_unit_frame_comes_in_pages() {
    let mut cfg = config();
    cfg.frame = big_frame(200, 100);
    let server = Server::start(cfg).await.unwrap();
    let mut c = connect(&server).await;
    c.join(TOKEN, "w").await;
    c.send(json!({"type": "get_targets", "frame": "model"}))
        .await;
    let mut seen = 0;
    let mut pages = 0;
    let mut largest = 0;
    while seen < 20_000 {
        let msg = match c.ws.next().await {
            Some(Ok(Message::Text(t))) => t,
            other => panic!("after {seen} units: {other:?}"),
        };
        largest = largest.max(msg.len());
        let v: Value = serde_json::from_str(msg.as_str()).unwrap();
        validate(&v);
        assert_eq!(v["type"], "targets");
        assert_eq!(v["offset"], seen, "pages in order, none skipped");
        assert_eq!(v["total"], 20_000);
        let units = v["units"].as_array().unwrap();
        assert_eq!(
            units[0]["id"],
            format!("A{:03}-{:03}", seen / 200, seen % 200)
        );
        seen += units.len();
        pages += 1;
    }
    assert_eq!(seen, 20_000);
    assert!(pages > 1);
    assert!(
        largest <= sv_stream::protocol::MAX_PAGE_BYTES,
        "page of {largest} bytes"
    );
    // the connection is still up and answers in order
    c.send(json!({"type": "ping", "t": 5})).await;
    assert_eq!(c.expect("pong").await["t"], 5);
    server.shutdown().await;
}

#[tokio::test]
async fn undo_takes_back_a_complete_for_everyone() {
    let server = Server::start(config()).await.unwrap();
    let mut a = connect(&server).await;
    let mut b = connect(&server).await;
    let (_, ready) = a.join(TOKEN, "welder-a").await;
    b.join(TOKEN, "welder-b").await;
    let u = ready["snapshot"]["next"].as_str().unwrap().to_string();
    a.send(json!({"type": "complete", "unit": u, "op_id": "op-1"}))
        .await;
    a.expect("progress").await;
    a.expect("ack").await;
    b.expect("progress").await;
    b.send(json!({"type": "undo", "unit": u, "op_id": "op-1"}))
        .await;
    assert_eq!(b.expect("error").await["code"], "not_undoable");
    a.send(json!({"type": "undo", "unit": u, "op_id": "op-1"}))
        .await;
    let ev = a.expect("reopened").await;
    assert_eq!(
        (ev["done"].clone(), ev["next"].clone()),
        (json!(0), json!(u))
    );
    let ack = a.expect("ack").await;
    assert_eq!(
        (ack["op"].clone(), ack["applied"].clone()),
        (json!("undo"), json!(true))
    );
    assert_eq!(b.expect("reopened").await["seq"], ev["seq"]);
    // the unit can be completed again with a new op id
    b.send(json!({"type": "complete", "unit": u, "op_id": "op-2"}))
        .await;
    assert_eq!(b.expect("progress").await["done"], 1);
    server.shutdown().await;
}

#[tokio::test]
async fn hostile_numbers_get_errors_or_valid_checks() {
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    c.join(TOKEN, "w").await;
    let id = frame().units[3].id.clone();
    let exact = pose_json(&target(3));
    // a huge quaternion of the same rotation is the same rotation, not 0 degrees of anything
    let turned = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 10f64.to_radians())
        * target(3).rotation;
    let q = turned.coords;
    let big: Vec<f64> = [q.x, q.y, q.z, q.w].iter().map(|v| v * 1e300).collect();
    c.send(json!({"type": "track", "unit": id, "part": "hub", "pose": {"position": exact["position"], "rotation": big}})).await;
    let ch = c.expect("check").await;
    approx(&ch["angle_error_deg"], 10.0, 1e-6);
    assert_eq!(ch["ok"], false);
    // far away: a finite error (validated as a number), never null
    c.send(json!({"type": "track", "unit": id, "part": "hub", "pose": {"position": [1e308, 1e308, 1e308], "rotation": exact["rotation"]}})).await;
    let ch = c.expect("check").await;
    assert!(ch["position_error_mm"].as_f64().unwrap() > 1e308);
    assert_eq!(ch["ok"], false);
    c.send(json!({"type": "register", "points": [[[0, 0, 0], [1e308, 1e308, 1e308]], [[1000, 0, 0], [-1e308, 1e308, 0]], [[0, 1000, 0], [1e308, -1e308, 1e308]]]})).await;
    assert_eq!(c.expect("error").await["code"], "degenerate");
    c.send(json!({"type": "overlap", "units": [frame().units[0].id, frame().units[1].id], "measured_mm": 1e300})).await;
    assert_eq!(c.expect("error").await["code"], "bad_message");
    server.shutdown().await;
}

#[tokio::test]
async fn wrong_tokens_are_throttled_per_address_and_short_tokens_refused() {
    // no try comes back while the test runs, however slowly (by default one every 2 s): the
    // sixth is refused on any machine
    let mut cfg = config();
    cfg.address_limits.auth_per_second = 1.0 / (100.0 * WAIT.as_secs_f64());
    let server = Server::start(cfg).await.unwrap();
    for k in 0..5 {
        let mut c = connect(&server).await;
        c.expect("welcome").await;
        c.send(json!({"type": "hello", "token": format!("guess-{k}")}))
            .await;
        assert_eq!(c.expect("error").await["code"], "unauthorized");
        assert_eq!(c.closed().await, Some(4401));
    }
    // the sixth try from 127.0.0.1 is refused unread, even with the right token
    let mut c = connect(&server).await;
    c.expect("welcome").await;
    c.send(json!({"type": "hello", "token": TOKEN})).await;
    let e = c.expect("error").await;
    assert_eq!(e["code"], "throttled");
    assert_eq!(c.closed().await, Some(4429));
    // another address is not affected
    let mut d = connect_from(&server, [127, 0, 0, 2]).await;
    let (_, ready) = d.join(TOKEN, "other").await;
    assert_eq!(ready["role"], "operator");
    let stats = server.stats();
    assert_eq!((stats.auth_failures, stats.auth_throttled), (5, 1));
    server.shutdown().await;

    let mut cfg = config();
    cfg.token = Some("OPER".into());
    let err = Server::start(cfg).await.err().unwrap().to_string();
    assert!(err.contains("at least 12"), "{err}");
}

#[tokio::test]
async fn junk_before_hello_cannot_keep_a_connection_pending() {
    let server = Server::start(config()).await.unwrap();
    let mut c = connect(&server).await;
    c.expect("welcome").await;
    let mut errors = 0;
    for _ in 0..40 {
        if c.ws.send(Message::text("junk")).await.is_err() {
            break;
        }
    }
    let code = loop {
        match c.try_recv(WAIT).await {
            Some(Ok(m)) => {
                assert_eq!(m["type"], "error");
                errors += 1;
            }
            Some(Err(code)) => break code,
            None => panic!("still open"),
        }
    };
    assert_eq!(code, Some(4408));
    assert!(errors <= 16, "{errors} errors before the close");
    server.shutdown().await;
}

#[tokio::test]
async fn every_acknowledged_event_is_fsynced_first() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg = config();
    cfg.state_path = Some(dir.path().join("state.sqlite"));
    let server = Server::start(cfg).await.unwrap();
    let mut c = connect(&server).await;
    c.join(TOKEN, "w").await;
    let before = server.stats().event_fsyncs;
    for k in 0..5 {
        let u = frame().units[k].id.clone();
        c.send(json!({"type": "complete", "unit": u, "op_id": format!("op-{k}")}))
            .await;
        c.expect("progress").await;
        c.expect("ack").await;
        // the ack left after the fsync: the counter already has it
        assert_eq!(server.stats().event_fsyncs, before + k as u64 + 1);
    }
    // a replayed op id stores nothing and syncs nothing
    c.send(json!({"type": "complete", "unit": frame().units[0].id, "op_id": "op-0"}))
        .await;
    assert_eq!(c.expect("ack").await["applied"], false);
    assert_eq!(server.stats().event_fsyncs, before + 5);
    server.shutdown().await;
}

#[tokio::test]
async fn a_full_disk_is_an_error_and_a_count_never_a_silent_drop() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("state.sqlite");
    let mut cfg = config();
    cfg.state_path = Some(path.clone());
    // first run: create the file, learn its size in pages
    Server::start(cfg.clone()).await.unwrap().shutdown().await;
    let pages: u64 = rusqlite::Connection::open(&path)
        .unwrap()
        .query_row("PRAGMA page_count", [], |r| r.get(0))
        .unwrap();
    cfg.state_max_pages = Some(pages);
    let server = Server::start(cfg).await.unwrap();
    let mut c = connect(&server).await;
    c.join(TOKEN, "w").await;
    let u = frame().units[0].id.clone();
    // a long op id and many tracks fill the capped file
    let mut internal = 0;
    for k in 0..40 {
        let op_id = format!("{k}-{}", "x".repeat(120));
        c.send(json!({"type": "complete", "unit": frame().units[k % 36].id, "op_id": op_id}))
            .await;
        loop {
            let m = c.recv().await;
            match m["type"].as_str().unwrap() {
                "error" if m["code"] == "internal" => {
                    internal += 1;
                    break;
                }
                "ack" | "error" => break,
                _ => {}
            }
        }
        if internal > 0 {
            break;
        }
    }
    assert!(internal > 0, "the capped file never filled");
    let stats = server.stats();
    assert!(stats.store_errors >= 1, "{stats:?}");
    // tracks still get their checks; the measurements that could not be written are an
    // error to this client and a count
    let pose = pose_json(&target(0));
    let mut failed_reported = false;
    for i in 0..40 {
        c.send(json!({"type": "track", "unit": u, "part": "hub", "pose": pose, "ref": i}))
            .await;
    }
    let mut checks = 0;
    // until every track is checked and the loss reported (not until a pause)
    while checks < 40 || !failed_reported {
        let Some(Ok(m)) = c.try_recv(WAIT).await else {
            break;
        };
        match m["type"].as_str().unwrap() {
            "check" => checks += 1,
            "error" => {
                assert_eq!(m["code"], "internal");
                assert!(m["message"]
                    .as_str()
                    .unwrap()
                    .contains("could not be stored"));
                failed_reported = true;
            }
            _ => {}
        }
    }
    assert_eq!(checks, 40);
    assert!(failed_reported, "no error for the lost measurements");
    assert!(server.stats().measurements_failed > 0);
    server.shutdown().await;
}
