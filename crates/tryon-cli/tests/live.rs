//! `tryon view --demo` live (issue 25, items 2 and 3): the scene streams frames over the
//! WebSocket, a grab and a drag move the grabbed particle to the hand's target, letting go frees
//! it, and garbage gets error messages without stopping the scene; a fold line (P3) builds the
//! scene again with the fold; in headless Chromium a line drawn on the garment does the same, and
//! a press and drag on the garment moves the cloth, with each drag's time to the frame that
//! applied it written to target/viewer-screenshots/live-latency.json for a person to read.

use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::{Message, WebSocket};

const TRYON: &str = env!("CARGO_BIN_EXE_tryon");

struct Server(Child);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts `tryon view --demo` on a free port; returns it and its address (host:port).
fn serve_demo() -> (Server, String) {
    let mut child = Command::new(TRYON)
        .args(["view", "--demo", "--port", "0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert!(line.contains("live"), "{line}");
    let url = line.split_whitespace().find(|w| w.starts_with("http://"));
    let host = url.unwrap_or_else(|| panic!("no address in {line:?}"));
    (
        Server(child),
        host.trim_start_matches("http://")
            .trim_end_matches('/')
            .to_string(),
    )
}

type Socket = WebSocket<TcpStream>;

fn connect(host: &str) -> Socket {
    let stream = TcpStream::connect(host).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    let (ws, _) = tungstenite::client(format!("ws://{host}/api/live"), stream).unwrap();
    ws
}

/// A frame as the page reads it: its number, ack, grabbed particle and coarse positions.
struct Frame {
    frame: u32,
    ack: u32,
    grabbed: i32,
    coarse: Vec<[f32; 3]>,
}

struct Counts {
    body: usize,
    coarse: usize,
    garment: usize,
}

fn frame(bytes: &[u8], c: &Counts) -> Frame {
    let points = c.body + c.coarse + c.garment;
    assert_eq!(
        bytes.len(),
        32 + 12 * points + c.garment.next_multiple_of(4),
        "frame size"
    );
    let u = |k: usize| u32::from_le_bytes(bytes[4 * k..4 * k + 4].try_into().unwrap());
    let f = |k: usize| f32::from_le_bytes(bytes[4 * k..4 * k + 4].try_into().unwrap());
    assert_eq!(u(0), 1);
    let first = 8 + 3 * c.body;
    Frame {
        frame: u(1),
        ack: u(2),
        grabbed: u(3) as i32,
        coarse: (0..c.coarse)
            .map(|i| [f(first + 3 * i), f(first + 3 * i + 1), f(first + 3 * i + 2)])
            .collect(),
    }
}

/// The next message: a frame, or a text answer.
fn next(ws: &mut Socket, c: &Counts) -> Result<Frame, serde_json::Value> {
    loop {
        match ws.read().unwrap() {
            Message::Binary(b) => return Ok(frame(&b, c)),
            Message::Text(t) => return Err(serde_json::from_str(t.as_str()).unwrap()),
            _ => continue,
        }
    }
}

fn next_frame(ws: &mut Socket, c: &Counts) -> Frame {
    loop {
        if let Ok(f) = next(ws, c) {
            return f;
        }
    }
}

fn next_answer(ws: &mut Socket, c: &Counts) -> serde_json::Value {
    loop {
        if let Err(a) = next(ws, c) {
            return a;
        }
    }
}

#[test]
fn a_live_demo_streams_frames_follows_a_drag_and_answers_garbage() {
    let (_server, host) = serve_demo();
    let mut ws = connect(&host);
    let Message::Text(h) = ws.read().unwrap() else {
        panic!("the header comes first")
    };
    let h: serde_json::Value = serde_json::from_str(h.as_str()).unwrap();
    assert_eq!(h["type"], "header");
    let n = |m: &str| h["header"][m]["vertices"].as_u64().unwrap() as usize;
    let c = Counts {
        body: n("body"),
        coarse: n("coarse"),
        garment: n("garment"),
    };
    assert!(c.coarse > 100 && c.garment > c.coarse, "the demo refines");
    let f0 = next_frame(&mut ws, &c);
    let f1 = next_frame(&mut ws, &c);
    assert!(f1.frame > f0.frame && f1.grabbed == -1);

    // Grab a hem particle (the lowest), lift it 0.15 m and pull it 0.1 m out over 10 frames.
    let (k, p) = (f1.coarse.iter().enumerate())
        .min_by(|a, b| a.1[1].total_cmp(&b.1[1]))
        .map(|(k, p)| (k, *p))
        .unwrap();
    let send =
        |ws: &mut Socket, v: serde_json::Value| ws.send(Message::text(v.to_string())).unwrap();
    send(
        &mut ws,
        serde_json::json!({"type": "grab", "point": p, "seq": 1}),
    );
    let a = next_answer(&mut ws, &c);
    assert_eq!(
        (a["type"].as_str(), a["particle"].as_u64()),
        (Some("grabbed"), Some(k as u64)),
        "{a}"
    );
    let target = [p[0], p[1] + 0.15, p[2] + 0.1];
    let mut last = f1;
    for s in 2..12u32 {
        let t = |i: usize| p[i] + (target[i] - p[i]) * (s - 1) as f32 / 10.0;
        send(
            &mut ws,
            serde_json::json!({"type": "drag", "target": [t(0), t(1), t(2)], "seq": s}),
        );
        loop {
            last = next_frame(&mut ws, &c);
            if last.ack >= s {
                break;
            }
        }
    }
    // The frame after the last drag's ack has the particle at the target.
    let f = next_frame(&mut ws, &c);
    assert_eq!(f.grabbed, k as i32);
    let gap = (0..3)
        .map(|i| (f.coarse[k][i] - target[i]).powi(2))
        .sum::<f32>()
        .sqrt();
    assert!(gap < 1e-3, "the grabbed particle is {gap} m from the hand");
    assert!(last.ack == 11);

    send(&mut ws, serde_json::json!({"type": "release", "seq": 12}));
    let mut freed = next_frame(&mut ws, &c);
    while freed.ack < 12 {
        freed = next_frame(&mut ws, &c);
    }
    assert_eq!(freed.grabbed, -1);
    let before = freed.coarse[k][1];
    let later = (0..15).map(|_| next_frame(&mut ws, &c)).last().unwrap();
    assert!(
        later.coarse[k][1] < before - 0.02,
        "let go, the hem falls back"
    );

    // Garbage: each gets an error naming what is wrong, and frames go on.
    let errors = [
        ("not json", "bad message"),
        (r#"{"type":"jump"}"#, "unknown variant `jump`"),
        (
            r#"{"type":"drag","target":[1,"x",3],"seq":1}"#,
            "bad message",
        ),
        (
            r#"{"type":"drag","target":[1e300,0,0],"seq":1}"#,
            "`target`",
        ),
        (
            r#"{"type":"grab","point":[0,99,0],"seq":1}"#,
            "no cloth within",
        ),
    ];
    for (text, says) in errors {
        ws.send(Message::text(text)).unwrap();
        let a = next_answer(&mut ws, &c);
        assert_eq!(a["type"], "error");
        assert!(a["message"].as_str().unwrap().contains(says), "{text}: {a}");
    }
    ws.send(Message::text("x".repeat(5000))).unwrap();
    assert!(
        next_answer(&mut ws, &c)["message"]
            .as_str()
            .unwrap()
            .contains("at most 4096")
    );
    ws.send(Message::binary(vec![1u8, 2, 3])).unwrap();
    assert!(
        next_answer(&mut ws, &c)["message"]
            .as_str()
            .unwrap()
            .contains("binary")
    );
    let more = next_frame(&mut ws, &c);
    assert!(more.frame > later.frame);
    // Over 64 KiB: the connection is closed, and the server serves the next one.
    let _ = ws.send(Message::text("y".repeat(100_000)));
    let start = Instant::now();
    while ws.read().is_ok() && start.elapsed() < Duration::from_secs(10) {}
    let mut again = connect(&host);
    assert!(
        matches!(again.read().unwrap(), Message::Text(_)),
        "a new page gets the header"
    );
    // A foreign origin cannot open the socket.
    let stream = TcpStream::connect(&host).unwrap();
    let req = tungstenite::handshake::client::Request::builder()
        .uri(format!("ws://{host}/api/live"))
        .header("Host", host.as_str())
        .header("Origin", "http://evil.example")
        .header("Connection", "Upgrade")
        .header("Upgrade", "websocket")
        .header("Sec-WebSocket-Version", "13")
        .header(
            "Sec-WebSocket-Key",
            tungstenite::handshake::client::generate_key(),
        )
        .body(())
        .unwrap();
    assert!(tungstenite::client(req, stream).is_err(), "refused");
}

#[test]
fn a_drag_in_chromium_moves_the_cloth_and_its_frames_come_back() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let viewer = root.join("tools/viewer");
    let ok = Path::new("/usr/bin/chromium").exists()
        && viewer.join("node_modules/playwright-core").is_dir();
    assert!(
        ok || std::env::var_os("TRYON_REQUIRE_BROWSER").is_none(),
        "TRYON_REQUIRE_BROWSER is set and Chromium or tools/viewer's npm packages are missing"
    );
    if !ok {
        eprintln!("skipping: no Chromium or no tools/viewer/node_modules (npm ci there)");
        return;
    }
    let (_server, host) = serve_demo();
    let shots = root.join("target/viewer-screenshots");
    let out = Command::new("node")
        .arg(viewer.join("test/live.mjs"))
        .arg(format!("http://{host}/"))
        .arg(&shots)
        .current_dir(&viewer)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value =
        serde_json::from_str(text.trim()).unwrap_or_else(|e| panic!("{e}: {text}"));
    assert_eq!(r["errors"], serde_json::json!([]), "console errors: {r}");
    assert_eq!(r["page_errors"], serde_json::json!([]));
    assert_eq!(r["live"], true);
    assert!(
        r["grabbed"].as_i64().unwrap() >= 0,
        "the press grabbed the cloth: {r}"
    );
    let at = |k: &str| -> Vec<f64> {
        r[k].as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (from, to) = (at("grabbed_from"), at("grabbed_to"));
    let moved = (0..3)
        .map(|i| (to[i] - from[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(moved > 0.1, "the drag moved the grabbed point {moved} m");
    assert_eq!(r["after_release"], -1, "letting go frees it");
    let mut lat: Vec<f64> = r["latencies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(lat.len() >= 20, "drags that came back: {}", lat.len());
    lat.sort_by(f64::total_cmp);
    let q = |p: f64| lat[((lat.len() - 1) as f64 * p).round() as usize];
    let report = serde_json::json!({
        "drags": lat.len(), "median_ms": q(0.5), "p95_ms": q(0.95), "max_ms": q(1.0),
        "scene_fps": r["scene_fps"], "page_pictures_per_s": r["fps"], "pixel_ratio": r["pixel_ratio"],
    });
    eprintln!("live drag to frame: {report}");
    std::fs::write(shots.join("live-latency.json"), report.to_string()).unwrap();
    // The drawn fold (P3): the scene was built again with it and the page started over on
    // meshes the line subdivided.
    let fold = &r["fold"];
    assert!(
        fold["after"].as_u64().unwrap() > fold["before"].as_u64().unwrap(),
        "a fold drawn in the page: {fold} ({})",
        r["fold_status"]
    );
    let garbage = r["garbage"]["answers"].as_array().unwrap();
    assert_eq!(garbage.len(), 7, "one error per bad message: {garbage:?}");
    assert!(
        r["frames_after_garbage"].as_u64().unwrap() > 10,
        "the scene goes on"
    );
}

/// The garment's positions in a frame message.
fn garment_of(bytes: &[u8], c: &Counts) -> Vec<[f32; 3]> {
    let f = |k: usize| f32::from_le_bytes(bytes[4 * k..4 * k + 4].try_into().unwrap());
    let first = 8 + 3 * (c.body + c.coarse);
    (0..c.garment)
        .map(|i| [f(first + 3 * i), f(first + 3 * i + 1), f(first + 3 * i + 2)])
        .collect()
}

fn counts_of(h: &serde_json::Value) -> Counts {
    let n = |m: &str| h["header"][m]["vertices"].as_u64().unwrap() as usize;
    Counts {
        body: n("body"),
        coarse: n("coarse"),
        garment: n("garment"),
    }
}

#[test]
fn a_fold_drawn_live_builds_the_scene_again_with_it() {
    let (_server, host) = serve_demo();
    let mut ws = connect(&host);
    ws.get_mut()
        .set_read_timeout(Some(Duration::from_secs(300)))
        .unwrap();
    let Message::Text(h) = ws.read().unwrap() else {
        panic!("the header comes first")
    };
    let c = counts_of(&serde_json::from_str(h.as_str()).unwrap());
    let garment = loop {
        if let Message::Binary(b) = ws.read().unwrap() {
            break garment_of(&b, &c);
        }
    };
    // A line down the front of the dress, slanting off the middle (a line along a column of the
    // mesh's vertices crosses no edge between them and adds none): in three bands of its height,
    // the front-most vertex a little farther to the side each time.
    let (lo, hi) = garment
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), p| (l.min(p[1]), h.max(p[1])));
    let line: Vec<[f32; 3]> = [(0.35f32, 0.03f32), (0.45, 0.06), (0.55, 0.09)]
        .iter()
        .map(|&(t, x)| {
            let y = lo + (hi - lo) * t;
            *garment
                .iter()
                .filter(|p| (p[1] - y).abs() < 0.02 && (p[0] - x).abs() < 0.015)
                .max_by(|a, b| a[2].total_cmp(&b[2]))
                .unwrap()
        })
        .collect();
    let fold = |points: &[[f32; 3]], seq: u32| {
        serde_json::json!({"type": "fold", "shape": "ridge", "height": 0.015, "points": points, "seq": seq})
            .to_string()
    };
    // Off the garment: the scene's own check says so, and the scene goes on as it was.
    let far: Vec<[f32; 3]> = line.iter().map(|p| [p[0], p[1], p[2] + 0.5]).collect();
    ws.send(Message::text(fold(&far, 1))).unwrap();
    let a = next_answer(&mut ws, &c);
    assert_eq!(a["type"], "error", "{a}");
    assert!(
        a["message"]
            .as_str()
            .unwrap()
            .starts_with("the drawn fold:"),
        "{a}"
    );
    ws.send(Message::text(fold(&line, 2))).unwrap();
    let (mut folded, mut header) = (false, None);
    while !(folded && header.is_some()) {
        match ws.read().unwrap() {
            Message::Text(t) => {
                let m: serde_json::Value = serde_json::from_str(t.as_str()).unwrap();
                match m["type"].as_str() {
                    Some("folded") => folded = true,
                    Some("header") => header = Some(counts_of(&m)),
                    _ => panic!("{m}"),
                }
            }
            _ => continue,
        }
    }
    let c2 = header.unwrap();
    assert!(
        c2.coarse > c.coarse,
        "the line subdivided the cloth: {} -> {}",
        c.coarse,
        c2.coarse
    );
    // Frames of the new scene follow, at its sizes.
    let f = loop {
        if let Message::Binary(b) = ws.read().unwrap() {
            if b.len()
                == 32 + 12 * (c2.body + c2.coarse + c2.garment) + c2.garment.next_multiple_of(4)
            {
                break frame(&b, &c2);
            }
        }
    };
    assert!(f.frame >= 1);
}
