//! Live steering (`tryon view SCENE`): a scene runs on its own thread at its frame rate while the
//! page watches and pulls the cloth (P4's drag) over a WebSocket at `/api/live`.
//!
//! The server speaks first: one text message `{"type":"header", "header": <view.bin's header>}`,
//! then one binary message per frame ([`encode_frame`]). The page sends text messages, each a
//! JSON object of at most [`MAX_MESSAGE`] bytes ([`Request`]): `grab` a point on the cloth, `drag`
//! it to a target, `release` it, `play` or pause, or draw a `fold` (P3's interaction: the scene is
//! built again with the fold and starts over, and every page gets the new header). A message the server cannot take gets
//! `{"type":"error","message":...}` naming what was wrong; nothing the page sends stops the
//! server. A drag wakes the scene's thread: the next frame starts once half a frame's time has
//! passed since the last one began, not a whole frame, and while a particle is held a frame
//! waits up to one and a half frames for the next drag (`Steering::gap`), so a drag shows
//! within one frame's work when the pointer moves at about the frame rate (while it keeps
//! moving faster, scene time runs up to twice the wall clock's pace: docs/decisions, *viewer and live*).

use axum::body::Bytes;
use axum::extract::ws::Message;
use serde::Deserialize;
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, RwLock};
use std::time::{Duration, Instant};
use tokio::sync::broadcast;
use tryon_core::math::{Real, Vec3};
use tryon_io::{LiveFrame, ViewHeader, encode_frame};

/// The largest message the page may send (bytes); larger ones get an error message. Messages
/// over [`MAX_FRAME`] close the connection (the WebSocket layer will not read them).
pub const MAX_MESSAGE: usize = 4096;
/// The largest WebSocket message read at all.
pub const MAX_FRAME: usize = 64 * 1024;
/// Farthest a coordinate the page sends may lie from the origin (m).
const MAX_COORDINATE: Real = 1000.0;

/// A scene running live, as the server drives it: one frame at a time, and the user's hand.
pub trait LiveSim: Send + 'static {
    /// What stays the same: the meshes' topology, the name, the frame rate.
    fn header(&self) -> ViewHeader;
    /// Makes the next frame.
    fn step(&mut self) -> LiveFrame;
    /// Work on the frame just sent that may wait for it (judging it for the next frame's
    /// figures).
    fn after_frame(&mut self) {}
    /// Takes the cloth particle nearest `point` into the user's hand; its number, or why none.
    fn grab(&mut self, point: Vec3) -> Result<u32, String>;
    /// Moves the hand's target (it is reached over the next frame).
    fn drag(&mut self, target: Vec3);
    /// Lets go.
    fn release(&mut self);
    /// Builds the scene again with a fold drawn along `points` (on the garment as it is now) and
    /// starts it over; the new header, or what is wrong with the line.
    fn fold(&mut self, line: &FoldLine) -> Result<ViewHeader, String> {
        let _ = line;
        Err("this scene cannot take folds".into())
    }
}

/// A fold line the page drew (P3).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FoldLine {
    /// `ridge` (out of the garment) or `valley` (into it).
    pub shape: String,
    /// How far it stands out or sinks in (m).
    pub height: Real,
    /// The line's points on the garment, in order (m).
    pub points: Vec<[Real; 3]>,
}

/// Most points a drawn fold line may have.
pub const MAX_FOLD_POINTS: usize = 64;

/// What the page may ask.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum Request {
    /// Take the cloth at `point` (m, the scene's frame); `seq` is echoed as the frame's ack.
    Grab { point: [Real; 3], seq: u32 },
    /// Move the hand to `target`.
    Drag { target: [Real; 3], seq: u32 },
    /// Let go.
    Release { seq: u32 },
    /// Run (`on`: true) or pause the scene.
    Play { on: bool },
    /// Draw a fold and build the scene again with it.
    Fold {
        #[serde(flatten)]
        line: FoldLine,
        seq: u32,
    },
}

impl Request {
    /// Reads one message of the page, or says what is wrong with it.
    pub fn parse(text: &str) -> Result<Request, String> {
        if text.len() > MAX_MESSAGE {
            return Err(format!(
                "message of {} bytes; at most {MAX_MESSAGE} are taken",
                text.len()
            ));
        }
        let r: Request = serde_json::from_str(text).map_err(|e| format!("bad message: {e}"))?;
        let far = |p: &[Real; 3]| p.iter().any(|c| !c.is_finite() || c.abs() > MAX_COORDINATE);
        let (key, points) = match &r {
            Request::Grab { point, .. } => ("point", std::slice::from_ref(point)),
            Request::Drag { target, .. } => ("target", std::slice::from_ref(target)),
            Request::Fold { line, .. } => {
                check_fold(line)?;
                ("points", line.points.as_slice())
            }
            _ => return Ok(r),
        };
        if let Some(p) = points.iter().find(|p| far(p)) {
            return Err(format!(
                "`{key}` {p:?}: each coordinate must be finite and within {MAX_COORDINATE} m"
            ));
        }
        Ok(r)
    }

    fn seq(&self) -> Option<u32> {
        match self {
            Request::Grab { seq, .. }
            | Request::Drag { seq, .. }
            | Request::Release { seq }
            | Request::Fold { seq, .. } => Some(*seq),
            Request::Play { .. } => None,
        }
    }
}

/// The checks of a drawn fold the scene's own do not make before building it.
fn check_fold(line: &FoldLine) -> Result<(), String> {
    if line.shape != "ridge" && line.shape != "valley" {
        return Err(format!(
            "fold `shape` {:?}: `ridge` or `valley`",
            line.shape
        ));
    }
    if !(line.height >= 0.001 && line.height <= 0.1) {
        return Err(format!("fold `height` {}: 0.001 to 0.1 m", line.height));
    }
    let n = line.points.len();
    if !(2..=MAX_FOLD_POINTS).contains(&n) {
        return Err(format!(
            "fold `points`: {n}; 2 to {MAX_FOLD_POINTS} are taken"
        ));
    }
    Ok(())
}

/// A request on its way to the scene's thread, with where its answer goes.
#[derive(Debug)]
pub struct Command {
    pub request: Request,
    pub reply: tokio::sync::mpsc::UnboundedSender<String>,
}

/// The scene thread's flags between frames.
#[derive(Debug)]
struct Steering {
    playing: bool,
    /// A drag came since the last frame: the next one is made sooner.
    urgent: bool,
    /// A particle is held: frames wait a little longer for the next drag.
    holding: bool,
    /// The last request's `seq` applied.
    ack: u32,
}

impl Steering {
    /// Time from one frame to the next. A drag's frame goes half a period after the last one, or
    /// at once if that has passed; while a particle is held and no drag has come, the next frame
    /// waits up to one and a half periods for one. Otherwise a frame every period. Frames at a
    /// steady period would fall just before the drags of a pointer moving at about the frame
    /// rate, so each drag would wait up to half a period; waiting for the drag instead makes its
    /// frame at once.
    fn gap(&self, period: Duration) -> Duration {
        match (self.urgent, self.holding) {
            (true, _) => period / 2,
            (false, true) => period * 3 / 2,
            (false, false) => period,
        }
    }

    fn apply(&mut self, sim: &mut dyn LiveSim, c: Command, out: &Outbox) {
        if let Some(s) = c.request.seq() {
            self.ack = s;
        }
        match c.request {
            Request::Grab { point, seq } => {
                let answer = match sim.grab(Vec3::from(point)) {
                    Ok(p) => {
                        self.holding = true;
                        serde_json::json!({"type": "grabbed", "seq": seq, "particle": p})
                    }
                    Err(m) => serde_json::json!({"type": "error", "seq": seq, "message": m}),
                };
                let _ = c.reply.send(answer.to_string());
                self.urgent = true;
            }
            Request::Drag { target, .. } => {
                sim.drag(Vec3::from(target));
                self.urgent = true;
            }
            Request::Release { .. } => {
                sim.release();
                self.holding = false;
            }
            Request::Play { on } => self.playing = on,
            Request::Fold { line, seq } => {
                let answer = match sim.fold(&line) {
                    Ok(h) => {
                        let text = serde_json::to_string(&h).unwrap_or_default();
                        out.publish_header(text);
                        serde_json::json!({"type": "folded", "seq": seq})
                    }
                    Err(m) => serde_json::json!({"type": "error", "seq": seq, "message": m}),
                };
                let _ = c.reply.send(answer.to_string());
            }
        }
    }
}

/// Where the scene's output goes: frames (and new headers) to every page, and the header a page
/// connecting now is sent first.
#[derive(Clone, Debug)]
pub struct Outbox {
    pub frames: broadcast::Sender<Message>,
    pub header: Arc<RwLock<String>>,
}

impl Outbox {
    /// Makes `header` (view.bin's, as JSON) the scene's and tells every page.
    pub fn publish_header(&self, header: String) {
        let text = header_message(&header);
        if let Ok(mut h) = self.header.write() {
            *h = header;
        }
        let _ = self.frames.send(Message::Text(text.into()));
    }
}

/// The message that gives a page the scene's header.
pub fn header_message(header: &str) -> String {
    format!(r#"{{"type":"header","header":{header}}}"#)
}

/// The scene's thread: makes a frame every 1/fps s while playing (sooner after a drag), hands
/// each to `frames`, and applies the page's requests between frames. Returns when every sender
/// of `commands` is gone.
pub fn run_scene(mut sim: Box<dyn LiveSim>, commands: Receiver<Command>, out: Outbox) {
    let fps = sim.header().fps;
    let period = Duration::from_secs_f64(1.0 / if fps > 0.0 { fps } else { 30.0 });
    let mut last = Instant::now() - period;
    let mut st = Steering {
        playing: true,
        urgent: false,
        holding: false,
        ack: 0,
    };
    loop {
        while let Ok(c) = commands.try_recv() {
            st.apply(sim.as_mut(), c, &out);
        }
        let now = Instant::now();
        let due = last + st.gap(period);
        if st.playing && now >= due {
            last = now;
            st.urgent = false;
            let f = sim.step();
            // No one watching is not an error.
            let _ = (out.frames).send(Message::Binary(Bytes::from(encode_frame(&f, st.ack))));
            sim.after_frame();
            continue;
        }
        let wait = match st.playing {
            true => due - now,
            false => Duration::from_secs(3600),
        };
        match commands.recv_timeout(wait) {
            Ok(c) => st.apply(sim.as_mut(), c, &out),
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return,
        }
    }
}

/// Where the sockets reach the scene: its requests' channel and its output.
#[derive(Debug)]
pub struct Hub {
    pub commands: Sender<Command>,
    pub out: Outbox,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_particle_waits_for_its_drag_and_a_drag_goes_soon() {
        let p = Duration::from_millis(30);
        let st = |urgent, holding| Steering {
            playing: true,
            urgent,
            holding,
            ack: 0,
        };
        assert_eq!(st(false, false).gap(p), Duration::from_millis(30));
        assert_eq!(st(false, true).gap(p), Duration::from_millis(45));
        assert_eq!(st(true, true).gap(p), Duration::from_millis(15));
        assert_eq!(st(true, false).gap(p), Duration::from_millis(15));
    }

    #[test]
    fn requests_are_read_and_bad_ones_named() {
        assert_eq!(
            Request::parse(r#"{"type":"drag","target":[0.1,1.2,0.3],"seq":7}"#),
            Ok(Request::Drag {
                target: [0.1, 1.2, 0.3],
                seq: 7
            })
        );
        assert_eq!(
            Request::parse(r#"{"type":"play","on":false}"#),
            Ok(Request::Play { on: false })
        );
        let bad = |t: &str| Request::parse(t).unwrap_err();
        assert!(bad("not json").contains("bad message"));
        assert!(bad(r#"{"type":"jump"}"#).contains("unknown variant `jump`"));
        assert!(bad(r#"{"type":"drag","target":[1,2],"seq":1}"#).contains("bad message"));
        assert!(bad(r#"{"type":"drag","target":[1,2,3],"seq":-1}"#).contains("bad message"));
        assert!(bad(r#"{"type":"release","seq":1,"extra":1}"#).contains("unknown field"));
        assert!(bad(r#"{"type":"grab","point":[1e9,0,0],"seq":1}"#).contains("`point`"));
        let fold = |shape: &str, h: f64, n: usize| {
            let pts = vec![[0.0, 1.0, 0.1]; n];
            Request::parse(&serde_json::json!({"type": "fold", "shape": shape, "height": h, "points": pts, "seq": 3}).to_string())
        };
        assert!(matches!(
            fold("ridge", 0.015, 3),
            Ok(Request::Fold { seq: 3, .. })
        ));
        assert!(
            fold("bump", 0.015, 3)
                .unwrap_err()
                .contains("`ridge` or `valley`")
        );
        assert!(fold("valley", 0.5, 3).unwrap_err().contains("0.001 to 0.1"));
        assert!(fold("valley", f64::NAN, 3).is_err());
        assert!(fold("ridge", 0.01, 1).unwrap_err().contains("2 to 64"));
        assert!(fold("ridge", 0.01, 65).is_err());
        let long = format!(
            r#"{{"type":"release","seq":1,"pad":"{}"}}"#,
            "x".repeat(5000)
        );
        assert!(bad(&long).contains("at most 4096"));
    }
}
