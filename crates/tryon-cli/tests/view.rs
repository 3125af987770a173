//! `tryon view DIR` (issue 25, items 1 and 3): the server on loopback answers the page, its bundle
//! and the run's data, refuses what it does not serve without falling over, and the page in a
//! real browser (Debian's headless Chromium driven by playwright-core, tools/viewer/test) draws
//! the garment, scrubs to a frame, and logs no errors. Screenshots land in
//! target/viewer-screenshots for a person to look at.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

const TRYON: &str = env!("CARGO_BIN_EXE_tryon");

struct Server(Child);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts `tryon view dir` on a free port; returns it and its address.
fn serve(dir: &Path) -> (Server, String) {
    let mut child = Command::new(TRYON)
        .args(["view", "--port", "0"])
        .arg(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let url = line.split_whitespace().find(|w| w.starts_with("http://"));
    let url = url
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .to_string();
    (Server(child), url)
}

/// One raw HTTP exchange: the status line and the body.
fn http(addr: &str, request: &[u8]) -> (String, Vec<u8>) {
    let host = addr.trim_start_matches("http://").trim_end_matches('/');
    let mut s = TcpStream::connect(host).unwrap();
    s.write_all(request).unwrap();
    let mut bytes = Vec::new();
    let _ = s.read_to_end(&mut bytes);
    let split = bytes
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .unwrap_or(bytes.len());
    let head = String::from_utf8_lossy(&bytes[..split]).to_string();
    let status = head.lines().next().unwrap_or("").to_string();
    (status, bytes[(split + 4).min(bytes.len())..].to_vec())
}

fn get(addr: &str, path: &str) -> (String, Vec<u8>) {
    let req = format!("GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
    http(addr, req.as_bytes())
}

fn run_demo(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tryon-view-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let ok = Command::new(TRYON)
        .args(["demo", "--quiet", "--frames", "40", "--out"])
        .arg(&dir)
        .status()
        .unwrap();
    assert!(ok.success());
    dir
}

#[test]
fn the_server_answers_its_routes_and_refuses_the_rest() {
    let dir = run_demo("routes");
    let (_server, url) = serve(&dir);
    assert!(url.starts_with("http://127.0.0.1:"), "loopback only: {url}");
    let (status, page) = get(&url, "/");
    assert!(status.contains("200"), "{status}");
    assert!(String::from_utf8_lossy(&page).contains("<script type=\"module\" src=\"/viewer.js\">"));
    let (status, js) = get(&url, "/viewer.js");
    assert!(status.contains("200") && js.len() > 100_000, "{status}");
    let (_, run) = get(&url, "/api/run");
    let run: serde_json::Value = serde_json::from_slice(&run).unwrap();
    // The referee judges every n-th of the 40 frames and the last (`judged_every`).
    let judged = run["stats"]["metrics"]["judged_frames"].as_u64().unwrap() as usize;
    let every = run["stats"]["metrics"]["judged_every"].as_u64().unwrap() as usize;
    assert_eq!(
        judged,
        40 / every + usize::from(40 % every != 0),
        "every {every}"
    );
    assert_eq!(run["per_frame"].as_array().unwrap().len(), judged);
    let ms = run["frame_ms"].as_array().unwrap();
    assert_eq!(ms.len(), judged, "each judged frame's stage times");
    let last = &ms[judged - 1];
    assert!(last["cloth"].as_f64().unwrap() > 0.0, "{last}");
    let (_, view) = get(&url, "/api/view.bin");
    assert_eq!(view, std::fs::read(dir.join("view.bin")).unwrap());
    assert!(get(&url, "/../stats.json").0.contains("404"));
    assert!(get(&url, "/api/nothing").0.contains("404"));
    let post = http(
        &url,
        b"POST /api/run HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 3\r\nConnection: close\r\n\r\nabc",
    );
    assert!(post.0.contains("405"), "{}", post.0);
    // Garbage and an oversized header: an error or a closed connection, and the server goes on.
    let _ = http(&url, b"\x00\x01garbage\r\n\r\n");
    let big = format!(
        "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: {}\r\n\r\n",
        "a".repeat(1 << 20)
    );
    let _ = http(&url, big.as_bytes());
    assert!(get(&url, "/").0.contains("200"), "still serving");
    // A page from elsewhere, or a name rebound to loopback, is refused.
    let foreign = http(
        &url,
        b"GET /api/run HTTP/1.1\r\nHost: evil.example\r\nConnection: close\r\n\r\n",
    );
    assert!(foreign.0.contains("403"), "{}", foreign.0);
    let origin = http(
        &url,
        b"GET /api/run HTTP/1.1\r\nHost: localhost:1\r\nOrigin: http://evil.example\r\nConnection: close\r\n\r\n",
    );
    assert!(origin.0.contains("403"), "{}", origin.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Frame `k`'s garment depths (quarter millimetres) in a view.bin whose header says it has them.
fn depths(bytes: &[u8], k: usize) -> Vec<u8> {
    let n = u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
    let h: serde_json::Value = serde_json::from_slice(&bytes[12..12 + n]).unwrap();
    assert_eq!(h["depth"], true, "the view carries depths");
    let count = |m: &str| h[m]["vertices"].as_u64().unwrap() as usize;
    let garment = count("garment");
    let floats = 1 + 3 * (count("body") + count("coarse") + garment);
    let frame = 4 * floats + garment.next_multiple_of(4);
    let at = 12 + n + k * frame + 4 * floats;
    bytes[at..at + garment].to_vec()
}

#[test]
fn the_view_carries_each_frames_depths_as_the_referee_judged_them() {
    // Without body collision the dress sinks into the mannequin: depths to see.
    let dir = std::env::temp_dir().join(format!("tryon-view-depth-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let ok = Command::new(TRYON)
        .args(["demo", "--quiet", "--frames", "12", "--set"])
        .arg("effects.body_collision=\"none\"")
        .arg("--out")
        .arg(&dir)
        .status()
        .unwrap();
    assert!(ok.success());
    let bytes = std::fs::read(dir.join("view.bin")).unwrap();
    let lines = std::fs::read_to_string(dir.join("frames.jsonl")).unwrap();
    let mut deepest = 0.0f64;
    for line in lines.lines() {
        let f: serde_json::Value = serde_json::from_str(line).unwrap();
        let k = f["frame"].as_u64().unwrap() as usize;
        let judged = f["max_penetration_m"].as_f64().unwrap();
        let max = *depths(&bytes, k).iter().max().unwrap() as f64 / 4000.0;
        // Quarter millimetres, 63.75 mm at most.
        let want = judged.min(63.75e-3);
        assert!(
            (max - want).abs() <= 0.000_125 + 1e-9,
            "frame {k}: view {max}, stats {judged}"
        );
        deepest = deepest.max(judged);
    }
    assert!(deepest > 0.005, "the dress sank in ({deepest} m)");
    assert!(
        depths(&bytes, 0).iter().all(|&d| d == 0),
        "frame 0 is not judged"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_folder_without_a_view_is_named() {
    let dir = std::env::temp_dir().join(format!("tryon-view-none-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(TRYON).arg("view").arg(&dir).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("has no view.bin"), "{err}");
    std::fs::write(dir.join("view.bin"), b"TRYONVW1\x05\x00\x00\x00{}").unwrap();
    let out = Command::new(TRYON).arg("view").arg(&dir).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "a damaged view.bin");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Whether this machine can drive a browser: Chromium, node, and tools/viewer's packages.
fn browser_ready(viewer: &Path) -> bool {
    let ok = Path::new("/usr/bin/chromium").exists()
        && viewer.join("node_modules/playwright-core").is_dir()
        && Command::new("node")
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success());
    assert!(
        ok || std::env::var_os("TRYON_REQUIRE_BROWSER").is_none(),
        "TRYON_REQUIRE_BROWSER is set and Chromium, node or tools/viewer's npm packages are missing"
    );
    ok
}

#[test]
fn the_page_draws_the_garment_scrubs_and_logs_no_errors_in_chromium() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let viewer = root.join("tools/viewer");
    if !browser_ready(&viewer) {
        eprintln!("skipping: no Chromium or no tools/viewer/node_modules (npm ci there)");
        return;
    }
    let dir = run_demo("browser");
    let (_server, url) = serve(&dir);
    let shots = root.join("target/viewer-screenshots");
    let out = Command::new("node")
        .arg(viewer.join("test/browser.mjs"))
        .arg(&url)
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
    eprintln!(
        "viewer: {} frames drawn a second (software GL {}, pixel ratio {})",
        r["fps"], r["software_gl"], r["pixel_ratio"]
    );
    assert_eq!(r["errors"], serde_json::json!([]), "console errors");
    assert_eq!(r["page_errors"], serde_json::json!([]));
    assert!(r["fps"].as_f64().unwrap() > 1.0, "it plays");
    assert_eq!(r["frames"], 41);
    assert_eq!(r["at_first"]["frame"], 0);
    assert_eq!(r["at_middle"]["frame"], 20, "scrubbing shows the frame");
    assert_eq!(r["at_middle"]["playing"], false, "scrubbing pauses");
    // The garment's colour (blue, garment_colour(0), under light) and the body's (skin) are in
    // the picture, and frame 20 is not frame 0.
    let first = pixels(&shots.join("frame-first.png"));
    let middle = pixels(&shots.join("frame-middle.png"));
    assert_eq!(tryon_io::garment_colour(0), [55, 85, 170]);
    let count = |f: &dyn Fn(i32, i32, i32) -> bool| {
        (middle.iter())
            .filter(|p| f(p[0] as i32, p[1] as i32, p[2] as i32))
            .count()
    };
    let blue = count(&|r, g, b| b > r + 50 && b > g + 30);
    let skin = count(&|r, g, b| r > b + 30 && r > g && r > 120);
    assert!(
        blue > 2000 && skin > 2000,
        "garment {blue} and body {skin} pixels"
    );
    let moved = first.iter().zip(&middle).filter(|(a, b)| a != b).count();
    assert!(
        moved > 1000,
        "frame 20 differs from frame 0 ({moved} pixels)"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

fn pixels(path: &Path) -> Vec<[u8; 3]> {
    let d = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = d.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    let step = info.color_type.samples();
    buf[..info.buffer_size()]
        .chunks(step)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}
