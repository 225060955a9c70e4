//! The API's errors: an HTTP status and a JSON body `{"error": "words", "field": "name"}`
//! that a person can read and a client can act on.

use axum::Json;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

#[derive(Debug, Clone, PartialEq)]
pub struct ApiError {
    pub status: StatusCode,
    pub message: String,
    /// The request field at fault (`song`, `params`, `steps`, …), when there is one.
    pub field: Option<String>,
    /// The server limit that refused the request (`max-queue`, `max-jobs-per-minute`, …; the
    /// `serve` flag that sets it), when a limit did.
    pub limit: Option<String>,
}

impl ApiError {
    pub fn new(status: StatusCode, message: impl Into<String>) -> Self {
        ApiError {
            status,
            message: message.into(),
            field: None,
            limit: None,
        }
    }

    /// A refusal by the server limit `limit` (named as its `serve` flag, without dashes in
    /// front): JSON `{"error", "limit"}`.
    pub fn limit(status: StatusCode, limit: &str, message: impl Into<String>) -> Self {
        ApiError {
            limit: Some(limit.to_string()),
            ..Self::new(status, message)
        }
    }

    /// 400 about `field`.
    pub fn field(field: &str, message: impl Into<String>) -> Self {
        ApiError {
            status: StatusCode::BAD_REQUEST,
            message: format!("{field}: {}", message.into()),
            field: Some(field.to_string()),
            limit: None,
        }
    }

    pub fn not_found(what: impl Into<String>) -> Self {
        Self::new(StatusCode::NOT_FOUND, what)
    }

    /// 500: the server's own fault (the database, the disk); logged where it happens.
    pub fn internal(message: impl Into<String>) -> Self {
        let message = message.into();
        tracing::error!("{message}");
        Self::new(StatusCode::INTERNAL_SERVER_ERROR, message)
    }
}

impl std::fmt::Display for ApiError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.status.as_u16(), self.message)
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let mut body = serde_json::json!({"error": self.message});
        if let Some(field) = &self.field {
            body["field"] = field.as_str().into();
        }
        if let Some(limit) = &self.limit {
            body["limit"] = limit.as_str().into();
        }
        (self.status, Json(body)).into_response()
    }
}

impl From<rusqlite::Error> for ApiError {
    fn from(e: rusqlite::Error) -> Self {
        ApiError::internal(format!("job database: {e}"))
    }
}

/// An error and every cause under it, on one line (what a failed job shows).
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let part = s.to_string();
        // Many errors already repeat their cause in their own message.
        if !text.contains(&part) {
            text.push_str(": ");
            text.push_str(&part);
        }
        source = s.source();
    }
    text
}
