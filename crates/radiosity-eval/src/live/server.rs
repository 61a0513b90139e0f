//! The page served on `127.0.0.1`: plain HTTP/1.1 on the standard library, a thread per client,
//! the feed as server-sent events ([`Server`]).
//!
//! Routes: `/` the page; `/meta` the header as JSON; `/geometry` the binary sent once;
//! `/events` the feed: `begin`, `points`, `frame`, `end` and `done` events, each a JSON
//! object, a frame's radiosity base64 `f32` inside it. A client that joins late is sent every
//! point so far and each run's latest radiosity, then what comes. `/held.js?id=X` answers only
//! once the page has posted `/drawn?id=X`, after drawing the comparison's end: a page that
//! asks for it (`?hold`) holds its `load` event until then, which is what lets a headless
//! browser's screenshot wait for the run's end.

use crate::error::LabError;
use crate::live::feed::{Feed, FeedState, Frame, point_json};
use crate::live::page::{base64, live_page};
use serde_json::{Value, json};
use std::collections::HashSet;
use std::io::{BufRead, BufReader, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

/// A server bound to a port of `127.0.0.1`, serving one feed.
pub struct Server {
    listener: TcpListener,
    address: SocketAddr,
}

impl Server {
    /// Binds `127.0.0.1:port` (`0`: a free port the system picks). A port in use is refused in
    /// one sentence.
    pub fn bind(port: u16) -> Result<Server, LabError> {
        let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, port)).map_err(|e| {
            let why = match e.kind() {
                std::io::ErrorKind::AddrInUse => {
                    "it is in use: pick another with --port, or leave --port out for a free one".to_string()
                }
                _ => e.to_string(),
            };
            LabError::Invalid(format!("cannot serve on 127.0.0.1:{port}: {why}"))
        })?;
        let address = listener.local_addr().map_err(|e| LabError::Invalid(format!("cannot serve: {e}")))?;
        Ok(Server { listener, address })
    }

    /// The page's address, `http://127.0.0.1:PORT/`.
    pub fn url(&self) -> String {
        format!("http://{}/", self.address)
    }

    /// Serves `feed` on threads of its own until the process ends.
    pub fn serve(self, feed: Arc<Feed>) {
        let drawn = Arc::new((Mutex::new(HashSet::new()), Condvar::new()));
        std::thread::spawn(move || {
            for stream in self.listener.incoming().flatten() {
                let (feed, drawn) = (feed.clone(), drawn.clone());
                std::thread::spawn(move || {
                    // A client that leaves mid-answer is no error of the run's.
                    let _ = answer(stream, &feed, &drawn);
                });
            }
        });
    }
}

type Drawn = (Mutex<HashSet<String>>, Condvar);

/// Answers one request.
fn answer(stream: TcpStream, feed: &Feed, drawn: &Drawn) -> std::io::Result<()> {
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut line = String::new();
    reader.read_line(&mut line)?;
    // The headers are read and left: no route needs them.
    loop {
        let mut header = String::new();
        if reader.read_line(&mut header)? == 0 || header.trim().is_empty() {
            break;
        }
    }
    let mut parts = line.split_whitespace();
    let (method, target) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""));
    let (path, query) = target.split_once('?').unwrap_or((target, ""));
    let id = query.split('&').find_map(|kv| kv.strip_prefix("id=")).unwrap_or("").to_string();
    let mut out = stream;
    match (method, path) {
        ("GET", "/" | "/index.html") => reply(&mut out, "text/html; charset=utf-8", live_page().as_bytes()),
        ("GET", "/meta") => reply(&mut out, "application/json", feed.scene.meta.to_string().as_bytes()),
        ("GET", "/geometry") => reply(&mut out, "application/octet-stream", &feed.scene.geometry),
        ("GET", "/events") => events(&mut out, feed),
        ("POST", "/drawn") => {
            drawn.0.lock().unwrap_or_else(|e| e.into_inner()).insert(id);
            drawn.1.notify_all();
            reply(&mut out, "text/plain", b"")
        }
        ("GET", "/held.js") => {
            let mut set = drawn.0.lock().unwrap_or_else(|e| e.into_inner());
            while !set.contains(&id) && !feed.closed() {
                set = drawn.1.wait_timeout(set, Duration::from_millis(200)).unwrap_or_else(|e| e.into_inner()).0;
            }
            drop(set);
            reply(&mut out, "text/javascript", b"window.held = true;")
        }
        ("GET", "/favicon.ico") => write!(out, "HTTP/1.1 204 No Content\r\nConnection: close\r\n\r\n"),
        _ => write!(out, "HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"),
    }
}

fn reply(out: &mut TcpStream, kind: &str, body: &[u8]) -> std::io::Result<()> {
    write!(
        out,
        "HTTP/1.1 200 OK\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    out.write_all(body)?;
    out.flush()
}

/// What one client has been sent of a run.
#[derive(Clone, Copy, Default)]
struct Cursor {
    begun: bool,
    points: usize,
    serial: Option<u64>,
    ended: bool,
}

/// Streams the feed to one client until it leaves or the feed closes.
fn events(out: &mut TcpStream, feed: &Feed) -> std::io::Result<()> {
    write!(
        out,
        "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\nConnection: keep-alive\r\n\r\n"
    )?;
    out.flush()?;
    let mut cursors: Vec<Cursor> = Vec::new();
    let mut done = false;
    let mut seen = u64::MAX;
    loop {
        // What is new is gathered under the lock and written outside it.
        let (messages, frames, version, finished) = {
            let state = feed.wait(seen, Duration::from_secs(15));
            let (messages, frames, finished) = news(&state, &mut cursors, done);
            (messages, frames, state.version, finished)
        };
        if feed.closed() {
            return Ok(());
        }
        if version == seen && messages.is_empty() && frames.is_empty() && finished.is_none() {
            // Nothing for 15 s: a comment keeps the connection open and finds a closed one.
            out.write_all(b": still running\n\n")?;
            out.flush()?;
            continue;
        }
        seen = version;
        for (kind, data) in messages {
            write!(out, "event: {kind}\ndata: {data}\n\n")?;
        }
        for (index, frame) in frames {
            let encoded = base64(frame.values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>().as_slice());
            let data = json!({"run": index, "point": point_json(&frame.point),
                "exposure": frame.exposure, "values": encoded});
            let text = format!("event: frame\ndata: {data}\n\n");
            out.write_all(text.as_bytes())?;
            feed.sent.0.fetch_add(1, Ordering::Relaxed);
            feed.sent.1.fetch_add(text.len() as u64, Ordering::Relaxed);
        }
        if let Some(summary) = finished {
            write!(out, "event: done\ndata: {summary}\n\n")?;
            done = true;
        }
        out.flush()?;
    }
}

/// The events a client with `cursors` has not been sent, the frames to send, and the `done`
/// event when the comparison has ended and it was not sent yet.
#[allow(clippy::type_complexity)]
fn news(
    state: &FeedState,
    cursors: &mut Vec<Cursor>,
    done: bool,
) -> (Vec<(&'static str, Value)>, Vec<(usize, Arc<Frame>)>, Option<Value>) {
    cursors.resize(state.runs.len(), Cursor::default());
    let (mut messages, mut frames) = (Vec::new(), Vec::new());
    for (index, (run, cursor)) in state.runs.iter().zip(cursors.iter_mut()).enumerate() {
        if run.started && !cursor.begun {
            messages.push(("begin", json!({"run": index})));
            cursor.begun = true;
        }
        if run.points.len() > cursor.points {
            let points: Vec<Value> = run.points[cursor.points..].iter().map(point_json).collect();
            messages.push(("points", json!({"run": index, "points": points})));
            cursor.points = run.points.len();
        }
        if let Some(latest) = &run.latest
            && cursor.serial != Some(latest.serial)
        {
            frames.push((index, latest.clone()));
            cursor.serial = Some(latest.serial);
        }
        if let Some(end) = &run.end
            && !cursor.ended
        {
            messages.push(("end", json!({"run": index, "end": end})));
            cursor.ended = true;
        }
    }
    // `done` is written after the frames: the page draws the end before it says so.
    let finished = (!done).then(|| state.done.clone()).flatten();
    (messages, frames, finished)
}
