//! Connection limits over real sockets: half-sent request heads are closed
//! after the header timeout while the server keeps answering others; an
//! idle keep-alive connection outlives the header timeout and is closed
//! after the idle timeout; past the connection cap a new connection is
//! closed at once and the open ones are still served.

use std::time::{Duration, Instant};

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use vigil::http::config::Settings;
use vigil::http::serve::ConnLimits;

use crate::helpers::spawn_limited;

const HALF_HEAD: &[u8] = b"POST /v1/scenarios/paper-v10/plan HTTP/1.1\r\nHost: vigil\r\n";
const HEALTH: &[u8] = b"GET /healthz HTTP/1.1\r\nHost: vigil\r\n\r\n";

/// Reads until the peer closes (Ok(bytes read)) or `within` passes (Err).
async fn read_to_close(s: &mut TcpStream, within: Duration) -> Result<Vec<u8>, ()> {
    let mut all = Vec::new();
    let mut buf = [0u8; 4096];
    let deadline = tokio::time::Instant::now() + within;
    loop {
        match tokio::time::timeout_at(deadline, s.read(&mut buf)).await {
            Err(_) => return Err(()),
            Ok(Ok(0) | Err(_)) => return Ok(all),
            Ok(Ok(n)) => all.extend_from_slice(&buf[..n]),
        }
    }
}

/// One request on an open connection; the response head's status line.
async fn health_on(s: &mut TcpStream) -> String {
    s.write_all(HEALTH).await.unwrap();
    let mut buf = vec![0u8; 4096];
    let n = tokio::time::timeout(Duration::from_secs(5), s.read(&mut buf))
        .await
        .expect("an answer")
        .unwrap();
    String::from_utf8_lossy(&buf[..n])
        .lines()
        .next()
        .unwrap_or_default()
        .to_owned()
}

fn addr(app: &crate::helpers::TestApp) -> String {
    app.address.trim_start_matches("http://").to_owned()
}

#[tokio::test]
async fn half_sent_heads_are_closed_after_the_header_timeout() {
    let limits = ConnLimits {
        header_timeout: Duration::from_millis(300),
        ..ConnLimits::default()
    };
    let app = spawn_limited(Settings::default(), limits).await;
    let mut slow = Vec::new();
    for _ in 0..50 {
        let mut s = TcpStream::connect(addr(&app)).await.unwrap();
        s.write_all(HALF_HEAD).await.unwrap();
        slow.push(s);
    }
    let opened = Instant::now();
    // Meanwhile the server answers others.
    let res = app.get("/healthz").await;
    assert_eq!(res.status(), reqwest::StatusCode::OK);
    assert!(opened.elapsed() < Duration::from_millis(300));
    for s in &mut slow {
        let got = read_to_close(s, Duration::from_secs(3)).await;
        assert!(got.is_ok(), "a half-sent head was still open after 3 s");
    }
    let waited = opened.elapsed();
    assert!(
        waited >= Duration::from_millis(250) && waited < Duration::from_secs(2),
        "closed after {waited:?} for a 300 ms header timeout"
    );
    let res = app.get("/healthz").await;
    assert_eq!(res.status(), reqwest::StatusCode::OK);
}

#[tokio::test]
async fn idle_keep_alive_connections_close_after_the_idle_timeout() {
    let limits = ConnLimits {
        header_timeout: Duration::from_millis(200),
        idle_timeout: Duration::from_millis(800),
        ..ConnLimits::default()
    };
    let app = spawn_limited(Settings::default(), limits).await;
    let mut s = TcpStream::connect(addr(&app)).await.unwrap();
    assert!(health_on(&mut s).await.contains("200"));
    // Idle past the header timeout: still open, and it serves again.
    tokio::time::sleep(Duration::from_millis(400)).await;
    assert!(health_on(&mut s).await.contains("200"));
    let idle_from = Instant::now();
    let got = read_to_close(&mut s, Duration::from_secs(3)).await;
    assert!(got.is_ok(), "an idle connection was still open after 3 s");
    let idle = idle_from.elapsed();
    assert!(
        idle >= Duration::from_millis(700) && idle < Duration::from_secs(2),
        "closed after {idle:?} idle for an 800 ms idle timeout"
    );
}

#[tokio::test]
async fn past_the_cap_new_connections_close_and_open_ones_are_served() {
    let limits = ConnLimits {
        max_connections: 4,
        ..ConnLimits::default()
    };
    let app = spawn_limited(Settings::default(), limits).await;
    let mut open = Vec::new();
    for _ in 0..4 {
        let mut s = TcpStream::connect(addr(&app)).await.unwrap();
        assert!(health_on(&mut s).await.contains("200"));
        open.push(s);
    }
    // The fifth is closed at once, without an answer.
    let mut extra = TcpStream::connect(addr(&app)).await.unwrap();
    let _ = extra.write_all(HEALTH).await;
    let got = read_to_close(&mut extra, Duration::from_secs(2)).await;
    assert_eq!(
        got,
        Ok(Vec::new()),
        "the connection past the cap was served"
    );
    // The open ones still are.
    for s in &mut open {
        assert!(health_on(s).await.contains("200"));
    }
    // Once one closes, a new one is served again.
    drop(open.pop());
    tokio::time::sleep(Duration::from_millis(100)).await;
    let mut again = TcpStream::connect(addr(&app)).await.unwrap();
    assert!(health_on(&mut again).await.contains("200"));
}
