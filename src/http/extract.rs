//! Extractors whose rejections are [`ApiError`]s, so that every failure,
//! including a malformed body, comes back as problem+json.

use axum::extract::{FromRequest, FromRequestParts};

use super::error::ApiError;

/// `axum::Json`, rejecting with [`ApiError`] (400 for a malformed body).
#[derive(Debug, Clone, Copy, Default, FromRequest)]
#[from_request(via(axum::Json), rejection(ApiError))]
pub struct Json<T>(pub T);

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
/// be made (which took a tenth of a plan's time each, and the more was
/// shed, the less was served). Otherwise exactly [`Json`].
#[derive(Debug, Clone, Copy, Default)]
pub struct QueuedJson<T>(pub T);

impl<S, T> FromRequest<S> for QueuedJson<T>
where
    S: Send + Sync,
    T: serde::de::DeserializeOwned,
{
    type Rejection = ApiError;

    async fn from_request(req: axum::extract::Request, state: &S) -> Result<Self, ApiError> {
        if super::queue_full() {
            // Drained, not parsed; a body too large is refused as usual.
            axum::body::Bytes::from_request(req, state).await?;
            super::count_shed();
            return Err(ApiError::Overloaded);
        }
        let Json(value) = Json::<T>::from_request(req, state).await?;
        Ok(Self(value))
    }
}
