//! `GET /healthz`.

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::extract::Json;

/// Body of `GET /healthz`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[schema(examples(json!({"status": "ok"})))]
pub struct Health {
    /// Always `"ok"` while the server answers.
    pub status: String,
}

/// `GET /healthz` → 200 `{"status":"ok"}`.
#[utoipa::path(
    get,
    path = "/healthz",
    operation_id = "getHealth",
    tag = "health",
    summary = "Liveness check",
    description = "Answers 200 `{\"status\":\"ok\"}` while the server is up. Never requires authentication.",
    responses(
        (status = 200, description = "The server is up.", body = Health,
            example = json!({"status": "ok"})),
    )
)]
pub async fn healthz() -> Json<Health> {
    Json(Health {
        status: "ok".to_owned(),
    })
}
