//! The headers every response carries, so that a page or file from this server cannot be
//! turned against its users:
//!
//! - `Content-Security-Policy`: scripts, styles, fonts and connections only from this server
//!   (the page's one inline script, the import map that names three.js, is allowed by its
//!   SHA-256 alone); no plugins, no `<base>`, no framing. An uploaded file that got rendered
//!   as a page could run nothing.
//! - `X-Content-Type-Options: nosniff`: a file is only ever what its type says.
//! - `X-Frame-Options: DENY` (and `frame-ancestors 'none'`): no clickjacking by framing.
//! - `Referrer-Policy: no-referrer`: a job's id is what lets one read it, so page addresses
//!   holding ids are not sent to other sites.
//!
//! Job files are sent as attachments by the file handler ([`crate::api`]).

use axum::extract::Request;
use axum::http::{HeaderValue, header};
use axum::middleware::Next;
use axum::response::Response;
use base64::Engine;
use sha2::{Digest, Sha256};

/// The policy for a page whose inline import map is `import_map` (its exact text between the
/// tags; `None` when the page has none).
pub fn content_security_policy(import_map: Option<&str>) -> String {
    let script = match import_map {
        Some(text) => {
            let digest = Sha256::digest(text.as_bytes());
            let b64 = base64::engine::general_purpose::STANDARD.encode(digest);
            format!("script-src 'self' 'sha256-{b64}'")
        }
        None => "script-src 'self'".to_string(),
    };
    format!(
        "default-src 'self'; {script}; style-src 'self'; img-src 'self' data: blob:; \
         media-src 'self' blob:; connect-src 'self'; worker-src 'self' blob:; \
         object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'"
    )
}

/// The text of the first `<script type="importmap">` element of `html`.
pub fn import_map_of(html: &str) -> Option<&str> {
    const OPEN: &str = "<script type=\"importmap\">";
    let start = html.find(OPEN)? + OPEN.len();
    let len = html[start..].find("</script>")?;
    Some(&html[start..start + len])
}

/// Middleware adding the headers to every response (`policy` from
/// [`content_security_policy`]).
pub async fn add(policy: HeaderValue, req: Request, next: Next) -> Response {
    let mut res = next.run(req).await;
    let h = res.headers_mut();
    h.insert(header::CONTENT_SECURITY_POLICY, policy);
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    res
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_import_map_is_allowed_by_its_hash_alone() {
        let html =
            r#"<head><script type="importmap">{"imports":{}}</script><script src="a.js"></script>"#;
        let map = import_map_of(html).unwrap();
        assert_eq!(map, r#"{"imports":{}}"#);
        let csp = content_security_policy(Some(map));
        // SHA-256 of `{"imports":{}}` in base64, from Python's hashlib.
        assert!(
            csp.contains(
                "script-src 'self' 'sha256-URrTy+Il/Nz0lHojVUx275hWqAWhkSF0VsHbUM4/6Hw=';"
            ),
            "{csp}"
        );
        assert!(!csp.contains("unsafe"), "{csp}");
        assert!(csp.contains("frame-ancestors 'none'"));
        assert_eq!(import_map_of("<p>no map</p>"), None);
        assert_eq!(
            content_security_policy(None)
                .matches("script-src 'self';")
                .count(),
            1
        );
    }
}
