//! `GET /healthz`.
//!
//! Liveness: it answers 200 while the server is up, whatever the database's
//! state, since plans on built-in, inline and already used scenarios keep
//! working without it. With `--database-url` the body also says whether
//! the database answers (checked every second), as the gauge
//! `vigil_database_up` does.

use axum::extract::State;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::extract::Json;
use super::state::AppState;

/// Body of `GET /healthz`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[schema(examples(json!({"status": "ok"}), json!({"status": "ok", "database": "down"})))]
pub struct Health {
    /// Always `"ok"` while the server answers.
    pub status: String,
    /// With `--database-url` only: `up` if the database answered its last
    /// check (every second), `down` if not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub database: Option<DatabaseState>,
}

/// Whether the scenario database answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum DatabaseState {
    /// It answered its last check.
    Up,
    /// It did not: catalogue writes and reads of scenarios not held here
    /// answer 503 until it is back.
    Down,
}

/// `GET /healthz` → 200 `{"status":"ok"}`.
#[utoipa::path(
    get,
    path = "/healthz",
    operation_id = "getHealth",
    tag = "health",
    summary = "Liveness check",
    description = "Answers 200 `{\"status\":\"ok\"}` while the server is up. Never requires authentication. \
        With a shared database (`--database-url`) the body adds `database`: `up` or `down`; the server \
        stays up (200) while the database is down.",
    responses(
        (status = 200, description = "The server is up.", body = Health,
            example = json!({"status": "ok"})),
    )
)]
pub async fn healthz(State(state): State<AppState>) -> Json<Health> {
    let database = state.registry.database().map(|db| {
        if db.is_up() {
            DatabaseState::Up
        } else {
            DatabaseState::Down
        }
    });
    Json(Health {
        status: "ok".to_owned(),
        database,
    })
}
