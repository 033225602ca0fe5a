//! The run's HTTP client and the requests it sends.

use anyhow::{Context, Result, bail};
use bytes::Bytes;
use reqwest::header::{AUTHORIZATION, CONTENT_TYPE, HeaderValue};

use super::target::Target;

/// The HTTP client of a run: HTTP/1.1, no proxy, Nagle off, up to
/// `connections` kept-alive connections.
///
/// # Errors
/// If the client cannot be built.
pub fn client(connections: usize) -> Result<reqwest::Client> {
    reqwest::Client::builder()
        .no_proxy()
        .tcp_nodelay(true)
        .pool_max_idle_per_host(connections.max(1))
        .build()
        .context("cannot build the HTTP client")
}

pub(super) fn auth_header(api_key: Option<&str>) -> Result<Option<HeaderValue>> {
    api_key
        .map(|k| {
            HeaderValue::from_str(&format!("Bearer {k}"))
                .context("the API key is not a valid header value")
        })
        .transpose()
}

pub(super) fn request(
    client: &reqwest::Client,
    target: &Target,
    seq: u64,
    auth: Option<&HeaderValue>,
) -> reqwest::RequestBuilder {
    let rb = match target {
        Target::Post { url, bodies } => {
            let body = bodies[(seq % bodies.len() as u64) as usize].clone();
            post(client, url, body)
        }
        Target::Get { url } => client.get(url),
        // Opening a session; the steps are sent by the session workers.
        Target::Session(t) => post(client, &t.sessions_url, t.create.clone()),
    };
    match auth {
        Some(a) => rb.header(AUTHORIZATION, a.clone()),
        None => rb,
    }
}

pub(super) fn post(client: &reqwest::Client, url: &str, body: Bytes) -> reqwest::RequestBuilder {
    client
        .post(url)
        .header(CONTENT_TYPE, HeaderValue::from_static("application/json"))
        .body(body)
}

pub(super) fn with_auth(
    rb: reqwest::RequestBuilder,
    auth: Option<&HeaderValue>,
) -> reqwest::RequestBuilder {
    match auth {
        Some(a) => rb.header(AUTHORIZATION, a.clone()),
        None => rb,
    }
}

/// Sends `rb` and reads its answer: the body of a 2xx, else an error
/// naming `what`, the status and the start of the body.
pub(super) async fn expect_ok(rb: reqwest::RequestBuilder, what: &str) -> Result<Bytes> {
    let res = rb
        .send()
        .await
        .with_context(|| format!("cannot reach {what}"))?;
    read_ok(res, what).await
}

/// The body of a 2xx answer, else an error naming `what`, the status and
/// the start of the body.
pub(super) async fn read_ok(res: reqwest::Response, what: &str) -> Result<Bytes> {
    let status = res.status();
    if !status.is_success() {
        let body = res.text().await.unwrap_or_default();
        let body: String = body.chars().take(500).collect();
        bail!("{what} answered {status}: {body}");
    }
    res.bytes()
        .await
        .with_context(|| format!("reading the answer of {what}"))
}
