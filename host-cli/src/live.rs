//! The live page: what the drive is doing, in a browser, while it runs — and a STOP button.
//!
//! ```text
//!  control loop ──► LiveFeed (owned by the loop; batches samples, never waits)
//!                     │ try_lock only: if the page's side holds the lock, the batch waits for
//!                     ▼ the next call — the control loop is never blocked by a viewer
//!                   LiveState (a ring of the last seconds, estimate, readiness, bus counters)
//!                     ▲
//!  HTTP thread (tiny_http) ── GET /?token=…        the page (uPlot embedded, works offline)
//!                          ── GET /events?token=…  Server-Sent Events: new samples + state, 10 /s
//!                          ── POST /stop  + header X-Propid-Token: … ──► the same stop flag as Ctrl-C
//! ```
//! Safety: the server binds to loopback unless told otherwise; every request needs the per-run
//! token printed on the terminal (a page of another site can neither read the data nor press
//! STOP: it does not know the token, and a cross-site form cannot set the header); the page can
//! only stop the drive — it never sends a setpoint.

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use propid_drive_host::live::{DriveView, LiveState};
use propid_drive_host::stand::Played;

/// How often the page is sent what is new.
const PUSH_PERIOD: Duration = Duration::from_millis(100);

/// Writes a Server-Sent Events response on the raw connection: a header, then what is new every
/// [`PUSH_PERIOD`], each message flushed; ends when the viewer goes or the server shuts down.
fn stream_events(
    w: &mut dyn std::io::Write,
    state: &LiveState,
    shutdown: &AtomicBool,
) -> std::io::Result<()> {
    w.write_all(
        b"HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-cache\r\nConnection: close\r\n\r\n",
    )?;
    let (mut after, mut estimates_after) = (0, 0);
    while !shutdown.load(Ordering::Relaxed) {
        let (json, seq, est) = state.update_since(after, estimates_after);
        after = seq;
        estimates_after = est;
        w.write_all(format!("data: {json}\n\n").as_bytes())?;
        w.flush()?;
        std::thread::sleep(PUSH_PERIOD);
    }
    Ok(())
}

/// The running server. Dropping it stops it.
pub struct LiveServer {
    /// The address it listens on.
    pub addr: SocketAddr,
    /// The per-run token every request must carry.
    pub token: String,
    shutdown: Arc<AtomicBool>,
    server: Arc<tiny_http::Server>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl LiveServer {
    /// The page's address, token included (what the user opens).
    pub fn url(&self) -> String {
        format!("http://{}/?token={}", self.addr, self.token)
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.shutdown.store(true, Ordering::Relaxed);
        self.server.unblock();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// A fresh random token (128 bits, hex).
pub fn new_token() -> String {
    let bytes: [u8; 16] = rand::random();
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Checks the address the user gave: loopback always; anything else only with `allow_remote`.
pub fn check_addr(addr: &str, allow_remote: bool) -> Result<SocketAddr, crate::InputError> {
    let parsed: SocketAddr = addr.parse().map_err(|_| {
        crate::InputError::invalid(format!(
            "--live `{addr}` is not an address like 127.0.0.1:8080"
        ))
    })?;
    if !parsed.ip().is_loopback() && !allow_remote {
        return Err(crate::InputError::invalid(format!(
            "--live {addr} is not a loopback address: anyone who can reach it and has the token could stop the drive; add --live-allow-remote to serve it anyway"
        )));
    }
    Ok(parsed)
}

/// Starts serving the page for `state`; STOP raises `stop`.
pub fn serve(
    addr: SocketAddr,
    state: Arc<LiveState>,
    stop: Arc<AtomicBool>,
    title: String,
) -> anyhow::Result<LiveServer> {
    let server = Arc::new(
        tiny_http::Server::http(addr)
            .map_err(|e| anyhow::anyhow!("cannot serve the live page on {addr}: {e}"))?,
    );
    let addr = server
        .server_addr()
        .to_ip()
        .context("the live page's listening address")?;
    let token = new_token();
    let shutdown = Arc::new(AtomicBool::new(false));
    let thread = {
        let (server, token, shutdown) = (Arc::clone(&server), token.clone(), Arc::clone(&shutdown));
        std::thread::Builder::new()
            .name("live-page".into())
            .spawn(move || accept_loop(&server, &token, &state, &stop, &shutdown, &title))
            .context("starting the live page's thread")?
    };
    Ok(LiveServer {
        addr,
        token,
        shutdown,
        server,
        thread: Some(thread),
    })
}

fn query_token(url: &str) -> Option<&str> {
    let query = url.split_once('?')?.1;
    query.split('&').find_map(|kv| kv.strip_prefix("token="))
}

fn header<'r>(request: &'r tiny_http::Request, name: &'static str) -> Option<&'r str> {
    request
        .headers()
        .iter()
        .find(|h| h.field.equiv(name))
        .map(|h| h.value.as_str())
}

fn text_response(code: u16, body: &str) -> tiny_http::Response<std::io::Cursor<Vec<u8>>> {
    tiny_http::Response::from_string(body).with_status_code(code)
}

fn content_type(value: &str) -> tiny_http::Header {
    tiny_http::Header::from_bytes("Content-Type", value).expect("a valid header")
}

fn accept_loop(
    server: &tiny_http::Server,
    token: &str,
    state: &Arc<LiveState>,
    stop: &Arc<AtomicBool>,
    shutdown: &Arc<AtomicBool>,
    title: &str,
) {
    let page = live_page(title);
    for request in server.incoming_requests() {
        if shutdown.load(Ordering::Relaxed) {
            break;
        }
        let url = request.url().to_string();
        let path = url.split('?').next().unwrap_or("");
        let method = request.method().clone();
        let authorised =
            query_token(&url) == Some(token) || header(&request, "X-Propid-Token") == Some(token);
        let result = match (method, path) {
            (_, _) if !authorised => request.respond(text_response(
                403,
                "forbidden: this page needs the run's token (printed on the terminal)\n",
            )),
            (tiny_http::Method::Get, "/") => request.respond(
                tiny_http::Response::from_string(page.clone())
                    .with_header(content_type("text/html; charset=utf-8")),
            ),
            (tiny_http::Method::Get, "/events") => {
                let (state, shutdown) = (Arc::clone(state), Arc::clone(shutdown));
                // Each viewer gets its own thread: a slow browser never holds up another one.
                // The stream is written by hand on the raw connection so that every message is
                // flushed as it is made (no chunking, no buffering until a chunk fills).
                let _ = std::thread::Builder::new()
                    .name("live-events".into())
                    .spawn(move || {
                        let mut w = request.into_writer();
                        let _ = stream_events(&mut *w, &state, &shutdown);
                    });
                Ok(())
            }
            // STOP must come with the header: a cross-site form or image cannot set it.
            (tiny_http::Method::Post, "/stop")
                if header(&request, "X-Propid-Token") == Some(token) =>
            {
                stop.store(true, Ordering::SeqCst);
                request.respond(text_response(
                    200,
                    "stopping: STANDBY and a zero setpoint\n",
                ))
            }
            (tiny_http::Method::Post, "/stop") => request.respond(text_response(
                403,
                "forbidden: STOP needs the X-Propid-Token header\n",
            )),
            _ => request.respond(text_response(404, "not found\n")),
        };
        let _ = result;
    }
}

/// The page's markup, style and application (files, included at build time).
const LIVE_HTML: &str = include_str!("../assets/live/live.html");
/// The live page's own style.
const LIVE_CSS: &str = include_str!("../assets/live/live.css");
/// The live page's application: reads the event stream, draws, sends STOP.
const LIVE_JS: &str = include_str!("../assets/live/live.js");

/// The page: uPlot charts fed by the event stream, the estimate, readiness, bus health, STOP.
/// The same for every run: the script reads the token from the page's address.
fn live_page(title: &str) -> String {
    let body = format!("<style>{LIVE_CSS}</style>\n{LIVE_HTML}<script>\n{LIVE_JS}</script>\n");
    crate::html::page(title, &[body])
}

/// Starts the live page for a drive if `addr` is given: prints the URL on stderr.
pub fn start_for_drive(
    addr: Option<&str>,
    allow_remote: bool,
    stop: &Arc<AtomicBool>,
    played: Played,
    title: &str,
) -> anyhow::Result<Option<(LiveServer, DriveView)>> {
    let Some(addr) = addr else {
        return Ok(None);
    };
    let addr = check_addr(addr, allow_remote)?;
    if !addr.ip().is_loopback() {
        eprintln!(
            "warning: the live page is served on {addr}, beyond this machine; anyone who reaches it with the token can stop the drive"
        );
    }
    let state = Arc::new(LiveState::default());
    let server = serve(
        addr,
        Arc::clone(&state),
        Arc::clone(stop),
        title.to_string(),
    )?;
    eprintln!(
        "live: open {} (STOP there does what Ctrl-C does)",
        server.url()
    );
    Ok(Some((server, DriveView::new(state, played))))
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_drive_host::live::{LiveFeed, LivePoint};
    use std::io::{BufRead, BufReader, Read, Write};
    use std::net::TcpStream;

    fn get(addr: SocketAddr, request: &str) -> (u16, String) {
        let mut s = TcpStream::connect(addr).unwrap();
        s.write_all(request.as_bytes()).unwrap();
        let mut text = String::new();
        let _ = s.set_read_timeout(Some(Duration::from_secs(5)));
        let _ = s.read_to_string(&mut text);
        let code = text
            .split_whitespace()
            .nth(1)
            .and_then(|c| c.parse().ok())
            .unwrap_or(0);
        (code, text)
    }

    #[test]
    fn token_guards_every_route_and_stop_needs_the_header() {
        let state = Arc::new(LiveState::default());
        let stop = Arc::new(AtomicBool::new(false));
        let server = serve(
            "127.0.0.1:0".parse().unwrap(),
            Arc::clone(&state),
            Arc::clone(&stop),
            "test".into(),
        )
        .unwrap();
        let (a, tok) = (server.addr, server.token.clone());
        let close = "Connection: close\r\n\r\n";
        assert_eq!(
            get(a, &format!("GET / HTTP/1.1\r\nHost: x\r\n{close}")).0,
            403
        );
        let (code, page) = get(
            a,
            &format!("GET /?token={tok} HTTP/1.1\r\nHost: x\r\n{close}"),
        );
        assert_eq!(code, 200);
        assert!(page.contains("STOP") && page.contains("uPlot"));
        // A cross-site form post knows neither the token nor how to set the header.
        let form =
            format!("POST /stop?token={tok} HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n{close}");
        assert_eq!(get(a, &form).0, 403);
        assert!(!stop.load(Ordering::SeqCst));
        let wrong = format!(
            "POST /stop HTTP/1.1\r\nHost: x\r\nX-Propid-Token: 00\r\nContent-Length: 0\r\n{close}"
        );
        assert_eq!(get(a, &wrong).0, 403);
        assert!(!stop.load(Ordering::SeqCst));
        let right = format!("POST /stop HTTP/1.1\r\nHost: x\r\nX-Propid-Token: {tok}\r\nContent-Length: 0\r\n{close}");
        assert_eq!(get(a, &right).0, 200);
        assert!(stop.load(Ordering::SeqCst));
    }

    #[test]
    fn events_carry_what_the_feed_published() {
        let state = Arc::new(LiveState::default());
        let mut feed = LiveFeed::new(Arc::clone(&state));
        for k in 0..5 {
            feed.sample(LivePoint {
                t: k as f64,
                setpoint: 0.5,
                force: 0.01,
                velocity: 100.0,
                acceleration: 1.0,
            });
        }
        feed.readiness("ENGAGED");
        feed.flush();
        let server = serve(
            "127.0.0.1:0".parse().unwrap(),
            Arc::clone(&state),
            Arc::new(AtomicBool::new(false)),
            "test".into(),
        )
        .unwrap();
        let mut s = TcpStream::connect(server.addr).unwrap();
        write!(
            s,
            "GET /events?token={} HTTP/1.1\r\nHost: x\r\n\r\n",
            server.token
        )
        .unwrap();
        let mut r = BufReader::new(s);
        let mut line = String::new();
        let data = loop {
            line.clear();
            r.read_line(&mut line).unwrap();
            if let Some(d) = line.trim_end().strip_prefix("data: ") {
                break d.to_string();
            }
        };
        let v: serde_json::Value = serde_json::from_str(&data).unwrap();
        assert_eq!(v["seq"], 5);
        assert_eq!(v["points"].as_array().unwrap().len(), 5);
        assert_eq!(v["readiness"], "ENGAGED");
    }

    #[test]
    fn remote_addresses_need_an_explicit_flag() {
        assert!(check_addr("127.0.0.1:8080", false).is_ok());
        assert!(check_addr("0.0.0.0:8080", false).is_err());
        assert!(check_addr("0.0.0.0:8080", true).is_ok());
        assert!(check_addr("localhost", false).is_err());
    }
}
