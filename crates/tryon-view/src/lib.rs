//! tryon-view: `tryon view DIR`, a web server on loopback that serves a finished run to a page
//! built on three.js. The page and its bundle (three.js and the viewer's code, bundled by esbuild
//! from tools/viewer, `cargo xtask viewer`) are compiled into the binary, so it works offline.
//!
//! Routes: `/` the page, `/viewer.js` its bundle, `/api/run` the run's figures (stats.json, and
//! its per-frame figures), `/api/view.bin` the frames (view.bin, checked before serving).
//! Everything else is 404; only GET is answered. `tryon view SCENE` runs the scene live instead
//! ([`live`], [`serve_live`]): `/api/live` is then a WebSocket streaming its frames and taking
//! the page's grabs and drags. Both answer only requests addressed to loopback.

pub mod live;
pub mod socket;

use axum::Router;
use axum::body::Bytes;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use std::net::{Ipv4Addr, SocketAddr};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use thiserror::Error;

/// The page.
pub const INDEX_HTML: &str = include_str!("../assets/index.html");
/// three.js and the viewer's code in one ES module.
pub const VIEWER_JS: &str = include_str!("../assets/viewer.js");
/// The largest view.bin served (it is held in memory).
const MAX_VIEW_BYTES: u64 = 2 << 30;

/// Why a run cannot be viewed.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ViewError {
    #[error("{}: not a run's folder: it has no view.bin (runs write it unless `[output] view = false`)", .0.display())]
    NoView(PathBuf),
    #[error("{}: {bytes} bytes; the viewer holds at most {MAX_VIEW_BYTES} (write fewer frames: `[output] view_every`)", path.display())]
    TooBig { path: PathBuf, bytes: u64 },
    #[error(transparent)]
    View(#[from] tryon_io::CacheError),
    #[error("{}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot listen on 127.0.0.1:{port}: {source}")]
    Listen { port: u16, source: std::io::Error },
    #[error("the server stopped: {0}")]
    Server(std::io::Error),
}

/// A finished run, read and checked, ready to serve.
#[derive(Debug)]
pub struct RunFiles {
    view: Bytes,
    run: Bytes,
    pub frames: u64,
    pub name: String,
}

impl RunFiles {
    /// Reads the run in `dir`: view.bin (checked whole) and stats.json (when there is one).
    pub fn read(dir: &Path) -> Result<RunFiles, ViewError> {
        let path = dir.join("view.bin");
        if !path.is_file() {
            return Err(ViewError::NoView(dir.to_path_buf()));
        }
        let (header, frames) = tryon_io::read_view_header(&path)?;
        let len = std::fs::metadata(&path)
            .map_err(|source| ViewError::Read {
                path: path.clone(),
                source,
            })?
            .len();
        if len > MAX_VIEW_BYTES {
            return Err(ViewError::TooBig { path, bytes: len });
        }
        let view = std::fs::read(&path).map_err(|source| ViewError::Read {
            path: path.clone(),
            source,
        })?;
        let stats: serde_json::Value = std::fs::read_to_string(dir.join("stats.json"))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or(serde_json::Value::Null);
        let per_frame = stats.get("per_frame").cloned().unwrap_or_default();
        let frame_ms = stats.get("frame_ms").cloned().unwrap_or_default();
        let run =
            serde_json::json!({ "stats": stats, "per_frame": per_frame, "frame_ms": frame_ms });
        Ok(RunFiles {
            view: Bytes::from(view),
            run: Bytes::from(serde_json::to_vec(&run).unwrap_or_default()),
            frames,
            name: header.name,
        })
    }
}

/// The page and its bundle.
pub(crate) fn page_routes<S: Clone + Send + Sync + 'static>() -> Router<S> {
    Router::new()
        .route(
            "/",
            get(|| async { typed("text/html; charset=utf-8", INDEX_HTML) }),
        )
        .route(
            "/viewer.js",
            get(|| async { typed("text/javascript; charset=utf-8", VIEWER_JS) }),
        )
        .fallback(|| async { (StatusCode::NOT_FOUND, "no such page\n") })
}

/// The server's routes over `files`.
pub fn router(files: RunFiles) -> Router {
    let files = Arc::new(files);
    let (run, view) = (files.clone(), files);
    page_routes()
        .route(
            "/api/run",
            get(move || async move { typed("application/json", run.run.clone()) }),
        )
        .route(
            "/api/view.bin",
            get(move || async move { typed("application/octet-stream", view.view.clone()) }),
        )
        .layer(axum::middleware::from_fn(socket::loopback_only))
}

pub(crate) fn typed(kind: &'static str, body: impl Into<axum::body::Body>) -> Response {
    ([(header::CONTENT_TYPE, kind)], body.into()).into_response()
}

/// Serves `files` on 127.0.0.1:`port` (0: any free port) until the process ends; `ready` is
/// told the address once it listens.
pub fn serve(files: RunFiles, port: u16, ready: impl FnOnce(SocketAddr)) -> Result<(), ViewError> {
    serve_router(router(files), port, ready)
}

/// Runs `sim` live on a thread of its own and serves it on 127.0.0.1:`port` (0: any free port)
/// until the process ends; `ready` is told the address once it listens.
pub fn serve_live(
    sim: Box<dyn live::LiveSim>,
    port: u16,
    ready: impl FnOnce(SocketAddr),
) -> Result<(), ViewError> {
    let header = sim.header();
    let name = header.name.clone();
    let header = serde_json::to_string(&header).unwrap_or_default();
    let (commands, requests) = std::sync::mpsc::channel();
    // A few frames of slack: a page slower than the scene skips frames rather than queueing them.
    let out = live::Outbox {
        frames: tokio::sync::broadcast::channel(4).0,
        header: Arc::new(std::sync::RwLock::new(header)),
    };
    let scene_out = out.clone();
    std::thread::Builder::new()
        .name("tryon-live".into())
        .spawn(move || live::run_scene(sim, requests, scene_out))
        .map_err(ViewError::Server)?;
    let hub = Arc::new(live::Hub { commands, out });
    serve_router(socket::live_router(hub, name), port, ready)
}

fn serve_router(app: Router, port: u16, ready: impl FnOnce(SocketAddr)) -> Result<(), ViewError> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(ViewError::Server)?;
    rt.block_on(async move {
        let listener = tokio::net::TcpListener::bind((Ipv4Addr::LOCALHOST, port))
            .await
            .map_err(|source| ViewError::Listen { port, source })?;
        let addr = listener.local_addr().map_err(ViewError::Server)?;
        ready(addr);
        // Frames go out as soon as they are written (Nagle's wait would hold a frame's tail
        // for the page's acknowledgement).
        let listener = axum::serve::ListenerExt::tap_io(listener, |tcp| {
            let _ = tcp.set_nodelay(true);
        });
        axum::serve(listener, app).await.map_err(ViewError::Server)
    })
}
