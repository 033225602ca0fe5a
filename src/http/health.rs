//! `GET /healthz`.

use serde::{Deserialize, Serialize};

use super::extract::Json;

/// Body of `GET /healthz`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Health {
    /// Always `"ok"` while the server answers.
    pub status: String,
}

/// `GET /healthz` → 200 `{"status":"ok"}`.
pub async fn healthz() -> Json<Health> {
    Json(Health {
        status: "ok".to_owned(),
    })
}
