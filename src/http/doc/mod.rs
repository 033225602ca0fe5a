//! The leaves of the OpenAPI document that the handlers name in their
//! `#[utoipa::path]` attributes: request shapes, error responses and
//! example bodies. [`super::openapi`] assembles the document from them and
//! the handlers; nothing here imports a handler.

pub mod bounds;
pub mod examples;
mod requests;
mod responses;

pub use requests::*;
pub use responses::*;
