//! Extractors whose rejections are [`ApiError`]s, so that every failure,
//! including a malformed body, comes back as problem+json.

use axum::body::Bytes;
use axum::extract::{FromRequest, FromRequestParts, Request};
use axum::http::{HeaderMap, header};
use serde::de::DeserializeOwned;

use super::error::ApiError;

/// `axum::Json`, rejecting with [`ApiError`] (400 for a malformed body).
///
/// Written out rather than derived `via(axum::Json)`: axum parses through
/// `serde_path_to_error`, which more than doubles the parse of a plan
/// request (measured in `docs/performance.md`, *Parsing a body*). Here a body is parsed plainly, and only one that fails is parsed
/// again by axum, for its message (which names the field's path).
#[derive(Debug, Clone, Copy, Default)]
pub struct Json<T>(pub T);

impl<S, T> FromRequest<S> for Json<T>
where
    S: Send + Sync,
    T: DeserializeOwned,
{
    type Rejection = ApiError;

    async fn from_request(req: Request, state: &S) -> Result<Self, ApiError> {
        if !json_content_type(req.headers()) {
            return Err(ApiError::missing_json_content_type());
        }
        let bytes = Bytes::from_request(req, state).await?;
        match serde_json::from_slice(&bytes) {
            Ok(value) => Ok(Self(value)),
            Err(plain) => Err(match axum::Json::<T>::from_bytes(&bytes) {
                Err(rejection) => rejection.into(),
                // Not expected: both parse the same bytes with the same serde.
                Ok(_) => ApiError::MalformedBody(plain.to_string()),
            }),
        }
    }
}

/// `application/json` or any `application/*+json`, as `axum::Json` accepts.
fn json_content_type(headers: &HeaderMap) -> bool {
    headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<mime::Mime>().ok())
        .is_some_and(|m| {
            m.type_() == "application"
                && (m.subtype() == "json" || m.suffix().is_some_and(|s| s == "json"))
        })
}

/// `axum::extract::Path`, rejecting with [`ApiError`].
#[derive(Debug, Clone, Copy, Default, FromRequestParts)]
#[from_request(via(axum::extract::Path), rejection(ApiError))]
pub struct Path<T>(pub T);

impl<T: serde::Serialize> axum::response::IntoResponse for Json<T> {
    fn into_response(self) -> axum::response::Response {
        axum::Json(self.0).into_response()
    }
}

/// The JSON body of a request whose work waits for the planning queue
/// ([`on_rayon`](super::on_rayon)). When the queue is already full the body
/// is read (so the connection stays usable) but not parsed, and the request
/// is shed at once with 503: under overload a shed request then costs the
/// HTTP exchange only, not a parse and a validation of a plan that will not
/// be made (the more CPU shedding takes, the less is left to serve). Otherwise exactly [`Json`].
#[derive(Debug, Clone, Copy, Default)]
pub struct QueuedJson<T>(pub T);

impl<S, T> FromRequest<S> for QueuedJson<T>
where
    S: Send + Sync,
    T: DeserializeOwned,
{
    type Rejection = ApiError;

    async fn from_request(req: Request, state: &S) -> Result<Self, ApiError> {
        if super::queue::queue_full() {
            // Drained, not parsed; a body too large is refused as usual.
            Bytes::from_request(req, state).await?;
            super::queue::count_shed();
            return Err(ApiError::Overloaded);
        }
        let Json(value) = Json::<T>::from_request(req, state).await?;
        Ok(Self(value))
    }
}
