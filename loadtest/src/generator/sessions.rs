//! Session mode's sessions: opened and warmed before the run, closed
//! after it.

use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context, Result};
use reqwest::header::HeaderValue;

use super::http::{expect_ok, post, read_ok, with_auth};
use super::target::SessionTarget;

/// One open session of a session-mode run.
#[derive(Debug)]
pub(super) struct SessionSlot {
    /// `{base}/v1/sessions/{id}`.
    pub(super) url: String,
    /// `{base}/v1/sessions/{id}/step`.
    pub(super) step_url: String,
    /// The same on every replica ([`SessionTarget::bases`]).
    pub(super) step_urls: Vec<String>,
    /// Steps finished (answered, failed or given up), in order: step `j`
    /// is sent once this reaches `j`.
    pub(super) done: tokio::sync::watch::Sender<u64>,
}

/// Opens `t.sessions` sessions and replays the warm-up steps into each,
/// a few sessions at a time (a 503 is retried after a pause).
///
/// # Errors
/// If a session cannot be created or a warm-up step fails; the sessions
/// already opened are closed first.
pub(super) async fn open_sessions(
    client: &reqwest::Client,
    t: &Arc<SessionTarget>,
    auth: Option<&HeaderValue>,
    timeout: Duration,
) -> Result<Vec<SessionSlot>> {
    let mut slots = Vec::with_capacity(t.sessions);
    for _ in 0..t.sessions {
        let created = expect_ok(
            with_auth(post(client, &t.sessions_url, t.create.clone()), auth).timeout(timeout),
            &format!("POST {}", t.sessions_url),
        )
        .await;
        let id = created.and_then(|body| {
            let v: serde_json::Value =
                serde_json::from_slice(&body).context("the new session is not JSON")?;
            v.get("id")
                .and_then(serde_json::Value::as_str)
                .map(str::to_owned)
                .context("the new session has no id")
        });
        match id {
            Ok(id) => {
                let url = format!("{}/{id}", t.sessions_url);
                slots.push(SessionSlot {
                    step_url: format!("{url}/step"),
                    step_urls: t
                        .bases
                        .iter()
                        .map(|b| format!("{b}/v1/sessions/{id}/step"))
                        .collect(),
                    url,
                    done: tokio::sync::watch::Sender::new(0),
                });
            }
            Err(e) => {
                close_sessions(client, &slots, auth, timeout).await;
                return Err(e);
            }
        }
    }
    // Warm-up: each session's steps in order, a few sessions at once so
    // that the server does not shed them.
    const AT_ONCE: usize = 4;
    let mut set = tokio::task::JoinSet::new();
    let mut warmed = Ok(());
    for (i, slot) in slots.iter().enumerate() {
        if set.len() == AT_ONCE
            && let Some(r) = set.join_next().await
        {
            warmed = warmed.and(r.context("a warm-up task failed")?);
        }
        if warmed.is_err() {
            break;
        }
        let (client, t, auth, url) = (
            client.clone(),
            Arc::clone(t),
            auth.cloned(),
            slot.step_url.clone(),
        );
        set.spawn(async move {
            for (k, body) in t.warmup.iter().enumerate() {
                let mut tries = 0;
                loop {
                    let res = with_auth(post(&client, &url, body.clone()), auth.as_ref())
                        .timeout(timeout)
                        .send()
                        .await;
                    if let Ok(r) = &res
                        && r.status() == reqwest::StatusCode::SERVICE_UNAVAILABLE
                        && tries < 100
                    {
                        tries += 1;
                        tokio::time::sleep(Duration::from_millis(20)).await;
                        continue;
                    }
                    let what = format!("warm-up step {k} of session {i} ({url})");
                    let res = res.with_context(|| format!("cannot reach {what}"))?;
                    read_ok(res, &what).await?;
                    break;
                }
            }
            Ok(())
        });
    }
    while let Some(r) = set.join_next().await {
        warmed = warmed.and(r.context("a warm-up task failed")?);
    }
    if let Err(e) = warmed {
        close_sessions(client, &slots, auth, timeout).await;
        return Err(e);
    }
    Ok(slots)
}

/// Deletes the sessions; a failure is reported on stderr, not an error of
/// the run (its figures stand).
pub(super) async fn close_sessions(
    client: &reqwest::Client,
    slots: &[SessionSlot],
    auth: Option<&HeaderValue>,
    timeout: Duration,
) {
    let mut failed = 0usize;
    let mut first = None;
    for slot in slots {
        let res = with_auth(client.delete(&slot.url), auth)
            .timeout(timeout)
            .send()
            .await;
        match res {
            Ok(r) if r.status().is_success() => {}
            Ok(r) => {
                failed += 1;
                first.get_or_insert_with(|| format!("DELETE {}: {}", slot.url, r.status()));
            }
            Err(e) => {
                failed += 1;
                first.get_or_insert_with(|| format!("DELETE {}: {e}", slot.url));
            }
        }
    }
    if failed > 0 {
        eprintln!(
            "vigil-loadtest: warning: {failed} of {} sessions not closed; first: {}",
            slots.len(),
            first.unwrap_or_default()
        );
    }
}
