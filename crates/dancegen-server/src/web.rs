//! The viewer, embedded in the binary (`web/`: the page, its scripts and the vendored
//! three.js with its licence), so the app works with no network and nothing to install.

use axum::body::Body;
use axum::http::{StatusCode, Uri, header};
use axum::response::{IntoResponse, Response};

use crate::error::ApiError;

#[derive(rust_embed::Embed)]
#[folder = "web/"]
#[exclude = "*.md"]
struct Web;

/// The content type of a viewer file, by extension (the few kinds `web/` holds).
fn content_type(path: &str) -> &'static str {
    match path.rsplit('.').next().unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "json" => "application/json",
        "png" => "image/png",
        "svg" => "image/svg+xml",
        "ico" => "image/x-icon",
        _ => "text/plain; charset=utf-8",
    }
}

/// `GET /` (the page, also for `/?job=<id>`) and the page's files.
pub async fn asset(uri: Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    let path = if path.is_empty() { "index.html" } else { path };
    match Web::get(path) {
        Some(file) => Response::builder()
            .status(StatusCode::OK)
            .header(header::CONTENT_TYPE, content_type(path))
            // The files change only with the binary; revalidate so an upgrade shows at once.
            .header(header::CACHE_CONTROL, "no-cache")
            .header(
                header::ETAG,
                format!(
                    "\"{}\"",
                    crate::owner::hex(&file.metadata.sha256_hash()[..8])
                ),
            )
            .body(Body::from(file.data.into_owned()))
            .unwrap_or_else(|_| StatusCode::INTERNAL_SERVER_ERROR.into_response()),
        None => ApiError::not_found(format!("no page /{path}")).into_response(),
    }
}

/// The page's inline import map (the text the Content-Security-Policy allows by its hash).
pub fn import_map() -> Option<String> {
    let page = Web::get("index.html")?;
    let html = std::str::from_utf8(&page.data).ok()?;
    crate::headers::import_map_of(html).map(str::to_string)
}
