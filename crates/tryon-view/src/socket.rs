//! The live server's routes: the page, `/api/run` saying the run is live, and the WebSocket at
//! `/api/live` that streams frames out and takes the page's requests in ([`crate::live`]).
//! Every route first checks the request's `Host` (and a WebSocket's `Origin`) names this
//! machine's loopback, so a page from elsewhere cannot steer the scene or read it through a
//! rebound name.

use crate::live::{Command, Hub, MAX_FRAME, Request};
use axum::Router;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Request as HttpRequest, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use futures_util::{SinkExt, StreamExt};
use std::sync::Arc;
use tokio::sync::broadcast::error::RecvError;

/// Whether a `Host` or `Origin` value names loopback (`127.0.0.1`, `localhost`, `[::1]`, any port).
pub fn loopback_name(value: &str) -> bool {
    let v = value
        .trim_start_matches("http://")
        .trim_start_matches("https://");
    let host = match v.strip_prefix('[') {
        Some(rest) => rest.split(']').next().unwrap_or(""),
        None => v.split(':').next().unwrap_or(""),
    };
    matches!(host, "127.0.0.1" | "localhost" | "::1")
}

/// Refuses requests whose `Host` (or `Origin`, when there is one) is not loopback.
pub async fn loopback_only(req: HttpRequest, next: Next) -> Response {
    let ok = |h: &HeaderMap, k| h.get(k).and_then(|v| v.to_str().ok()).map(loopback_name);
    let headers = req.headers();
    if ok(headers, header::HOST) != Some(true) || ok(headers, header::ORIGIN) == Some(false) {
        return (
            StatusCode::FORBIDDEN,
            "tryon view answers only requests to 127.0.0.1 or localhost\n",
        )
            .into_response();
    }
    next.run(req).await
}

/// The live server's routes over `hub`.
pub fn live_router(hub: Arc<Hub>, name: String) -> Router {
    let run = serde_json::json!({ "live": true, "stats": { "scene": name } }).to_string();
    crate::page_routes()
        .route(
            "/api/run",
            get(move || async move { crate::typed("application/json", run) }),
        )
        .route("/api/live", get(upgrade))
        .with_state(hub)
        .layer(middleware::from_fn(loopback_only))
}

async fn upgrade(ws: WebSocketUpgrade, State(hub): State<Arc<Hub>>) -> Response {
    ws.max_message_size(MAX_FRAME)
        .max_frame_size(MAX_FRAME)
        .on_upgrade(move |socket| session(socket, hub))
}

/// One page's connection: the header, then frames as they come (a page too slow for them skips
/// some) and answers, while its requests go to the scene.
async fn session(socket: WebSocket, hub: Arc<Hub>) {
    let (mut out, mut input) = socket.split();
    let header = match hub.out.header.read() {
        Ok(h) => crate::live::header_message(&h),
        Err(_) => return,
    };
    if out.send(Message::Text(header.into())).await.is_err() {
        return;
    }
    let (reply, mut answers) = tokio::sync::mpsc::unbounded_channel::<String>();
    let mut frames = hub.out.frames.subscribe();
    let writer = tokio::spawn(async move {
        loop {
            let m = tokio::select! {
                f = frames.recv() => match f {
                    Ok(m) => m,
                    Err(RecvError::Lagged(_)) => continue,
                    Err(RecvError::Closed) => break,
                },
                a = answers.recv() => match a {
                    Some(text) => Message::Text(text.into()),
                    None => break,
                },
            };
            if out.send(m).await.is_err() {
                break;
            }
        }
        let _ = out.close().await;
    });
    while let Some(m) = input.next().await {
        let text = match m {
            Ok(Message::Text(t)) => t,
            Ok(Message::Binary(_)) => {
                let _ = reply.send(error_text("binary messages are not taken; send JSON text"));
                continue;
            }
            Ok(Message::Close(_)) => break,
            Ok(_) => continue,
            Err(e) => {
                // Over MAX_FRAME, or not WebSocket at all: said, then the connection ends.
                let _ = reply.send(error_text(&format!("{e}; the connection is closed")));
                break;
            }
        };
        match Request::parse(text.as_str()) {
            Ok(request) => {
                let c = Command {
                    request,
                    reply: reply.clone(),
                };
                if hub.commands.send(c).is_err() {
                    let _ = reply.send(error_text("the scene has stopped"));
                    break;
                }
            }
            Err(m) => {
                let _ = reply.send(error_text(&m));
            }
        }
    }
    drop(reply);
    // The writer ends once the answers channel is empty and closed, after the last error is sent.
    let abort = writer.abort_handle();
    if tokio::time::timeout(std::time::Duration::from_secs(1), writer)
        .await
        .is_err()
    {
        abort.abort();
    }
}

/// An error message to the page.
fn error_text(message: &str) -> String {
    serde_json::json!({ "type": "error", "message": message }).to_string()
}

#[cfg(test)]
mod tests {
    use super::loopback_name;

    #[test]
    fn only_loopback_names_pass() {
        for ok in [
            "127.0.0.1:8737",
            "localhost",
            "http://localhost:1",
            "[::1]:80",
            "http://127.0.0.1",
        ] {
            assert!(loopback_name(ok), "{ok}");
        }
        for bad in [
            "evil.example",
            "127.0.0.1.evil.example",
            "localhost.evil:80",
            "http://10.0.0.1",
            "",
            "[::2]:1",
        ] {
            assert!(!loopback_name(bad), "{bad}");
        }
    }
}
